# SPDX-License-Identifier: MIT
"""The `stepramp` command line.

    stepramp sim   --steps N --accel A --decel D --speed V --spr S --fclk F [--prescale P] [--waves FILE] [--json FILE]
    stepramp model (same options, no --waves)
    stepramp plot FILE.json [-o FILE.png]
    stepramp shell [--model] [--waves FILE.ghw] [--build DIR]   (the AVR446 demo's commands, from stdin)

Both print (or write with --json) one JSON object:
    {"tool": "sim"|"model", "inputs": {...}, "registers": {...}, "edges": [...], "final_position": int, "error": null}
`edges` are the clock cycles of each STEP rising edge, counted from the clock edge that sampled start. Invalid
input: exit status 2, "error" holds the reason, nothing is simulated. sim and model give identical edges.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

from stepramp.model import edges as model_edges
from stepramp.plan import plan_move


def _move_args(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--steps", type=int, required=True, help="signed step count (microsteps)")
    parser.add_argument("--accel", type=float, required=True, help="acceleration, rad/s^2")
    parser.add_argument("--decel", type=float, required=True, help="deceleration, rad/s^2")
    parser.add_argument("--speed", type=float, required=True, help="maximum speed, rad/s")
    parser.add_argument("--spr", type=float, required=True, help="steps per revolution, microsteps included")
    parser.add_argument("--fclk", type=float, required=True, help="core clock, Hz")
    parser.add_argument("--prescale", type=int, default=1, help="base timer period in clocks (default 1)")
    parser.add_argument("--json", type=Path, help="write the JSON here instead of stdout")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="stepramp", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    sim = sub.add_parser("sim", help="run a move on the RTL (GHDL) and report every step edge")
    _move_args(sim)
    sim.add_argument("--waves", type=Path, help="write a waveform (.ghw, or .fst)")
    sim.add_argument("--build", type=Path, help="simulation build directory (default: a temporary one)")
    model = sub.add_parser("model", help="the same move from the bit-exact Python model")
    _move_args(model)
    plot = sub.add_parser("plot", help="draw a `stepramp sim` or `stepramp model` JSON file to a PNG")
    plot.add_argument("file", type=Path, help="the JSON written by `stepramp sim|model --json FILE`")
    plot.add_argument("-o", "--out", type=Path, help="PNG to write (default: FILE with .png)")
    shell = sub.add_parser("shell", help="the AVR446 demo application's commands on the RTL, read from stdin")
    shell.add_argument("--model", action="store_true", help="run the bit-exact model instead of the RTL")
    shell.add_argument("--waves", type=Path, help="write the session's waveform (.ghw, or .fst)")
    shell.add_argument("--build", type=Path, help="simulation build directory (default: a temporary one)")
    return parser


def plot_file(path: Path, png: Path | None) -> int:
    """`stepramp plot`: step rate against time (with the bit-exact model and the ideal) and the deviation."""
    from stepramp.plot import plot_move  # needs matplotlib

    move = json.loads(path.read_text())
    if move.get("error") or not move.get("registers"):
        print(f"stepramp plot: {path} holds no move ({move.get('error')})", file=sys.stderr)
        return 2
    png = png or path.with_suffix(".png")
    plot_move(move, png, model_edges=model_edges(plan_move(**move["inputs"])))
    print(png)
    return 0


def run_move(tool: str, args: argparse.Namespace) -> tuple[dict[str, Any], int]:
    """Plan and run one move with the model or the RTL; returns the JSON object and the exit status."""
    inputs = {k: getattr(args, k) for k in ("steps", "accel", "decel", "speed", "spr", "fclk", "prescale")}
    out: dict[str, Any] = {
        "tool": tool,
        "inputs": inputs,
        "registers": None,
        "edges": [],
        "final_position": 0,
        "error": None,
    }
    try:
        plan = plan_move(**inputs)
    except ValueError as exc:
        out["error"] = str(exc)
        return out, 2
    out["registers"] = dataclasses.asdict(plan)
    if tool == "model":
        out["edges"] = model_edges(plan)
        out["final_position"] = args.steps
        return out, 0

    from stepramp.enginesim import simulate  # needs cocotb and GHDL, the model does not

    with tempfile.TemporaryDirectory(prefix="stepramp-sim-") as tmp:
        build = args.build or Path(tmp)
        results = simulate([plan], build, waves=args.waves, log_file=build.resolve() / "sim.log")
    if not results or not results[0].done:
        out["error"] = "the RTL did not finish the move (hang); see the simulation log"
        return out, 1
    res = results[0]
    out["edges"] = res.edges
    out["final_position"] = res.final_position
    if res.error:
        out["error"] = f"the engine flagged error code {res.err_code}"
        return out, 1
    return out, 0


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.command == "plot":
        return plot_file(args.file, args.out)
    if args.command == "shell":
        from stepramp.shell import main as shell_main

        return shell_main(model=args.model, waves=args.waves, build=args.build)
    if args.command in ("sim", "model"):
        out, status = run_move(args.command, args)
        text = json.dumps(out, indent=None)
        if args.json:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(text + "\n")
        else:
            print(text)
        if out["error"]:
            print(f"stepramp {args.command}: {out['error']}", file=sys.stderr)
        return status
    return 2


if __name__ == "__main__":
    sys.exit(main())
