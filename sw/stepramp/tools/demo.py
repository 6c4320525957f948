# SPDX-License-Identifier: MIT
"""`make demo`: the AVR446 demo's default move, run on the RTL through the bus with the Python driver.

The move of the AVR446 demo application (its info line `Motor pos: 0   a:4000 d:4000 s:2000 m:400`: a 200-step
motor half-stepped, so 400 steps/rev; accel and decel 40 rad/s^2, speed 20 rad/s, 400 steps) on stepramp_plb
clocked at 250 kHz with PRESCALE 1 (4 us ticks), programmed over the PLB-like IPIF by stepramp.board.driver.StepRamp, as
`stepramp shell` does (stepramp.sim.session). Writes to build/demo/: the GHW waveform and a GTKWave save file that lays
it out (stepramp.sim.waves), move.json (the `stepramp sim` JSON contract), profile.png (step rate against time: RTL,
bit-exact model, ideal trapezoid; and each pulse's deviation from the ideal, with the other ramp arithmetic's model
beside it), report.txt and report.json; prints a short table and the paths.

--ramp exact runs the core built with G_RAMP = 1 (docs/algorithm.md, "Exact step times") at the same 4 us tick from a
1 MHz clock with PRESCALE 4 (the exact mode's shortest interval is 256 clocks); the plot then compares it with the
AVR446 recurrence's model.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from stepramp.board.driver import StepRampError
from stepramp.board.plan import RAMP_AVR446, RAMP_EXACT, RAMPS, plan_move
from stepramp.models.engine import edges as model_edges
from stepramp.models.engine import tick_times
from stepramp.sim.waves import signal_paths, write_gtkw
from stepramp.tools.shell import SHELL_CONFIG, SHELL_EXACT_CONFIG
from stepramp.tools.summary import summarise_edges

DEMO_MOVE: dict[str, Any] = {"steps": 400, "accel": 40.0, "decel": 40.0, "speed": 20.0, **SHELL_CONFIG}
DEMO_EXACT_MOVE: dict[str, Any] = {**DEMO_MOVE, **SHELL_EXACT_CONFIG}
"""The same move in exact mode: the same 4 us tick from a 1 MHz clock with PRESCALE 4."""


def summarise(move: dict[str, Any], edges: list[int]) -> dict[str, Any]:
    """Figures of merit of a simulated move against the ideal trapezoid (times in ticks and seconds): the summary of
    `stepramp sim --summary` (stepramp.tools.summary), with the pulse count as "steps"."""
    figures = summarise_edges(move, edges)
    return {"steps": figures.pop("pulses"), **figures}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("build/demo"))
    parser.add_argument("--ramp", choices=sorted(RAMPS), default="avr446", help="the core's ramp arithmetic (G_RAMP)")
    args = parser.parse_args(argv)
    out: Path = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)

    from stepramp.sim.session import RtlSession, SessionError  # needs cocotb and GHDL

    ramp = RAMPS[args.ramp]
    demo_move = DEMO_EXACT_MOVE if ramp == RAMP_EXACT else DEMO_MOVE
    other = DEMO_MOVE if ramp == RAMP_EXACT else DEMO_EXACT_MOVE
    other_ramp = RAMP_AVR446 if ramp == RAMP_EXACT else RAMP_EXACT
    plan = plan_move(**demo_move, ramp=ramp)
    waves = out / "stepramp_demo.ghw"
    print(
        "stepramp demo: the AVR446 demo move (400 steps, 40 rad/s^2, 20 rad/s, 400 steps/rev) on stepramp_plb "
        f"(G_RAMP = {ramp}: {args.ramp}) at {demo_move['fclk'] / 1e3:g} kHz, PRESCALE {demo_move['prescale']},\n"
        "  programmed over the PLB-like bus by the Python driver; simulating ..."
    )
    config = {**SHELL_CONFIG, **demo_move, "ramp": ramp}
    config = {k: config[k] for k in ("fclk", "spr", "prescale", "ramp")}
    try:
        with RtlSession(out / "sim", config=config, waves=waves, log_file=out / "sim.log") as session:
            missing = session.missing_signals(signal_paths())
            rtl = session.move(demo_move["steps"], demo_move["accel"], demo_move["decel"], demo_move["speed"])
    except (SessionError, StepRampError, ValueError) as exc:
        print(f"  the simulation failed: {exc}", file=sys.stderr)
        return 1
    gtkw = write_gtkw(
        out / "stepramp_demo.gtkw",
        waves,
        duration_s=rtl.end_s * 1.02,
        marker_s=(rtl.start_s + rtl.end_s) / 2,
        title="stepramp demo: the AVR446 demo move",
    )
    model = model_edges(plan)
    move_json = {
        "tool": "sim",
        "inputs": demo_move,
        **({"ramp": args.ramp} if ramp == RAMP_EXACT else {}),
        "registers": rtl.plan.to_dict(),
        "edges": rtl.edges,
        "final_position": rtl.position,
        "error": None,
    }
    (out / "move.json").write_text(json.dumps(move_json) + "\n")
    if len(rtl.edges) != len(model):
        print(
            f"  the RTL emitted {len(rtl.edges)} steps, the model {len(model)}: see {out / 'move.json'}",
            file=sys.stderr,
        )
        return 1
    figures = summarise(demo_move, rtl.edges)
    other_plan = plan_move(**other, ramp=other_ramp)
    other_name = "exact" if other_ramp == RAMP_EXACT else "avr446"
    other_figures = summarise(other, model_edges(other_plan))
    figures["ramp"] = args.ramp
    figures[f"{other_name}_model_max_deviation_ticks"] = other_figures["max_deviation_ticks"]
    figures["final_position"] = rtl.position
    figures["rtl_equals_model"] = rtl.edges == model and rtl.plan == plan
    figures["start_to_done_s"] = rtl.end_s - rtl.start_s
    figures["missing_waveform_signals"] = missing
    lines = [
        "stepramp demo report",
        f"move                  {demo_move} ({args.ramp} ramp, G_RAMP = {ramp})",
        f"steps emitted         {figures['steps']} (POSITION read back: {rtl.position})",
        f"move time             {figures['move_time_s'] * 1e3:.3f} ms "
        f"(ideal {figures['ideal_move_time_s'] * 1e3:.3f} ms)",
        f"peak speed            {figures['peak_speed_rad_s']:.3f} rad/s "
        f"(ideal triangle peak {figures['ideal_peak_speed_rad_s']:.3f} rad/s)",
        f"largest deviation     {figures['max_deviation_ticks']:.2f} ticks = "
        f"{figures['max_deviation_c0']:.4f} c0 at pulse {figures['max_deviation_pulse']} "
        f"(c0 = {figures['c0_slow_ticks']:.0f} ticks)",
        f"the {other_name} ramp       largest deviation {other_figures['max_deviation_ticks']:.2f} ticks "
        f"(its model, the same move and tick)",
        f"RTL edges == model    {figures['rtl_equals_model']}",
        f"bus, program to DONE  {figures['start_to_done_s'] * 1e3:.3f} ms (register writes, move, interrupt, status)",
    ]
    (out / "report.txt").write_text("\n".join(lines) + "\n")
    (out / "report.json").write_text(json.dumps(figures, indent=2) + "\n")
    try:
        from stepramp.tools.plot import plot_move

        compare = {f"{other_name} model": tick_times(other_plan)}
        plot_move(move_json, out / "profile.png", model_edges=model, compare=compare)
        png = str(out / "profile.png")
    except ImportError:
        png = "(matplotlib missing: no plot)"
    print("\n".join("  " + line for line in lines[2:]))
    print(
        f"  waveform   {waves}\n  layout     {gtkw}  (gtkwave {gtkw}, or make waves)\n"
        f"  plot       {png}\n  report     {out / 'report.txt'}\n  json       {out / 'move.json'}"
    )
    if missing:
        print(f"  the waveform layout names signals the RTL does not have: {missing}", file=sys.stderr)
    return 0 if figures["rtl_equals_model"] and not missing else 1


if __name__ == "__main__":
    sys.exit(main())
