# SPDX-License-Identifier: MIT
"""The register map is consistent, and the generated VHDL, C and Markdown files are up to date."""

from __future__ import annotations

from stepramp.board import regmap
from stepramp.tools import regmap_gen


def test_offsets_are_unique_aligned_and_inside_the_window() -> None:
    offsets = [r.offset for r in regmap.REGISTERS]
    assert len(set(offsets)) == len(offsets)
    assert all(o % 4 == 0 and o < 1 << regmap.ADDR_BITS for o in offsets)


def test_fields_fit_and_do_not_overlap() -> None:
    for reg in regmap.REGISTERS:
        used = 0
        for f in reg.fields:
            assert f.lsb >= 0 and f.lsb + f.width <= 32, f"{reg.name}.{f.name}"
            assert f.reset < 1 << f.width, f"{reg.name}.{f.name} reset"
            assert used & f.mask == 0, f"{reg.name}.{f.name} overlaps"
            used |= f.mask


def test_error_codes_fit_err_code() -> None:
    width = regmap.REGISTERS_BY_NAME["STATUS"].field("ERR_CODE").width
    codes = [code for code, _ in regmap.ERROR_CODES.values()]
    assert len(set(codes)) == len(codes)
    assert all(0 <= c < 1 << width for c in codes)


def test_id_value() -> None:
    assert regmap.ID_VALUE >> 16 == 0x5352
    assert regmap.REGISTERS_BY_NAME["ID"].reset == regmap.ID_VALUE


def test_split_wide() -> None:
    assert regmap.split_wide((0x1234 << 32) | 0x89ABCDEF, 48) == (0x89ABCDEF, 0x1234)


def test_generated_files_are_up_to_date() -> None:
    for path, make in regmap_gen.OUTPUTS.items():
        assert path.exists(), f"{path} missing: run python -m stepramp.tools.regmap_gen"
        assert path.read_text() == make(), f"{path} is out of date: run python -m stepramp.tools.regmap_gen"
