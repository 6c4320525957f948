# SPDX-License-Identifier: MIT
"""Coordinated linear moves: several axes started on the same clock that accelerate, cruise and stop together.

docs/algorithm.md, "Coordinated moves". The path's accel, decel and speed are given for the lead axis (the one with
the most steps). Axis i covers L_i = |N_i| - 1 steps (an N-step move covers N - 1 steps: pulse k at position k,
pulse 0 at t = 0), so with r_i = L_i / L_lead and the accel, decel and speed scaled by r_i its ideal trajectory is
r_i times the lead's: the same trapezoid (or triangle) in time, every phase boundary and the end at the same
instant. Each axis is planned by plan_move with the scaled values (its checks and errors unchanged; its accel_seed
already without the accel recurrence's mean truncation, plan.accel_truncation); then one of its registers changes so
that its quantized last pulse lands on the tick nearest the ideal end, the same tick for every axis:

* interval L (c_last, and c_first, c_sa, c_sd where they are interval L) is the time from the predicted pulse L - 1
  to the middle of that tick (0 to 1 tick after t_end; later only if an axis's last interval would otherwise be
  shorter than the move's shortest). The prediction (time_before_last) sums the plan's exact values and, in closed
  form, its recurrence values from their rounded seeds with the recurrences' mean truncation: within a few 0.01 tick
  of the model. So c_last also takes back the half decel deficit that plan_move leaves (its move ends 0.007 cd0
  early, and cd0 differs by axis) and every seed's rounding.

An axis of 1 step has its only pulse at t = 0 (it covers no distance: r = 0); it is planned with the path's
values and cannot end with the others. An axis of 0 steps emits nothing. The C driver computes the same plans bit for
bit (sw/c/src/stepramp_coord.c, sw/tests/test_c_coord.py).
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

from stepramp.board.change import Change, plan_change, speed_at_pulse
from stepramp.board.plan import (
    FRAC_CRUISE,
    FRAC_RAMP,
    MAX_STEPS,
    REG_WIDTHS,
    MoveInfo,
    Plan,
    _check_int,
    _to_fixed,
    accel_truncation,
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
    as A_0 (P(1) + .. + P(n)) plus accel_truncation(n), n = sa - 2, and the decel recurrence's from decel_seed as
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
        t += (plan.accel_seed * unit_a + accel_truncation(n)) / _Q16
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


def _end_on(plan: Plan, info: MoveInfo, rest: float, target: float) -> tuple[Plan, float]:
    """The plan (2 steps or more) with its last interval set so that pulse N - 1 lies at `target` ticks (`rest`: its
    time_before_last), and that interval's value before rounding. Every register that holds interval L gets it
    (c_last; c_first when L = 1; c_sa, c_sd when sa, sd = L), as a plan's coinciding registers all hold the same
    value."""
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

    # the time each axis needs before its last interval (plan_move's seeds are already without the truncation)
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
    values but for interval L (ending on that tick).

    Raises ValueError with the reason for bad input (no axes, more than MAX_AXES, all 0 steps, a step count that is
    not an integer or too large, plan_move's reasons for an axis, naming the axis, a path of MAX_END_TICKS or more).
    """
    return plan_coordinated_info(steps, accel, decel, speed, spr, fclk, prescale)[0]


STOP_MARGIN = 2
"""Clocks after a commit within which pulse P - 1 must not fall (the script planner's MARGIN): the take-over pulse
moves one on when it would."""


@dataclass(frozen=True)
class AxisStop:
    """One axis of a coordinated stop on the line (plan_coordinated_stop). pulse: the take-over pulse P_i (0: the axis
    takes no CHANGE, it ends on its target or is not moving); speed: u_i (steps/s) at P_i; natural: N_i, its nearest
    rest decelerating at its coordinated decel from P_i (its target when it cannot take over); target: T_i, the pulse
    it rests on; change: the segment taken over at P_i (None: no CHANGE)."""

    pulse: int
    speed: float
    natural: int
    target: int
    change: Change | None


@dataclass(frozen=True)
class CoordStop:
    """A coordinated stop on the line: the lead's rest R_L (a pulse of the lead), each axis's AxisStop, and the
    fallback's reason when the stop cannot be made by take-overs (then SYNC_SOFT_STOP of the moving axes is the
    driver's stop; None otherwise)."""

    rest: int
    axes: tuple[AxisStop, ...]
    fallback: str | None = None

    @property
    def changes(self) -> list[int]:
        """The axes that take a CHANGE."""
        return [i for i, axis in enumerate(self.axes) if axis.change is not None]


def _take_over_pulse(edges: Sequence[int], commit: int) -> int | None:
    """change_pulse's pulse for a commit at `commit` (None when the motion ends first), one later when pulse P - 1
    would fall within STOP_MARGIN clocks of the commit."""
    emitted = bisect.bisect_right(edges, commit)
    k = max(emitted + 1, bisect.bisect_left(edges, commit + 400))
    if k < len(edges) and edges[k - 1] <= commit + STOP_MARGIN:
        k += 1
    return k if k < len(edges) else None


def coordinated_stop_pulses(
    plans: Sequence[Plan], edges: Sequence[Sequence[int]], commits: int | Sequence[int]
) -> list[int]:
    """Each axis's take-over pulse for a coordinated stop: change_pulse(edges[i], W_i) (one later when pulse P - 1
    would fall within STOP_MARGIN clocks of W_i), 0 for an axis that takes none (fewer than 2 steps, or its motion
    ends within the lead). edges[i]: axis i's STEP edges, all of its plan's, on the clock axis of the commits;
    commits: W_i, one edge for all or one per axis."""
    n = len(plans)
    at = [commits] * n if isinstance(commits, int) else list(commits)
    if len(edges) != n or len(at) != n:
        raise ValueError(f"{n} plans, {len(edges)} edge lists and {len(at)} commit edges")
    return [_take_over_pulse(edges[i], at[i]) or 0 if plans[i].steps >= 2 else 0 for i in range(n)]


def plan_coordinated_stop(
    plans: Sequence[Plan],
    info: CoordInfo,
    edges: Sequence[Sequence[int]],
    commits: int | Sequence[int],
    accel: float,
    decel: float,
    speed: float,
    spr: float,
    fclk: float,
    prescale: int = 1,
) -> CoordStop:
    """The take-overs that stop a running coordinated move on the line (docs/algorithm.md, "Coordinated moves": the
    coordinated stop on the line): coordinated_stop_pulses, then plan_coordinated_stop_at. plans, info:
    plan_coordinated_info's for accel, decel, speed (the path's, rad/s^2 and rad/s), spr, fclk, prescale; edges[i]:
    axis i's STEP edges (all of its plan's, on the clock axis of the commits); commits: the edge W_i at which axis
    i's CTRL.CHANGE is committed (one for all, or one per axis)."""
    pulses = coordinated_stop_pulses(plans, edges, commits)
    return plan_coordinated_stop_at(plans, info, pulses, accel, decel, speed, spr, fclk, prescale)


def plan_coordinated_stop_at(
    plans: Sequence[Plan],
    info: CoordInfo,
    pulses: Sequence[int],
    accel: float,
    decel: float,
    speed: float,
    spr: float,
    fclk: float,
    prescale: int = 1,
) -> CoordStop:
    """The coordinated stop on the line from each axis's take-over pulse P_i (0: none; stepramp_plan_coordinated_stop
    in C, bit-identical). u_i = speed_at_pulse of its move at P_i; N_i = P_i + ceil(u_i^2 / (2 d_i));
    R_L = min(L_lead, max_i ceil(N_i L_lead / L_i)); T_i = floor((2 L_i R_L + L_lead) / (2 L_lead)) (round halves
    up); the segment is plan_change(u_i, T_i - P_i, a_i, d_i, v_i). An axis that takes no CHANGE (P_i = 0, or
    P_i >= L_i) ends on its target L_i, which R_L then respects (R_L >= ceil((2 L_i - 1) L_lead / (2 L_i))). No
    CHANGE where T_i = L_i. A plan_change that raises: CoordStop.fallback names the axis and its reason."""
    n = len(plans)
    if len(pulses) != n or len(info.ratios) != n:
        raise ValueError(f"{n} plans, {len(pulses)} pulses, {len(info.ratios)} ratios")
    lead_len = plans[info.lead].steps - 1
    moving = [i for i in range(n) if plans[i].steps >= 2 and lead_len >= 1]
    speeds = [0.0] * n
    naturals = [0] * n
    need = 0
    for i in moving:
        length = plans[i].steps - 1
        pulse = pulses[i]
        if pulse <= 0 or pulse >= length:
            naturals[i] = length
            need = max(need, -(-((2 * length - 1) * lead_len) // (2 * length)))
            continue
        move = info.infos[i]
        u = speed_at_pulse(move, pulse)
        stop = min(math.ceil(u * u / (2.0 * move.d)), 1 << 40)
        speeds[i], naturals[i] = u, pulse + stop
        need = max(need, -(-(naturals[i] * lead_len) // length))
    rest = min(lead_len, need)
    out: list[AxisStop] = []
    for i in range(n):
        if i not in moving:
            out.append(AxisStop(0, 0.0, 0, max(plans[i].steps - 1, 0), None))
            continue
        length = plans[i].steps - 1
        target = (2 * length * rest + lead_len) // (2 * lead_len)
        pulse = pulses[i] if 0 < pulses[i] < length else 0
        if pulse == 0 or target >= length:
            out.append(AxisStop(pulse, speeds[i], naturals[i], length, None))
            continue
        ratio = info.ratios[i]
        try:
            change = plan_change(
                speeds[i],
                target - pulse,
                accel * ratio,
                decel * ratio,
                speed * ratio,
                spr,
                fclk,
                prescale,
                plans[i].ramp,
            )
        except ValueError as err:
            return CoordStop(rest, tuple(out), f"axis {i}: {err}")
        if change.back is not None:  # (T_i >= N_i: not expected)
            return CoordStop(rest, tuple(out), f"axis {i}: its take-over would need a move back")
        out.append(AxisStop(pulse, speeds[i], naturals[i], target, change))
    return CoordStop(rest, tuple(out))
