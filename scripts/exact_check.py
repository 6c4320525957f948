#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""`stepramp model --ramp exact --summary` on the 64 profiles and on random moves: the largest deviation of any
pulse from the ideal, in ticks (docs/algorithm.md, "Exact step times": within 1 tick).

    .venv/bin/python scripts/exact_check.py [--seed N] [--moves 1000]

Each move goes through the command line's own entry point (stepramp.tools.cli.main, in this process, so that a
thousand moves do not start a thousand interpreters); the summary's max_deviation_ticks is computed from the model's
edges and the ideal trapezoid (stepramp.tools.summary). Exit status 1 when a pulse is a tick or more off.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from stepramp.sim.profiles import EXACT_PROFILES, random_exact_moves
from stepramp.tools.cli import main as cli_main


def deviation(move: dict[str, Any], out: Path) -> float:
    """`stepramp model --ramp exact --summary` of one move: its max_deviation_ticks."""
    argv = ["model", "--ramp", "exact", "--summary", "--json", str(out), *(f"--{k}={v}" for k, v in move.items())]
    status = cli_main(argv)
    result = json.loads(out.read_text())
    if status != 0:
        raise RuntimeError(f"stepramp {' '.join(argv)}: exit {status}: {result['error']}")
    return float(result["summary"]["max_deviation_ticks"])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seed", type=int, default=int(time.time()))
    parser.add_argument("--moves", type=int, default=1000, help="random moves besides the 64 profiles")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "move.json"
        profiles = [deviation(p.args(), out) for p in EXACT_PROFILES]
        moves = [deviation(m, out) for m in random_exact_moves(args.seed, args.moves, long_moves=4)]
    worst = max(profiles + moves)
    print(
        f"stepramp model --ramp exact: {len(profiles)} profiles, worst {max(profiles):.4f} ticks; seed {args.seed}: "
        f"{len(moves)} random moves, worst {max(moves):.4f} ticks; every pulse within 1 tick: {worst < 1.0}"
    )
    return 0 if worst < 1.0 else 1


if __name__ == "__main__":
    sys.exit(main())
