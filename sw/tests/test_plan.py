# SPDX-License-Identifier: MIT
"""Tests of the driver's setup math (stepramp.board.plan)."""

from __future__ import annotations

import dataclasses
import math
import re
from fractions import Fraction

import pytest

from stepramp.board.plan import (
    FRAC_CRUISE,
    FRAC_RAMP,
    MAX_STEPS,
    MIN_INTERVAL_CLKS,
    REG_WIDTHS,
    SEED_FACTOR,
    Plan,
    decel_product,
    plan_move,
    plan_move_info,
)
from stepramp.models import ideal
from stepramp.models.engine import tick_times
from stepramp.sim.profiles import INVALID_INPUTS, PROFILES

SPR = 200.0
ALPHA = 2.0 * math.pi / SPR
#: The plan table of docs/algorithm.md ("What the driver computes"): each field of Plan, in order, and its width in
#: bits (uint31: 31, Q32.16: 48, Q32.32: 64, Q16.16: 32; the seeds' registers are 64 bits: Q32.16 in AVR446 mode,
#: a seed word in exact mode).
TABLE: list[tuple[str, int]] = [
    ("steps", 31),
    ("direction", 1),
    ("prescale", 16),
    ("c_first", 48),
    ("c_last", 48),
    ("sa", 31),
    ("c_sa", 48),
    ("sd", 31),
    ("c_sd", 48),
    ("accel_seed", 64),
    ("decel_seed", 64),
    ("cruise", 64),
    ("stop_ratio", 32),
]
TABLE_FIELDS = [name for name, _ in TABLE]


def _args(steps: int, a: float, d: float, v: float, fclk: float = 1e6, prescale: int = 1) -> dict:
    """plan_move arguments from steps units (a, d in steps/s^2, v in steps/s), spr 200."""
    return {
        "steps": steps,
        "accel": a * ALPHA,
        "decel": d * ALPHA,
        "speed": v * ALPHA,
        "spr": SPR,
        "fclk": fclk,
        "prescale": prescale,
    }


def test_constants() -> None:
    assert FRAC_RAMP == 16
    assert FRAC_CRUISE == 32
    assert MIN_INTERVAL_CLKS == 64
    assert MAX_STEPS == 2**31 - 1
    assert abs(SEED_FACTOR - 0.6759782400672847) < 1e-15


def test_fields_and_widths_match_the_table() -> None:
    # the registers, then `ramp` (not a register: the core's G_RAMP the plan is for)
    assert [f.name for f in dataclasses.fields(Plan)] == [*TABLE_FIELDS, "ramp"]
    assert dict(TABLE) == REG_WIDTHS
    plan = plan_move(**_args(100, 1e5, 1e5, 2000.0))
    d = plan.to_dict()
    assert list(d) == TABLE_FIELDS
    assert d == {k: v for k, v in dataclasses.asdict(plan).items() if k != "ramp"}
    assert all(type(v) is int for v in d.values())


def test_plan_rejects_values_that_do_not_fit() -> None:
    good = plan_move(**_args(100, 1e5, 1e5, 2000.0)).to_dict()
    Plan(**good)
    for name, width in REG_WIDTHS.items():
        with pytest.raises(ValueError, match=f"Plan.{name}"):
            Plan(**{**good, name: 1 << width})
        with pytest.raises(ValueError, match=f"Plan.{name}"):
            Plan(**{**good, name: -1})


@pytest.mark.parametrize(("kwargs", "message"), INVALID_INPUTS, ids=[m for _, m in INVALID_INPUTS])
def test_invalid_inputs(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        plan_move(**kwargs)


def test_bool_is_not_an_integer() -> None:
    with pytest.raises(ValueError, match="prescale must be an integer"):
        plan_move(**_args(10, 1e5, 1e5, 2000.0, prescale=True))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="steps must be an integer"):
        plan_move(**{**_args(10, 1e5, 1e5, 2000.0), "steps": True})


def test_zero_and_one_step_moves() -> None:
    for steps in (0, 1, -1):
        plan = plan_move(**_args(steps, 1e5, 1e5, 2000.0))
        assert plan.steps == abs(steps)
        assert plan.direction == (1 if steps < 0 else 0)
        assert plan.sa == plan.sd == plan.c_first == plan.c_last == plan.cruise == 0
    # no interval, so no speed limit either
    assert plan_move(**_args(1, 1e5, 1e5, 1e9)).steps == 1


def test_largest_step_count() -> None:
    plan = plan_move(**_args(-MAX_STEPS, 1e5, 2e5, 4000.0))
    assert (plan.steps, plan.direction) == (MAX_STEPS, 1)
    n_a, n_d = 4000.0**2 / 2e5, 4000.0**2 / 4e5
    assert plan.sa == math.floor(n_a) + 1
    assert plan.sd == math.floor(MAX_STEPS - 1 - n_d) + 1


def test_direction_from_sign() -> None:
    pos = plan_move(**_args(500, 3e5, 2e5, 5000.0))
    neg = plan_move(**_args(-500, 3e5, 2e5, 5000.0))
    assert pos.direction == 0
    assert neg.direction == 1
    assert dataclasses.replace(neg, direction=0) == pos


def test_sa_sd_speed_reached() -> None:
    # AVR446 scenario 1: max_s_lim = v^2 / (2 a) < accel_lim = L d / (a + d)
    a, d, v, steps = 40000.0, 25000.0, 3000.0, 700
    length = steps - 1
    max_s_lim = v * v / (2 * a)  # 112.5
    accel_lim = length * d / (a + d)
    assert max_s_lim < accel_lim
    decel_val = max_s_lim * a / d  # steps needed to stop: 180
    plan, info = plan_move_info(**_args(steps, a, d, v))
    assert not info.triangle
    assert plan.sa == math.floor(max_s_lim) + 1 == 113
    assert plan.sd == math.floor(length - decel_val) + 1 == 520
    assert info.v_peak == pytest.approx(v)


def test_sa_sd_decel_before_speed_reached() -> None:
    # AVR446 scenario 2: max_s_lim > accel_lim: decel starts at n1 = L d / (a + d)
    a, d, v, steps = 40000.0, 25000.0, 6000.0, 700
    length = steps - 1
    accel_lim = length * d / (a + d)  # 268.8
    assert v * v / (2 * a) > accel_lim
    plan, info = plan_move_info(**_args(steps, a, d, v))
    assert info.triangle
    assert plan.sa == plan.sd == math.floor(accel_lim) + 1 == 269
    assert info.v_peak == pytest.approx(math.sqrt(2 * a * accel_lim))
    assert info.m0 == length - plan.sd - 1


def _recurrence_by_sum(seed: float, n: int) -> list[float]:
    """The continuous recurrence values A_1 .. A_n from A_0 = seed, one multiplication at a time."""
    values = []
    for k in range(1, n + 1):
        seed *= (4 * k - 1) / (4 * k + 1)
        values.append(seed)
    return values


def test_exact_intervals_and_seeds() -> None:
    """c_last, c_sa, c_sd are the ideal intervals; c_first is the ideal interval 1 plus half the accel recurrence's
    time deficit (ideal time of intervals 2 .. sa-1 less the recurrence values there), and each seed carries half
    its ramp's deficit spread over its recurrence values (the accel seed less the integer recurrence's mean
    truncation): recomputed here by plain summation, from ideal.py."""
    for args in (_args(700, 40000.0, 25000.0, 3000.0), _args(-350, 1000.0, 90000.0, 800.0, 8e6, 3)):
        plan, info = plan_move_info(**args)
        move = ideal.ideal_move(**args)
        iv = move.intervals()
        length = len(iv)
        c0 = ideal.c0(args["accel"], SPR, args["fclk"], args["prescale"])
        cd0 = ideal.cd0(args["decel"], SPR, args["fclk"], args["prescale"])
        # accel: intervals 2 .. sa-1 take A_1 .. A_(sa-2)
        seed_a = 0.6759782400672847 * c0
        accel_values = _recurrence_by_sum(seed_a, plan.sa - 2)
        deficit_a = sum(iv[1 : plan.sa - 1]) - sum(accel_values)
        assert 0.01 * c0 < deficit_a < 0.014 * c0  # the recurrence runs fast near rest
        for field, i, extra in (
            ("c_first", 1, deficit_a / 2),
            ("c_last", length, 0.0),
            ("c_sa", plan.sa, 0.0),
            ("c_sd", plan.sd, 0.0),
        ):
            assert getattr(plan, field) == pytest.approx((iv[i - 1] + extra) * 2**16, abs=2), field
        scale_a = 1 + deficit_a / 2 / sum(accel_values)
        # less the integer recurrence's mean truncation: 1 - P(j) LSB at index j, spread over values summing to
        # sum(accel_values) / seed_a seeds (docs/algorithm.md, "Recurrence deficit")
        unit_a = sum(accel_values) / seed_a
        truncation = sum(1.0 - value / seed_a for value in accel_values)
        assert plan.accel_seed == pytest.approx(seed_a * scale_a * 2**16 - truncation / unit_a, abs=1)
        f_tick = args["fclk"] / args["prescale"]
        assert plan.cruise == pytest.approx(f_tick * ALPHA / args["speed"] * 2**32, rel=1e-15, abs=1)
        # decel: intervals sd+1 .. L-1 take D_m0 .. D_1, the recurrence run forward from cd0' for m0 steps
        decel_values = _recurrence_by_sum(0.6759782400672847 * cd0, info.m0)
        assert info.m0 == length - plan.sd - 1 >= 1
        deficit_d = sum(iv[plan.sd : length - 1]) - sum(decel_values)
        assert 0.01 * cd0 < deficit_d < 0.014 * cd0
        scale_d = 1 + deficit_d / 2 / sum(decel_values)
        assert plan.decel_seed == pytest.approx(decel_values[-1] * scale_d * 2**16, abs=1)
        # the plan's model: the move ends half the decel deficit early, never more than half a deficit off
        assert tick_times(plan)[-1] - move.time_at(length) == pytest.approx(-deficit_d / 2, abs=2)


def test_decel_seed_unused_is_zero() -> None:
    # n_d = 0.3: sd == L, m0 = -1
    plan, info = plan_move_info(**_args(50, 1e5, 1000.0**2 / 0.6, 1000.0))
    assert info.m0 < 1
    assert plan.decel_seed == 0


def test_decel_product() -> None:
    assert decel_product(0) == 1.0
    assert decel_product(1) == pytest.approx(3 / 5, rel=1e-15)
    exact = Fraction(1)
    for k in range(1, 301):
        exact *= Fraction(4 * k - 1, 4 * k + 1)
    assert decel_product(300) == pytest.approx(float(exact), rel=1e-14)
    # Gamma-function form
    for m in (10, 257, 5000):
        ref = math.exp(math.lgamma(m + 0.75) + math.lgamma(1.25) - math.lgamma(m + 1.25) - math.lgamma(0.75))
        assert decel_product(m) == pytest.approx(ref, rel=1e-11)
    # the recurrence holds across the switch-over and up to the largest index
    for m in (255, 256, 257, 258, 10**6, 2**31 - 3):
        assert decel_product(m) / decel_product(m - 1) == pytest.approx((4 * m - 1) / (4 * m + 1), rel=1e-14)
    # asymptotics: prod ~ Gamma(5/4) / Gamma(3/4) / sqrt(m + 1/2) (relative correction O(m^-2)).
    # Two plain lgamma values of ~4.4e10 would cancel to ~3e-6 relative here, i.e. ~0.15 cd0 over the ramp.
    m = 2**31 - 3
    ref = math.gamma(1.25) / math.gamma(0.75) / math.sqrt(m + 0.5)
    assert decel_product(m) == pytest.approx(ref, rel=1e-14)


def test_cruise_mean_period_over_max_steps() -> None:
    # Q32.32 rounding of the period is enough: over 2^31 - 1 cruise steps the error stays < 1 tick, plus what
    # the double inputs themselves carry (a few ulp of the period per step, relevant only for huge periods).
    for fclk, speed, prescale in ((10e6, 0.777, 1), (50e6, 12.3456, 7), (1e6, 0.0301, 1), (1e8, 1e-3, 1)):
        plan = plan_move(MAX_STEPS, 1e3, 1e3, speed, SPR, fclk, prescale)
        period = Fraction(fclk) / prescale * Fraction(2 * math.pi) / Fraction(SPR) / Fraction(speed)
        total = plan.cruise * MAX_STEPS >> 32
        assert abs(total - period * MAX_STEPS) < 1 + float(period) * MAX_STEPS * 2**-50


def test_speed_limit() -> None:
    # the shortest interval floor(f_tick / v_peak) * prescale must be >= MIN_INTERVAL_CLKS
    too_fast = "speed too high for the hardware to compute the next delay in time"
    for fclk, prescale, ticks in ((1e6, 1, 64), (8e6, 2, 32), (1e6, 5, 13), (1e6, 32, 2), (1e7, 100, 1)):
        v_ok = fclk / prescale / (ticks + 1e-6)
        v_bad = fclk / prescale / (ticks - 1e-6)
        plan_move(**_args(1000, 1e8, 1e8, v_ok, fclk, prescale))
        with pytest.raises(ValueError, match=too_fast if ticks > 1 else "interval shorter than 1 tick"):
            plan_move(**_args(1000, 1e8, 1e8, v_bad, fclk, prescale))


def test_speed_limit_uses_triangle_peak() -> None:
    # requested 1e5 steps/s (10 ticks) but the short move peaks at sqrt(a L) = 7071 steps/s (141 ticks)
    plan, info = plan_move_info(**_args(101, 5e5, 5e5, 1e5))
    assert info.triangle
    assert info.min_interval == pytest.approx(1e6 / math.sqrt(5e5 * 100))
    assert plan.sa == plan.sd == 51


def test_interval_shorter_than_one_tick() -> None:
    with pytest.raises(ValueError, match="interval shorter than 1 tick"):
        plan_move(**_args(1000, 1e10, 1e10, 2e6))


def test_register_overflow() -> None:
    # f_tick = 1 Hz; the cruise period (and interval 1) just below / above 2^32 ticks
    big = 2.0**32
    plan = plan_move(**_args(3, 1e-12, 1e-12, 1.0 / (big - 4096.0), fclk=1.0))
    assert abs(plan.cruise / 2**32 - (2**32 - 4096)) < 1e-3
    assert plan.c_first >> 16 < 2**32
    with pytest.raises(ValueError, match="overflows its register"):
        plan_move(**_args(3, 1e-12, 1e-12, 1.0 / (big + 4096.0), fclk=1.0))


def test_every_profile_is_valid() -> None:
    for p in PROFILES:
        plan = plan_move(**p.args())
        assert plan.steps == abs(p.steps)
        if plan.steps >= 2:
            length = plan.steps - 1
            assert 1 <= plan.sa <= plan.sd <= length
            # where rules coincide, the registers hold the same exact value
            if plan.sa == 1:
                assert plan.c_sa == plan.c_first
            if plan.sd == length:
                assert plan.c_sd == plan.c_last
            if plan.sa == plan.sd:
                assert plan.c_sa == plan.c_sd
            if length == 1:
                assert plan.c_first == plan.c_last
