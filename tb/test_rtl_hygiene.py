# SPDX-License-Identifier: MIT
"""Every RTL file analyses under VHDL-93c and VHDL-2008; every top synthesises with no latch."""

from __future__ import annotations

from pathlib import Path

import pytest

from stepramp.sim.runner import HDL_DIR, HDL_FILES, SYNTH_TOPS
from stepramp.tools.rtlcheck import analyse, synth


def test_every_rtl_file_exists() -> None:
    missing = [name for name in HDL_FILES if not (HDL_DIR / name).exists()]
    assert not missing, f"missing RTL files: {missing}"


@pytest.mark.parametrize("std", ["93c", "08"])
def test_rtl_analyses(std: str, tmp_path: Path) -> None:
    errors = analyse(std, tmp_path)
    assert not errors, "\n".join(errors)


@pytest.mark.parametrize("top", sorted(SYNTH_TOPS))
def test_rtl_synthesises_without_latch(top: str, tmp_path: Path) -> None:
    work = tmp_path / "work"
    assert not analyse("08", work)
    errors = synth(top, SYNTH_TOPS[top], work, tmp_path)
    assert not errors, "\n".join(errors)
    assert (tmp_path / f"{top}.v").stat().st_size > 0
