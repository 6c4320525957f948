# SPDX-License-Identifier: MIT
"""The synthesis report's --docs rewrite of the pages' entity rows (no synthesis tool needed)."""

from __future__ import annotations

from pathlib import Path

from stepramp.tools.synth import update_docs

PAGE = """# x

| entity | iCE40 LUT4 | FF | carry | HX8K fmax (MHz) |
|---|---|---|---|---|
| `stepramp_divider` | 517 | 231 | 137 | 57.05 |
| `stepramp_prio_enc` | 61 | 0 | 0 | - |
| `stepramp_other` | 1 | 2 | 3 | - |

| `stepramp_divider` is mentioned in prose | here |
"""

REPORT = {
    "stepramp_plb": {
        "entities": {
            "stepramp_divider": {"lut4": 1234, "ff": 200, "carry": 70, "fmax_mhz": 80.456},
            "stepramp_prio_enc": {"lut4": 60, "ff": 0, "carry": 0, "fmax_mhz": None},
        }
    }
}


def test_rows_are_rewritten_and_the_rest_kept(tmp_path: Path) -> None:
    page = tmp_path / "p.md"
    page.write_text(PAGE)
    assert update_docs(REPORT, pages=tmp_path) == [page]
    text = page.read_text()
    assert "| `stepramp_divider` | 1,234 | 200 | 70 | 80.46 |" in text
    assert "| `stepramp_prio_enc` | 60 | 0 | 0 | - |" in text
    # an entity the report does not hold keeps its row, prose is untouched
    assert "| `stepramp_other` | 1 | 2 | 3 | - |" in text
    assert "| `stepramp_divider` is mentioned in prose | here |" in text
    # a second run changes nothing
    assert update_docs(REPORT, pages=tmp_path) == []
