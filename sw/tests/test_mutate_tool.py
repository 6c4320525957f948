# SPDX-License-Identifier: MIT
"""stepramp.tools.mutate without a simulator: its sites and its table of equivalent mutants."""

from __future__ import annotations

from pathlib import Path

from stepramp.sim.runner import HDL_DIR, HDL_FILES
from stepramp.tools.mutate import EQUIVALENT, Mutant, sites


def test_every_equivalent_verdict_names_a_current_site() -> None:
    """A verdict whose line changed lapses: the table must not keep one for a line that no longer exists."""
    current = {m.site for f in HDL_FILES for m in sites(HDL_DIR / f)}
    stale = [key for key in EQUIVALENT if key not in current]
    assert not stale, f"EQUIVALENT names sites the RTL no longer has: {stale}"


def test_a_site_follows_its_line_not_its_number(tmp_path: Path) -> None:
    """The same line one row lower (or indented differently) keeps its site; another line does not share it."""
    body = "  load <= start_req and not busy_any;\n"
    first, second = tmp_path / "stepramp_a.vhd", tmp_path / "stepramp_b.vhd"
    first.write_text(body)
    second.write_text("\n" + body.replace("  ", "      ", 1))
    (m1,) = sites(first)
    (m2,) = sites(second)
    assert (m1.line, m2.line) == (1, 2) and m1.col != m2.col
    assert m1.site.split(":", 1)[1] == m2.site.split(":", 1)[1]
    line = "  load <= start_req and busy_any;"
    other = Mutant("stepramp_a.vhd", 1, line.index("and"), "logic", "and", "or", line)
    assert other.site != m1.site
