# SPDX-License-Identifier: MIT
"""`make bench`: how fast the simulations run, in clocks per second during a move, per bench.

One long move (stepramp.sim.profiles' trap_long_cruise: about 90,000 clocks, 360,000 in exact mode) on the engine
bench, each bus top and each multi-axis top (3 axes), and the engine bench and the PLB-like top again with the exact
ramp (G_RAMP = 1), with the regression's own benches (tb/speed_bench.py): the bus master, the driver, the monitors
(functional coverage only when STEPRAMP_COVERAGE_DIR names a folder). Prints per bench the simulated clocks, the
wall time and clocks/s, and the simulator's CPU time and clocks per CPU second (the figure that does not depend on
what else the machine runs). Each bench runs --repeat times (5): the fastest run is printed, and the slowest's clocks
per CPU second beside it (on a shared machine the same run varies by up to a half: 135,000 to 205,000 clocks per
CPU second for the PLB-like top's move within minutes in session 19; scripts/simcount.sh counts instructions
instead). The RTL is built once (stepramp.sim.runner.build_once) and the build is not timed.

    python -m stepramp.tools.simbench [--tops stepramp_plb ...] [--exact TOP ...] [--profile NAME] [--repeat N]
        [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any

from stepramp.sim.runner import build_once, ghdl_backend, run_cocotb

REPO = Path(__file__).resolve().parents[3]
TOPS = ("stepramp_engine", "stepramp_plb", "stepramp_axil", "stepramp_multi_plb", "stepramp_multi_axil")
#: The axis count of the multi-axis tops here (as tb/test_multi_rtl.py builds them).
AXES = 3


def measure(top: str, out: Path, profile: str, ramp: int = 0) -> dict[str, Any]:
    """Run tb/speed_bench.py on one top (ramp: its G_RAMP, not for the multi-axis tops); its result (clocks, wall_s,
    cpu_s, steps)."""
    folder = out / (f"{top}_exact" if ramp else top)
    folder.mkdir(parents=True, exist_ok=True)
    result = folder / "speed.json"
    result.unlink(missing_ok=True)
    params: dict[str, object] = {"G_AXES": AXES} if top.startswith("stepramp_multi") else {}
    if ramp:
        params["G_RAMP"] = ramp
    env = {
        "STEPRAMP_SPEED_RESULT": str(result),
        "SPEED_PROFILE": profile,
        "SPEED_RAMP": str(ramp),
        "MULTI_AXES": str(AXES),
    }
    build_once(top)  # (not timed: the build is shared with the regression's)
    run_cocotb(top, "speed_bench", folder, parameters=params, extra_env=env, log_file=folder / "sim.log")
    if not result.exists():
        raise RuntimeError(f"{top}: the speed bench wrote no result; see {folder / 'sim.log'}")
    return json.loads(result.read_text())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tops", nargs="*", default=list(TOPS), help="benches to run (default: all)")
    ap.add_argument("--profile", default="trap_long_cruise", help="the move (a name of stepramp.sim.profiles)")
    ap.add_argument(
        "--exact",
        nargs="*",
        default=["stepramp_engine", "stepramp_plb"],
        help="benches also run with the exact ramp (G_RAMP = 1)",
    )
    ap.add_argument(
        "--repeat",
        type=int,
        default=5,
        help="runs of each bench; the fastest is printed, with the slowest's clocks/s (a shared machine's noise)",
    )
    ap.add_argument("--out", type=Path, default=REPO / "build" / "simbench")
    ap.add_argument("--json", type=Path, default=None, help="also write the figures here")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(REPO / "tb"))  # the benches (PYTHONPATH of the simulator is this process's sys.path)
    os.environ.setdefault("STEPRAMP_COVERAGE_DIR", "")
    rows = []
    print(f"simulation speed during a move ({args.profile}; GHDL back end {ghdl_backend() or '?'})")
    print(f"{'bench':<22}{'clocks':>9}{'wall s':>9}{'clocks/s':>11}{'cpu s':>8}{'clocks/cpu-s':>14}{'slowest run':>13}")
    runs = [(top, 0) for top in args.tops] + [(top, 1) for top in args.exact if top in args.tops]
    for top, ramp in runs:
        tries = []
        for _ in range(max(args.repeat, 1)):
            t = measure(top, args.out.resolve(), args.profile, ramp)
            t["clocks_per_s"] = t["clocks"] / t["wall_s"]
            t["clocks_per_cpu_s"] = t["clocks"] / t["cpu_s"]
            tries.append(t)
        r = max(tries, key=lambda t: t["clocks_per_cpu_s"])
        r["ramp"] = ramp
        r["slowest_clocks_per_cpu_s"] = min(t["clocks_per_cpu_s"] for t in tries)
        rows.append(r)
        name = f"{top} (exact)" if ramp else top
        print(
            f"{name:<22}{r['clocks']:>9}{r['wall_s']:>9.2f}{r['clocks_per_s']:>11,.0f}{r['cpu_s']:>8.2f}"
            f"{r['clocks_per_cpu_s']:>14,.0f}{r['slowest_clocks_per_cpu_s']:>13,.0f}"
        )
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
