# SPDX-License-Identifier: MIT
"""The register map: the one source of truth for the bus registers of the stepramp core.

From this description `python -m stepramp.tools.regmap_gen` writes the VHDL constants package
(hdl/stepramp_regs_pkg.vhd), the C header (sw/c/stepramp_regs.h) and the Markdown table (docs/registers.md);
the Python driver uses it directly. A test checks that the generated files are up to date.

All registers are 32 bits wide, at byte offsets on a 32-bit bus. Motion registers (STEPS .. STOP_RATIO) may be
written at any time: the core latches them at the edge that accepts START, so a write during a move (or while a
START is held back) prepares the next one (shadowing).
"""

from __future__ import annotations

from dataclasses import dataclass, field

#: Access kinds of a field.
RO = "RO"  # read only
RW = "RW"  # read/write
W1C = "W1C"  # sticky flag, cleared by writing 1
WS = "WS"  # write 1 to act (a strobe); reads 0

ID_MAGIC = 0x5352  # "SR"
VERSION_MAJOR = 0
VERSION_MINOR = 3
ID_VALUE = (ID_MAGIC << 16) | (VERSION_MAJOR << 8) | VERSION_MINOR


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


def _value(name: str, offset: int, access: str, width: int, description: str, reset: int = 0) -> Register:
    """A register that holds one value in its low bits."""
    return Register(name, offset, description, (Field("VALUE", 0, width, access, reset, description),))


#: Engine error causes, as reported in STATUS.ERR_CODE (the lowest code wins when several apply).
ERROR_CODES: dict[str, tuple[int, str]] = {
    "NONE": (0, "no error"),
    "PRESCALE": (1, "PRESCALE is 0"),
    "BOUNDS": (2, "SA or SD outside 1 .. STEPS-1, or SA > SD"),
    "C_FIRST": (3, "C_FIRST below one tick while the move has intervals"),
    "C_LAST": (4, "C_LAST below one tick while used"),
    "C_SA": (5, "C_SA below one tick while used"),
    "C_SD": (6, "C_SD below one tick while used"),
    "CRUISE": (7, "CRUISE below one tick while a cruise interval exists"),
    "ACCEL_SEED": (8, "ACCEL_SEED below one tick while the accel recurrence is used"),
    "DECEL_SEED": (9, "DECEL_SEED below one tick while the decel recurrence is used"),
    "LATE": (10, "the next delay was not ready in time (speed too high for the clock); the move stopped"),
    "ZERO_TICKS": (11, "an interval of zero ticks would have been emitted; the move stopped"),
    "RANGE": (12, "a recurrence value left its 48-bit range; the move stopped"),
    "STEPS": (13, "STEPS is -2^31 (|steps| must be <= 2^31 - 1)"),
    "POS_BUSY": (14, "POSITION written while a move runs (the write was ignored)"),
    "CFG_BUSY": (15, "DRIVE, STEP_WIDTH, DIR_TIMING, PWM_PERIOD or STEP_SPACE written while a move runs (ignored)"),
    "STEP_SPACE": (
        16,
        "a pulse would have come less than STEP_WIDTH + STEP_SPACE clocks after the previous one (the two would "
        "merge on the STEP pin); it was not emitted and the move stopped",
    ),
}

REGISTERS: tuple[Register, ...] = (
    _value("ID", 0x00, RO, 32, "Identification: 0x5352 ('SR') in bits 31:16, version major.minor below", ID_VALUE),
    Register(
        "CTRL",
        0x04,
        "Commands (write 1) and interrupt enables",
        (
            Field("START", 0, 1, WS, 0, "start the move programmed in STEPS .. STOP_RATIO (ignored while busy)"),
            Field(
                "SOFT_STOP",
                1,
                1,
                WS,
                0,
                "decelerate at the programmed decel to zero, then done; also cancels a held START",
            ),
            Field(
                "HARD_STOP", 2, 1, WS, 0, "no step pulse from the next clock on, then done; also cancels a held START"
            ),
            Field("IRQ_DONE_EN", 8, 1, RW, 0, "irq follows STATUS.DONE"),
            Field("IRQ_ERROR_EN", 9, 1, RW, 0, "irq follows STATUS.ERROR"),
            Field("ENABLE", 16, 1, RW, 0, "ENABLE output to the motor driver; '0' also switches the windings off"),
        ),
    ),
    Register(
        "STATUS",
        0x08,
        "State and sticky flags",
        (
            Field("STATE", 0, 2, RO, 0, "engine state: 0 STOP, 1 ACCEL, 2 RUN, 3 DECEL"),
            Field("BUSY", 2, 1, RO, 0, "a move is running"),
            Field("DIR", 3, 1, RO, 0, "direction of the current or last move (1: position counts down)"),
            Field("DONE", 4, 1, W1C, 0, "a move ended (normally, stopped or rejected); write 1 to clear"),
            Field("ERROR", 5, 1, W1C, 0, "a move was rejected or stopped on an error; write 1 to clear"),
            Field("DIR_FAULT", 6, 1, RO, 0, "a step came while DIR disagreed with the engine (never expected)"),
            Field("ERR_CODE", 8, 5, RO, 0, "cause of the last error (table below)"),
        ),
    ),
    _value("STEPS", 0x0C, RW, 32, "signed step count of the next move (two's complement; -2^31 is rejected)"),
    _value("PRESCALE", 0x10, RW, 16, "base timer period in clocks (1 .. 65535; 0 is rejected at START)", 1),
    _value(
        "C_FIRST_LO",
        0x14,
        RW,
        32,
        "interval 1 (exact, plus half the accel recurrence deficit), Q32.16 ticks, bits 31:0",
    ),
    _value("C_FIRST_HI", 0x18, RW, 16, "interval 1, bits 47:32"),
    _value("C_LAST_LO", 0x1C, RW, 32, "exact last interval, Q32.16, bits 31:0"),
    _value("C_LAST_HI", 0x20, RW, 16, "exact last interval, bits 47:32"),
    _value("SA", 0x24, RW, 31, "index of the accel-side boundary interval"),
    _value("C_SA_LO", 0x28, RW, 32, "exact interval SA, Q32.16, bits 31:0"),
    _value("C_SA_HI", 0x2C, RW, 16, "exact interval SA, bits 47:32"),
    _value("SD", 0x30, RW, 31, "index of the decel-side boundary interval"),
    _value("C_SD_LO", 0x34, RW, 32, "exact interval SD, Q32.16, bits 31:0"),
    _value("C_SD_HI", 0x38, RW, 16, "exact interval SD, bits 47:32"),
    _value("ACCEL_SEED_LO", 0x3C, RW, 32, "accel recurrence seed (0.676 c0 plus a deficit share), Q32.16, bits 31:0"),
    _value("ACCEL_SEED_HI", 0x40, RW, 16, "accel recurrence seed, bits 47:32"),
    _value(
        "DECEL_SEED_LO",
        0x44,
        RW,
        32,
        "decel recurrence value at its start index (plus a deficit share), Q32.16, bits 31:0",
    ),
    _value("DECEL_SEED_HI", 0x48, RW, 16, "decel recurrence start value, bits 47:32"),
    _value("CRUISE_LO", 0x4C, RW, 32, "cruise period, Q32.32 ticks, bits 31:0 (fraction)"),
    _value("CRUISE_HI", 0x50, RW, 32, "cruise period, bits 63:32 (integer ticks)"),
    _value("STOP_RATIO", 0x54, RW, 32, "accel / decel, Q16.16: sizes the decel ramp of a soft stop"),
    _value("POSITION", 0x58, RW, 32, "signed position in steps; written only while stopped"),
    _value("CUR_DELAY", 0x5C, RO, 32, "integer ticks of the interval now counting down"),
    _value("STEP_COUNT", 0x60, RO, 31, "pulses emitted in the current (or last) move"),
    Register(
        "DRIVE",
        0x64,
        "Stepping outputs; written only while stopped",
        (
            Field("MODE", 0, 3, RW, 0, "0 STEP/DIR only, 1 wave, 2 full step, 3 half step, 4 sine/cosine PWM"),
            Field("USTEP_LOG2", 4, 3, RW, 0, "PWM microsteps per full step = 2^USTEP_LOG2 (at most G_MICROSTEPS)"),
        ),
    ),
    _value("STEP_WIDTH", 0x68, RW, 16, "STEP high time in clocks (0 acts as 1); below the shortest interval", 1),
    Register(
        "DIR_TIMING",
        0x6C,
        "DIR setup and hold around STEP rising edges; written only while stopped",
        (
            Field("SETUP", 0, 16, RW, 0, "DIR setup before a STEP rising edge, clocks (at least 5 are kept)"),
            Field("HOLD", 16, 16, RW, 0, "DIR hold after a STEP rising edge, clocks (0 acts as 1)"),
        ),
    ),
    _value("PWM_PERIOD", 0x70, RW, 16, "PWM carrier period in clocks (0 or 1: windings off in mode 4)"),
    _value(
        "STEP_SPACE",
        0x74,
        RW,
        16,
        "shortest STEP low time in clocks (0 acts as 1): two STEP rising edges are at least STEP_WIDTH + STEP_SPACE "
        "apart, or the move stops with error STEP_SPACE; written only while stopped",
        1,
    ),
)

REGISTERS_BY_NAME: dict[str, Register] = {r.name: r for r in REGISTERS}

#: Address bits the core decodes (a 128-byte window).
ADDR_BITS = 7


def offset(name: str) -> int:
    """Byte offset of a register."""
    return REGISTERS_BY_NAME[name].offset


def split_wide(value: int, width: int) -> tuple[int, int]:
    """A wide unsigned register value as its (LO, HI) 32-bit words."""
    if not 0 <= value < (1 << width):
        raise ValueError(f"{value} does not fit in {width} bits")
    return value & 0xFFFF_FFFF, value >> 32
