# SPDX-License-Identifier: MIT
"""The second simulator: `ghdl synth` writes a top's netlist as Verilog, which Icarus Verilog simulates under the same
cocotb benches (stepramp.sim.runner.run_cocotb(..., netlist=True); tests in tb/test_netlist.py)."""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Mapping
from pathlib import Path

from stepramp.sim.runner import hdl_sources


def write_netlist(toplevel: str, out_dir: Path, generics: Mapping[str, object] | None = None) -> Path:
    """`ghdl synth --out=verilog` of toplevel (with its generics) into out_dir/<toplevel>.v; RuntimeError with the
    reason when GHDL or Icarus is missing or synthesis fails."""
    for tool, package in (("ghdl", "ghdl"), ("iverilog", "iverilog")):
        if shutil.which(tool) is None:
            raise RuntimeError(f"'{tool}' is not on PATH: the netlist simulation needs it (apt install {package})")
    out_dir.mkdir(parents=True, exist_ok=True)
    work = out_dir / "ghdl_synth"
    work.mkdir(exist_ok=True)
    cmd = [
        "ghdl",
        "synth",
        "--std=08",
        f"--workdir={work}",
        *[f"-g{name}={value}" for name, value in (generics or {}).items()],
        "--out=verilog",
        *[str(p) for p in hdl_sources(toplevel)],
        "-e",
        toplevel,
    ]
    result = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=600)
    if result.returncode != 0:
        raise RuntimeError(f"ghdl synth of {toplevel} failed:\n{result.stderr}")
    netlist = out_dir / f"{toplevel}.v"
    netlist.write_text(result.stdout)
    return netlist
