# SPDX-License-Identifier: MIT
"""The stop model (stepramp.models.engine.edges_with_stop) against physics: soft stop and hard stop.

Expected values come from the move's physical inputs (stepramp.models.ideal: the speed at a position, the ideal last
interval; the decel in steps/s^2), never from the model's own arithmetic. The stop rules themselves are in
docs/algorithm.md ("Soft stop") and docs/stepramp_engine.md.

Speed at pulse p: the ideal trajectory's speed at position p (stepramp.models.ideal.IdealMove.speed_at). The reciprocal
of interval p is the *mean* speed over that interval; in an acceleration from rest it is half the speed at pulse 1
(and (sqrt(p) + sqrt(p - 1)) / (2 sqrt(p)) of it in general), which would make the stopping distance of a correct
stop look 0.5 * accel / decel steps too long.

First interval of an ACCEL stop (m >= 2): against the ideal interval of a deceleration at d from the ideal speed at
pulse p over one step, (v - sqrt(v^2 - 2 d)) / d. The rule starts the stop's ramp from D = the plan's interval
p + 1 (A_p), the mean speed over [p, p + 1] of the acceleration, where the decel ramp wants the mean over the
stop's first step: the interval is up to 1 / (4 p) short (p = 1: 18 % with accel >> decel), and m = floor of the
stopping distance makes the ramp up to one step short of the speed's own (the first interval up to about
0.25 / m long, at m = 2 only). Tolerance FIRST_P / p + FIRST_M / m + FIRST_REL, plus one tick of emission.
With m = 1 the first interval is c_last (checked as the last interval).
"""

from __future__ import annotations

import functools
import itertools
import math
import random
from dataclasses import dataclass

import pytest

from stepramp.board.plan import Plan, plan_move, plan_move_info
from stepramp.models import ideal
from stepramp.models.engine import (
    ACCEL,
    DECEL,
    FIRST_PULSE_LATENCY,
    RUN,
    edges,
    edges_with_stop,
    interval_values,
    phase_of,
    soft_stop_pulse,
    soft_stop_values,
)
from stepramp.sim.profiles import PROFILES, PROFILES_BY_NAME, Profile

#: Tolerances of the brief: stopping distance 2 steps + 3 %, last interval 2 % + 2 ticks, transition 2 %.
DIST_STEPS = 2.0
DIST_REL = 0.03
LAST_REL = 0.02
LAST_TICKS = 2.0
TRANSITION_REL = 0.02
#: First interval of an ACCEL stop against the ideal (see above): 1 / (4 p) + 0.3 / m + 2 %; measured worst on
#: PROFILES and the extreme ratios: 18.7 % (p = 1, m = 100, accel = 100 * decel), within 0.02 of this bound.
FIRST_P = 0.25
FIRST_M = 0.3
FIRST_REL = 0.02
RANDOM_REQUESTS = 40
MAX_PULSES_PER_PROFILE = 200


@dataclass
class Physics:
    """The move's physical quantities (from the inputs only)."""

    move: ideal.IdealMove
    decel: float  # steps/s^2
    ratio: float  # accel / decel

    def speed_ticks(self, x: float) -> float:
        """Ideal speed at position x in steps per tick."""
        return self.move.speed_at(x) / self.move.f_tick

    def stop_distance(self, x: float) -> float:
        """Steps needed to stop from the ideal speed at x with the programmed decel: v^2 / (2 d)."""
        v = self.move.speed_at(x)
        return v * v / (2.0 * self.decel)

    @functools.cached_property
    def last_interval(self) -> float:
        """Exact last interval of a deceleration to rest (ticks): the ideal move's own last interval."""
        return self.move.time_at(self.move.length) - self.move.time_at(self.move.length - 1)

    def first_stop_interval(self, x: float) -> float:
        """Ticks of the first step of a deceleration at d from the ideal speed at x (0 if it cannot go a step)."""
        v = self.speed_ticks(x)
        d = self.decel / self.move.f_tick**2
        disc = v * v - 2.0 * d
        return (v - math.sqrt(disc)) / d if disc >= 0.0 else 0.0


def physics(profile: Profile) -> Physics:
    move = ideal.ideal_move(**profile.args())
    return Physics(move, move.d, move.a / move.d)


def request_edges(plan: Plan, rng: random.Random) -> list[int]:
    """Request edges: random ones, and around the edges of a few pulses (edge - 1, edge, edge + 1)."""
    normal = edges(plan)
    if not normal:
        return [0, 1, 2, 3]
    last = normal[-1]
    out = {0, 1, 2, last - 1, last, last + 1}
    out.update(rng.randint(1, last) for _ in range(RANDOM_REQUESTS))
    for k in rng.sample(range(len(normal)), min(len(normal), 8)):
        out.update((normal[k] - 1, normal[k], normal[k] + 1))
    return sorted(e for e in out if e >= 0)


def tick_intervals(plan: Plan, pulse_edges: list[int]) -> list[int]:
    """Intervals in ticks between consecutive pulses (index j - 1 holds interval j)."""
    return [(b - a) // plan.prescale for a, b in itertools.pairwise(pulse_edges)]


def request_decided_at(normal: list[int], k: int) -> int:
    """A request edge whose soft stop is decided at pulse k >= 1: the edge of pulse k - 2 (the first pulse after it
    is k - 1), or edge 1 for k = 1 (before pulse 0's edge)."""
    return normal[k - 2] if k >= 2 else 1


def check_soft(profile: Profile, plan: Plan, phys: Physics, normal: list[int], e: int) -> tuple[str, str] | None:
    """All physics checks of one soft stop at edge e (normal: the move's edges); returns (phase, outcome)."""
    got = edges_with_stop(plan, "soft", e)
    what = f"{profile.name} soft stop at edge {e}"
    length = plan.steps - 1
    assert len(got) <= max(plan.steps, 0), what
    assert all(x > FIRST_PULSE_LATENCY - 1 for x in got), what
    p = soft_stop_pulse(plan, e)
    # the rule (docs/algorithm.md, "Soft stop"): q the first pulse strictly after e, decided at p = q + 1; ignored
    # before edge 1 (the start edge is not busy), when no pulse comes after e, or when q is the last pulse
    q = next((k for k, x in enumerate(normal) if x > e), None)
    assert p == (q + 1 if e >= 1 and q is not None and q + 1 < len(normal) else None), f"{what}: p = {p}, q = {q}"
    if p is None:
        assert got == normal, f"{what}: a request outside the move changed it"
        return None
    # everything up to p is the plan's
    assert got[: p + 1] == normal[: p + 1], f"{what}: pulses up to p = {p} changed"
    if p >= length:
        assert got == normal, what
        return ("LAST", "ignored")
    phase = phase_of(plan, p)
    if phase == DECEL:
        assert got == normal, f"{what}: a soft stop in DECEL changed the move"
        return (phase, "ignored")
    dist = phys.stop_distance(p)
    tol = DIST_STEPS + DIST_REL * dist
    if got == normal:
        # Ignored because the plan's own deceleration ends no later: its remaining distance is not longer.
        assert length - p <= dist + tol, f"{what}: ignored although {length - p} steps > stop {dist:.2f}"
        return (phase, "ignored")
    stop_steps = len(got) - 1 - p
    assert stop_steps < length - p, what
    assert dist - tol <= stop_steps <= dist + tol, (
        f"{what}: stopped in {stop_steps} steps after pulse {p}, physics {dist:.2f} (tol {tol:.2f})"
    )
    if stop_steps == 0:
        return (phase, "ends at p")
    iv = tick_intervals(plan, got)
    after = iv[p:]  # intervals p + 1 .. p + m
    if phase == RUN:
        # No speed increase once the stop takes effect: the first new interval against the cruise speed ...
        current = 1.0 / phys.speed_ticks(p)
        assert after[0] >= (1.0 - TRANSITION_REL) * current - 1, (
            f"{what}: interval {p + 1} = {after[0]} ticks, faster than the speed at pulse {p} ({current:.2f} ticks)"
        )
    elif stop_steps >= 2:
        # ... in ACCEL the first interval of the stop's ramp against a deceleration from the speed at pulse p
        ideal_first = phys.first_stop_interval(p)
        rel = FIRST_P / p + FIRST_M / stop_steps + FIRST_REL
        assert abs(after[0] - ideal_first) <= rel * ideal_first + 1, (
            f"{what}: interval {p + 1} = {after[0]} ticks, ideal {ideal_first:.2f} (tol {rel:.3f})"
        )
    # ... then never shorter (the emitted ticks may jitter by one from the fractional carry; the values may not)
    assert all(b >= a - 1 for a, b in itertools.pairwise(after)), f"{what}: intervals shorten: {after}"
    values = soft_stop_values(plan, p)
    assert values is not None, what
    assert all(b >= a for a, b in itertools.pairwise(values[p:])), f"{what}: interval values shorten"
    if stop_steps >= 2:
        # the stop's ramp starts from the plan's interval p + 1: never faster than the plan would have gone on
        plan_next = next(itertools.islice(interval_values(plan), p, None))
        assert values[p] >= plan_next, f"{what}: first stop interval below the plan's interval {p + 1}"
    # The last interval is the exact last interval of a deceleration to rest.
    exact_last = phys.last_interval
    assert abs(after[-1] - exact_last) <= LAST_REL * exact_last + LAST_TICKS, (
        f"{what}: last interval {after[-1]} ticks, exact {exact_last:.2f}"
    )
    if len(after) >= 2:
        assert after[-1] >= after[-2], what
    return (phase, "stopped")


def check_hard(plan: Plan, normal: list[int], e: int) -> None:
    got = edges_with_stop(plan, "hard", e)
    what = f"hard stop at edge {e}"
    assert got == normal[: len(got)], f"{what}: not a prefix of the move"
    assert all(x < e for x in got), f"{what}: a pulse at or after the request"
    if e >= 0:
        assert len(got) == sum(1 for x in normal if x < e), f"{what}: a pulse before the request is missing"


@pytest.mark.parametrize("profile", PROFILES, ids=[p.name for p in PROFILES])
def test_stops_against_physics(profile: Profile) -> None:
    """Soft and hard stops at many request times on every profile."""
    plan = plan_move(**profile.args())
    phys = physics(profile)
    rng = random.Random(f"stop-{profile.name}")
    normal = edges(plan)
    for e in request_edges(plan, rng):
        check_soft(profile, plan, phys, normal, e)
        check_hard(plan, normal, e)


def test_soft_stop_at_every_pulse_covers_every_outcome() -> None:
    """A soft stop decided at (up to 200) pulses of every profile, around sa and sd, and at the last pulse."""
    seen: set[tuple[str, str]] = set()
    for profile in PROFILES:
        plan = plan_move(**profile.args())
        phys = physics(profile)
        normal = edges(plan)
        pulses = set(range(1, len(normal), max(1, len(normal) // MAX_PULSES_PER_PROFILE)))
        pulses.update(k for b in (plan.sa, plan.sd, len(normal) - 1) for k in (b - 1, b, b + 1) if 1 <= k < len(normal))
        for k in sorted(pulses):
            # a request at the edge of pulse k - 2 is decided at pulse k
            outcome = check_soft(profile, plan, phys, normal, request_decided_at(normal, k))
            if outcome is not None:
                seen.add(outcome)
    for phase in (ACCEL, RUN):
        assert (phase, "stopped") in seen
        assert (phase, "ignored") in seen
    assert (ACCEL, "ends at p") in seen
    assert (DECEL, "ignored") in seen
    assert ("LAST", "ignored") in seen


def test_soft_stop_examples() -> None:
    """Hand-checked cases on trap_basic (accel == decel, so a stop at pulse p in ACCEL takes p more steps)."""
    profile = PROFILES_BY_NAME["trap_basic"]
    plan, info = plan_move_info(**profile.args())
    assert plan.stop_ratio == 1 << 16
    normal = edges(plan)
    # a stop requested in interval 10 (at pulse 9's edge): the first pulse after it is 10, so it is decided at
    # pulse 11 and lasts 11 more steps: 23 pulses in all
    assert soft_stop_pulse(plan, normal[9]) == 11
    got = edges_with_stop(plan, "soft", normal[9])
    assert len(got) == 23
    assert got[:12] == normal[:12]
    # requested one edge before pulse 10: still pulse 11; at its edge: pulse 12 (pulse 10's is not after it)
    assert edges_with_stop(plan, "soft", normal[10] - 1) == got
    assert len(edges_with_stop(plan, "soft", normal[10])) == 25
    # the start edge is not busy: ignored; edge 1 (before pulse 0 is out): decided at pulse 1, m = 1: 3 pulses;
    # at pulse 0's edge: decided at pulse 2, m = 2: 5 pulses
    assert edges_with_stop(plan, "soft", 0) == normal
    assert soft_stop_pulse(plan, 1) == 1
    first = edges_with_stop(plan, "soft", 1)
    assert len(first) == 3 and first[:2] == normal[:2]
    assert len(edges_with_stop(plan, "soft", FIRST_PULSE_LATENCY)) == 5
    # in RUN the stop takes L - sd + 1 steps: the length of the plan's own decel ramp (intervals sd .. L); a
    # request at pulse k - 1's edge is decided at pulse k + 1: pulses 0 .. k + 1 + L - sd + 1
    k = plan.sa + 40
    assert phase_of(plan, k + 1) == RUN
    length = plan.steps - 1
    assert len(edges_with_stop(plan, "soft", normal[k - 1])) == k + length - plan.sd + 3
    assert length - plan.sd + 1 == length - math.floor(info.x_d)
    # in ACCEL the stop's ramp starts from the plan's interval p + 1: its first interval is D_(m-1) from D_m = A_p
    values = soft_stop_values(plan, 10)
    assert values is not None
    plain = list(itertools.islice(interval_values(plan), 11))
    d_m = plain[10] >> 16
    assert values[10] == (d_m + (2 * d_m) // (4 * 10 - 1)) << 16
    # decided in DECEL (at pulse sd: requested at pulse sd - 2's edge), or at the last pulse L (requested at pulse
    # L - 2's edge), or the first pulse after the request is the last (requested at pulse L - 1's edge), or after
    # the move: no change
    assert soft_stop_pulse(plan, normal[plan.sd - 2]) == plan.sd
    assert edges_with_stop(plan, "soft", normal[plan.sd - 2]) == normal
    assert edges_with_stop(plan, "soft", normal[plan.sd]) == normal
    assert soft_stop_pulse(plan, normal[-3]) == length
    assert edges_with_stop(plan, "soft", normal[-3]) == normal
    assert soft_stop_pulse(plan, normal[-2]) is None
    assert edges_with_stop(plan, "soft", normal[-2]) == normal
    assert edges_with_stop(plan, "soft", normal[-1]) == normal
    assert edges_with_stop(plan, "soft", normal[-1] + 100) == normal
    # hard stop: the pulse due at the request's edge is suppressed, the start edge wins, idle edges do nothing
    assert edges_with_stop(plan, "hard", normal[5]) == normal[:5]
    assert edges_with_stop(plan, "hard", normal[5] + 1) == normal[:6]
    assert edges_with_stop(plan, "hard", 0) == []
    assert edges_with_stop(plan, "hard", FIRST_PULSE_LATENCY) == []
    assert edges_with_stop(plan, "hard", normal[-1] + 1) == normal
    with pytest.raises(ValueError, match="kind"):
        edges_with_stop(plan, "gentle", 10)


def test_stop_ratio_field() -> None:
    """stop_ratio = accel / decel in Q16.16, rounded and saturated; 0 for moves without an interval."""
    for profile in PROFILES:
        plan = plan_move(**profile.args())
        if plan.steps <= 1:
            assert plan.stop_ratio == 0
            continue
        ratio = profile.accel / profile.decel
        assert abs(plan.stop_ratio - ratio * 2**16) <= 0.5
    base = PROFILES_BY_NAME["trap_basic"].args()
    huge = plan_move(**{**base, "accel": base["decel"] * 70_000.0, "steps": 3})
    assert huge.stop_ratio == 2**32 - 1


def test_soft_stop_with_extreme_ratios() -> None:
    """accel / decel of 1/100 .. 100 on a long ramp: the stop lands within tolerance in every ACCEL interval."""
    for ratio in (0.01, 0.1, 0.5, 1.0, 2.0, 10.0, 100.0):
        n_a = 100.0
        n_d = n_a * ratio
        fclk, spr, period = 1e6, 200.0, 80.0
        alpha = 2.0 * math.pi / spr
        v = fclk / period
        profile = Profile(
            f"ratio_{ratio}",
            int(n_a + n_d + 50),
            alpha * v * v / (2.0 * n_a),
            alpha * v * v / (2.0 * n_d),
            alpha * v,
            spr,
            fclk,
        )
        plan = plan_move(**profile.args())
        phys = physics(profile)
        normal = edges(plan)
        outcomes = {
            check_soft(profile, plan, phys, normal, request_decided_at(normal, k)) for k in range(1, plan.sa, 3)
        }
        assert outcomes <= {(ACCEL, "stopped"), (ACCEL, "ends at p")}, outcomes
        # with decel = 100 * accel the stopping distance is below one step in all of this ramp: the move ends at p
        assert ((ACCEL, "stopped") in outcomes) == (ratio >= 0.1), (ratio, outcomes)
