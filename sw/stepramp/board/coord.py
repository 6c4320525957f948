# SPDX-License-Identifier: MIT
"""Coordinated linear moves: several axes started on the same clock that accelerate, cruise and stop together.

docs/algorithm.md, "Coordinated moves". The path's accel, decel and speed are given for the lead axis (the one with
the most steps). Axis i covers L_i = |N_i| - 1 steps (an N-step move covers N - 1 steps: pulse k at position k,
pulse 0 at t = 0), so with r_i = L_i / L_lead and the accel, decel and speed scaled by r_i its ideal trajectory is
r_i times the lead's: the same trapezoid (or triangle) in time, every phase boundary and the end at the same
instant. Each axis is planned by plan_move with the scaled values (its checks and errors unchanged); then two of its
registers change so that its quantized last pulse lands on the tick nearest the ideal end, the same tick for every
axis:

* accel_seed loses the accel recurrence's mean truncation: the integer recurrence (remainder carried) runs about one
  Q32.16 LSB per value above the exact one (n - (P(1) + .. + P(n)) LSB over n values, _accel_bias), 2^-16 tick per
  step, which plan_move leaves (30 ticks after a ramp of 2,000,000 steps); spread over the values like the deficit;
* interval L (c_last, and c_first, c_sa, c_sd where they are interval L) is the time from the predicted pulse L - 1
  to the middle of that tick (0 to 1 tick after t_end; later only if an axis's last interval would otherwise be
  shorter than the move's shortest). The prediction (time_before_last) sums the plan's exact values and, in closed
  form, its recurrence values from their rounded seeds with the recurrences' mean truncation: within a few 0.01 tick
  of the model. So c_last also takes back the half decel deficit that plan_move leaves (its move ends 0.007 cd0
  early, and cd0 differs by axis) and every seed's rounding.

An axis of 1 step has its only pulse at t = 0 (it covers no distance: r = 0); it is planned with the path's
values and cannot end with the others. An axis of 0 steps emits nothing. The C driver computes the same plans bit for
bit (sw/c/stepramp_coord.c, sw/tests/test_c_coord.py).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

from stepramp.board.plan import (
    FRAC_CRUISE,
    FRAC_RAMP,
    MAX_STEPS,
    REG_WIDTHS,
    MoveInfo,
    Plan,
    _check_int,
    _to_fixed,
    check_motion_args,
    decel_product,
    plan_move_info,
)

MAX_AXES = 8
"""Most axes one coordinated move plans (the multi-axis top's count)."""
MAX_END_TICKS = 2.0**48
"""The longest path, in ticks, whose end the doubles place on a tick (a double below 2^48 resolves 1/16 tick): 32 days
at 100 MHz. A longer path is refused (a larger prescale makes fewer ticks of it)."""

_Q16 = float(1 << FRAC_RAMP)
_Q32 = float(1 << FRAC_CRUISE)


@dataclass(frozen=True)
class CoordInfo:
    """Informative values of a coordinated move (not registers)."""

    lead: int
    """Index of the lead axis: the first of the axes with the most steps."""
    ratios: tuple[float, ...]
    """r_i = L_i / L_lead for each axis (1.0 for the lead; 0.0 for an axis of 0 or 1 step, or when the lead has
    fewer than 2 steps): its accel, decel and speed are the path's times r_i."""
    infos: tuple[MoveInfo, ...]
    """Each axis's plan_move_info of its scaled values (before its last interval was set)."""
    t_end: float
    """The ideal end of the path, ticks from pulse 0 (the lead's trajectory; 0.0 when the lead has < 2 steps)."""
    end_tick: int
    """The tick on which every axis of 2 steps or more puts its last pulse: floor(t_end + 1/2), the tick nearest the
    ideal end (its middle is 0 to 1 tick after it, so that no last interval is shortened for it), or the first tick
    at which every axis's last interval is at least floor(min_interval) + 1/4, when that is later. Pulse N - 1 at edge
    FIRST_PULSE_LATENCY + prescale * end_tick when the prediction is right (docs/algorithm.md)."""
    last_intervals: tuple[float, ...]
    """Each axis's last interval before its rounding (ticks): end_tick + 1/2 minus time_before_last; 0.0 for an axis
    of fewer than 2 steps."""


def _accel_bias(n: int) -> float:
    """Mean amount (Q32.16 LSB) by which the accel recurrence's n values A_1 .. A_n exceed A_0 (P(1) + .. + P(n)).

    A_j = A_(j-1) - q_j, (4j + 1) q_j + r_j = 2 A_(j-1) + r_(j-1): A_j is the exact recurrence plus E_j with
    E_j = E_(j-1) (4j - 1) / (4j + 1) + (r_j - r_(j-1)) / (4j + 1). With the remainders uniform (mean 2 j, r_0 = 0)
    the mean of E_j is 1 - P(j), and the sum over j = 1 .. n is n - (P(1) + .. + P(n)): about one LSB per value.
    """
    return n - (2.0 * (n + 0.75) * decel_product(n) - 1.5)


def _decel_bias(m0: int) -> float:
    """Mean amount (Q32.16 LSB) by which the decel recurrence's values D_(m0-1) .. D_1 exceed D_m0 P(m) / P(m0).

    D_(m-1) = D_m + q, (4m - 1) q + r' = 2 D_m + r: the error grows as E_(m-1) = E_m (4m + 1) / (4m - 1) +
    (r - r') / (4m - 1). The first step (r = 0) loses (2 m0 - 1) / (4 m0 - 1) on average, every later one gains
    2 / (4m - 1); so E_m + 1 = 2 m0 / (4 m0 - 1) P(m) / P(m0 - 1), and the sum over m = 1 .. m0 - 1 is
    2 m0 / (4 m0 - 1) (2 (M + 3/4) - 3/2 / P(M)) - M with M = m0 - 1: about -sqrt(m0) LSB.
    """
    big_m = m0 - 1
    if big_m < 1:
        return 0.0
    return 2.0 * m0 / (4.0 * m0 - 1.0) * (2.0 * (big_m + 0.75) - 1.5 / decel_product(big_m)) - big_m


def time_before_last(plan: Plan) -> float:
    """The predicted time (ticks) from pulse 0 to pulse N - 2 of a plan: the sum of its interval values 1 .. L - 1
    (docs/algorithm.md, "Which value each interval gets"); 0.0 for fewer than 3 steps.

    c_first, c_sa, c_sd and the cruise intervals exactly (in doubles); the accel recurrence's values from accel_seed
    as A_0 (P(1) + .. + P(n)) plus _accel_bias(n), n = sa - 2, and the decel recurrence's from decel_seed as
    D_m0 (D_1 + .. + D_m0) / D_m0 plus _decel_bias(m0), m0 = L - sd - 1: closed forms, no recurrence is run. The
    engine's time of pulse N - 2 is the floor of the exact sum; this prediction is within a small fraction of a
    tick of it for ramps up to millions of steps (sw/tests/test_coord.py::test_time_before_last_predicts_the_model).
    """
    length = plan.steps - 1
    if length < 2:
        return 0.0
    sa, sd = plan.sa, plan.sd
    t = plan.c_first / _Q16
    if 1 < sa < length:
        t += plan.c_sa / _Q16
    if 1 < sd < length and sd != sa:
        t += plan.c_sd / _Q16
    n = sa - 2
    if n >= 1:  # intervals 2 .. sa - 1: A_1 .. A_n
        unit_a = 2.0 * (n + 0.75) * decel_product(n) - 1.5
        t += (plan.accel_seed * unit_a + _accel_bias(n)) / _Q16
    m0 = length - sd - 1
    if m0 >= 1:  # intervals sd + 1 .. L - 1: D_m0 .. D_1
        unit_d = 2.0 * (m0 + 0.75) - 1.5 / decel_product(m0)
        t += (plan.decel_seed * unit_d + _decel_bias(m0)) / _Q16
    cruise_count = sd - sa - 1
    if cruise_count >= 1:  # intervals sa + 1 .. sd - 1
        t += float(plan.cruise) * float(cruise_count) / _Q32
    return t


def ideal_end(info: MoveInfo) -> float:
    """The ideal trajectory's duration in ticks (stepramp.models.ideal.IdealMove.t_end * f_tick) from a MoveInfo;
    0.0 without an interval."""
    if info.length < 1:
        return 0.0
    t_a = info.v_peak / info.a
    t_d = t_a + (info.x_d - info.x_a) / info.v_peak
    return (t_d + info.v_peak / info.d) * info.f_tick


def seed_without_truncation(plan: Plan) -> int:
    """accel_seed less the accel recurrence's mean truncation spread over its n = sa - 2 values (Q32.16, rounded):
    round(_accel_bias(n) / (P(1) + .. + P(n))), about 0.68 sqrt(n) LSB, far below the seed (it is 0.676 c0 and
    c0 >= 2 sqrt(n) ticks); the seed itself without an accel recurrence (n < 1)."""
    n = plan.sa - 2
    if n < 1:
        return plan.accel_seed
    unit_a = 2.0 * (n + 0.75) * decel_product(n) - 1.5
    return plan.accel_seed - round(_accel_bias(n) / unit_a)


def _end_on(plan: Plan, info: MoveInfo, rest: float, target: float) -> tuple[Plan, float]:
    """The plan (2 steps or more, its seed already without the truncation) with its last interval set so that pulse
    N - 1 lies at `target` ticks (`rest`: its time_before_last), and that interval's value before rounding. Every
    register that holds interval L gets it (c_last; c_first when L = 1; c_sa, c_sd when sa, sd = L), as a plan's
    coinciding registers all hold the same value."""
    length = plan.steps - 1
    last = target - rest
    if not last >= math.floor(info.min_interval):  # not expected: the end tick leaves 1/4 tick (doubles err 1/16)
        raise ValueError(
            f"its last interval, set to end with the path, would be {last:.6g} ticks, shorter than the move's "
            f"shortest interval (floor({info.min_interval:.6g}) ticks)"
        )
    value = _to_fixed("c_last", last, FRAC_RAMP, REG_WIDTHS["c_last"])
    fields = {"c_last": value}
    if length == 1:
        fields["c_first"] = value
    if plan.sa == length:
        fields["c_sa"] = value
    if plan.sd == length:
        fields["c_sd"] = value
    return replace(plan, **fields), last


def _check_steps(steps: Sequence[int]) -> list[int]:
    if isinstance(steps, (str, bytes)) or not isinstance(steps, Sequence):
        raise ValueError(f"steps must be a sequence of step counts, one per axis, got {steps!r}")
    if len(steps) == 0:
        raise ValueError("no axes: a coordinated move needs at least one step count")
    if len(steps) > MAX_AXES:
        raise ValueError(f"{len(steps)} axes: at most {MAX_AXES} axes are coordinated")
    return list(steps)


def plan_coordinated_info(
    steps: Sequence[int],
    accel: float,
    decel: float,
    speed: float,
    spr: float,
    fclk: float,
    prescale: int = 1,
) -> tuple[list[Plan], CoordInfo]:
    """Like plan_coordinated, also returning the informative CoordInfo."""
    counts = _check_steps(steps)
    accel, decel, speed, spr, fclk, prescale = check_motion_args(accel, decel, speed, spr, fclk, prescale)
    for axis, value in enumerate(counts):
        counts[axis] = _check_int(f"axis {axis}: steps", value)
        if abs(counts[axis]) > MAX_STEPS:
            raise ValueError(f"axis {axis}: |steps| must be <= 2^31 - 1 = {MAX_STEPS}, got {counts[axis]}")
    if all(n == 0 for n in counts):
        raise ValueError("every axis has 0 steps: there is no move to coordinate")

    lengths = [abs(n) - 1 for n in counts]
    lead = lengths.index(max(lengths))
    lead_length = lengths[lead]
    plans: list[Plan] = []
    infos: list[MoveInfo] = []
    ratios: list[float] = []
    for axis, (n, length) in enumerate(zip(counts, lengths, strict=True)):
        # 0 and 1 step: no interval, no distance (r = 0 would be no move); planned with the path's values
        ratio = length / lead_length if length >= 1 else 0.0
        try:
            if ratio > 0.0:
                plan, info = plan_move_info(n, accel * ratio, decel * ratio, speed * ratio, spr, fclk, prescale)
            else:
                plan, info = plan_move_info(n, accel, decel, speed, spr, fclk, prescale)
        except ValueError as exc:
            raise ValueError(f"axis {axis} ({n} steps, accel, decel and speed times {ratio:.6g}): {exc}") from exc
        plans.append(plan)
        infos.append(info)
        ratios.append(ratio)

    # the accel recurrence's truncation out of each seed, then the time each axis needs before its last interval
    plans = [replace(plan, accel_seed=seed_without_truncation(plan)) if plan.steps >= 2 else plan for plan in plans]
    rests = [time_before_last(plan) if plan.steps >= 2 else 0.0 for plan in plans]
    # The end tick: the one nearest t_end, whose middle is 0 to 1 tick after it (every axis's floor lands on that tick
    # unless its prediction errs by 1/2 tick, and no last interval is shortened for it), or later when an axis's last
    # interval would otherwise be shorter than floor(min_interval) + 1/4 (a decel so steep that interval L is about
    # the cruise period, and the axis's quantized plan runs a fraction of a tick late): the same tick for every axis.
    t_end = ideal_end(infos[lead])
    if not t_end < MAX_END_TICKS:
        raise ValueError(
            f"the path lasts {t_end:.6g} ticks, 2^48 or more: too long to put the axes' ends on one tick; "
            "use a larger prescale"
        )
    end_tick = math.floor(t_end + 0.5)
    for plan, info, rest in zip(plans, infos, rests, strict=True):
        if plan.steps >= 2:
            end_tick = max(end_tick, math.ceil(rest + math.floor(info.min_interval) - 0.25))
    target = end_tick + 0.5
    lasts: list[float] = []
    for axis, (plan, info, rest) in enumerate(zip(plans, infos, rests, strict=True)):
        last = 0.0
        if plan.steps >= 2:
            try:
                plans[axis], last = _end_on(plan, info, rest, target)
            except ValueError as exc:
                raise ValueError(f"axis {axis} ({counts[axis]} steps): {exc}") from exc
        lasts.append(last)
    info = CoordInfo(lead, tuple(ratios), tuple(infos), t_end, end_tick, tuple(lasts))
    return plans, info


def plan_coordinated(
    steps: Sequence[int],
    accel: float,
    decel: float,
    speed: float,
    spr: float,
    fclk: float,
    prescale: int = 1,
) -> list[Plan]:
    """Plan a coordinated linear move: one Plan per axis, to be started on the same clock.

    steps: each axis's signed step count (1 .. MAX_AXES axes, not all 0); accel, decel in rad/s^2 and speed in rad/s
    are the lead axis's (the axis with the most steps), spr steps/rev and fclk Hz as in plan_move, shared by the
    axes. Every axis of 2 steps or more accelerates, cruises and decelerates with the lead (its accel, decel and
    speed are the path's times L_i / L_lead) and puts its last pulse on the same tick, the one nearest the ideal end;
    an axis of 1 step pulses once at the start, one of 0 steps not at all. Each plan is plan_move's of its scaled
    values but for accel_seed (less the recurrence's mean truncation) and interval L (ending on that tick).

    Raises ValueError with the reason for bad input (no axes, more than MAX_AXES, all 0 steps, a step count that is
    not an integer or too large, plan_move's reasons for an axis, naming the axis, a path of MAX_END_TICKS or more).
    """
    return plan_coordinated_info(steps, accel, decel, speed, spr, fclk, prescale)[0]
