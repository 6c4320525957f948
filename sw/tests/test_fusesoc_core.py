# SPDX-License-Identifier: MIT
"""stepramp.core (FuseSoC) lists the RTL in stepramp.sim.runner.HDL_FILES order, and the VHDL testbench it simulates
carries the register values and edges of the model for its move. No simulator, no FuseSoC: plain file checks."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml  # PyYAML: a dependency of vsg (pinned in the dev extra)

from stepramp.board.driver import plan_writes
from stepramp.board.plan import plan_move
from stepramp.board.regmap import ID_VALUE, offset
from stepramp.models.engine import edges
from stepramp.sim.runner import HDL_DIR, HDL_FILES

ROOT = Path(__file__).resolve().parents[2]
CORE = ROOT / "stepramp.core"
TB = ROOT / "tb" / "vhdl" / "stepramp_plb_tb.vhd"

#: The bus tops come last in compile order. Until they are in HDL_FILES they are expected after it, in this order;
#: once HDL_FILES lists them this adds nothing and the core must follow HDL_FILES exactly.
_TOPS = ("stepramp_core.vhd", "stepramp_plb.vhd", "stepramp_axil.vhd")

#: The move of the testbench: `stepramp model --steps 20 --accel 1000 --decel 1000 --speed 50 --spr 200 --fclk 1e6`.
_MOVE = {"steps": 20, "accel": 1000.0, "decel": 1000.0, "speed": 50.0, "spr": 200.0, "fclk": 1e6}


def _core() -> dict[str, Any]:
    text = CORE.read_text()
    assert text.startswith("CAPI=2:\n"), "a CAPI2 core file starts with the line 'CAPI=2:'"
    return yaml.safe_load(text)


def _compile_order() -> list[str]:
    return [*HDL_FILES, *(top for top in _TOPS if top not in HDL_FILES)]


def test_rtl_fileset_is_the_compile_order() -> None:
    rtl = _core()["filesets"]["rtl"]
    assert rtl["files"] == [f"hdl/{name}" for name in _compile_order()]
    assert rtl["file_type"] == "vhdlSource-2008"
    assert all((HDL_DIR / name).exists() for name in _compile_order())


def test_targets() -> None:
    core = _core()
    tb_files = core["filesets"]["tb"]["files"]
    assert tb_files == ["tb/vhdl/stepramp_plb_tb.vhd"]
    assert all((ROOT / f).exists() for f in tb_files)
    targets = core["targets"]
    assert targets["default"]["filesets"] == ["rtl"]
    assert targets["sim"]["filesets"] == ["rtl", "tb"]
    assert targets["sim"]["toplevel"] == "stepramp_plb_tb"
    assert targets["lint"]["toplevel"] == "stepramp_plb"
    for name in ("sim", "lint"):
        assert targets[name]["flow"] == "sim"
        assert targets[name]["flow_options"]["tool"] == "ghdl"


def test_core_version_is_the_id_version() -> None:
    version = _core()["name"].split(":")[-1]
    assert version == f"{(ID_VALUE >> 8) & 0xFF}.{ID_VALUE & 0xFF}"


def _vhdl_constant(name: str) -> str:
    """The text between ':=' and the closing ');' of a VHDL array constant of the testbench, comments removed."""
    text = re.sub(r"--[^\n]*", "", TB.read_text())
    match = re.search(rf"constant {name}\b[^:]*:[^:]*:=\s*\((.*?)\);", text, re.DOTALL)
    assert match, f"constant {name} not found in {TB.name}"
    return match.group(1)


def test_testbench_move_is_the_models() -> None:
    plan = plan_move(_MOVE["steps"], _MOVE["accel"], _MOVE["decel"], _MOVE["speed"], _MOVE["spr"], _MOVE["fclk"])
    words = re.findall(r"\(\s*16#([0-9A-Fa-f]+)#\s*,\s*x\"([0-9A-Fa-f_]+)\"\s*\)", _vhdl_constant("C_MOVE"))
    tb_writes = [(int(off, 16), int(value.replace("_", ""), 16)) for off, value in words]
    assert tb_writes == plan_writes(plan)
    assert (offset("STOP_RATIO"), 0x0001_0000) in tb_writes
    tb_edges = [int(e) for e in re.findall(r"\d+", _vhdl_constant("C_EDGES"))]
    assert tb_edges == edges(plan)
