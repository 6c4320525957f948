# SPDX-License-Identifier: MIT
"""The `stepramp` command line without a simulator: the model's JSON contract, invalid input, and the plot."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stepramp.board.plan import RAMP_EXACT, plan_move
from stepramp.board.script import load_script, plan_script
from stepramp.models.engine import edges
from stepramp.tools.cli import main

MOVE = ["--steps", "-150", "--accel", "900", "--decel", "700", "--speed", "40", "--spr", "200", "--fclk", "1e6"]


def test_model_json_contract(tmp_path: Path) -> None:
    out = tmp_path / "m.json"
    assert main(["model", *MOVE, "--json", str(out)]) == 0
    got = json.loads(out.read_text())
    assert set(got) == {"tool", "inputs", "registers", "edges", "final_position", "error"}
    assert got["tool"] == "model"
    assert got["error"] is None
    plan = plan_move(-150, 900.0, 700.0, 40.0, 200.0, 1e6)
    assert got["registers"] == plan.to_dict()
    assert got["edges"] == edges(plan)
    assert got["final_position"] == -150
    assert len(got["edges"]) == 150


def test_invalid_input_exits_2_with_the_reason(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = [a if a != "900" else "-900" for a in MOVE]
    assert main(["model", *bad]) == 2
    got = json.loads(capsys.readouterr().out)
    assert got["edges"] == []
    assert "accel must be finite and > 0" in got["error"]


def test_plot_writes_a_png(tmp_path: Path) -> None:
    data = tmp_path / "m.json"
    assert main(["model", *MOVE, "--json", str(data)]) == 0
    assert main(["plot", str(data)]) == 0
    png = data.with_suffix(".png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert png.stat().st_size > 10_000
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"tool": "model", "error": "x", "registers": None}))
    assert main(["plot", str(bad)]) == 2


def test_model_in_exact_mode(tmp_path: Path) -> None:
    """`--ramp exact`: the exact plan's registers and edges, "ramp": "exact" in the JSON, every pulse within 1 tick of
    the ideal (the summary's max_deviation_ticks, computed from the ideal trapezoid); a move too fast for the exact
    mode is refused with the reason (the same move is valid in the AVR446 mode)."""
    slow = [*MOVE[:-1], "4e6", "--prescale", "4"]  # the same ticks, 256 clocks per step at the cruise
    out = tmp_path / "e.json"
    assert main(["model", *slow, "--ramp", "exact", "--json", str(out)]) == 0
    got = json.loads(out.read_text())
    assert got["ramp"] == "exact"
    plan = plan_move(-150, 900.0, 700.0, 40.0, 200.0, 4e6, 4, ramp=RAMP_EXACT)
    assert got["registers"] == plan.to_dict() and got["edges"] == edges(plan)
    assert main(["model", *slow, "--ramp", "exact", "--summary", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["summary"]["max_deviation_ticks"] < 1.0
    faster = {"40": "400", "900": "90000", "700": "70000"}
    fast = [faster.get(a, a) for a in MOVE]  # 78 clocks per step at the cruise
    assert main(["model", *fast, "--ramp", "exact", "--json", str(out)]) == 2
    assert "< 256 clocks" in json.loads(out.read_text())["error"]
    assert main(["model", *fast, "--json", str(out)]) == 0


def test_script_in_exact_mode(tmp_path: Path) -> None:
    """`--script --ramp exact` plans the script in exact mode (its edges those of a script that says "ramp":
    "exact"); a script that says otherwise is refused."""
    script = {"fclk": 4e6, "spr": 200.0, "prescale": 4, "commands": [{"at": 0, "op": "move", "steps": 120}]}
    script["commands"][0] |= {"accel": 900.0, "decel": 700.0, "speed": 40.0}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(script))
    out = tmp_path / "o.json"
    assert main(["model", "--script", str(path), "--ramp", "exact", "--json", str(out)]) == 0
    got = json.loads(out.read_text())
    want = plan_script(load_script({**script, "ramp": "exact"}))
    assert got["edges"] == want.edges and got["rejected"] == []
    assert got["edges"] != plan_script(load_script(script)).edges  # the AVR446 mode's differ
    path.write_text(json.dumps({**script, "ramp": "avr446"}))
    assert main(["model", "--script", str(path), "--ramp", "exact", "--json", str(out)]) == 2
