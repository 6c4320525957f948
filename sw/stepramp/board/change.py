# SPDX-License-Identifier: MIT
"""Continuation segments: a change while moving as a new plan that takes over at a pulse.

docs/algorithm.md, "Changes while moving". The driver side: from the speed at the pulse P where the change takes
effect and the new accel, decel, speed and target, the segment's register values (the exact intervals and the
seeds, in doubles, each rounded once, as plan.py does for a move from rest).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

from stepramp.board.plan import (
    SEED_FACTOR,
    MoveInfo,
    _check_int,
    _cruise,
    _stop_ratio,
    _to_fixed,
    check_motion_args,
    decel_product,
    min_interval_clks,
    plan_move,
    steps_units,
)
from stepramp.models.exact import ramp_constant
from stepramp.spec import DOWN, FRAC_RAMP, MAX_STEPS, RAMP_AVR446, RAMP_EXACT, REG_WIDTHS, UP, Plan, Segment, check_ramp


@dataclass(frozen=True)
class Change:
    """What plan_change returns: the segment taken over at pulse P, the speed it starts at (steps/s, snapped to its
    head ramp) and, when the target lies inside the stop distance, the move from rest back to it (signed steps
    relative to the segment's direction: always negative), else None. pieces: the segment's ideal profile."""

    segment: Segment
    start_speed: float
    back: Plan | None
    #: The segment's ideal profile (the one its exact intervals come from, from the snapped start speed): pieces
    #: (x_start, x_end, s0, slope) in which the squared speed (steps/s)^2 is s0 + slope * x, x in steps from pulse P
    #: (speed_at_segment_pulse). The stop before a move back is one piece; empty for a segment of length 0.
    pieces: tuple[tuple[float, float, float, float], ...] = ()


def change_pulse(edges_so_far: list[int], commit_edge: int, lead_pulses: int = 2, lead_clocks: int = 400) -> int:
    """The pulse the driver names for a change committed at clock edge commit_edge (the issue's rule): the first
    pulse at least lead_pulses after the pulses emitted by then and at least lead_clocks after the commit. The
    running motion's edges must reach that far (edges_so_far)."""
    emitted = bisect.bisect_right(edges_so_far, commit_edge)
    k = max(emitted + lead_pulses - 1, bisect.bisect_left(edges_so_far, commit_edge + lead_clocks))
    if k >= len(edges_so_far):
        raise ValueError("the running motion ends before the change could take over")
    return k


def speed_at_pulse(info: MoveInfo, p: int) -> float:
    """Speed (steps/s) of a planned move's trapezoid at its pulse p (position p): the u of plan_change."""
    if info.length <= 0 or p <= 0 or p >= info.length:
        return 0.0
    x = float(p)
    if x <= info.x_a:
        return math.sqrt(2.0 * info.a * x)
    if x <= info.x_d:
        return info.v_peak
    return math.sqrt(2.0 * info.d * (info.length - x))


def speed_at_segment_pulse(change: Change, j: int) -> float:
    """Speed (steps/s) of a segment's ideal profile (Change.pieces) at its pulse j (j steps after pulse P): the u of
    a later plan_change that takes over in this segment; 0 at and after its end."""
    x = float(j)
    for x_start, x_end, s0, slope in change.pieces:
        if x_start <= x <= x_end:
            return math.sqrt(max(s0 + slope * x, 0.0))
    return 0.0


def _sum_products(lo: int, hi: int) -> float:
    """P(lo + 1) + .. + P(hi), P = decel_product: the sums telescope, S(n) = 2 (n + 3/4) P(n) - 3/2."""

    def s(n: int) -> float:
        return 2.0 * (n + 0.75) * decel_product(n) - 1.5

    return s(hi) - s(lo)


class _Profile:
    """The segment's exact trajectory in pieces where the squared speed is linear in the position x (counted from
    pulse P): s^2(x) = s0 + slope * x on [x_start, x_end]; interval i is the time from x = i - 1 to i."""

    def __init__(self, f_tick: float) -> None:
        self.f_tick = f_tick
        self.pieces: list[tuple[float, float, float, float]] = []

    def add(self, x_start: float, x_end: float, s0: float, slope: float) -> None:
        if x_end > x_start:
            self.pieces.append((x_start, x_end, s0, slope))

    def interval(self, i: int) -> float:
        """Exact interval i in ticks: 2 dx / (s(x1) + s(x2)) on each piece it overlaps (no cancellation)."""
        t = 0.0
        for x_start, x_end, s0, slope in self.pieces:
            x1, x2 = max(x_start, i - 1.0), min(x_end, float(i))
            if x2 > x1:
                s1 = math.sqrt(max(s0 + slope * x1, 0.0))
                s2 = math.sqrt(max(s0 + slope * x2, 0.0))
                t += 2.0 * (x2 - x1) / (s1 + s2)
        return t * self.f_tick


def plan_change(
    u: float,
    remaining: int | None,
    accel: float,
    decel: float,
    speed: float,
    spr: float,
    fclk: float,
    prescale: int = 1,
    ramp: int = RAMP_AVR446,
) -> Change:
    """The continuation from speed u (steps/s, >= 0) at pulse P with new accel, decel (rad/s^2) and speed (rad/s):
    to the target `remaining` steps ahead of P (>= 0), or endless (None: jog at `speed`), for the core's ramp
    arithmetic (plan.RAMP_AVR446 or RAMP_EXACT). Raises ValueError with the reason when the segment does not fit the
    engine."""
    ramp = check_ramp(ramp)
    accel, decel, speed, spr, fclk, prescale = check_motion_args(accel, decel, speed, spr, fclk, prescale)
    if isinstance(u, bool) or not isinstance(u, (int, float)) or not (math.isfinite(u) and u >= 0.0):
        raise ValueError(f"the speed at the change must be finite and >= 0, got {u!r}")
    if remaining is not None:
        remaining = _check_int("remaining", remaining)
        if not 0 <= remaining <= MAX_STEPS:
            raise ValueError(f"remaining must be in 0 .. 2^31 - 1 steps, got {remaining}")
    f_tick, a, d, v = steps_units(accel, decel, speed, spr, fclk, prescale, squares=True)
    ratio = _stop_ratio(accel, decel)
    # the decel ramp's index at u: rest k steps ahead (floored)
    k = _steps("the stop distance from the speed at the change", u * u / (2.0 * d))
    if remaining is not None and remaining < k:
        # The target is inside the stop distance (or behind the motor): to rest k steps ahead, then back from rest.
        try:
            back = plan_move(-(k - remaining), accel, decel, speed, spr, fclk, prescale, ramp)
        except ValueError as err:
            raise ValueError(f"the target lies {k - remaining} steps behind the stop; the move back: {err}") from err
        stop = ((0.0, float(k), 2.0 * d * k, -2.0 * d),) if k >= 1 else ()
        return Change(_stop_segment(k, d, f_tick, prescale, ratio, ramp), math.sqrt(2.0 * d * k), back, stop)
    if remaining == 0:
        return Change(_stop_segment(0, d, f_tick, prescale, ratio, ramp), 0.0, None)

    positioning = remaining is not None
    end = float(remaining) if remaining is not None else math.inf
    cap2 = 2.0 * d * end  # the fastest start that still stops at the target
    profile = _Profile(f_tick)
    head, index, x_h = UP, 0, 0.0
    if u < v:
        x0 = u * u / (2.0 * a)
        n0 = round(x0) if x0 < 2.0**31 else 1 << 31
        if n0 >= 1 << 31:
            raise ValueError(f"the accel ramp's index at the speed at the change, {x0:.6g}, does not fit 31 bits")
        cap = cap2 / (2.0 * a)
        if positioning and cap < n0:  # (an infinite cap is none)
            n0 = math.floor(cap)
        start2 = 2.0 * a * n0
        peak2 = min(v * v, 2.0 * a * d * (end + n0) / (a + d)) if positioning else v * v
        if start2 < peak2:  # the head: the accel ramp of a virtual move from rest n0 steps behind P
            index, x_h = n0, (peak2 - start2) / (2.0 * a)
            profile.add(0.0, x_h, start2, 2.0 * a)
        else:  # the snap reaches the speed: cruise from interval 1
            start2 = peak2 = min(v * v, cap2)
    else:
        start2, peak2 = 2.0 * d * k, v * v
        if start2 > peak2:  # the head: the decel ramp towards a virtual rest k steps ahead, down to v
            head, index, x_h = DOWN, k, (start2 - peak2) / (2.0 * d)
            profile.add(0.0, x_h, start2, -2.0 * d)
        else:  # the snap is at or below the speed: cruise at v from interval 1
            start2 = peak2 = min(v * v, cap2)
    x_c = end - peak2 / (2.0 * d)
    profile.add(x_h, x_c, peak2, 0.0)
    if positioning:
        profile.add(x_c, end, cap2, -2.0 * d)
    v_peak = math.sqrt(peak2)
    _check_speed(f_tick, max(v_peak, math.sqrt(start2)), prescale, ramp, a, d)
    if v_peak == 0.0:
        raise ValueError("cruise overflows its register: the cruise speed is 0 in doubles; use a larger accel or decel")

    last = remaining if remaining is not None else MAX_STEPS

    def boundary(x: float) -> int:
        return min(max(math.floor(min(x, last)) + 1, 1), last)

    sa = boundary(x_h)
    # sa <= sd, as the engine's BOUNDS check needs: in a triangle x_h and x_c meet, and rounding may put x_h past x_c
    sd = max(boundary(x_c), sa) if positioning else 0
    t_first = profile.interval(1)
    n = sa - 2  # the head's recurrence intervals 2 .. sa - 1
    if ramp == RAMP_EXACT:  # the head's ramp constant (a down head decelerates at d); no deficit to put back
        seed = 0.0
        head_constant = ramp_constant(f_tick * math.sqrt(2.0 / (a if head == UP else d)))
    elif head == UP:
        c0 = f_tick * math.sqrt(2.0 / a)
        seed = SEED_FACTOR * c0 * decel_product(index)
        if n >= 1:  # A_{n0+1} .. A_{n0+n} against the ideal from virtual position n0 + 1 to n0 + n + 1
            unit = _sum_products(index, index + n) / decel_product(index)
            half = (c0 * (math.sqrt(index + n + 1.0) - math.sqrt(index + 1.0)) - seed * unit) / 2.0
            # the integer recurrence's mean truncation from index n0 with r = 0 (plan.accel_truncation for n0 = 0)
            trunc = n - (2.0 * index + 3.0) / (4.0 * index + 3.0) * unit
            t_first, seed = t_first + half, seed + half / unit - trunc / unit / (1 << FRAC_RAMP)
    else:
        cd0 = f_tick * math.sqrt(2.0 / d)
        seed = SEED_FACTOR * cd0 * decel_product(max(index - 2, 0))
        if n >= 1:  # D_{K-2} .. D_{K-1-n} against the ideal from K - 1 to K - 1 - n steps before the virtual rest
            unit = _sum_products(index - 2 - n, index - 2) / decel_product(index - 2)
            half = (cd0 * (math.sqrt(index - 1.0) - math.sqrt(index - 1.0 - n)) - seed * unit) / 2.0
            t_first, seed = t_first + half, seed + half / unit
    return Change(
        Segment(
            length=remaining,
            prescale=prescale,
            sa=sa,
            sd=sd,
            accel_seed=head_constant
            if ramp == RAMP_EXACT
            else _to_fixed("accel_seed", seed, FRAC_RAMP, REG_WIDTHS["c_first"]),
            cruise=_cruise(f_tick, v_peak),
            stop_ratio=ratio,
            head=head,
            head_index=index,
            # a soft stop in the cruise of a jog: v^2 / (2 d) rounded up, the L - sd + 1 a move would take
            run_stop=_steps("the stop from the jog speed", peak2 / (2.0 * d), up=True) if remaining is None else 0,
            ramp=ramp,
            **_fields(profile, remaining, sa, sd, d, f_tick, t_first, ramp, peak2),
        ),
        math.sqrt(start2),
        None,
        tuple(profile.pieces),
    )


def _fields(
    profile: _Profile,
    length: int | None,
    sa: int,
    sd: int,
    d: float,
    f_tick: float,
    t_first: float,
    ramp: int = RAMP_AVR446,
    peak2: float = 0.0,
) -> dict[str, int]:
    """c_first, c_last, c_sa, c_sd and decel_seed (the final ramp's, with half its deficit put back as in a move; in
    exact mode its ramp constant, which a soft stop needs even where the segment has no final ramp)."""
    w48 = REG_WIDTHS["c_first"]
    out = {"c_first": 0, "c_last": 0, "c_sa": 0, "c_sd": 0, "decel_seed": 0}
    if length is not None and length < 1:
        return out
    cd0 = f_tick * math.sqrt(2.0 / d)
    out["c_first"] = _to_fixed("c_first", t_first, FRAC_RAMP, w48)
    out["c_sa"] = _to_fixed("c_sa", profile.interval(sa), FRAC_RAMP, w48)
    if ramp == RAMP_EXACT:
        out["decel_seed"] = ramp_constant(cd0)
    if length is None:  # c_last: the last step of a soft stop, the exact last step of a decel at d (cd0)
        out["c_last"] = _to_fixed("c_last", cd0, FRAC_RAMP, w48)
        if ramp == RAMP_EXACT:  # c_sd: the first interval of a stop in the cruise (cruise, then decel to rest)
            out["c_sd"] = _to_fixed("c_sd", _run_stop_first(peak2, d, f_tick), FRAC_RAMP, w48)
        return out
    out["c_last"] = _to_fixed("c_last", profile.interval(length), FRAC_RAMP, w48)
    out["c_sd"] = _to_fixed("c_sd", profile.interval(sd), FRAC_RAMP, w48)
    m0 = length - sd - 1
    if m0 >= 1 and ramp == RAMP_AVR446:
        cd0 = f_tick * math.sqrt(2.0 / d)
        seed_d = SEED_FACTOR * cd0 * decel_product(m0)
        unit_d = 2.0 * (m0 + 0.75) - 1.5 / decel_product(m0)
        seed_d += (cd0 * (math.sqrt(m0 + 1.0) - 1.0) - seed_d * unit_d) / 2.0 / unit_d
        out["decel_seed"] = _to_fixed("decel_seed", seed_d, FRAC_RAMP, w48)
    return out


def _run_stop_first(peak2: float, d: float, f_tick: float) -> float:
    """Interval 1 of an exact-mode soft stop in a jog's cruise at v = sqrt(peak2): m = ceil(v^2 / (2 d)) steps, the
    cruise goes on for m - v^2 / (2 d) of a step, then the decel at d comes to rest at step m (ticks)."""
    n_d = peak2 / (2.0 * d)
    m = _steps("the stop from the jog speed", n_d, up=True)
    profile = _Profile(f_tick)
    profile.add(0.0, m - n_d, peak2, 0.0)
    profile.add(m - n_d, float(m), 2.0 * d * m, -2.0 * d)  # the squared speed s0 + slope x is 0 at x = m
    return profile.interval(1)


def _stop_segment(k: int, d: float, f_tick: float, prescale: int, ratio: int, ramp: int = RAMP_AVR446) -> Segment:
    """A decel at d to rest k steps ahead: no head, the decel ramp of a move (sa = sd = 1)."""
    profile = _Profile(f_tick)
    profile.add(0.0, float(k), 2.0 * d * k, -2.0 * d)
    seg = _fields(profile, k, 1, 1, d, f_tick, profile.interval(1) if k >= 1 else 0.0, ramp)
    return Segment(
        length=k,
        prescale=prescale,
        sa=1 if k >= 1 else 0,
        sd=1 if k >= 1 else 0,
        accel_seed=0,
        cruise=0,
        stop_ratio=ratio,
        head=UP,
        head_index=0,
        ramp=ramp,
        **seg,
    )


def _steps(what: str, x: float, up: bool = False) -> int:
    """floor(x) (ceil with up) as a step count below 2^31, or ValueError with `what` it is."""
    if not x < 2.0**31:
        raise ValueError(f"{what} is {x:.6g} steps: more than 2^31 - 1")
    return math.ceil(x) if up else math.floor(x)


def _check_speed(
    f_tick: float, fastest: float, prescale: int, ramp: int = RAMP_AVR446, a: float = 1.0, d: float = 1.0
) -> None:
    """The segment's shortest interval must leave the engine its MIN_INTERVAL_CLKS (MIN_INTERVAL_CLKS_EXACT in exact
    mode, _WIDE when the ramp constant of a or d is 2^48 or more), as plan.py checks a move."""
    shortest = f_tick / fastest if fastest > 0.0 else math.inf
    least = min_interval_clks(ramp, f_tick * math.sqrt(2.0 / a), f_tick * math.sqrt(2.0 / d))
    if not shortest >= 1.0 or (math.isfinite(shortest) and math.floor(shortest) * prescale < least):
        raise ValueError(
            f"speed too high for the hardware to compute the next delay in time: shortest interval "
            f"floor({shortest:.6g}) ticks * prescale {prescale} < {least} clocks"
        )
