# SPDX-License-Identifier: MIT
"""The exact ramp arithmetic (docs/algorithm.md, "Exact step times"): ramp values as differences of rounded
integer square roots.

A ramp from rest with first interval c0 ticks reaches position x at c0 * sqrt(x) ticks. With the ramp constant
``C = round(c0^2 * 2^(2 F))`` (F = FRAC_EXACT fraction bits of the root), ``root(C * x)`` is that time in Q.F,
rounded, and the interval from position x to x + 1 is ``root(C * (x + 1)) - root(C * x)``. The registers hold C as
a seed word, a 60-bit mantissa m and a scale e with C = m * 4^e (ramp_constant, constant_of). The differences
telescope: a run of them sums to the difference of two rounded roots, so no error accumulates along a ramp.

This module is plain integer arithmetic (``math.isqrt``); it does not follow the RTL's iterations.
"""

from __future__ import annotations

import math

FRAC_EXACT = 4
"""Fraction bits of the exact ramp's root (a time in Q.4 ticks); its values are shifted to Q32.16."""

SEED_WIDTH = 64
"""Width of a seed word (the ACCEL_SEED / DECEL_SEED register pairs in exact mode): the ramp constant as a mantissa
and a scale."""

MANT_WIDTH = 60
"""Bits 59:0 of a seed word: the mantissa m."""

SCALE_MAX = 6
"""Bits 63:60 of a seed word: the scale e, 0 .. SCALE_MAX; the ramp constant is C = m * 4^e."""

C_MAX = (1 << 72) - (1 << 36)
"""The largest ramp constant: root(C) <= 2^36 - 1 Q.4 ticks, so every ramp value fits Q32.16 (c0 below 2^32 ticks:
(2^32 - 1)^2 * 2^8 < C_MAX)."""

C_NARROW = 1 << 48
"""Ramp constants below this (c0 below 2^20 ticks) keep the engine's shorter latency budget (MIN_INTERVAL_CLKS_EXACT
= 256 clocks; stepramp.board.plan.min_interval_clks)."""

C_WIDTH = 72
"""A ramp constant is below 2^72."""

INDEX_WIDTH = 31
"""Width of a ramp index x (the value asked for is the interval from x to x + 1 of the ramp)."""

RADICAND_WIDTH = 92
"""m * (x + 1) < 2^60 * 2^31 = 2^91: the square root's radicand fits 92 bits (an even number: bit pairs); the scale
appends e zero pairs below it (the root of m (x + 1) 4^e)."""

_SHIFT_Q16 = 16 - FRAC_EXACT


def root(radicand: int) -> int:
    """sqrt(radicand) rounded to the nearest integer (no ties: sqrt of an integer is never k + 1/2)."""
    if radicand < 0:
        raise ValueError(f"root of a negative number: {radicand}")
    s = math.isqrt(radicand)
    return s + 1 if radicand - s * s > s else s


def seed_word(mantissa: int, scale: int) -> int:
    """The seed word of C = mantissa * 4^scale: scale in bits 63:60, mantissa in bits 59:0."""
    if not 0 <= mantissa < 1 << MANT_WIDTH or not 0 <= scale < 1 << (SEED_WIDTH - MANT_WIDTH):
        raise ValueError(f"mantissa {mantissa} or scale {scale} does not fit its field")
    return scale << MANT_WIDTH | mantissa


def mantissa_scale(seed: int) -> tuple[int, int]:
    """(m, e) of a seed word (no range check of e)."""
    if not 0 <= seed < 1 << SEED_WIDTH:
        raise ValueError(f"seed word {seed} does not fit {SEED_WIDTH} bits")
    return seed & ((1 << MANT_WIDTH) - 1), seed >> MANT_WIDTH


def constant_of(seed: int) -> int:
    """The ramp constant C = m * 4^e of a seed word; ValueError when e > SCALE_MAX (the engine refuses such a seed)."""
    m, e = mantissa_scale(seed)
    if e > SCALE_MAX:
        raise ValueError(f"seed word {seed:#x}: scale {e} above {SCALE_MAX}")
    return m << (2 * e)


def ramp_constant(c0_ticks: float) -> int:
    """The seed word of the ramp whose first interval from rest is c0 ticks: C = round(c0^2 * 2^(2F)) as m * 4^e with
    the smallest scale e whose mantissa m = round(c0^2 * 2^(2F) / 4^e) fits 60 bits (e = 0 and m = C below 2^60;
    above, the double c0^2 * 2^(2F) has no bits below 4^e, so C is still its exact value). ValueError when C is not
    in 1 .. C_MAX (c0 must be in 0.044 .. 2^32 - 1 ticks; the exact mode then needs another PRESCALE)."""
    scaled = c0_ticks * c0_ticks * (1 << (2 * FRAC_EXACT))
    value = 0
    scale = 0
    if math.isfinite(scaled):
        value = round(scaled)
        while value >= 1 << MANT_WIDTH and scale < SCALE_MAX:
            scale += 1
            value = round(scaled / (1 << (2 * scale)))  # a power of two: exact in doubles
    if not 0 < value << (2 * scale) <= C_MAX:
        fix = (
            "lower the prescale or the accel/decel"
            if value == 0 and scaled < 1
            else "raise the prescale or the accel/decel"
        )
        raise ValueError(
            f"exact ramp: c0 = {c0_ticks:.6g} ticks gives a ramp constant outside 1 .. 2^72 - 2^36 "
            f"(c0 must be in 0.044 .. 2^32 - 1 ticks): {fix}"
        )
    return seed_word(value, scale)


def narrow(seed: int) -> bool:
    """Whether the seed word's ramp constant is below C_NARROW (2^48)."""
    return constant_of(seed) < C_NARROW


def time_q(constant: int, x: int) -> int:
    """The ramp's time at position x in Q.F ticks, rounded: root(C * x)."""
    return root(constant * x)


def value_q4(constant: int, x: int) -> int:
    """The interval from position x to x + 1 of the ramp, in Q.F ticks."""
    return time_q(constant, x + 1) - time_q(constant, x)


def value(seed: int, x: int) -> int:
    """The interval from position x to x + 1 of the ramp of a seed word, as a Q32.16 ramp value (what the next-delay
    unit answers)."""
    if not 0 <= x < 1 << INDEX_WIDTH:
        raise ValueError(f"ramp index {x} is not in 0 .. 2^31 - 1")
    constant = constant_of(seed)
    if constant > C_MAX:
        raise ValueError(f"ramp constant {constant} is above 2^72 - 2^36")
    return value_q4(constant, x) << _SHIFT_Q16


def ramp_sum_q16(seed: int, lo: int, hi: int) -> int:
    """Sum of value(seed, x) for x = lo .. hi - 1 (Q32.16): the telescoped difference, in O(1)."""
    if hi <= lo:
        return 0
    constant = constant_of(seed)
    return (time_q(constant, hi) - time_q(constant, lo)) << _SHIFT_Q16
