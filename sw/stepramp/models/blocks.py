# SPDX-License-Identifier: MIT
"""Reference models of the core's arithmetic blocks: priority encoder, divider, base timer.

These follow the documented behaviour of each block (docs/stepramp_divider.md and friends), not the RTL's
structure: the divider's results come from Python's own integer division, and its latency from the
documented formula.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass


def msb(value: int) -> int:
    """Index of the most significant '1' of a non-negative integer; 0 for 0."""
    if value < 0:
        raise ValueError(f"msb of a negative number: {value}")
    return max(value.bit_length() - 1, 0)


def prio_enc(value: int, width: int) -> tuple[int, bool]:
    """Priority encoder: (index of the most significant '1', zero flag) of a width-bit value."""
    if not 0 <= value < (1 << width):
        raise ValueError(f"{value} does not fit in {width} bits")
    return msb(value), value == 0


@dataclass(frozen=True)
class Division:
    """Result of one division as the divider reports it."""

    quotient: int
    remainder: int
    div_zero: bool
    latency: int  # clock edges from the one that samples start to the one that raises done


def divider_latency(numerator: int, denominator: int) -> int:
    """Documented latency: 1 when D = 0 or N = 0, else 1 + floor(msb(N) / 2) + 1 (radix 4: one iteration per
    numerator bit pair from the pair that holds its most significant '1' down; the quotient has no '1' above it)."""
    if denominator == 0 or numerator == 0:
        return 1
    return 1 + msb(numerator) // 2 + 1


def divide(numerator: int, denominator: int, width: int, den_width: int | None = None) -> Division:
    """What the divider answers for numerator / denominator: a width-bit numerator and quotient, a den_width-bit
    denominator and remainder (den_width defaults to width). On D = 0 the quotient is all ones and the remainder
    the numerator's low den_width bits."""
    den_width = width if den_width is None else den_width
    limit = 1 << width
    if not (0 <= numerator < limit and 0 <= denominator < 1 << den_width):
        raise ValueError(f"operands {numerator}, {denominator} do not fit in {width} / {den_width} bits")
    latency = divider_latency(numerator, denominator)
    if denominator == 0:
        return Division(limit - 1, numerator % (1 << den_width), True, latency)
    q, r = divmod(numerator, denominator)
    return Division(q, r, False, latency)


def timer_ticks(prescale_at: Iterable[tuple[int, int]], restart: int, cycles: int) -> list[int]:
    """Edges after which the base timer's tick is '1', for edges restart+1 .. restart+cycles.

    prescale_at lists (edge, prescale) pairs: the prescale input value from that edge on (the first pair's
    edge must be <= restart). A new value takes effect at the next tick; prescale 0 behaves as 1.
    Ticks follow at restart + P, then every P' edges where P' is the value seen when the tick happens.
    """
    schedule = sorted(prescale_at)
    if not schedule or schedule[0][0] > restart:
        raise ValueError("prescale must be defined at the restart edge")

    def prescale(edge: int) -> int:
        value = schedule[0][1]
        for at, p in schedule:
            if at <= edge:
                value = p
        return max(value, 1)

    ticks: list[int] = []
    next_tick = restart + prescale(restart)
    while next_tick <= restart + cycles:
        ticks.append(next_tick)
        next_tick += prescale(next_tick)
    return ticks


def iter_msb_pairs(width: int) -> Iterator[tuple[int, int]]:
    """Corner operand pairs for a width-bit divider: 0, 1, max, powers of two, all-ones, N = D, N < D."""
    top = (1 << width) - 1
    specials = {0, 1, 2, 3, top, top - 1, top >> 1, (top >> 1) + 1}
    for b in range(width):
        specials.update({1 << b, (1 << b) - 1, (1 << b) + 1, top ^ (1 << b)})
    values = sorted(v for v in specials if 0 <= v <= top)
    for n in values:
        for d in values:
            yield n, d


# ---------------------------------------------------------------------------------------------------------------
# The next-delay unit (docs/stepramp_engine.md, "stepramp_next_delay"): one recurrence step of docs/algorithm.md
# ---------------------------------------------------------------------------------------------------------------

#: Ramp values are Q32.16: 48 bits.
RAMP_VALUE_LIMIT = 1 << 48


def recurrence_iterations(numerator: int) -> int:
    """k, the divider iterations of one recurrence step: floor(msb(num) / 2) + 1, or 0 when num = 0 (the
    denominator, never 0 here, does not change it)."""
    if numerator == 0:
        return 0
    return msb(numerator) // 2 + 1


@dataclass(frozen=True)
class NextDelayAnswer:
    """What the next-delay unit answers to one request."""

    value: int  # the exact result: A_n or D_m (outside 0 .. 2^48 - 1 when ovf)
    remainder: int
    ovf: bool  # the value left the Q32.16 range
    latency: int  # clock edges from the edge that samples req to the edge after which ans_valid is '1'


def next_delay(seed: bool, decel: bool, index: int, value: int, remainder: int) -> NextDelayAnswer:
    """The answer to a request: a seed is value itself, remainder 0, at the sampling edge; a step is

    accel (answer A_n, n = index):  num = 2 A_(n-1) + r, den = 4n + 1, A_n = A_(n-1) - num div den
    decel (answer D_m, m = index):  num = 2 D_(m+1) + r, den = 4m + 3, D_m = D_(m+1) + num div den

    (docs/algorithm.md with the answer's index; 4m + 3 is the spec's 4m' - 1, m' = m + 1), registered 2 + k edges
    after the sampling edge, k = recurrence_iterations(num).
    """
    if seed:
        return NextDelayAnswer(value, 0, False, 0)
    result, r = recurrence_step(decel, index, value, remainder)
    latency = 2 + recurrence_iterations(2 * value + remainder)
    return NextDelayAnswer(result, r, not 0 <= result < RAMP_VALUE_LIMIT, latency)


def recurrence_step(decel: bool, index: int, value: int, remainder: int) -> tuple[int, int]:
    """The value and remainder of one recurrence step (next_delay's answer without its timing): A_n from A_(n-1)
    (accel, n = index, den 4n + 1) or D_m from D_(m+1) (decel, m = index, den 4m + 3), the remainder carried."""
    q, r = divmod(2 * value + remainder, 4 * index + (3 if decel else 1))
    return (value + q if decel else value - q), r
