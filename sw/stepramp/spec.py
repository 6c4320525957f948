# SPDX-License-Identifier: MIT
"""The engine's inputs as docs/algorithm.md specifies them: a move's registers (Plan), a continuation segment's
(Segment), their widths and fixed-point formats, and the ramp kinds.

The lowest layer of the package: the driver (stepramp.board) fills these in, the models (stepramp.models) run them;
this module imports nothing of stepramp.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import Any

FRAC_RAMP = 16
"""Fraction bits of the ramp values (Q32.16)."""
FRAC_CRUISE = 32
"""Fraction bits of the cruise period (Q32.32)."""
RAMP_AVR446 = 0
"""Plan.ramp: the AVR446 recurrence (the core's G_RAMP = 0, the default)."""
RAMP_EXACT = 1
"""Plan.ramp: the exact ramp, differences of rounded square roots (G_RAMP = 1; docs/algorithm.md, "Exact step
times")."""
MAX_STEPS = 2**31 - 1
MAX_PRESCALE = 2**16 - 1

REG_WIDTHS: dict[str, int] = {
    "steps": 31,
    "direction": 1,
    "prescale": 16,
    "c_first": 48,
    "c_last": 48,
    "sa": 31,
    "c_sa": 48,
    "sd": 31,
    "c_sd": 48,
    "accel_seed": 64,
    "decel_seed": 64,
    "cruise": 64,
    "stop_ratio": 32,
}
"""Width in bits of each register (field of Plan)."""


def check_widths(obj: Any, widths: dict[str, int]) -> None:
    """ValueError unless each field of a dataclass named in widths is an int that fits its unsigned register."""
    for f in fields(obj):
        if f.name in widths:
            value, width = getattr(obj, f.name), widths[f.name]
            if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value < 1 << width:
                name = f"{type(obj).__name__}.{f.name}"
                raise ValueError(f"{name} = {value!r} does not fit an unsigned {width}-bit register")


def check_ramp(ramp: int) -> int:
    """ValueError unless ramp is RAMP_AVR446 or RAMP_EXACT."""
    if isinstance(ramp, bool) or ramp not in (RAMP_AVR446, RAMP_EXACT):
        raise ValueError(f"ramp must be {RAMP_AVR446} (avr446) or {RAMP_EXACT} (exact), got {ramp!r}")
    return ramp


@dataclass(frozen=True)
class Plan:
    """The engine's inputs for one move (field by field the table of docs/algorithm.md)."""

    steps: int
    direction: int
    prescale: int
    c_first: int
    c_last: int
    sa: int
    c_sa: int
    sd: int
    c_sd: int
    accel_seed: int
    decel_seed: int
    cruise: int
    stop_ratio: int
    ramp: int = RAMP_AVR446
    """Not a register: the ramp arithmetic the plan is for (RAMP_AVR446 or RAMP_EXACT, the core's G_RAMP)."""

    def __post_init__(self) -> None:
        check_widths(self, REG_WIDTHS)
        check_ramp(self.ramp)

    def to_dict(self) -> dict[str, int]:
        """The registers as a plain dict (field name -> unsigned integer)."""
        return {name: value for name, value in asdict(self).items() if name in REG_WIDTHS}


UP = "up"
DOWN = "down"

SHARED_FIELDS = tuple(name for name in REG_WIDTHS if name not in ("steps", "direction"))
"""The fields a segment shares with a move's Plan (all but steps and direction)."""
SEGMENT_WIDTHS = {**{name: REG_WIDTHS[name] for name in SHARED_FIELDS}, "head_index": 31, "run_stop": 31}
"""A segment's register widths."""


@dataclass(frozen=True)
class Segment:
    """The engine's inputs for a continuation: a plan over the segment's own intervals 1 .. length, with a head ramp
    that may start at speed (up: accel recurrence from index head_index; down: decel recurrence towards a virtual
    rest at the end of interval head_index). length None: endless (jog); run_stop is then the length of a soft
    stop decided in its cruise (a positioning segment takes L - sd + 1, as a move does)."""

    length: int | None
    head: str
    head_index: int
    prescale: int
    sa: int
    sd: int
    c_first: int
    c_sa: int
    c_sd: int
    c_last: int
    accel_seed: int
    decel_seed: int
    cruise: int
    stop_ratio: int
    run_stop: int = 0
    ramp: int = RAMP_AVR446
    """Not a register: the ramp arithmetic (RAMP_AVR446 or RAMP_EXACT), as Plan.ramp."""

    def __post_init__(self) -> None:
        check_ramp(self.ramp)
        if self.length is not None and not 0 <= self.length <= MAX_STEPS:
            raise ValueError(f"Segment.length = {self.length!r} is not in 0 .. 2^31 - 1 (or None: endless)")
        if self.head not in (UP, DOWN):
            raise ValueError(f"Segment.head = {self.head!r} is neither {UP!r} nor {DOWN!r}")
        check_widths(self, SEGMENT_WIDTHS)

    @property
    def head_prod(self) -> int:
        """HEAD_PROD: n0 * stop_ratio for an up head (Q31.16; 2^47 or more reads as bit 47 alone), 0 for a down one."""
        if self.head == DOWN:
            return 0
        return min(self.head_index * self.stop_ratio, 1 << 47)

    def registers(self, direction: int) -> tuple[Plan, dict[str, int]]:
        """The registers: a Plan (STEPS = length + 1, or 1 for an endless segment: only its sign counts) and the
        SEGMENT .. HEAD_PROD fields, as the engine's port names."""
        steps = self.length + 1 if self.length is not None else 1
        shared = {name: getattr(self, name) for name in SHARED_FIELDS}
        plan = Plan(steps=steps, direction=direction, ramp=self.ramp, **shared)
        segment = {
            "head_down": int(self.head == DOWN),
            "endless": int(self.length is None),
            "head_index": self.head_index,
            "run_stop": self.run_stop,
            "head_prod": self.head_prod,
        }
        return plan, segment

    @classmethod
    def of_move(cls, plan: Plan) -> Segment:
        """A move from rest as a segment (head up from index 0): its intervals 1 .. N - 1, the same values."""
        shared = {name: getattr(plan, name) for name in SHARED_FIELDS}
        return cls(length=max(plan.steps - 1, 0), head=UP, head_index=0, ramp=plan.ramp, **shared)
