# SPDX-License-Identifier: MIT
"""`make demo`: the AVR446 demo's default move, simulated on the RTL, written to build/demo/.

The move of the AVR446 demo application (a 200-step motor half-stepping, so 400 steps/rev; accel and decel
40 rad/s^2, speed 20 rad/s, 400 steps) on a 1 MHz core clock with PRESCALE 1 (1 us ticks). Writes:
move.json (the `stepramp sim` JSON), the waveform, profile.png (step rate against time: RTL, model, ideal) and
report.txt; prints a short summary.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import sys
from pathlib import Path
from typing import Any

from stepramp.ideal import c0, ideal_move
from stepramp.model import FIRST_PULSE_LATENCY
from stepramp.model import edges as model_edges
from stepramp.plan import plan_move

DEMO_MOVE: dict[str, Any] = {
    "steps": 400,
    "accel": 40.0,
    "decel": 40.0,
    "speed": 20.0,
    "spr": 400.0,
    "fclk": 1e6,
    "prescale": 1,
}


def summarise(move: dict[str, Any], edges: list[int]) -> dict[str, Any]:
    """Figures of merit of a simulated move against the ideal trapezoid (times in ticks and seconds)."""
    prescale = move["prescale"]
    f_tick = move["fclk"] / prescale
    ideal = ideal_move(**move)
    ticks = [(e - FIRST_PULSE_LATENCY) / prescale for e in edges]
    deviation = [t - ti for t, ti in zip(ticks, ideal.pulse_times(), strict=True)]
    intervals = [b - a for a, b in itertools.pairwise(ticks)]
    c0_slow = c0(min(move["accel"], move["decel"]), move["spr"], move["fclk"], prescale)
    alpha = 2 * 3.141592653589793 / move["spr"]
    worst = max(range(len(deviation)), key=lambda k: abs(deviation[k])) if deviation else 0
    return {
        "steps": len(edges),
        "move_time_s": ticks[-1] / f_tick if ticks else 0.0,
        "ideal_move_time_s": ideal.t_end,
        "peak_speed_rad_s": alpha * f_tick / min(intervals) if intervals else 0.0,
        "ideal_peak_speed_rad_s": ideal.v_peak * alpha,
        "max_deviation_ticks": abs(deviation[worst]) if deviation else 0.0,
        "max_deviation_pulse": worst,
        "max_deviation_c0": abs(deviation[worst]) / c0_slow if deviation else 0.0,
        "c0_slow_ticks": c0_slow,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("build/demo"))
    args = parser.parse_args(argv)
    out: Path = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)

    from stepramp.enginesim import simulate  # needs cocotb and GHDL

    plan = plan_move(**DEMO_MOVE)
    waves = out / "stepramp_demo.ghw"
    print("stepramp demo: AVR446 default move (400 steps, 40 rad/s^2, 20 rad/s, 400 steps/rev), 1 MHz clock")
    print("  simulating the RTL with GHDL ...")
    results = simulate([plan], out / "sim", waves=waves, log_file=out / "sim.log")
    if not results or not results[0].done or results[0].error:
        print(f"  the simulation failed; see {out / 'sim.log'}", file=sys.stderr)
        return 1
    rtl = results[0]
    model = model_edges(plan)
    move_json = {
        "tool": "sim",
        "inputs": DEMO_MOVE,
        "registers": dataclasses.asdict(plan),
        "edges": rtl.edges,
        "final_position": rtl.final_position,
        "error": None,
    }
    (out / "move.json").write_text(json.dumps(move_json) + "\n")
    figures = summarise(DEMO_MOVE, rtl.edges)
    figures["rtl_equals_model"] = rtl.edges == model
    lines = [
        "stepramp demo report",
        f"move                  {DEMO_MOVE}",
        f"steps emitted         {figures['steps']} (position {rtl.final_position})",
        f"move time             {figures['move_time_s'] * 1e3:.3f} ms "
        f"(ideal {figures['ideal_move_time_s'] * 1e3:.3f} ms)",
        f"peak speed            {figures['peak_speed_rad_s']:.3f} rad/s "
        f"(ideal triangle peak {figures['ideal_peak_speed_rad_s']:.3f} rad/s)",
        f"largest deviation     {figures['max_deviation_ticks']:.2f} ticks = "
        f"{figures['max_deviation_c0']:.4f} c0 at pulse {figures['max_deviation_pulse']} "
        f"(c0 = {figures['c0_slow_ticks']:.0f} ticks)",
        f"RTL edges == model    {figures['rtl_equals_model']}",
    ]
    (out / "report.txt").write_text("\n".join(lines) + "\n")
    (out / "report.json").write_text(json.dumps(figures, indent=2) + "\n")
    try:
        from stepramp.plot import plot_move

        plot_move(move_json, out / "profile.png", model_edges=model)
        png = str(out / "profile.png")
    except ImportError:
        png = "(matplotlib missing: no plot)"
    print("\n".join("  " + line for line in lines[2:]))
    print(
        f"  waveform   {waves}\n  json       {out / 'move.json'}\n  report     {out / 'report.txt'}\n  plot       {png}"
    )
    return 0 if figures["rtl_equals_model"] else 1


if __name__ == "__main__":
    sys.exit(main())
