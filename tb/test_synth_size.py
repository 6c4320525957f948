# SPDX-License-Identifier: MIT
"""The PLB-like top synthesises for iCE40 with no latch, and is not more than 10 % larger than the recorded figure.

The figure is scripts/synth_baseline.json (written by `python -m stepramp.synth --record`, i.e. after a deliberate
change in size); `make synth` reports the full table with fmax.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from stepramp.synth import BASELINE, ice40_cells, ice40_summary, netlist

TOP = "stepramp_plb"


@pytest.fixture(scope="module")
def cells(tmp_path_factory: pytest.TempPathFactory) -> dict[str, int]:
    assert shutil.which("yosys"), "yosys is needed for the size check (Debian: apt-get install yosys)"
    out: Path = tmp_path_factory.mktemp("synth")
    found, _ = ice40_cells(TOP, netlist(TOP, out), out)  # both raise on a latch
    return found


def test_no_latch_cells(cells: dict[str, int]) -> None:
    assert not [name for name in cells if "LATCH" in name.upper()]
    assert cells.get("SB_LUT4", 0) > 0


def test_size_within_ten_percent_of_the_record(cells: dict[str, int]) -> None:
    recorded = json.loads(BASELINE.read_text())[TOP]
    now = ice40_summary(cells)
    for key in ("lut4", "ff"):
        assert now[key] <= 1.10 * recorded[key], (
            f"{TOP}: {now[key]} iCE40 {key} against {recorded[key]} recorded (+10 % allowed); "
            "if the growth is intended, record it with `python -m stepramp.synth --record`"
        )
