# SPDX-License-Identifier: MIT
"""The model's golden checksums (sw/tests/golden/checksums.json, written by scripts/golden.py on the tree before issue
34's refactoring; stepramp.tools.golden says what they cover): every profile's edges and stops, 1,000 random moves,
200 random scripts and the named scripts, in both ramps, recomputed and compared. A difference means the model's
edges (or the script planner's actions) changed; rewrite the file only when that is meant. The checksums were
re-recorded in session 20 for the soft-stop rule of issue 35 (a stop decided one pulse later): only the stops and the
scripts with a soft stop changed.

* test_golden_checksums: all of them, recomputed (about 10 s);
* test_golden_inputs_unchanged: the random generators still give the recorded inputs (else a difference in the
  checksums is the generator's, not the model's);
* test_golden_detects_a_change: a one-LSB change of one plan register changes its checksum.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import pytest

from stepramp.board.plan import plan_move
from stepramp.sim.profiles import PROFILES
from stepramp.tools import golden
from stepramp.tools.summary import summarise_model

GOLDEN = Path(__file__).resolve().parent / "golden" / "checksums.json"


@pytest.fixture(scope="module")
def want() -> dict[str, Any]:
    return json.loads(GOLDEN.read_text())


@pytest.fixture(scope="module")
def got() -> dict[str, Any]:
    return golden.compute(progress=lambda msg: None)


def test_golden_inputs_unchanged(want: dict[str, Any], got: dict[str, Any]) -> None:
    assert want["seed"] == golden.SEED
    assert golden.differences(want["inputs"], got["inputs"]) == []


@pytest.mark.parametrize("ramp", ["avr446", "exact"])
def test_golden_checksums(want: dict[str, Any], got: dict[str, Any], ramp: str) -> None:
    print(f"seed {golden.SEED}")
    assert len(want[ramp]["moves"]) == golden.MOVE_COUNT and len(want[ramp]["scripts"]) == golden.SCRIPT_COUNT
    assert golden.differences(want[ramp], got[ramp]) == []


def test_golden_detects_a_change(want: dict[str, Any]) -> None:
    profile = PROFILES[0]
    plan = plan_move(**profile.args())
    assert summarise_model(profile.args(), plan)["checksum"] == want["avr446"]["profiles"][profile.name]
    nudged = dataclasses.replace(plan, accel_seed=plan.accel_seed + 1)
    assert summarise_model(profile.args(), nudged)["checksum"] != want["avr446"]["profiles"][profile.name]
