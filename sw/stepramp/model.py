# SPDX-License-Identifier: MIT
"""Bit-exact integer model of the ramp engine (docs/algorithm.md, followed literally).

The RTL is compared edge for edge with :func:`edges`.
"""

from __future__ import annotations

import bisect
import itertools
from collections.abc import Iterable, Iterator

from .plan import FRAC_CRUISE, FRAC_RAMP, Plan

FIRST_PULSE_LATENCY = 2
"""Clock edges from the edge sampling start = '1' to the edge after which pulse 0 is high."""

ACCEL = "ACCEL"
RUN = "RUN"
DECEL = "DECEL"

_SHIFT = FRAC_CRUISE - FRAC_RAMP
_FRAC_MASK = (1 << FRAC_CRUISE) - 1


def interval_values(plan: Plan) -> Iterator[int]:
    """The Q32.32 value of every interval i = 1 .. L, in order (rule order of the spec)."""
    length = plan.steps - 1
    sa, sd = plan.sa, plan.sd
    c_first = plan.c_first << _SHIFT
    c_last = plan.c_last << _SHIFT
    c_sa = plan.c_sa << _SHIFT
    c_sd = plan.c_sd << _SHIFT
    cruise = plan.cruise
    # accel recurrence: acc_val = A_n, acc_r its remainder
    acc_n, acc_val, acc_r = 0, plan.accel_seed, 0
    # decel recurrence: dec_val = D_m (dec_m is None until the first decel value is emitted)
    dec_m: int | None = None
    dec_val, dec_r = plan.decel_seed, 0
    for i in range(1, length + 1):
        if i == 1:
            value = c_first
        elif i == length:
            value = c_last
        elif i == sa:
            value = c_sa
        elif i == sd:
            value = c_sd
        elif i < sa:
            while acc_n < i - 1:  # A_n from A_{n-1}
                acc_n += 1
                q, acc_r = divmod(2 * acc_val + acc_r, 4 * acc_n + 1)
                acc_val -= q
            value = acc_val << _SHIFT
        elif i > sd:
            if dec_m is None:  # first decel value: D_{m0} = decel_seed, r = 0
                dec_m = length - sd - 1
            while dec_m > length - i:  # D_{m-1} from D_m
                q, dec_r = divmod(2 * dec_val + dec_r, 4 * dec_m - 1)
                dec_val += q
                dec_m -= 1
            value = dec_val << _SHIFT
        else:
            value = cruise
        yield value


def tick_times(plan: Plan) -> list[int]:
    """Pulse times T_k in ticks, k = 0 .. N-1 (T_0 = 0), through the 32-bit fractional accumulator."""
    if plan.steps == 0:
        return []
    times = [0]
    t = 0
    acc = 0
    for value in interval_values(plan):
        s = acc + value
        t += s >> FRAC_CRUISE
        acc = s & _FRAC_MASK
        times.append(t)
    return times


def edges(plan: Plan) -> list[int]:
    """Clock edge after which pulse k is high: FIRST_PULSE_LATENCY + prescale * T_k."""
    return [FIRST_PULSE_LATENCY + plan.prescale * t for t in tick_times(plan)]


def phases(plan: Plan) -> list[str]:
    """FSM state during each interval i = 1 .. L: ACCEL, RUN or DECEL."""
    sa, sd = plan.sa, plan.sd
    low = min(sa, sd)
    out = []
    for i in range(1, plan.steps):
        if i < low:
            out.append(ACCEL)
        elif sa <= i < sd:
            out.append(RUN)
        else:
            out.append(DECEL)
    return out


# ---------------------------------------------------------------------------------------------------------------
# Stops (docs/algorithm.md, "Soft stop"; docs/stepramp_engine.md for the hard stop)
# ---------------------------------------------------------------------------------------------------------------

SOFT = "soft"
HARD = "hard"

STOP_RATIO_FRAC = 16
"""Fraction bits of Plan.stop_ratio (Q16.16, accel / decel)."""


def phase_of(plan: Plan, i: int) -> str:
    """The spec's phase of interval i (also used for pulse i in the soft-stop rule): ACCEL, RUN or DECEL."""
    if i < min(plan.sa, plan.sd):
        return ACCEL
    if plan.sa <= i < plan.sd:
        return RUN
    return DECEL


def soft_stop_length(plan: Plan, p: int) -> int | None:
    """m, the number of intervals after pulse p of a soft stop decided at pulse p; None when it is ignored.

    0 means the move ends with pulse p. The new last pulse is p + m.
    """
    length = plan.steps - 1
    if p >= length:  # pulse p is the last one (or there is none): nothing to shorten
        return None
    phase = phase_of(plan, p)
    if phase == DECEL:
        return None
    # ACCEL: v^2 / (2 d) = p * accel / decel; RUN: the plan's own decel ramp from cruise (intervals sd .. L)
    m = p * plan.stop_ratio >> STOP_RATIO_FRAC if phase == ACCEL else length - plan.sd + 1
    if p + m >= length:  # the plan's own deceleration ends no later
        return None
    return m


def soft_stop_values(plan: Plan, p: int) -> list[int] | None:
    """Q32.32 values of intervals 1 .. p + m when a soft stop is decided at pulse p; None when it is ignored.

    Intervals 1 .. p are the plan's. D is the Q32.16 value of interval p + 1 in the plan (which exists: p + m < L
    with m >= 1): A_p (ACCEL, p + 1 < sa), c_sa (ACCEL, p + 1 = sa), cruise >> 16 (RUN; p + 1 < sd there). The
    reverse decel recurrence runs from D_m := D, remainder 0; interval p + j gets D_{m-j} (j = 1 .. m-1) and
    interval p + m gets c_last.
    """
    m = soft_stop_length(plan, p)
    if m is None:
        return None
    values = list(itertools.islice(interval_values(plan), p + 1))
    # D: Q32.16 (c_sa and A_p are Q32.16, so the shift is exact; cruise is truncated)
    d_val = values.pop() >> _SHIFT
    if m == 0:
        return values
    rem = 0
    for j in range(m, 1, -1):  # D_{j-1} from D_j
        q, rem = divmod(2 * d_val + rem, 4 * j - 1)
        d_val += q
        values.append(d_val << _SHIFT)
    values.append(plan.c_last << _SHIFT)
    return values


def _edges_of_values(plan: Plan, values: Iterable[int]) -> list[int]:
    """Edges of pulse 0 and of the pulse ending each interval value, through the fractional accumulator."""
    out = [FIRST_PULSE_LATENCY]
    t = 0
    acc = 0
    for value in values:
        s = acc + value
        t += s >> FRAC_CRUISE
        acc = s & _FRAC_MASK
        out.append(FIRST_PULSE_LATENCY + plan.prescale * t)
    return out


def soft_stop_pulse(plan: Plan, request_edge: int) -> int | None:
    """p, the pulse at which a soft stop sampled at request_edge is decided; None when the request is ignored.

    The request counts only while the engine is busy (edges 1 .. the last pulse's edge; edge 0, the start edge,
    is not busy). p is the first pulse whose edge is strictly after request_edge.
    """
    return _first_pulse_after(edges(plan), request_edge)


def _first_pulse_after(normal: list[int], request_edge: int) -> int | None:
    if request_edge < 1 or not normal or request_edge >= normal[-1]:
        return None
    return bisect.bisect_right(normal, request_edge)


def edges_with_stop(plan: Plan, kind: str, request_edge: int) -> list[int]:
    """Edges of the pulses the engine emits when a stop strobe is sampled '1' at request_edge (edge 0 = start).

    kind "hard": every pulse whose edge is before request_edge (a pulse due at request_edge itself is suppressed);
    at the start edge (0) the hard stop wins and nothing is emitted; after the move it changes nothing.
    kind "soft": see soft_stop_pulse and soft_stop_values; pulse 0 is the last when p = 0.
    """
    if kind not in (SOFT, HARD):
        raise ValueError(f"kind must be {SOFT!r} or {HARD!r}, got {kind!r}")
    normal = edges(plan)
    if kind == HARD:
        return normal if request_edge < 0 else normal[: bisect.bisect_left(normal, request_edge)]
    p = _first_pulse_after(normal, request_edge)
    values = None if p is None else soft_stop_values(plan, p)
    if values is None:
        return normal
    return _edges_of_values(plan, values)
