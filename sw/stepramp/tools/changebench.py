# SPDX-License-Identifier: MIT
"""`make bench`: the change latency of CTRL.CHANGE, from the driver's planner (no simulator).

For random command scripts (stepramp.sim.scripts.random_script, seed 1 unless given) every take-over the driver
commits: the clocks and pulses from the committing write (its edge W) to the STEP edge of pulse P, where the new
segment takes over (its interval 1 follows pulse P), grouped by the ramp phase of interval P. The rule that picks P
is the issue's: the first pulse at least 2 pulses and 400 clocks after W (stepramp.board.change.change_pulse), so
the latency is max(2 pulses, 400 clocks) rounded up to the next pulse.

    python -m stepramp.tools.changebench [--scripts N] [--seed S]
"""

from __future__ import annotations

import argparse
import bisect
import itertools
import random
import statistics
from collections import defaultdict

from stepramp.board.regmap import offset
from stepramp.board.script import CHANGE, START, load_script, plan_script
from stepramp.sim.scripts import random_script


def _phase(intervals: list[int], p: int) -> str:
    """ACCEL, RUN or DECEL of interval p (the one that ends at pulse p) from the neighbouring intervals."""
    if p < 1 or p + 1 >= len(intervals):
        return "end"
    before, after = intervals[p - 1], intervals[p + 1]
    if abs(before - after) <= 1:
        return "RUN"
    return "ACCEL" if after < before else "DECEL"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scripts", type=int, default=400)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    rng = random.Random(args.seed)
    clocks: dict[str, list[int]] = defaultdict(list)
    pulses: dict[str, list[int]] = defaultdict(list)
    for _ in range(args.scripts):
        result = plan_script(load_script(random_script(rng)))
        edges = result.edges
        intervals = [0] + [b - a for a, b in itertools.pairwise(edges)]
        # Pulse 0 of each motion: the first edge after a START, or a queued start (5 or 7 clocks after the last
        # pulse of the motion before; within a motion pulses are at least 64 clocks apart).
        firsts = sorted(
            {bisect.bisect_left(edges, a.at + 5) for a in result.actions if a.ctrl & START}
            | {i for i in range(1, len(edges)) if intervals[i] in (5, 7)}
        )
        seen: set[int] = set()
        for action in result.actions:
            first_of_command = action.command not in seen
            seen.add(action.command)
            if action.ctrl != CHANGE or not first_of_command:  # (a queue's second take-over is at the boundary)
                continue
            emitted = bisect.bisect_right(edges, action.at)
            first = firsts[bisect.bisect_right(firsts, emitted - 1) - 1]
            p = first + dict(action.writes)[offset("CHANGE_AT")]
            if p >= len(edges):
                continue
            phase = _phase(intervals, p)
            clocks[phase].append(edges[p] - action.at)
            pulses[phase].append(p - emitted + 1)
    print(f"change latency, {args.scripts} random scripts (seed {args.seed}): from the commit to pulse P's STEP edge")
    print(f"{'phase':6} {'changes':>7} {'clocks min / median / max':>28} {'pulses min / median / max':>27}")
    for phase in ("ACCEL", "RUN", "DECEL", "end"):
        if not clocks[phase]:
            continue
        c, n = clocks[phase], pulses[phase]
        print(
            f"{phase:6} {len(c):7d} {min(c):8d} / {statistics.median(c):8.0f} / {max(c):6d} "
            f"{min(n):8d} / {statistics.median(n):6.0f} / {max(n):5d}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
