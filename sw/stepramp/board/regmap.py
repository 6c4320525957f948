# SPDX-License-Identifier: MIT
"""The register map of the stepramp core, as Python objects for the driver, the models and the benches.

The one source is the SystemRDL file rdl/stepramp.rdl. `python -m stepramp.tools.regmap_gen` compiles it
(systemrdl-compiler) and writes the plain tables of regmap.json (package data beside this module) that this module
reads (so that the driver needs no compiler), the VHDL package (hdl/stepramp_regs_pkg.vhd, with the register file's
masks and resets), the C header (sw/c/src/stepramp_regs.h), the Markdown table (docs/registers.md) and IP-XACT
(rdl/stepramp.xml). sw/tests/test_regmap.py checks that every generated file is current.

All registers are 32 bits wide, at byte offsets on a 32-bit bus. Motion registers (STEPS .. STOP_RATIO) may be
written at any time: the core latches them at the edge that accepts START, so a write during a move (or while a
START is held back) prepares the next one (shadowing).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from importlib import resources

#: Access kinds of a field.
RO = "RO"  # read only
RW = "RW"  # read/write
W1C = "W1C"  # sticky flag, cleared by writing 1
WS = "WS"  # write 1 to act (a strobe); reads 0


@dataclass(frozen=True)
class Field:
    """A bit field of a register."""

    name: str
    lsb: int
    width: int
    access: str
    reset: int
    description: str

    @property
    def mask(self) -> int:
        return ((1 << self.width) - 1) << self.lsb


@dataclass(frozen=True)
class Register:
    """A 32-bit register at a byte offset."""

    name: str
    offset: int
    description: str
    fields: tuple[Field, ...] = field(default_factory=tuple)

    @property
    def access(self) -> str:
        kinds = {f.access for f in self.fields}
        return kinds.pop() if len(kinds) == 1 else "mixed"

    @property
    def reset(self) -> int:
        return sum(f.reset << f.lsb for f in self.fields)

    def field(self, name: str) -> Field:
        for f in self.fields:
            if f.name == name:
                return f
        raise KeyError(f"{self.name} has no field {name}")


#: The generated tables, read as package data (so an installed package finds them as well as a source tree).
_DATA = json.loads(resources.files("stepramp.board").joinpath("regmap.json").read_text(encoding="utf-8"))

#: Error causes, as reported in STATUS.ERR_CODE (when several meet at one edge, the order of docs/stepramp_plb.md,
#: "Verification", decides): name -> (code, description), from the .rdl's enum.
ERROR_CODES: dict[str, tuple[int, str]] = {e["name"]: (e["code"], e["description"]) for e in _DATA["error_codes"]}

REGISTERS: tuple[Register, ...] = tuple(
    Register(r["name"], r["offset"], r["description"], tuple(Field(**f) for f in r["fields"]))
    for r in _DATA["registers"]
)

REGISTERS_BY_NAME: dict[str, Register] = {r.name: r for r in REGISTERS}

#: The ID register's reset value: 0x5352 ("SR") in bits 31:16, the version major.minor in 13:8 and 7:0, in bit 15
#: the core's ramp arithmetic (G_RAMP; 0 in the reset value: a core built with G_RAMP = 1 reads ID_RAMP_BIT set), and
#: in bit 14 NO_WINDINGS (0 in the reset value: a core built with G_WINDINGS false has no winding outputs, A1 .. B2
#: stay '0', DRIVE.MODE reads 0 and ignores writes, and it reads ID_WINDINGS_BIT set).
ID_VALUE = REGISTERS_BY_NAME["ID"].reset
ID_MAGIC = ID_VALUE >> 16
ID_RAMP_BIT = 15
ID_WINDINGS_BIT = 14
VERSION_MAJOR = (ID_VALUE >> 8) & 0x3F
VERSION_MINOR = ID_VALUE & 0xFF

#: Address bits the core decodes: the register window rounded up to a power of two (256 bytes).
ADDR_BITS: int = _DATA["addr_bits"]


def offset(name: str) -> int:
    """Byte offset of a register."""
    return REGISTERS_BY_NAME[name].offset


def _span(first: str, last: str) -> tuple[str, ...]:
    return tuple(r.name for r in REGISTERS if offset(first) <= r.offset <= offset(last))


#: The staging registers: plain storage written at any time, taken by the engine at START (the move's, then the
#: segment's, and CHANGE_AT: docs/algorithm.md, "When the move is latched" and "Changes while moving"); locked while
#: STATUS.PENDING.
STAGING: tuple[str, ...] = _span("STEPS", "STOP_RATIO") + _span("SEGMENT", "CHANGE_AT")


#: Registers that change on their own, every clock: TIME_LO, the clock count since reset (a read also copies the
#: count's bits 63:32 into TIME_HI). Tests that read "every register" expect the clock count there, not a constant.
LIVE: tuple[str, ...] = ("TIME_LO",)


def split_wide(value: int, width: int) -> tuple[int, int]:
    """A wide unsigned register value as its (LO, HI) 32-bit words."""
    if not 0 <= value < (1 << width):
        raise ValueError(f"{value} does not fit in {width} bits")
    return value & 0xFFFF_FFFF, value >> 32
