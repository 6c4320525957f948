# SPDX-License-Identifier: MIT
"""Every RTL file analyses under VHDL-93c and VHDL-2008; every top synthesises with no latch."""

from __future__ import annotations

import functools
import re
import tempfile
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


@functools.cache
def _analysed() -> Path:
    """The RTL analysed under VHDL-2008, once per process (each top's synthesis reads it; ghdl synth does not write
    the library)."""
    work = Path(tempfile.mkdtemp(prefix="rtl_hygiene_")) / "work"
    errors = analyse("08", work)
    assert not errors, "\n".join(errors)
    return work


@pytest.mark.parametrize("top", sorted(SYNTH_TOPS))
def test_rtl_synthesises_without_latch(top: str, tmp_path: Path) -> None:
    errors = synth(top, SYNTH_TOPS[top], _analysed(), tmp_path)
    assert not errors, "\n".join(errors)
    assert (tmp_path / f"{top}.v").stat().st_size > 0


def test_port_names_follow_the_convention() -> None:
    """docs/conventions.md, "Port names" rule 1: no port carries a direction mark (_i, _o, _in, _out, din, dout)."""
    port = re.compile(r"^\s+([A-Za-z0-9_]+)\s+:\s+(in|out|inout)\s", re.MULTILINE)
    marked = re.compile(r"(_(i|o|in|out)|^din|^dout)$", re.IGNORECASE)
    ports = {(f, m.group(1)) for f in HDL_FILES for m in port.finditer((HDL_DIR / f).read_text())}
    assert len(ports) > 100, "the port pattern no longer matches the entity declarations"
    bad = sorted(f"{f}: {name}" for f, name in ports if marked.search(name))
    assert not bad, f"ports with a direction mark: {bad}"


_ENTITY = re.compile(r"^\s*entity\s+(\w+)\s+is\b", re.MULTILINE | re.IGNORECASE)
_INSTANCE = re.compile(r"\bentity\s+work\.(\w+)", re.IGNORECASE)


def test_files_are_listed_in_compile_order() -> None:
    """Every `entity work.X` a file instantiates is declared in a file listed before it in HDL_FILES (the order
    hdl_sources, stepramp.core and the integration guide analyse the files in)."""
    declared: set[str] = set()
    late = []
    for name in HDL_FILES:
        text = (HDL_DIR / name).read_text()
        late += [f"{name} instantiates {e} before its file" for e in _INSTANCE.findall(text) if e not in declared]
        declared.update(e.lower() for e in _ENTITY.findall(text))
    assert not late, late


@pytest.mark.parametrize(
    ("top", "slave"), [("stepramp_plb", "stepramp_plb_slave"), ("stepramp_axil", "stepramp_axil_slave")]
)
def test_single_tops_use_the_bus_slaves(top: str, slave: str) -> None:
    """The bus logic exists once (issue 34): a single-axis top instantiates its bus slave and the core, and has no
    process of its own."""
    text = (HDL_DIR / f"{top}.vhd").read_text()
    assert sorted(set(_INSTANCE.findall(text))) == sorted({slave, "stepramp_core"})
    assert not re.search(r"^\s*\w+\s*:\s*process\b", text, re.MULTILINE), f"{top} has a process of its own"
