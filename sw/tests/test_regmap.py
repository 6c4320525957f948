# SPDX-License-Identifier: MIT
"""The register map is consistent, and the generated VHDL, C and Markdown files are up to date."""

from __future__ import annotations

import re

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


def test_files_made_from_the_rdl_are_up_to_date() -> None:
    """regmap.json (what the driver reads) and the IP-XACT file equal a fresh compile of rdl/stepramp.rdl."""
    for path, text in regmap_gen.rdl_outputs(regmap_gen.compile_rdl()).items():
        assert path.exists() and path.read_text() == text, (
            f"{path} is out of date: run python -m stepramp.tools.regmap_gen"
        )


def test_ipxact_parses_back_to_the_same_registers() -> None:
    """rdl/stepramp.xml read by an IP-XACT reader (PeakRDL's importer into systemrdl-compiler): every register at its
    offset, every field at its bits with its reset value and software access, as the Python map has them."""
    from peakrdl_ipxact import IPXACTImporter
    from systemrdl import RDLCompiler

    compiler = RDLCompiler()
    IPXACTImporter(compiler).import_file(str(regmap_gen.IPXACT))
    top = compiler.elaborate().top
    (block,) = top.children()  # the memory map's one address block
    seen = {}
    for reg in block.registers():
        fields = {f.inst_name: (f.low, f.width, f.get_property("reset") or 0, f.is_sw_writable) for f in reg.fields()}
        seen[reg.inst_name] = (reg.address_offset, fields)
    want = {
        r.name: (r.offset, {f.name: (f.lsb, f.width, f.reset, f.access != regmap.RO) for f in r.fields})
        for r in regmap.REGISTERS
    }
    assert seen == want


def test_register_file_masks_and_resets_come_from_the_map() -> None:
    """hdl/stepramp_regs_pkg.vhd's per-word tables (which stepramp_regfile uses for its storage words) hold each
    register's RW bits and reset value, recomputed here from the fields."""
    text = regmap_gen.VHDL_PKG.read_text()
    for table, value in (
        ("C_REG_RW_MASK", lambda r: sum(f.mask for f in r.fields if f.access == regmap.RW)),
        ("C_REG_RESET", lambda r: sum(f.reset << f.lsb for f in r.fields)),
    ):
        body = text.split(f"constant {table} : t_reg_words :=")[1].split(");")[0]
        rows = dict(re.findall(r"(\d+)\s+=> x\"([0-9A-F]{8})\"", body))
        assert {int(k): int(v, 16) for k, v in rows.items()} == {r.offset // 4: value(r) for r in regmap.REGISTERS}
    regfile = (regmap_gen.REPO / "hdl" / "stepramp_regfile.vhd").read_text()
    assert "C_REG_RW_MASK(w)" in regfile and "C_REG_RESET(" in regfile
