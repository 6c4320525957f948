# SPDX-License-Identifier: MIT
"""Bit-exact integer model of the ramp engine (docs/algorithm.md, followed literally).

The RTL is compared edge for edge with :func:`edges`.
"""

from __future__ import annotations

from collections.abc import Iterator

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
