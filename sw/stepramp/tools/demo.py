# SPDX-License-Identifier: MIT
"""`make demo`: the AVR446 demo's default move, run on the RTL through the bus with the Python driver.

The move of the AVR446 demo application (its info line `Motor pos: 0   a:4000 d:4000 s:2000 m:400`: a 200-step
motor half-stepped, so 400 steps/rev; accel and decel 40 rad/s^2, speed 20 rad/s, 400 steps) on stepramp_plb
clocked at 250 kHz with PRESCALE 1 (4 us ticks), programmed over the PLB-like IPIF by stepramp.board.driver.StepRamp, as
`stepramp shell` does (stepramp.sim.session). Writes to build/demo/: the GHW waveform and a GTKWave save file that lays
it out (stepramp.sim.waves), move.json (the `stepramp sim` JSON contract), profile.png (step rate against time: RTL,
bit-exact model, ideal trapezoid; and each pulse's deviation from the ideal), report.txt and report.json; prints a
short table and the paths.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path
from typing import Any

from stepramp.board.driver import StepRampError
from stepramp.board.plan import plan_move
from stepramp.models.engine import edges as model_edges
from stepramp.sim.waves import signal_paths, write_gtkw
from stepramp.tools.shell import SHELL_CONFIG
from stepramp.tools.summary import summarise_edges

DEMO_MOVE: dict[str, Any] = {"steps": 400, "accel": 40.0, "decel": 40.0, "speed": 20.0, **SHELL_CONFIG}


def summarise(move: dict[str, Any], edges: list[int]) -> dict[str, Any]:
    """Figures of merit of a simulated move against the ideal trapezoid (times in ticks and seconds): the summary of
    `stepramp sim --summary` (stepramp.tools.summary), with the pulse count as "steps"."""
    figures = summarise_edges(move, edges)
    return {"steps": figures.pop("pulses"), **figures}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("build/demo"))
    args = parser.parse_args(argv)
    out: Path = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)

    from stepramp.sim.session import RtlSession, SessionError  # needs cocotb and GHDL

    plan = plan_move(**DEMO_MOVE)
    waves = out / "stepramp_demo.ghw"
    print(
        "stepramp demo: the AVR446 demo move (400 steps, 40 rad/s^2, 20 rad/s, 400 steps/rev) on stepramp_plb at "
        f"{DEMO_MOVE['fclk'] / 1e3:g} kHz,\n  programmed over the PLB-like bus by the Python driver; simulating ..."
    )
    try:
        with RtlSession(out / "sim", config=SHELL_CONFIG, waves=waves, log_file=out / "sim.log") as session:
            missing = session.missing_signals(signal_paths())
            rtl = session.move(DEMO_MOVE["steps"], DEMO_MOVE["accel"], DEMO_MOVE["decel"], DEMO_MOVE["speed"])
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
        "inputs": DEMO_MOVE,
        "registers": dataclasses.asdict(rtl.plan),
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
    figures = summarise(DEMO_MOVE, rtl.edges)
    figures["final_position"] = rtl.position
    figures["rtl_equals_model"] = rtl.edges == model and rtl.plan == plan
    figures["start_to_done_s"] = rtl.end_s - rtl.start_s
    figures["missing_waveform_signals"] = missing
    lines = [
        "stepramp demo report",
        f"move                  {DEMO_MOVE}",
        f"steps emitted         {figures['steps']} (POSITION read back: {rtl.position})",
        f"move time             {figures['move_time_s'] * 1e3:.3f} ms "
        f"(ideal {figures['ideal_move_time_s'] * 1e3:.3f} ms)",
        f"peak speed            {figures['peak_speed_rad_s']:.3f} rad/s "
        f"(ideal triangle peak {figures['ideal_peak_speed_rad_s']:.3f} rad/s)",
        f"largest deviation     {figures['max_deviation_ticks']:.2f} ticks = "
        f"{figures['max_deviation_c0']:.4f} c0 at pulse {figures['max_deviation_pulse']} "
        f"(c0 = {figures['c0_slow_ticks']:.0f} ticks)",
        f"RTL edges == model    {figures['rtl_equals_model']}",
        f"bus, program to DONE  {figures['start_to_done_s'] * 1e3:.3f} ms (register writes, move, interrupt, status)",
    ]
    (out / "report.txt").write_text("\n".join(lines) + "\n")
    (out / "report.json").write_text(json.dumps(figures, indent=2) + "\n")
    try:
        from stepramp.tools.plot import plot_move

        plot_move(move_json, out / "profile.png", model_edges=model)
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
