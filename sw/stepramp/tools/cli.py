# SPDX-License-Identifier: MIT
"""The `stepramp` command line.

    stepramp sim   --steps N --accel A --decel D --speed V --spr S --fclk F [--prescale P] [--waves FILE] [--json FILE]
                   [--summary]
    stepramp model (same options, no --waves)
    stepramp sim   --script FILE [--json OUT] [--waves W] [--build DIR] [--top plb|axil]
    stepramp model --script FILE [--json OUT]
    stepramp plot FILE.json [-o FILE.png]
    stepramp shell [--model] [--waves FILE.ghw] [--build DIR]   (the AVR446 demo's commands, from stdin)

Both print (or write with --json) one JSON object:
    {"tool": "sim"|"model", "inputs": {...}, "registers": {...}, "edges": [...], "final_position": int, "error": null}
`edges` are the clock cycles of each STEP rising edge, counted from the clock edge that sampled start. Invalid
input: exit status 2, "error" holds the reason, nothing is simulated. sim and model give identical edges.
The object is written as it is produced (the edges chunk by chunk), so `stepramp model` takes bounded memory for any
valid move. --summary writes "summary" (pulse count, last edge, move time, peak speed, largest deviation from the
ideal, checksum of the edges; docs/algorithm.md, "Long moves") in place of "edges". What would not fit the memory
budget (`stepramp sim` beyond SIM_MAX_PULSES pulses, `stepramp plot` of a too large move) exits with status 2 and
the reason.

With --script FILE (a JSON command script, docs/algorithm.md "The script contract") the move options are not taken;
the object is {"tool", "script": the input, "edges": STEP rising edges on the commands' clock axis, "positions":
POSITION after each, "rejected": the refused commands, "error"}: `model` from stepramp.board.script.plan_script,
`sim` from the RTL (stepramp.sim.script_sim, either bus top).
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import sys
import tempfile
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, TextIO

from stepramp.board.plan import RAMPS, plan_move
from stepramp.models.engine import edge_chunks
from stepramp.models.engine import edges as model_edges
from stepramp.tools.summary import summarise_edges, summarise_model

MEMORY_BUDGET_MB = 300
"""Peak memory every command keeps to; what would need more is refused (exit status 2)."""
SIM_MAX_PULSES = 1_000_000
"""`stepramp sim` keeps every edge of the RTL's move in memory (the testbench, its result file, the front end)."""
PLOT_MAX_PULSES = 1_000_000
"""`stepramp plot` draws every pulse (and the model's and the ideal's)."""
PLOT_MAX_BYTES = 64 << 20
"""`stepramp plot` reads the whole file."""

EdgeChunks = Iterable[list[int]]
"""A move's edges, in order, in lists (stepramp.models.engine.edge_chunks, or the RTL's one list)."""


#: The move options: required unless --script is given (main checks, as argparse cannot say "unless").
MOVE_OPTIONS = ("steps", "accel", "decel", "speed", "spr", "fclk")


def _move_args(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--steps", type=int, help="signed step count (microsteps); --steps .. --fclk: without --script")
    parser.add_argument("--accel", type=float, help="acceleration, rad/s^2")
    parser.add_argument("--decel", type=float, help="deceleration, rad/s^2")
    parser.add_argument("--speed", type=float, help="maximum speed, rad/s")
    parser.add_argument("--spr", type=float, help="steps per revolution, microsteps included")
    parser.add_argument("--fclk", type=float, help="core clock, Hz")
    parser.add_argument("--prescale", type=int, help="base timer period in clocks (default 1)")
    parser.add_argument("--json", type=Path, help="write the JSON here instead of stdout")
    parser.add_argument(
        "--summary", action="store_true", help='write "summary" (counts, times, deviation, checksum) instead of "edges"'
    )
    parser.add_argument(
        "--script", type=Path, help="run a command script (JSON) instead of one move; the move options are not taken"
    )
    parser.add_argument(
        "--ramp",
        choices=sorted(RAMPS),
        help="the ramp arithmetic (the core's G_RAMP): avr446 (default) or exact; sets a script's \"ramp\" too",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="stepramp", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    sim = sub.add_parser("sim", help="run a move on the RTL (GHDL) and report every step edge")
    _move_args(sim)
    sim.add_argument("--waves", type=Path, help="write a waveform (.ghw, or .fst)")
    sim.add_argument("--build", type=Path, help="simulation build directory (default: a temporary one)")
    sim.add_argument(
        "--top",
        choices=("plb", "axil"),
        default="plb",
        help='the bus top a --script runs on (a script with "axes": the multi-axis top of that bus)',
    )
    model = sub.add_parser("model", help="the same move from the bit-exact Python model")
    _move_args(model)
    plot = sub.add_parser("plot", help="draw a `stepramp sim` or `stepramp model` JSON file to a PNG")
    plot.add_argument("file", type=Path, help="the JSON written by `stepramp sim|model --json FILE`")
    plot.add_argument("-o", "--out", type=Path, help="PNG to write (default: FILE with .png)")
    shell = sub.add_parser("shell", help="the AVR446 demo application's commands on the RTL, read from stdin")
    shell.add_argument("--model", action="store_true", help="run the bit-exact model instead of the RTL")
    shell.add_argument("--waves", type=Path, help="write the session's waveform (.ghw, or .fst)")
    shell.add_argument("--build", type=Path, help="simulation build directory (default: a temporary one)")
    shell.add_argument("--ramp", choices=sorted(RAMPS), default="avr446", help="the core's ramp arithmetic (G_RAMP)")
    return parser


def plot_file(path: Path, png: Path | None) -> int:
    """`stepramp plot`: step rate against time (with the bit-exact model and the ideal) and the deviation."""
    from stepramp.tools.plot import plot_move  # needs matplotlib

    size = path.stat().st_size
    if size > PLOT_MAX_BYTES:
        return _plot_refusal(f"{path} is {size} bytes, more than the {PLOT_MAX_BYTES} a plot reads")
    move = json.loads(path.read_text())
    if move.get("error") or not move.get("registers"):
        print(f"stepramp plot: {path} holds no move ({move.get('error')})", file=sys.stderr)
        return 2
    if "edges" not in move:
        print(f"stepramp plot: {path} holds no edges (written with --summary)", file=sys.stderr)
        return 2
    pulses = max(len(move["edges"]), abs(move["inputs"]["steps"]))
    if pulses > PLOT_MAX_PULSES:
        return _plot_refusal(f"the move has {pulses} pulses, more than the {PLOT_MAX_PULSES} a plot draws")
    png = png or path.with_suffix(".png")
    plan = plan_move(**move["inputs"], ramp=RAMPS[move.get("ramp", "avr446")])
    plot_move(move, png, model_edges=model_edges(plan))
    print(png)
    return 0


def _plot_refusal(reason: str) -> int:
    print(f"stepramp plot: {reason} (memory budget {MEMORY_BUDGET_MB} MB)", file=sys.stderr)
    return 2


def run_move(tool: str, args: argparse.Namespace) -> tuple[dict[str, Any], int, EdgeChunks]:
    """Plan and run one move with the model or the RTL.

    Returns the JSON object, the exit status and the edges in chunks, which write_move writes in the place of the
    object's "edges" (the model's are produced lazily, as they are written). With --summary the object holds
    "summary" instead of "edges" and the chunks are empty.
    """
    inputs = {k: getattr(args, k) for k in ("steps", "accel", "decel", "speed", "spr", "fclk", "prescale")}
    summary = bool(getattr(args, "summary", False))
    ramp = args.ramp or "avr446"
    out: dict[str, Any] = {
        "tool": tool,
        "inputs": inputs,
        **({"ramp": ramp} if ramp != "avr446" else {}),  # the default's JSON is the one it always was
        "registers": None,
        "summary" if summary else "edges": None if summary else [],
        "final_position": 0,
        "error": None,
    }
    try:
        plan = plan_move(**inputs, ramp=RAMPS[ramp])
    except ValueError as exc:
        out["error"] = str(exc)
        return out, 2, []
    out["registers"] = plan.to_dict()
    if tool == "model":
        out["final_position"] = args.steps
        if summary:
            out["summary"] = summarise_model(inputs, plan)
            return out, 0, []
        return out, 0, edge_chunks(plan)

    if plan.steps > SIM_MAX_PULSES:
        out["error"] = (
            f"stepramp sim keeps every edge in memory: {plan.steps} pulses are more than its {SIM_MAX_PULSES} "
            f"(memory budget {MEMORY_BUDGET_MB} MB); `stepramp model` streams any move"
        )
        return out, 2, []

    from stepramp.sim.engine_sim import simulate  # needs cocotb and GHDL, the model does not

    with tempfile.TemporaryDirectory(prefix="stepramp-sim-") as tmp:
        build = args.build or Path(tmp)
        results = simulate([plan], build, waves=args.waves, log_file=build.resolve() / "sim.log")
    if not results or not results[0].done:
        out["error"] = "the RTL did not finish the move (hang); see the simulation log"
        return out, 1, []
    res = results[0]
    out["final_position"] = res.final_position
    chunks: EdgeChunks = []
    if summary:
        out["summary"] = summarise_edges(inputs, res.edges)
    else:
        chunks = [res.edges]
    if res.error:
        out["error"] = f"the engine flagged error code {res.err_code}"
        return out, 1, chunks
    return out, 0, chunks


def _check_options(args: argparse.Namespace) -> str | None:
    """The options' combination: the reason it is refused, or None (argparse checks each option alone)."""
    given = [f"--{name}" for name in (*MOVE_OPTIONS, "prescale") if getattr(args, name) is not None]
    if args.script is not None:
        if given or args.summary:
            return f"--script takes no move options ({', '.join([*given, *(['--summary'] if args.summary else [])])})"
        return None
    missing = [f"--{name}" for name in MOVE_OPTIONS if getattr(args, name) is None]
    if missing:
        return f"the following arguments are required (without --script): {', '.join(missing)}"
    if args.prescale is None:
        args.prescale = 1
    return None


def run_script(tool: str, args: argparse.Namespace) -> tuple[dict[str, Any], int]:
    """Plan (model) or simulate (sim) a command script: the JSON object and the exit status (2: invalid script,
    nothing simulated)."""
    from stepramp.board.script import load_script, plan_script

    out: dict[str, Any] = {"tool": tool, "script": None, "edges": [], "positions": [], "rejected": [], "error": None}
    try:
        obj = json.loads(args.script.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        out["error"] = f"cannot read the script {args.script}: {exc}"
        return out, 2
    if args.ramp is not None and isinstance(obj, dict):
        if obj.get("ramp", args.ramp) != args.ramp:
            out["error"] = f'--ramp {args.ramp} but the script says "ramp": {obj["ramp"]!r}'
            return out, 2
        obj["ramp"] = args.ramp
    out["script"] = obj
    from stepramp.board.multi_script import is_multi

    if is_multi(obj):
        return run_multi_script(tool, args, obj, out)
    try:
        planned = plan_script(load_script(obj))
    except ValueError as exc:
        out["error"] = str(exc)
        return out, 2
    if tool == "model":
        from stepramp.board.script import core_rejections

        rejected = planned.rejected + core_rejections(planned.errors)
        out |= {"edges": planned.edges, "positions": planned.positions, "rejected": rejected}
        return out, 0

    from stepramp.sim.script_sim import simulate_script  # needs cocotb and GHDL, the model does not

    with tempfile.TemporaryDirectory(prefix="stepramp-sim-") as tmp:
        build = args.build or Path(tmp)
        result = simulate_script(obj, build, top=args.top, waves=args.waves)
    out |= {key: result[key] for key in ("edges", "positions", "rejected")}
    return out, 0


def run_multi_script(
    tool: str, args: argparse.Namespace, obj: dict[str, Any], out: dict[str, Any]
) -> tuple[dict[str, Any], int]:
    """A multi-axis script (it gives "axes"): "edges" and "positions" one list per axis; "rejected" each axis's
    refusals and, per axis, the error STATUS holds at the end ({"at": until, "op": "core", "axis", "reason"})."""
    from stepramp.board.multi_script import plan_multi_script
    from stepramp.board.script import core_rejections

    try:
        planned = plan_multi_script(obj)
    except ValueError as exc:
        out["error"] = str(exc)
        return out, 2
    if planned.conflicts:
        out["error"] = "the axes' actions overlap on the bus: " + "; ".join(planned.conflicts)
        return out, 2
    if tool == "model":
        edges = [r.edges for r in planned.results]
        positions = [r.positions for r in planned.results]
        codes = [r.errors[-1][1] if r.errors else 0 for r in planned.results]
    else:
        from stepramp.sim.script_sim import simulate_multi  # needs cocotb and GHDL, the model does not

        with tempfile.TemporaryDirectory(prefix="stepramp-sim-") as tmp:
            result = simulate_multi([planned], args.build or Path(tmp), top=args.top)[0]
        edges, positions = result["edges"], result["positions"]
        codes = [(s >> 8) & 0x1F if s >> 5 & 1 else 0 for s in result["status"]]
    rejected = [{**r, "axis": axis} for axis, p in enumerate(planned.results) for r in p.rejected]
    for axis, code in enumerate(codes):
        if code:
            rejected += [{**r, "axis": axis} for r in core_rejections([(planned.until, code)])]
    out |= {"edges": edges, "positions": positions, "rejected": rejected}
    return out, 0


def write_move(write: Callable[[str], object], out: dict[str, Any], chunks: EdgeChunks) -> None:
    """Write the JSON object and a newline, the edges chunk by chunk in the place of out["edges"].

    The text is exactly json.dumps(out with the edges filled in) + "\\n": the separators ", " and ": ", keys in
    order, each edge chunk's items as json.dumps writes a list's.
    """
    write("{")
    for n, (key, value) in enumerate(out.items()):
        write(", " if n else "")
        write(json.dumps(key) + ": ")
        if key != "edges":
            write(json.dumps(value))
            continue
        write("[")
        first = True
        for part in itertools.chain([value], chunks):  # edges already in out first (none in run_move's)
            if len(part) == 0:
                continue
            write(("" if first else ", ") + json.dumps(part)[1:-1])
            first = False
        write("]")
    write("}\n")


def _emit(out: dict[str, Any], chunks: EdgeChunks, target: Path | None) -> None:
    if target is None:
        write_move(sys.stdout.write, out, chunks)
        sys.stdout.flush()
        return
    target.parent.mkdir(parents=True, exist_ok=True)
    with target.open("w", encoding="utf-8") as stream:
        write_move(stream.write, out, chunks)


def _quiet_broken_pipe(stream: TextIO) -> None:
    """The reader went away (stepramp model ... | head): no traceback, and no second error at exit."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, stream.fileno())
    os.close(devnull)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.command == "plot":
        return plot_file(args.file, args.out)
    if args.command == "shell":
        from stepramp.tools.shell import main as shell_main

        return shell_main(model=args.model, waves=args.waves, build=args.build, ramp=RAMPS[args.ramp])
    if args.command in ("sim", "model"):
        refused = _check_options(args)
        if refused is not None:
            print(f"stepramp {args.command}: {refused}", file=sys.stderr)
            return 2
        if args.script is not None:
            out, status = run_script(args.command, args)
            chunks: EdgeChunks = []
        else:
            out, status, chunks = run_move(args.command, args)
        try:
            _emit(out, chunks, args.json)
        except BrokenPipeError:
            _quiet_broken_pipe(sys.stdout)
            return 1
        if out["error"]:
            print(f"stepramp {args.command}: {out['error']}", file=sys.stderr)
        return status
    return 2


if __name__ == "__main__":
    sys.exit(main())
