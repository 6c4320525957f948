# SPDX-License-Identifier: MIT
"""Continuation segments (docs/algorithm.md, "Changes while moving"): the driver's segments through the bit-exact
model, judged by the ideal motion after the change (stepramp.models.ideal.IdealSegment), not by themselves.

Random cases print their seed (STEPRAMP_SEED replays one); the bound is that of a move from rest.
"""

from __future__ import annotations

import bisect
import math
import os
import random
from dataclasses import dataclass

import pytest

from stepramp.board.change import DOWN, UP, Change, Segment, change_pulse, plan_change, speed_at_pulse
from stepramp.board.plan import FRAC_CRUISE, MIN_INTERVAL_CLKS, plan_move, plan_move_info
from stepramp.models import ideal
from stepramp.models.engine import (
    accumulate,
    change_edges,
    segment_stop_length,
    segment_stop_values,
    segment_ticks,
    segment_values,
    soft_stop_values,
)
from stepramp.models.engine import edges as model_edges
from stepramp.sim.profiles import PROFILES

BOUND_C0 = 0.008  # units of c0 of the slower ramp (a or d), as sw/tests/test_model.py holds a move
BOUND_TICKS = 2.0
# A soft stop in a down head continues its recurrence to rest without the decel deficit put back (0.014 c0 near
# rest, docs/algorithm.md "Recurrence deficit"); a soft stop in a move is not held to the pulse bound at all.
STOP_BOUND_C0 = 0.016
SEED = int(os.environ.get("STEPRAMP_SEED", "20261126"))


@dataclass(frozen=True)
class Case:
    """A change in physical units: speed u (steps/s) at the change, the distance, and plan_change's other arguments
    (accel, decel, speed, spr, fclk, prescale)."""

    u: float
    remaining: int | None
    args: dict[str, float]

    @classmethod
    def of(cls, u: float, remaining: int | None, *rest: float) -> Case:
        names = ("accel", "decel", "speed", "spr", "fclk", "prescale")
        return cls(u, remaining, {"prescale": 1, **dict(zip(names, rest, strict=False))})

    @property
    def accel(self) -> float:
        return self.args["accel"]

    @property
    def decel(self) -> float:
        return self.args["decel"]

    @property
    def speed(self) -> float:
        return self.args["speed"]

    @property
    def alpha(self) -> float:
        return 2.0 * math.pi / self.args["spr"]

    @property
    def f_tick(self) -> float:
        return self.args["fclk"] / self.args["prescale"]

    def plan(self) -> Change:
        return plan_change(self.u, self.remaining, **self.args)


def _kind(change: Change) -> str:
    seg = change.segment
    kind = "stop" if change.back is not None else seg.head
    return kind if seg.length is not None else f"{kind}-jog"


def _check(case: Case) -> tuple[str, float]:
    """Every pulse of the segment within the bound of the ideal from the snapped start speed; returns (kind, worst
    error in c0 of the slower ramp)."""
    change = case.plan()
    seg = change.segment
    a, d, v = case.accel / case.alpha, case.decel / case.alpha, case.speed / case.alpha
    count = seg.length if seg.length is not None else seg.sa + 400
    ticks = segment_ticks(seg, count)
    judge = ideal.IdealSegment(change.start_speed, a, d, v, seg.length, case.f_tick).pulse_times(count)
    c0_slow = case.f_tick * math.sqrt(2.0 / min(a, d))
    errors = [abs(t - x) for t, x in zip(ticks, judge, strict=True)]
    worst = max(errors)
    assert worst <= BOUND_C0 * c0_slow + BOUND_TICKS, (
        f"{case}: pulse {errors.index(worst)} is {worst:.2f} ticks off the ideal ({worst / c0_slow:.5f} c0)"
    )
    return _kind(change), worst / c0_slow


def _random_case(rng: random.Random) -> Case | None:
    spr = rng.choice([200.0, 400.0, 1600.0, 3200.0])
    fclk = rng.choice([1e6, 2e6, 10e6])
    accel, decel = rng.uniform(5.0, 500.0), rng.uniform(5.0, 500.0)
    speed = rng.uniform(2.0, 60.0)
    alpha = 2.0 * math.pi / spr
    v = speed / alpha
    u = rng.uniform(0.0, 1.5) * v * rng.choice([0, 1, 1, 1])
    if fclk / max(v, u) < 80.0:  # faster than the engine allows (64 clocks): not a case the driver plans
        return None
    return Case.of(u, rng.choice([None, rng.randint(0, 3000)]), accel, decel, speed, spr, fclk)


def test_the_judge_from_rest_is_the_ideal_move() -> None:
    # IdealSegment with u = 0 is the ideal trapezoid / triangle of stepramp.models.ideal, written differently.
    for length, v in ((1000, 40.0), (1000, 400.0), (37, 5.0)):
        move = ideal.IdealMove(length, 300.0, 120.0, v, 1e6, *_shape(length, 300.0, 120.0, v))
        seg = ideal.IdealSegment(0.0, 300.0, 120.0, v, length, 1e6)
        for k in range(length + 1):
            assert seg.time_at(k) == pytest.approx(move.time_at(k), rel=1e-9, abs=1e-6)


def _shape(length: int, a: float, d: float, v: float) -> tuple[float, float, float, bool]:
    n_a, n_d = v * v / (2 * a), v * v / (2 * d)
    if n_a + n_d <= length:
        return n_a, length - n_d, v, False
    x_p = length * d / (a + d)
    return x_p, x_p, math.sqrt(2 * a * x_p), True


def test_positioning_segments_keep_the_engine_bounds() -> None:
    # The engine refuses (BOUNDS) a segment with sa < 1, sd < sa or sd > L (docs/registers.md, STATUS.ERR_CODE): a
    # change in the final decel of a move to a farther target at the same speed gave sa = 31 > sd = 30 (a triangle whose
    # x_h rounds past x_c); and 2,000 random changes.
    cases = [Case.of(718.0961047225787, 87, 300.0, 300.0, 60.0, 200.0, 1e6)]
    rng = random.Random(SEED)
    while len(cases) < 2000:
        case = _random_case(rng)
        if case is not None and case.remaining:
            cases.append(case)
    for case in cases:
        seg = plan_change(case.u, case.remaining, **case.args).segment
        if seg.length is not None and seg.length >= 1:
            assert 1 <= seg.sa <= seg.sd <= seg.length, f"{case}: {seg}"


def test_random_segments_against_physics() -> None:
    rng = random.Random(SEED)
    print(f"seed {SEED} (STEPRAMP_SEED={SEED} replays it)")
    kinds: dict[str, int] = {}
    worst = 0.0
    checked = 0
    while checked < 400:
        case = _random_case(rng)
        if case is None:
            continue
        kind, err = _check(case)
        kinds[kind] = kinds.get(kind, 0) + 1
        worst = max(worst, err)
        checked += 1
    print(f"400 segments, worst {worst:.5f} c0, kinds {sorted(kinds.items())}")
    assert set(kinds) == {"up", "down", "stop", "up-jog", "down-jog"}, kinds


@pytest.mark.parametrize("profile", [p for p in PROFILES if abs(p.steps) > 8][:24:3], ids=lambda p: p.name)
def test_changes_from_every_phase_of_a_move(profile) -> None:  # type: ignore[no-untyped-def]
    """From pulses in ACCEL, RUN and DECEL of a planned move: faster, slower, a nearer and a farther target, a target
    behind the motor. The start is within one step of the new ramp of the speed at the pulse, the motion never
    faster than the commanded speed or the speed at the change, and it ends exactly on the target."""
    args = profile.args()
    _, info = plan_move_info(**args)
    alpha = 2.0 * math.pi / args["spr"]
    checked = 0
    for p in sorted({1, info.length // 5, info.length // 2, (4 * info.length) // 5, info.length - 2}):
        u = speed_at_pulse(info, p)
        left = info.length - p
        for speed_factor, accel_factor, target in (
            (1.5, 1.0, left),
            (0.5, 2.0, left),
            (1.0, 0.5, left + 500),
            (0.8, 1.0, left // 3),
            (1.0, 1.0, 0),
        ):
            new_speed = args["speed"] * speed_factor
            if math.floor(args["fclk"] / args["prescale"] / (new_speed / alpha)) * args["prescale"] < MIN_INTERVAL_CLKS:
                continue  # faster than the engine allows: plan_change refuses it (test_bad_changes_raise_...)
            case = Case.of(
                u, target, args["accel"] * accel_factor, args["decel"], new_speed, args["spr"], args["fclk"],
                args["prescale"],
            )  # fmt: skip
            change = case.plan()
            a, d = case.accel / alpha, case.decel / alpha
            seg = change.segment
            step2 = 2.0 * max(a, d)  # one step of a ramp, in squared speed
            assert abs(change.start_speed**2 - u * u) <= step2 * (1 + 1e-9), (profile.name, p, change.start_speed, u)
            _check(case)
            fastest = max(new_speed / alpha, change.start_speed)
            shortest = min(segment_values(seg, seg.length or 0), default=1 << 80) / (1 << FRAC_CRUISE)
            assert shortest >= case.f_tick / fastest * (1 - 1e-3), (profile.name, p, shortest, case.f_tick / fastest)
            back = 0 if change.back is None else change.back.steps
            assert (seg.length or 0) - back == target, (profile.name, p, seg.length, back, target)
            assert change.back is None or change.back.direction == 1
            checked += 1
    assert checked >= 10, f"{profile.name}: only {checked} changes fit the engine's speed limit"


def test_named_changes() -> None:
    """Speed up and slow down in RUN, a retarget inside the stop distance and one behind the motor, jog from rest."""
    spr, fclk, accel, decel, speed = 400.0, 1e6, 100.0, 80.0, 20.0
    alpha = 2.0 * math.pi / spr
    v = speed / alpha
    faster = Case.of(v, 4000, accel, decel, 2 * speed, spr, fclk).plan()
    assert faster.segment.head == UP and faster.segment.head_index == round(v * v / (2 * accel / alpha))
    slower = Case.of(v, 4000, accel, decel, speed / 2, spr, fclk).plan()
    assert slower.segment.head == DOWN and slower.segment.head_index == math.floor(v * v / (2 * decel / alpha))
    stop_distance = v * v / (2 * decel / alpha)
    inside = Case.of(v, int(stop_distance) - 50, accel, decel, speed, spr, fclk).plan()
    assert inside.back is not None and inside.segment.length == math.floor(stop_distance)
    assert inside.segment.length - inside.back.steps == int(stop_distance) - 50
    behind = Case.of(v, 0, accel, decel, speed, spr, fclk).plan()
    assert behind.back is not None and behind.back.steps == behind.segment.length
    jog = Case.of(0.0, None, accel, decel, speed, spr, fclk).plan()
    assert jog.segment.length is None and jog.segment.head_index == 0 and jog.start_speed == 0.0
    for case in (
        Case.of(v, 4000, accel, decel, 2 * speed, spr, fclk),
        Case.of(v, 4000, accel, decel, speed / 2, spr, fclk),
        Case.of(v, int(stop_distance) - 50, accel, decel, speed, spr, fclk),
        Case.of(0.0, None, accel, decel, speed, spr, fclk),
        Case.of(v, None, accel, decel, speed / 4, spr, fclk),
    ):
        _check(case)


def test_speed_at_pulse_is_the_trapezoid() -> None:
    for profile in PROFILES[:12]:
        args = profile.args()
        _, info = plan_move_info(**args)
        move = ideal.ideal_move(args["steps"], args["accel"], args["decel"], args["speed"], args["spr"], args["fclk"])
        for p in range(0, info.length + 1, max(info.length // 17, 1)):
            assert speed_at_pulse(info, p) == pytest.approx(move.speed_at(p), rel=1e-12, abs=1e-12), (profile.name, p)


@pytest.mark.parametrize(
    ("kwargs", "reason"),
    [
        ({"u": -1.0}, "speed at the change"),
        ({"u": math.nan}, "speed at the change"),
        ({"remaining": -1}, "remaining"),
        ({"accel": 0.0}, "accel"),
        ({"speed": 1e9, "remaining": None}, "too high"),
        ({"prescale": 0}, "prescale"),
    ],
)
def test_bad_changes_raise_with_the_reason(kwargs: dict[str, float | None], reason: str) -> None:
    base: dict[str, float | int | None] = {
        "u": 10.0, "remaining": 100, "accel": 50.0, "decel": 50.0, "speed": 10.0, "spr": 400.0, "fclk": 1e6,
        "prescale": 1,
    }  # fmt: skip
    base.update(kwargs)
    with pytest.raises(ValueError, match=reason):
        plan_change(**base)  # type: ignore[arg-type]


def test_a_soft_stop_in_a_move_from_rest_is_as_in_the_move() -> None:
    # The segment's stop rules reduce to those of a move (sw/tests/test_model_stop.py judges those against physics).
    for profile in PROFILES[:12]:
        plan = plan_move(**profile.args())
        seg = Segment.of_move(plan)
        for p in range(0, plan.steps + 1, max(plan.steps // 23, 1)):
            assert segment_stop_values(seg, p) == soft_stop_values(plan, p), (profile.name, p)


def _stop_cases(rng: random.Random, head: str) -> list[tuple[Case, Change]]:
    out: list[tuple[Case, Change]] = []
    while len(out) < 60:
        case = _random_case(rng)
        if case is None:
            continue
        change = case.plan()
        if change.back is None and change.segment.head == head and change.segment.sa >= 3:
            out.append((case, change))
    return out


def test_a_soft_stop_in_a_down_head_goes_on_to_its_rest() -> None:
    """Down head: the stop is the head's own decel continued to the virtual rest K, within the pulse bound of the
    ideal decel from the segment's start speed to rest K steps ahead."""
    rng = random.Random(SEED + 1)
    print(f"seed {SEED} (STEPRAMP_SEED={SEED} replays it)")
    worst = 0.0
    for case, change in _stop_cases(rng, DOWN):
        seg = change.segment
        a, d = case.accel / case.alpha, case.decel / case.alpha
        k = seg.head_index
        judge = ideal.IdealSegment(change.start_speed, a, d, change.start_speed, k, case.f_tick).pulse_times(k)
        c0_slow = case.f_tick * math.sqrt(2.0 / min(a, d))
        for p in sorted({1, seg.sa // 2, seg.sa - 1}):
            values = segment_stop_values(seg, p)
            if seg.length is not None and k >= seg.length:
                assert values is None  # the segment's own decel ends no later
                continue
            assert values is not None and len(values) == k, (case, p)
            ticks = accumulate(values)
            err = max(abs(t - x) for t, x in zip(ticks, judge, strict=True))
            assert err <= STOP_BOUND_C0 * c0_slow + BOUND_TICKS, (case, p, err / c0_slow)
            worst = max(worst, err / c0_slow)
    print(f"down-head stops: worst {worst:.5f} c0")


@pytest.mark.parametrize("head", [UP, DOWN])
def test_a_soft_stop_takes_the_stop_distance(head: str) -> None:
    """In an up head and in the cruise (jog or positioning), m is v_p^2 / (2 d) from the ideal speed at pulse p, to
    within a step and the Q16.16 ratio's rounding; the stop's first interval is never shorter than the segment's."""
    rng = random.Random(SEED + 2)
    print(f"seed {SEED} (STEPRAMP_SEED={SEED} replays it)")
    for case, change in _stop_cases(rng, head):
        seg = change.segment
        a, d = case.accel / case.alpha, case.decel / case.alpha
        peak2 = (case.f_tick * (1 << FRAC_CRUISE) / seg.cruise) ** 2  # the cruise speed, from its register
        top = seg.sa + 5 if seg.length is None else seg.length
        for p in sorted({1, seg.sa // 2, seg.sa - 1, seg.sa, seg.sa + 3, top - 1}):
            if head == DOWN and p < seg.sa:
                continue  # the previous test
            m = segment_stop_length(seg, p)
            if m is None:
                continue
            v2 = min(change.start_speed**2 + 2.0 * a * p, peak2) if p < seg.sa else peak2
            want = v2 / (2.0 * d)
            assert abs(m - want) <= 1.0 + want * 2.0**-16 / (case.accel / case.decel), (case, p, m, want)
            values = segment_stop_values(seg, p)
            assert values is not None and len(values) == p + m
            if m >= 2:
                assert values[p] >= segment_values(seg, p + 1)[p], (case, p)


@pytest.mark.parametrize("profile", [p for p in PROFILES if abs(p.steps) > 200][:6], ids=lambda p: p.name)
def test_a_change_taken_over_at_a_pulse(profile) -> None:  # type: ignore[no-untyped-def]
    """A change committed at clock edges in ACCEL, RUN and DECEL of a move (docs/algorithm.md, the take-over's
    design): the pulse the driver names is at least 2 pulses and 400 clocks after the commit; pulses up to it are the
    move's; after it every pulse lies within the bound (plus the tick the carried fraction may add) of the ideal
    motion from there; the target is reached exactly."""
    args = profile.args()
    plan, info = plan_move_info(**args)
    alpha = 2.0 * math.pi / args["spr"]
    f_tick = args["fclk"] / args["prescale"]
    before = model_edges(plan)
    checked = 0
    for commit in (before[len(before) // 10], before[len(before) // 2], before[(9 * len(before)) // 10]):
        try:
            p = change_pulse(before, commit)
        except ValueError:
            continue
        assert p >= bisect.bisect_right(before, commit) + 1 and before[p] >= commit + 400
        for factor in (1.5, 0.6):
            speed = args["speed"] * factor
            if math.floor(f_tick / (speed / alpha)) * args["prescale"] < MIN_INTERVAL_CLKS:
                continue
            case = Case.of(speed_at_pulse(info, p), info.length - p, args["accel"], args["decel"], speed,
                           args["spr"], args["fclk"], args["prescale"])  # fmt: skip
            change = case.plan()
            if change.back is not None:
                continue  # a stop and a move back: two motions (test_named_changes, test_changes_from_every_phase...)
            edges = change_edges(Segment.of_move(plan), p, change.segment, args["prescale"])
            assert edges[: p + 1] == before[: p + 1]
            assert len(edges) == len(before), "the target is the move's own"
            a, d, v = case.accel / alpha, case.decel / alpha, speed / alpha
            judge = ideal.IdealSegment(change.start_speed, a, d, v, change.segment.length, f_tick)
            c0_slow = f_tick * math.sqrt(2.0 / min(a, d))
            t_p = (edges[p] - edges[0]) / args["prescale"]
            for i, edge in enumerate(edges[p:]):
                err = abs((edge - edges[0]) / args["prescale"] - t_p - judge.time_at(float(i)))
                assert err <= BOUND_C0 * c0_slow + BOUND_TICKS + 1.0, (profile.name, p, i, err / c0_slow)
            checked += 1
    assert checked >= 2, f"{profile.name}: only {checked} changes could be taken over"


def test_a_long_up_head_keeps_the_bound() -> None:
    # An up head runs the accel recurrence from index n0 with r = 0; its mean truncation (n - S(n) LSB from rest,
    # about n - U / 2 from n0 > 0) is out of its seed as out of a move's (docs/algorithm.md, "Changes while moving").
    # A jog from rest with a head of 1,500,000 steps to a cruise of 1 tick (left in: 22.9 ticks late, past the bound
    # 21.6) and a head of 1,200,000 steps from n0 = 300,000 (left in: 12.7 ticks late): every pulse within the bound,
    # and the head's last pulse (sa - 1) within 2 ticks of the ideal plus what the seed's rounding can put there, half
    # an LSB times U, the head's values in seeds (U summed here plainly; 0.014 ticks from rest, 5.7 from n0).
    spr, fclk, prescale = 400.0, 5e7, 64
    alpha, f_tick = 2.0 * math.pi / spr, fclk / prescale
    v = f_tick  # steps/s: a cruise of 1 tick
    a = v * v / (2.0 * 1_500_000)
    for n0 in (0, 300_000):
        u = math.sqrt(2.0 * a * n0)
        change = plan_change(u, None, a * alpha, a * alpha, v * alpha, spr, fclk, prescale)
        seg = change.segment
        assert seg.head == UP and seg.head_index == n0 and seg.sa - 2 > 1_100_000
        count = seg.sa + 10
        ticks = segment_ticks(seg, count)
        judge = ideal.IdealSegment(change.start_speed, a, a, v, None, f_tick).pulse_times(count)
        bound = BOUND_C0 * f_tick * math.sqrt(2.0 / a) + BOUND_TICKS
        worst = max(abs(t - x) for t, x in zip(ticks, judge, strict=True))
        assert worst <= bound, f"n0 = {n0}: worst pulse {worst:.3f} ticks from the ideal, bound {bound:.3f}"
        p, unit = 1.0, 0.0
        for j in range(n0 + 1, n0 + seg.sa - 1):  # A_j / A_n0 for the head's values A_(n0+1) .. A_(n0+sa-2)
            p *= (4 * j - 1) / (4 * j + 1)
            unit += p
        tol = 2.0 + 0.5 * unit / 65536
        at_end = ticks[seg.sa - 1] - judge[seg.sa - 1]
        assert abs(at_end) <= tol, f"n0 = {n0}: pulse sa - 1 = {seg.sa - 1} is {at_end:.3f} ticks off (tol {tol:.3f})"
