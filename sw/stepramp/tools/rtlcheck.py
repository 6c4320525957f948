# SPDX-License-Identifier: MIT
"""RTL hygiene: every file analyses under --std=93c and --std=08, every top synthesises with no latch.

`ghdl synth` refuses to infer a latch unless given --latches, so a clean run proves there is none. When
yosys is installed, the Verilog netlist GHDL writes is also read by yosys and checked for latch cells, which
catches the case-without-default trap of GHDL 2.0's Verilog writer.

Usage: python -m stepramp.tools.rtlcheck [--out DIR] [TOP ...]   (default: every top in stepramp.sim.runner.SYNTH_TOPS)
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from stepramp.sim.runner import HDL_DIR, HDL_FILES, SYNTH_TOPS, hdl_sources


def run(cmd: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, check=False)


def analyse(std: str, workdir: Path) -> list[str]:
    """Analyse every RTL file under one VHDL standard; return error messages."""
    errors: list[str] = []
    workdir.mkdir(parents=True, exist_ok=True)
    for src in hdl_sources():
        res = run(["ghdl", "-a", f"--std={std}", f"--workdir={workdir}", str(src)], workdir)
        if res.returncode != 0:
            errors.append(f"{src.name} does not analyse with --std={std}:\n{res.stderr}")
    return errors


_CASE = re.compile(r"(    case \(([^)]*)\)\n(?:(?!    endcase).*\n)*?)(    endcase)")
_LHS = re.compile(r": (\w+) <=")


def add_case_defaults(verilog: str) -> str:
    """Give every `case` that GHDL 2.0's Verilog writer emits without `default` an all-x default.

    GHDL drops the default of its one-hot multiplexers when writing Verilog, and yosys then infers a latch
    for the unreachable selector values. GHDL itself already refused any real latch, so an x default (free for
    the optimiser) restores the netlist's meaning.
    """

    def fix(match: re.Match[str]) -> str:
        body = match.group(1)
        lhs = _LHS.search(body)
        if "default" in body or lhs is None:
            return match.group(0)
        return f"{body}      default: {lhs.group(1)} <= 'bx;\n{match.group(3)}"

    return _CASE.sub(fix, verilog)


def synth(top: str, generics: dict[str, int], workdir: Path, out_dir: Path) -> list[str]:
    """Synthesise one top with ghdl (no latch allowed) and, if present, re-check the netlist with yosys."""
    gen = [f"-g{k}={v}" for k, v in generics.items()]
    verilog = out_dir / f"{top}.v"
    res = run(["ghdl", "synth", "--std=08", f"--workdir={workdir}", *gen, "--out=verilog", top], workdir)
    if res.returncode != 0:
        return [f"ghdl synth {top} failed:\n{res.stderr}"]
    verilog.write_text(add_case_defaults(res.stdout))
    (out_dir / f"{top}.ghdl.log").write_text(res.stderr)
    if shutil.which("yosys") is None:
        return []
    script = (
        f"read_verilog {verilog}; hierarchy -top {top}; proc; "
        "select -assert-none t:$dlatch t:$adlatch t:$dlatchsr t:$_DLATCH_* t:$_DLATCHSR_*"
    )
    res = run(["yosys", "-q", "-p", script], out_dir)
    (out_dir / f"{top}.yosys.log").write_text(res.stdout + res.stderr)
    if res.returncode != 0 or "Latch inferred" in res.stdout:
        return [f"yosys finds a latch (or fails) in {top}:\n{res.stdout}{res.stderr}"]
    return []


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("build/synth_check"))
    parser.add_argument("tops", nargs="*", default=list(SYNTH_TOPS))
    args = parser.parse_args(argv)
    missing = [f for f in HDL_FILES if not (HDL_DIR / f).exists()]
    errors: list[str] = [f"missing RTL file {f}" for f in missing]
    out: Path = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        for std in ("93c", "08"):
            errors += analyse(std, Path(tmp) / std)
        for top in args.tops:
            errors += synth(top, SYNTH_TOPS[top], Path(tmp) / "08", out)
    for line in errors:
        print(line, file=sys.stderr)
    print(f"synth check: {len(args.tops)} tops, {len(hdl_sources())} files, {len(errors)} problems")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
