# SPDX-License-Identifier: MIT
"""The exact ramp arithmetic (docs/algorithm.md, "Exact step times"): ramp values as differences of rounded
integer square roots.

A ramp from rest with first interval c0 ticks reaches position x at c0 * sqrt(x) ticks. With the ramp constant
``C = round(c0^2 * 2^(2 F))`` (F = FRAC_EXACT fraction bits of the root), ``root(C * x)`` is that time in Q.F,
rounded, and the interval from position x to x + 1 is ``root(C * (x + 1)) - root(C * x)``. The differences
telescope: a run of them sums to the difference of two rounded roots, so no error accumulates along a ramp.

This module is plain integer arithmetic (``math.isqrt``); it does not follow the RTL's iterations.
"""

from __future__ import annotations

import math

FRAC_EXACT = 4
"""Fraction bits of the exact ramp's root (a time in Q.4 ticks); its values are shifted to Q32.16."""

C_WIDTH = 48
"""Width of a ramp constant (the ACCEL_SEED / DECEL_SEED registers in exact mode)."""

INDEX_WIDTH = 31
"""Width of a ramp index x (the value asked for is the interval from x to x + 1 of the ramp)."""

RADICAND_WIDTH = 80
"""C * (x + 1) < 2^48 * 2^31 = 2^79: the square root's radicand fits 80 bits (an even number: bit pairs)."""

_SHIFT_Q16 = 16 - FRAC_EXACT


def root(radicand: int) -> int:
    """sqrt(radicand) rounded to the nearest integer (no ties: sqrt of an integer is never k + 1/2)."""
    if radicand < 0:
        raise ValueError(f"root of a negative number: {radicand}")
    s = math.isqrt(radicand)
    return s + 1 if radicand - s * s > s else s


def ramp_constant(c0_ticks: float) -> int:
    """C = round(c0^2 * 2^(2F)) for a ramp whose first interval from rest is c0 ticks; ValueError when it does not
    fit C_WIDTH bits (the exact mode then needs a larger PRESCALE)."""
    scaled = c0_ticks * c0_ticks * (1 << (2 * FRAC_EXACT))
    value = round(scaled) if math.isfinite(scaled) else 1 << C_WIDTH
    if not 0 < value < 1 << C_WIDTH:
        fix = "raise the prescale or the accel/decel" if value else "lower the prescale or the accel/decel"
        raise ValueError(
            f"exact ramp: c0 = {c0_ticks:.6g} ticks gives a ramp constant outside 1 .. 2^{C_WIDTH} - 1 "
            f"(c0 must be in 0.044 .. 2^{(C_WIDTH - 2 * FRAC_EXACT) // 2} ticks): {fix}"
        )
    return value


def time_q(constant: int, x: int) -> int:
    """The ramp's time at position x in Q.F ticks, rounded: root(C * x)."""
    return root(constant * x)


def value_q4(constant: int, x: int) -> int:
    """The interval from position x to x + 1 of the ramp, in Q.F ticks."""
    return time_q(constant, x + 1) - time_q(constant, x)


def value(constant: int, x: int) -> int:
    """The interval from position x to x + 1, as a Q32.16 ramp value (what the next-delay unit answers)."""
    if not 0 <= x < 1 << INDEX_WIDTH:
        raise ValueError(f"ramp index {x} is not in 0 .. 2^31 - 1")
    if not 0 <= constant < 1 << C_WIDTH:
        raise ValueError(f"ramp constant {constant} does not fit {C_WIDTH} bits")
    return value_q4(constant, x) << _SHIFT_Q16


def ramp_sum_q16(constant: int, lo: int, hi: int) -> int:
    """Sum of value(constant, x) for x = lo .. hi - 1 (Q32.16): the telescoped difference, in O(1)."""
    if hi <= lo:
        return 0
    return (time_q(constant, hi) - time_q(constant, lo)) << _SHIFT_Q16
