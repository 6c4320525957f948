# SPDX-License-Identifier: MIT
"""The second simulator: `ghdl synth` writes a top's netlist as Verilog, which Icarus Verilog simulates under the same
cocotb benches (stepramp.sim.runner.run_cocotb(..., netlist=True); tests in tb/test_netlist.py)."""

from __future__ import annotations

import re
import shutil
import subprocess
from collections.abc import Mapping
from pathlib import Path

from stepramp.sim.runner import hdl_sources


def write_netlist(toplevel: str, out_dir: Path, generics: Mapping[str, object] | None = None) -> Path:
    """`ghdl synth --out=verilog` of toplevel (with its generics) into out_dir/<toplevel>.v, its multiplexer defaults
    restored from `--out=vhdl` of the same netlist (restore_case_defaults); RuntimeError with the reason when GHDL or
    Icarus is missing or synthesis fails."""
    for tool, package in (("ghdl", "ghdl"), ("iverilog", "iverilog")):
        if shutil.which(tool) is None:
            raise RuntimeError(f"'{tool}' is not on PATH: the netlist simulation needs it (apt install {package})")
    out_dir.mkdir(parents=True, exist_ok=True)
    work = out_dir / "ghdl_synth"
    work.mkdir(exist_ok=True)
    texts: dict[str, str] = {}
    for lang in ("verilog", "vhdl"):
        cmd = [
            "ghdl",
            "synth",
            "--std=08",
            f"--workdir={work}",
            *[f"-g{name}={value}" for name, value in (generics or {}).items()],
            f"--out={lang}",
            *[str(p) for p in hdl_sources(toplevel)],
            "-e",
            toplevel,
        ]
        result = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=600)
        if result.returncode != 0:
            raise RuntimeError(f"ghdl synth of {toplevel} failed:\n{result.stderr}")
        texts[lang] = result.stdout
    (out_dir / f"{toplevel}.netlist.vhd").write_text(texts["vhdl"])
    netlist = out_dir / f"{toplevel}.v"
    netlist.write_text(restore_case_defaults(texts["verilog"], texts["vhdl"]))
    return netlist


_MODULE = re.compile(r"(?m)^(?=module )")
_ARCHITECTURE = re.compile(r"(?m)^(?=architecture )")
_SELECT = re.compile(r"with \w+ select (\w+) <=\n(?:.*\n)*?\s+(\S.*?) when others;")
_CASE = re.compile(r"(    case \(([^)]*)\)\n(?:(?!    endcase).*\n)*?)(    endcase)")
_LHS = re.compile(r": (\w+) <=")


def _verilog_value(vhdl: str, context: str) -> str:
    """A VHDL netlist operand (a name, 'b' or "bits") as Verilog. An 'X' (GHDL's default of a multiplexer whose
    selector covers every value, e.g. a constant table) stays unknown: x in Verilog."""
    if re.fullmatch(r"\w+", vhdl):
        return vhdl
    if re.fullmatch(r"'[01X]'", vhdl):
        return f"1'b{vhdl[1].lower()}"
    if re.fullmatch(r'"[01X]+"', vhdl):
        return f"{len(vhdl) - 2}'b{vhdl[1:-1].lower()}"
    raise RuntimeError(f"{context}: cannot translate the multiplexer default {vhdl!r} to Verilog")


def restore_case_defaults(verilog: str, vhdl: str) -> str:
    """GHDL 2.0's Verilog writer drops the default of its one-hot multiplexers (ghdl/ghdl#2041, fixed after 2.0): it
    writes `case` without `default`, so a selector that matches no branch keeps the output's old value, X at the
    start, which Verilog then spreads. The VHDL writer keeps it (`with sel select o <= ... d when others;`), and both
    name the nets alike: each default is taken from there, module by module (from the architecture of the entity of
    the same name)."""
    defaults: dict[str, dict[str, str]] = {}
    for unit in _ARCHITECTURE.split(vhdl):
        name = re.match(r"architecture \w+ of (\w+) is", unit)
        if name:
            defaults[name.group(1)] = dict(_SELECT.findall(unit))
    out: list[str] = []
    for module in _MODULE.split(verilog):
        name = re.match(r"module (\w+)", module)
        table = defaults.get(name.group(1), {}) if name else {}

        def fix(
            match: re.Match[str], table: dict[str, str] = table, module_name: str = name.group(1) if name else ""
        ) -> str:
            body = match.group(1)
            lhs = _LHS.search(body)
            if "default" in body or lhs is None:
                return match.group(0)
            target = lhs.group(1)
            if target not in table:
                raise RuntimeError(f"{module_name}: no default for {target} in the VHDL netlist")
            value = _verilog_value(table[target], f"{module_name}.{target}")
            return f"{body}      default: {target} <= {value};\n{match.group(3)}"

        out.append(_CASE.sub(fix, module))
    return "".join(out)
