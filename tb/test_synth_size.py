# SPDX-License-Identifier: MIT
"""Every entity of the PLB-like top synthesises for iCE40 with no latch, and none is more than 10 % larger than its
recorded figure.

The figures are scripts/synth_baseline.json (written by `python -m stepramp.tools.synth --record`, i.e. after a
deliberate change in size): iCE40 LUT4 and FF of each entity as the top instantiates it, with the entities below it
(synth_ice40 -noflatten), so that a growth fails where it starts. `make synth` reports the full table with fmax.
"""

from __future__ import annotations

import functools
import json
import shutil
from pathlib import Path

import pytest

from stepramp.tools.synth import BASELINE, entity_cells_cached, ice40_summary

TOP = "stepramp_plb"
REPO = Path(__file__).resolve().parents[1]


@functools.cache
def _synthesised() -> dict[str, dict[str, int]]:
    """The synthesis, once per regression (stepramp.tools.synth.entity_cells_cached: keyed by the RTL's and the
    synthesis script's contents and the yosys version, under a file lock, so that the tests of this module share one
    yosys run whichever worker runs them, and `make test` can start it while the bootstrap runs)."""
    return entity_cells_cached(TOP, REPO / "build" / "synth_size")


@pytest.fixture(scope="module")
def entities() -> dict[str, dict[str, int]]:
    assert shutil.which("yosys"), "yosys is needed for the size check (Debian: apt-get install yosys)"
    return _synthesised()


def test_no_latch_cells(entities: dict[str, dict[str, int]]) -> None:
    latches = {e: [n for n in cells if "LATCH" in n.upper()] for e, cells in entities.items()}
    assert not any(latches.values()), latches
    assert entities[TOP].get("SB_LUT4", 0) > 0


def test_every_entity_is_recorded(entities: dict[str, dict[str, int]]) -> None:
    recorded = json.loads(BASELINE.read_text())[TOP]
    assert sorted(recorded) == sorted(entities), (
        "record the new entity list with `python -m stepramp.tools.synth --record`"
    )


def test_size_within_ten_percent_of_the_record(entities: dict[str, dict[str, int]]) -> None:
    recorded = json.loads(BASELINE.read_text())[TOP]
    problems = []
    for name, cells in entities.items():
        now = ice40_summary(cells)
        for key in ("lut4", "ff"):
            if name in recorded and now[key] > 1.10 * recorded[name][key]:
                problems.append(f"{name}: {now[key]} iCE40 {key} against {recorded[name][key]} recorded")
    assert not problems, (
        "\n".join(problems) + "\n(+10 % allowed; if the growth is intended, record it with "
        "`python -m stepramp.tools.synth --record`)"
    )
