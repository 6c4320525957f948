# SPDX-License-Identifier: MIT
"""`stepramp sim` (the RTL under GHDL) and `stepramp model` give identical JSON edges, through the command line."""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path

import pytest

BIN = Path(sys.executable).parent / "stepramp"

MOVES = [
    ["--steps", "-90", "--accel", "2000", "--decel", "600", "--speed", "60", "--spr", "200", "--fclk", "1e6"],
    [
        "--steps",
        "40",
        "--accel",
        "50",
        "--decel",
        "80",
        "--speed",
        "5",
        "--spr",
        "400",
        "--fclk",
        "2e6",
        "--prescale",
        "3",
    ],
]


@pytest.mark.parametrize("move", MOVES, ids=["trapezoid", "triangle_prescale_3"])
def test_sim_equals_model(move: list[str], tmp_path: Path) -> None:
    model = json.loads(subprocess.run([BIN, "model", *move], capture_output=True, text=True, check=True).stdout)
    waves = tmp_path / "move.ghw"
    run = subprocess.run([BIN, "sim", *move, "--waves", str(waves)], capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    sim = json.loads(run.stdout)
    assert sim["tool"] == "sim"
    assert sim["error"] is None
    assert sim["registers"] == model["registers"]
    assert sim["edges"] == model["edges"]
    assert sim["final_position"] == model["final_position"]
    assert waves.stat().st_size > 0


def test_sim_summary_equals_model_summary(tmp_path: Path) -> None:
    """`--summary` from the RTL's edges and from the model's chunks: the same figures and the same checksum."""
    move = MOVES[0]
    model = json.loads(
        subprocess.run([BIN, "model", *move, "--summary"], capture_output=True, text=True, check=True).stdout
    )
    edges = json.loads(subprocess.run([BIN, "model", *move], capture_output=True, text=True, check=True).stdout)
    out = tmp_path / "sim.json"
    run = subprocess.run(
        [BIN, "sim", *move, "--summary", "--json", str(out), "--build", str(tmp_path / "build")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout == ""
    sim = json.loads(out.read_text())
    assert list(sim) == ["tool", "inputs", "registers", "summary", "final_position", "error"]
    assert sim["error"] is None
    assert sim["summary"] == model["summary"]
    assert sim["final_position"] == model["final_position"]
    plain = hashlib.sha256(b"".join(e.to_bytes(8, "little") for e in edges["edges"])).hexdigest()
    assert sim["summary"]["checksum"] == "sha256:" + plain
    assert sim["summary"]["pulses"] == len(edges["edges"])


def test_sim_invalid_input_simulates_nothing() -> None:
    bad = [*MOVES[0][:-2], "--fclk=-1e6"]
    run = subprocess.run([BIN, "sim", *bad], capture_output=True, text=True, check=False)
    assert run.returncode == 2
    assert "fclk must be finite and > 0" in json.loads(run.stdout)["error"]


def test_sim_equals_model_in_exact_mode(tmp_path: Path) -> None:
    """`--ramp exact`: `stepramp sim` runs the engine built with G_RAMP = 1; its edges equal `stepramp model
    --ramp exact`'s, and differ from the AVR446 mode's (the same move)."""
    move = [*MOVES[1][:-2], "--prescale", "4"]  # 2 MHz, PRESCALE 4: a slow triangle, 40 steps
    model = json.loads(
        subprocess.run([BIN, "model", *move, "--ramp", "exact"], capture_output=True, text=True, check=True).stdout
    )
    avr = json.loads(subprocess.run([BIN, "model", *move], capture_output=True, text=True, check=True).stdout)
    cmd = [BIN, "sim", *move, "--ramp", "exact", "--build", str(tmp_path)]
    run = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    sim = json.loads(run.stdout)
    assert sim["ramp"] == "exact" and sim["error"] is None
    assert sim["registers"] == model["registers"] and sim["edges"] == model["edges"]
    assert sim["edges"] != avr["edges"]


def test_sim_accepts_a_slow_exact_ramp(tmp_path: Path) -> None:
    """`--ramp exact` with ramp constants above 2^48 (c0 = 1.40e6 ticks at 50 MHz, PRESCALE 1: a scaled seed word,
    docs/algorithm.md "Exact step times"): `stepramp sim` takes the move the AVR446 ramp takes, its summary (edges'
    checksum) equals `stepramp model`'s, and every pulse is within 1 tick of the ideal ramp (max_deviation_ticks, the
    judge stepramp.models.ideal)."""
    move = ["--steps", "3", "--accel", "64.9", "--decel", "40", "--speed", "100", "--spr", "400", "--fclk", "50e6"]
    model = json.loads(
        subprocess.run(
            [BIN, "model", *move, "--ramp", "exact", "--summary"], capture_output=True, text=True, check=True
        ).stdout
    )
    assert model["registers"]["decel_seed"] >= 1 << 48, "the move does not need a scaled ramp constant"
    out = tmp_path / "sim.json"
    cmd = [BIN, "sim", *move, "--ramp", "exact", "--summary", "--json", str(out), "--build", str(tmp_path / "build")]
    run = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    sim = json.loads(out.read_text())
    assert sim["error"] is None and sim["registers"] == model["registers"]
    assert sim["summary"] == model["summary"]
    assert sim["summary"]["max_deviation_ticks"] <= 1.0
