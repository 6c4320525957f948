# SPDX-License-Identifier: MIT
"""The `stepramp` command line without a simulator: the model's JSON contract, invalid input, and the plot."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stepramp.board.plan import plan_move
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
