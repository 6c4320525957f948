# SPDX-License-Identifier: MIT
"""Coordinated linear moves (stepramp.board.coord): the axes end together, by physics and by the bit-exact model.

The requirement: the last pulses of all axes lie within max(2 ticks, 0.01 c0 of the slowest axis) of each other, the
times from the bit-exact engine model (stepramp.models.engine.last_edge), c0 the first interval of the slowest axis
(the largest: the path's accel times the smallest L_i / L_lead). An axis of 1 step has its only pulse at t = 0 (in the
ideal too: it covers no distance) and is not one of the axes that end together; test_one_and_zero_step_axes.

Expected values come from the physics (stepramp.models.ideal, the ratios L_i / L_lead computed here), never from the
planner. Random moves print their seed (STEPRAMP_SEED replays them) and the worst spread.
"""

from __future__ import annotations

import dataclasses
import math
import os
import random
import re
from collections import Counter
from dataclasses import dataclass
from typing import Any

import pytest

from stepramp.board.coord import MAX_AXES, plan_coordinated, plan_coordinated_info, time_before_last
from stepramp.board.plan import MIN_INTERVAL_CLKS, Plan, plan_move, plan_move_info
from stepramp.models import ideal
from stepramp.models.engine import FIRST_PULSE_LATENCY, last_edge, tick_chunks, tick_times, value_runs
from stepramp.sim.profiles import design_args

SEED = int(os.environ.get("STEPRAMP_SEED", "20261202"))
RANDOM_COUNT = 1000
BOUND_TICKS = 2.0
BOUND_C0 = 0.01
MOVE_BOUND_C0 = 0.008  # a move's own bound against its ideal trajectory (test_model.py), kept by every axis
Path = dict[str, Any]
"""accel, decel, speed, spr, fclk, prescale: the path's values (the lead axis's), plan_coordinated's keywords."""


@dataclass(frozen=True)
class Outcome:
    """The model's end of every axis of a coordinated move, and the requirement's bound."""

    ends: dict[int, int]
    """axis -> tick of its last pulse (axes of 2 steps or more)."""
    spread: int
    c0_slow: float
    bound: float
    t_end: float
    """The ideal end of the path (ticks), from stepramp.models.ideal."""


def ratios(steps: list[int]) -> list[float]:
    """r_i = L_i / L_lead, L = |N| - 1 (the ideal's convention: an N-step move covers N - 1 steps); 0 below 2 steps."""
    lead = max(abs(n) for n in steps) - 1
    return [(abs(n) - 1) / lead if abs(n) >= 2 else 0.0 for n in steps]


def end_tick(plan: Plan) -> int:
    """The model's tick of the plan's last pulse."""
    edge = last_edge(plan)
    assert edge is not None
    return (edge - FIRST_PULSE_LATENCY) // plan.prescale


def outcome(steps: list[int], path: Path, plans: list[Plan]) -> Outcome:
    """The requirement judged on the model's ends: c0 of the slowest axis from the physics."""
    r = ratios(steps)
    ends = {axis: end_tick(plan) for axis, plan in enumerate(plans) if abs(steps[axis]) >= 2}
    spread = max(ends.values()) - min(ends.values()) if ends else 0
    slow = min((r[axis] for axis in ends), default=1.0)
    c0_slow = ideal.c0(path["accel"] * slow, path["spr"], path["fclk"], path["prescale"])
    lead = max(abs(n) for n in steps)
    move = ideal.ideal_move(lead, **path)
    return Outcome(ends, spread, c0_slow, max(BOUND_TICKS, BOUND_C0 * c0_slow), move.t_end * move.f_tick)


def check_plans(steps: list[int], path: Path, plans: list[Plan], what: str) -> None:
    """Each plan is plan_move's of the scaled values but for its last interval, which stays a valid interval close to
    its exact value (so each axis keeps plan_move's checks and the engine's limits)."""
    r = ratios(steps)
    assert len(plans) == len(steps), what
    for axis, (n, plan) in enumerate(zip(steps, plans, strict=True)):
        scale = r[axis] if r[axis] > 0.0 else 1.0
        scaled = {**path, **{key: path[key] * scale for key in ("accel", "decel", "speed")}}
        base, info = plan_move_info(n, **scaled)
        length = abs(n) - 1
        if length < 1:
            assert plan == base, f"{what}: axis {axis}"
            continue
        # only interval L is set (every register holding it holds the same value); accel_seed is plan_move's, the
        # accel recurrence's truncation already out of it (not taken out twice)
        ends = {"c_last": plan.c_last}
        ends |= {"c_first": plan.c_last} if length == 1 else {}
        ends |= {"c_sa": plan.c_last} if plan.sa == length else {}
        ends |= {"c_sd": plan.c_last} if plan.sd == length else {}
        assert plan == dataclasses.replace(base, **ends), f"{what}: axis {axis}"
        assert 1 <= plan.sa <= plan.sd <= length, f"{what}: axis {axis}"
        last = plan.c_last / 65536
        assert last >= math.floor(info.min_interval), f"{what}: axis {axis} last interval {last}, {info.min_interval}"
        assert math.floor(last) * plan.prescale >= MIN_INTERVAL_CLKS, f"{what}: axis {axis}"
        # the last interval moves by the decel ramp's uncorrected deficit (0.007 cd0), the seeds' rounding and ticks
        exact = base.c_last / 65536
        assert abs(last - exact) <= 0.01 * exact + 2.0, f"{what}: axis {axis} last interval {last}, exact {exact}"


def check_pulses(steps: list[int], path: Path, plans: list[Plan], what: str) -> float:
    """Every pulse of every axis against its own ideal trajectory (the scaled values, from stepramp.models.ideal):
    within a move's bound, 0.008 c0 + 2 ticks (c0 of the slower of the axis's accel and decel). Returns the worst
    error as a fraction of that bound."""
    r = ratios(steps)
    worst = 0.0
    for axis, (n, plan) in enumerate(zip(steps, plans, strict=True)):
        if abs(n) < 2:
            continue
        scaled = {**path, "accel": path["accel"] * r[axis], "decel": path["decel"] * r[axis]}
        scaled["speed"] = path["speed"] * r[axis]
        times = tick_times(plan)
        want = ideal.pulse_times(n, **scaled)
        c0 = ideal.c0(min(scaled["accel"], scaled["decel"]), path["spr"], path["fclk"], path["prescale"])
        errs = [abs(t - w) for t, w in zip(times, want, strict=True)]
        k = max(range(len(errs)), key=errs.__getitem__)
        bound = MOVE_BOUND_C0 * c0 + 2.0
        assert errs[k] <= bound, f"{what}: axis {axis} pulse {k} off by {errs[k]:.3f} ticks (bound {bound:.3f})"
        worst = max(worst, errs[k] / bound)
    return worst


def check_move(steps: list[int], path: Path, what: str = "") -> Outcome:
    """The requirement for one coordinated move, and each axis's last pulse within a tick of the ideal end."""
    what = f"{what} steps={steps} path={path}"
    plans = plan_coordinated(steps, **path)
    check_plans(steps, path, plans, what)
    res = outcome(steps, path, plans)
    assert res.spread <= res.bound, f"{what}: last pulses spread over {res.spread} ticks > {res.bound:.3f}: {res}"
    for axis, tick in res.ends.items():
        assert abs(tick - res.t_end) <= 1.0, f"{what}: axis {axis} ends at {tick}, ideal end {res.t_end:.3f}"
    return res


# --------------------------------------------------------------------------------------------------------------------
# the ideal: the rule makes the trajectories proportional (physics only)
# --------------------------------------------------------------------------------------------------------------------


def _time_of_fraction(move: ideal.IdealMove, fraction: float) -> float:
    return move.time_at(fraction * move.length)


@pytest.mark.parametrize("seed", range(4))
def test_scaled_ideal_trajectories_are_proportional(seed: int) -> None:
    # axis i with the path's accel, decel and speed times L_i / L_lead is at r_i x_lead(t) at every t: the same
    # trapezoid or triangle in time, every pulse k at the lead's time of position k / r_i, the same end
    rng = random.Random(SEED + seed)
    for _ in range(100):
        lead = rng.randint(2, 5000)
        path = design_args(lead, rng.uniform(70.0, 5000.0), rng.uniform(0.3, 3000.0), rng.uniform(0.3, 3000.0))
        del path["steps"]
        other = rng.randint(2, lead) * rng.choice((1, -1))
        r = (abs(other) - 1) / (lead - 1)
        move = ideal.ideal_move(lead, **path)
        scaled = {**path, "accel": path["accel"] * r, "decel": path["decel"] * r, "speed": path["speed"] * r}
        axis = ideal.ideal_move(other, **scaled)
        assert axis.triangle == move.triangle
        assert axis.t_end == pytest.approx(move.t_end, rel=1e-12)
        assert axis.t_a == pytest.approx(move.t_a, rel=1e-12)
        assert axis.t_d == pytest.approx(move.t_d, rel=1e-12, abs=1e-12 * move.t_end)
        ks = sorted({*range(0, axis.length + 1, max(axis.length // 200, 1)), axis.length - 1, axis.length})
        for k in ks:  # position k / r, exactly L_lead at the end (the sqrt near rest is steep)
            x = k * move.length / axis.length
            assert abs(axis.time_at(k) - move.time_at(x)) <= 1e-9 * (move.time_at(x) + move.f_tick), (k, path)
        for fraction in (0.1, 0.5, 0.9):
            t = _time_of_fraction(move, fraction)
            assert _time_of_fraction(axis, fraction) == pytest.approx(t, rel=1e-9)


def test_scaling_by_step_counts_would_not_end_together() -> None:
    # the N-step convention matters: scaled by N_i / N_lead instead of (N_i - 1) / (N_lead - 1), a 2-step axis
    # beside a 101-step lead would end at a different time (its one interval is then a 1/50.5 scale of the lead's
    # motion over 2 steps of 100)
    path = {"accel": 40.0, "decel": 40.0, "speed": 20.0, "spr": 400.0, "fclk": 1e6, "prescale": 1}
    lead = ideal.ideal_move(101, **path)
    good, wrong = 1 / 100, 2 / 101
    for r, same in ((good, True), (wrong, False)):
        scaled = {**path, "accel": path["accel"] * r, "decel": path["decel"] * r, "speed": path["speed"] * r}
        axis = ideal.ideal_move(2, **scaled)
        assert (axis.t_end == pytest.approx(lead.t_end, rel=1e-12)) is same


# --------------------------------------------------------------------------------------------------------------------
# named moves
# --------------------------------------------------------------------------------------------------------------------

AVR446 = {"accel": 40.0, "decel": 40.0, "speed": 20.0, "spr": 400.0, "fclk": 1e6, "prescale": 1}


def _designed(lead: int, period: float, n_a: float, n_d: float, **kw: Any) -> Path:
    path = design_args(lead, period, n_a, n_d, **kw)
    del path["steps"]
    return path


# the decel 28 times slower than the accel: scaled by L_i / L_lead alone (test_scaled_plans_alone_miss_the_bound),
# each axis ends early by half its decel ramp's recurrence deficit, 0.007 cd0, and the cd0 differ by axis
ASYMMETRIC = (
    [1778, 406, 9],
    {
        "accel": 83.73934936001515,
        "decel": 2.941431008571455,
        "speed": 62.25143406166214,
        "spr": 200.0,
        "fclk": 129297.42681053962,
        "prescale": 1,
    },
)

# a decel 27 times steeper than the accel at a cruise of 64.6 clocks (1.01 ticks): interval L is about one cruise
# interval, and the end tick nearest the ideal end would shorten axis 1's below floor(min_interval) = 1 tick
STEEP = (
    [5644, 612],
    {
        "accel": 394815273.05268425,
        "decel": 10715760890.10831,
        "speed": 1932.2515955679603,
        "spr": 400.0,
        "fclk": 11110648.035935236,
        "prescale": 64,
    },
)

NAMED: dict[str, tuple[list[int], Path]] = {
    "avr446 demo, three axes": ([400, 200, -100], AVR446),
    "avr446 demo, the lead negative": ([-400, 399, 3, 2], AVR446),
    "asymmetric: decel 28 times slower": ASYMMETRIC,
    "asymmetric: accel 100 times slower": ([3000, -2000, 40], _designed(3000, 90.0, 1000.0, 10.0)),
    "triangle with small axes": ([50, 17, -3, 2], _designed(50, 80.0, 400.0, 300.0)),
    "triangle, lead of 3 steps": ([3, -2, 3], _designed(3, 80.0, 40.0, 40.0)),
    "lead of 2 steps": ([2, -2, 1, 0], AVR446),
    "one axis": ([400], AVR446),
    "eight axes": ([1000, -999, 500, 250, 7, 3, 2, -1], _designed(1000, 100.0, 200.0, 120.0)),
    "prescale 50, long cruise": ([120_000, 90_001, -3], _designed(120_000, 2.0, 3000.0, 5000.0, prescale=50)),
    "prescale 64 at the speed limit, long ramps": (
        [300_000, -123_457, 10],
        _designed(300_000, 1.0, 60_000.0, 40_000.0, spr=400.0, fclk=5e7, prescale=64),
    ),
    "equal axes": ([777, -777, 777], _designed(777, 150.0, 100.0, 100.0)),
    "steep decel near the speed limit: the end a tick later": STEEP,
}


@pytest.mark.parametrize("name", NAMED)
def test_named_moves_end_together(name: str) -> None:
    steps, path = NAMED[name]
    res = check_move(steps, path, name)
    print(f"{name}: ends {res.ends}, spread {res.spread} ticks (bound {res.bound:.2f}, c0_slow {res.c0_slow:.1f})")
    if max(abs(n) for n in steps) <= 5000:
        check_pulses(steps, path, plan_coordinated(steps, **path), name)


def test_scaled_plans_alone_miss_the_bound() -> None:
    # the checker fails where it should: the axes planned by plan_move with the scaled values and nothing else end
    # 0.03 c0 apart here (each early by half its own decel deficit); plan_coordinated's end within a tick of each other
    steps, path = ASYMMETRIC
    r = ratios(steps)
    plain = [
        plan_move(n, **{**path, "accel": path["accel"] * k, "decel": path["decel"] * k, "speed": path["speed"] * k})
        for n, k in zip(steps, r, strict=True)
    ]
    bad = outcome(steps, path, plain)
    assert bad.spread > bad.bound
    assert bad.spread > 0.02 * bad.c0_slow
    good = outcome(steps, path, plan_coordinated(steps, **path))
    assert good.spread <= 1


def test_the_end_waits_for_a_last_interval_at_the_speed_limit() -> None:
    # the common end tick is the one nearest the ideal end unless an axis's last interval would then be shorter than
    # floor(min_interval) ticks (its floor would emit an interval shorter than the move's shortest): then the first
    # later tick that leaves every axis's last interval 1/4 tick more, the same for all axes
    steps, path = STEEP
    plans, info = plan_coordinated_info(steps, **path)
    assert info.end_tick == math.floor(info.t_end + 0.5) + 1
    for plan, move in zip(plans, info.infos, strict=True):
        assert plan.c_last / 65536 >= math.floor(move.min_interval)
    res = check_move(steps, path)
    assert set(res.ends.values()) == {info.end_tick}
    assert 0.5 < info.end_tick - res.t_end < 1.0


def test_a_long_accel_ramp_keeps_its_time() -> None:
    # the accel recurrence runs about one Q32.16 LSB per value above the exact one (its remainder truncates): left in
    # the seed, the move would be n / 2^16 ticks late after n values, 22.9 ticks after this ramp of 1,500,000 steps
    # at a cruise of 1 tick (prescale 64), beyond a move's bound of 0.008 c0 + 2 = 21.6 ticks. plan_move's seed is
    # without that truncation, and the coordinated plan keeps that seed (it does not take the truncation out twice):
    # the pulse at the end of the ramp is within 2 ticks of the ideal in both
    n_a = 1_500_000
    steps = 2 * n_a + 1000
    path = _designed(steps, 1.0, float(n_a), float(n_a), spr=400.0, fclk=5e7, prescale=64)
    [plan] = plan_coordinated([steps], **path)
    plain = plan_move(steps, **path)
    k = plan.sa - 1
    want = ideal.ideal_move(steps, **path).time_at(k)
    c0 = ideal.c0(path["accel"], path["spr"], path["fclk"], path["prescale"])

    def tick(p: Plan) -> int:  # the model's tick of pulse k, the chunks read up to it
        seen = 0
        for chunk in tick_chunks(p):
            if seen + len(chunk) > k:
                return int(chunk[k - seen])
            seen += len(chunk)
        raise AssertionError(f"no pulse {k}")

    assert plain.sa == plan.sa and plain.accel_seed == plan.accel_seed
    assert n_a / 65536 > MOVE_BOUND_C0 * c0 + 2.0  # the truncation left in would break the bound
    assert abs(tick(plain) - want) <= 2.0
    assert abs(tick(plan) - want) <= 2.0


def test_one_and_zero_step_axes() -> None:
    # a 1-step axis emits its only pulse at the start (edge FIRST_PULSE_LATENCY, t = 0): it covers no distance, in
    # the ideal too (L = 0), and no register can delay pulse 0; it does not end with the others. A 0-step axis emits
    # nothing. The others end together.
    steps = [400, 1, -1, 0, 250]
    plans, info = plan_coordinated_info(steps, **AVR446)
    assert plans[1] == plan_move(1, **AVR446)
    assert plans[2] == plan_move(-1, **AVR446)
    assert plans[3] == plan_move(0, **AVR446)
    assert last_edge(plans[1]) == last_edge(plans[2]) == FIRST_PULSE_LATENCY
    assert last_edge(plans[3]) is None
    assert info.ratios[1:4] == (0.0, 0.0, 0.0)
    res = check_move(steps, AVR446)
    assert set(res.ends) == {0, 4}
    assert res.spread == 0


def test_the_lead_is_the_first_with_the_most_steps() -> None:
    _, info = plan_coordinated_info([10, -30, 30, 2], **AVR446)
    assert info.lead == 1
    assert info.ratios == (9 / 29, 1.0, 1.0, 1 / 29)
    # the lead is plan_move's plan but for its last interval
    plans = plan_coordinated([30, 10], **AVR446)
    check_plans([30, 10], AVR446, plans, "lead")
    assert dataclasses.replace(plans[0], c_last=0) == dataclasses.replace(plan_move(30, **AVR446), c_last=0)


# --------------------------------------------------------------------------------------------------------------------
# random moves
# --------------------------------------------------------------------------------------------------------------------


def _log_uniform(rng: random.Random, lo: float, hi: float) -> float:
    return math.exp(rng.uniform(math.log(lo), math.log(hi)))


def random_move(rng: random.Random) -> tuple[list[int], Path]:
    """2 to 4 axes, steps from 0 to 100,000 (a third of the other axes small: 0 to 12 steps), trapezoids and
    triangles, accel / decel up to 1000 times apart both ways, prescale 1 to 65535, cruise from the speed limit up."""
    prescale = rng.choice((1, 1, 2, 3, 8, 64, 1000, 65535))
    spr = rng.choice((24.0, 200.0, 400.0, 1600.0, 3200.0, 51200.0))
    fclk = _log_uniform(rng, 1e5, 2e8)
    period = math.ceil(MIN_INTERVAL_CLKS / prescale) * _log_uniform(rng, 1.0, 1.1) + _log_uniform(rng, 1e-3, 1e4)
    n_a = _log_uniform(rng, 0.05, 3e4)
    n_d = n_a * _log_uniform(rng, 1e-3, 1e3)
    lead = round(_log_uniform(rng, 2.0, 1e5))
    steps = [lead]
    for _ in range(rng.randint(1, 3)):
        small = rng.random() < 0.3
        n = rng.randint(0, min(12, lead)) if small else round(_log_uniform(rng, 1.0, lead))
        steps.append(n * rng.choice((1, -1)))
    rng.shuffle(steps)
    return steps, _designed(lead, period, n_a, n_d, spr=spr, fclk=fclk, prescale=prescale)


def test_random_moves_end_together() -> None:
    rng = random.Random(SEED)
    print(f"seed {SEED} (STEPRAMP_SEED={SEED} replays it)")
    kinds: Counter[str] = Counter()
    worst_ticks, worst_c0, worst_dev = 0, 0.0, 0.0
    refused = 0
    checked = 0
    while checked < RANDOM_COUNT:
        steps, path = random_move(rng)
        try:
            plans = plan_coordinated(steps, **path)
        except ValueError as exc:  # a scaled axis plan_move refuses (delays too long): refused, with the axis
            reason = str(exc)
            refused += 1
            assert reason.startswith("axis "), reason
            continue
        res = check_move(steps, path, f"random move {checked} (seed {SEED})")
        checked += 1
        worst_ticks = max(worst_ticks, res.spread)
        worst_c0 = max(worst_c0, res.spread / res.c0_slow)
        worst_dev = max([worst_dev, *(abs(t - res.t_end) for t in res.ends.values())])
        lead = plan_move_info(max(steps, key=abs), **path)[1]
        kinds["triangle" if lead.triangle else "trapezoid"] += 1
        kinds["3 or 4 axes"] += len(steps) >= 3
        kinds["prescale > 1"] += path["prescale"] > 1
        kinds["decel < accel / 10"] += path["decel"] < path["accel"] / 10
        kinds["accel < decel / 10"] += path["accel"] < path["decel"] / 10
        for n, plan in zip(steps, plans, strict=True):
            kinds[f"{abs(n)}-step axis" if abs(n) <= 3 else "ramps > 3000 steps" if plan.sa > 3000 else "other"] += 1
            kinds["negative axis"] += n < 0
    print(
        f"{checked} moves ({refused} refused): worst spread of the last pulses {worst_ticks} ticks, "
        f"{worst_c0:.3g} c0_slow; worst last pulse {worst_dev:.3f} ticks from the ideal end; {dict(kinds)}"
    )
    for kind in (
        "triangle",
        "trapezoid",
        "0-step axis",
        "1-step axis",
        "2-step axis",
        "3-step axis",
        "ramps > 3000 steps",
    ):
        assert kinds[kind] >= 10, kinds
    for kind in ("3 or 4 axes", "prescale > 1", "decel < accel / 10", "accel < decel / 10", "negative axis"):
        assert kinds[kind] >= 100, kinds


def test_random_small_moves_keep_every_pulse_within_a_moves_bound() -> None:
    # the whole pulse train of each axis, not only its end, against the ideal of its scaled values
    rng = random.Random(SEED + 1)
    print(f"seed {SEED + 1} (STEPRAMP_SEED={SEED} replays it)")
    worst = 0.0
    checked = 0
    while checked < 150:
        steps, path = random_move(rng)
        if max(abs(n) for n in steps) > 3000:
            continue
        try:
            plans = plan_coordinated(steps, **path)
        except ValueError:
            continue
        worst = max(worst, check_pulses(steps, path, plans, f"random move {checked} (seed {SEED + 1}) {steps} {path}"))
        checked += 1
    print(f"{checked} moves: worst pulse at {worst:.3f} of its bound")


# --------------------------------------------------------------------------------------------------------------------
# the prediction behind the end: time_before_last against the model's sum of interval values
# --------------------------------------------------------------------------------------------------------------------


def _model_time_before_last(plan: Plan) -> float:
    """The exact sum (ticks) of the model's interval values 1 .. L - 1 (their accumulated time before the floor)."""
    total = 0
    left = plan.steps - 2
    for value, count in value_runs(plan):
        take = min(count, left)
        total += value * take
        left -= take
        if left == 0:
            break
    return total / 2**32


@pytest.mark.parametrize("seed", range(2))
def test_time_before_last_predicts_the_model(seed: int) -> None:
    # closed forms for the recurrences (their mean truncation included) against the model running them: within
    # 0.02 ticks for ramps up to 200,000 steps (without the truncation terms the accel ramp's sum is off by about one
    # Q32.16 LSB per value: 3 ticks at 200,000 values)
    rng = random.Random(SEED + 10 + seed)
    worst = 0.0
    for _ in range(40):
        prescale = rng.choice((1, 64, 65535))
        period = math.ceil(MIN_INTERVAL_CLKS / prescale) * _log_uniform(rng, 1.0, 2.0)
        n_a, n_d = _log_uniform(rng, 1.0, 2e5), _log_uniform(rng, 1.0, 2e5)
        steps = round(n_a + n_d + _log_uniform(rng, 1.0, 1e5)) if rng.random() < 0.7 else round(n_a + n_d) // 2 + 3
        plan = plan_move(**design_args(steps, period, n_a, n_d, 200.0, _log_uniform(rng, 1e5, 1e8), prescale))
        err = abs(time_before_last(plan) - _model_time_before_last(plan))
        assert err <= 0.02, f"{plan}: predicted {time_before_last(plan)}, model {_model_time_before_last(plan)}"
        worst = max(worst, err)
    print(f"worst prediction error {worst:.2e} ticks")


def test_time_before_last_of_a_hand_made_plan() -> None:
    # test_model.py's hand-made plan (L = 8, sa = 4, sd = 5): the exact values c_first, c_sa, c_sd and, from the
    # seeds, A_1 + A_2 = A_0 (P(1) + P(2)) plus the mean truncation 2 - (P(1) + P(2)), D_2 + D_1 as D_2 (1 + 1 / P'(2))
    plan = Plan(9, 0, 3, 0x38000, 0x50000, 4, 0x24000, 5, 0x28000, 0x30000, 0x20002, 0x1_8000_0000, 1 << 16)
    p1, p2 = 3 / 5, 3 / 5 * 7 / 9
    accel = 0x30000 * (p1 + p2) + 2 - (p1 + p2)
    # D_1 = D_2 * 9/7: the first step of the recurrence from r = 0 loses (2 * 2 - 1) / 7 on average
    decel = 0x20002 * (1 + 9 / 7) - 3 / 7
    want = (0x38000 + 0x24000 + 0x28000 + accel + decel) / 65536
    assert time_before_last(plan) == pytest.approx(want, rel=1e-12)
    assert abs(time_before_last(plan) - _model_time_before_last(plan)) < 1e-4
    for n in (0, 1, 2):  # nothing before the last interval of a 2-step move, no interval below it
        assert time_before_last(dataclasses.replace(plan, steps=n, sa=1, sd=1)) == 0.0


# --------------------------------------------------------------------------------------------------------------------
# bad input
# --------------------------------------------------------------------------------------------------------------------

BAD_INPUTS: list[tuple[Any, Path, str]] = [
    ([], AVR446, "no axes"),
    ([1] * (MAX_AXES + 1), AVR446, "9 axes: at most 8 axes are coordinated"),
    ([0, 0, 0], AVR446, "every axis has 0 steps"),
    ([10, 2.5], AVR446, "axis 1: steps must be an integer"),
    ([10, True], AVR446, "axis 1: steps must be an integer"),
    ([10, -(2**31)], AVR446, "axis 1: |steps| must be <= 2^31 - 1 = 2147483647, got -2147483648"),
    ("12", AVR446, "steps must be a sequence of step counts"),
    (12, AVR446, "steps must be a sequence of step counts"),
    ([10, 5], {**AVR446, "accel": 0.0}, "accel must be finite and > 0"),
    ([10, 5], {**AVR446, "speed": math.nan}, "speed must be finite and > 0"),
    ([10, 5], {**AVR446, "prescale": 0}, "prescale must be an integer in 1 .. 65535"),
    # the lead too fast for the engine: plan_move's reason, for the lead's axis
    (
        [10, 400],
        {**AVR446, "accel": 1e6, "decel": 1e6, "speed": 1e4},
        "axis 1 (400 steps, accel, decel and speed times 1): speed too high",
    ),
    # a path of 2^48 ticks or more (7,000 years of 1.3 MHz ticks): its end is not placed on a tick by doubles
    (
        [329_689_501],
        {"accel": 3.8e7, "decel": 1.55e5, "speed": 8.77e-7, "spr": 10756.75, "fclk": 84743112.2, "prescale": 64},
        "the path lasts 2.90756e+17 ticks, 2^48 or more",
    ),
    # a 2-step axis beside a long, slow lead: its one interval lasts the whole move, more than 2^32 ticks
    (
        [100_000, 2],
        _designed(100_000, 60_000.0, 10.0, 10.0),
        "axis 1 (2 steps, accel, decel and speed times 1.00001e-05): c_first = ",
    ),
]


@pytest.mark.parametrize(("steps", "path", "reason"), BAD_INPUTS, ids=[r for _, _, r in BAD_INPUTS])
def test_bad_input_raises_with_the_reason(steps: Any, path: Path, reason: str) -> None:
    with pytest.raises(ValueError, match="^" + re.escape(reason)):
        plan_coordinated(steps, **path)


def test_every_axis_count_from_one_to_eight() -> None:
    for count in range(1, MAX_AXES + 1):
        steps = [round(500 / (k + 1)) * (-1) ** k for k in range(count)]
        res = check_move(steps, AVR446, f"{count} axes")
        assert len(res.ends) == count
