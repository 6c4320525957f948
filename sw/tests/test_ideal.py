# SPDX-License-Identifier: MIT
"""Physics checks of the ideal trajectory (the judge)."""

from __future__ import annotations

import itertools
import math

import pytest

from stepramp.models import ideal

SPR = 200.0
ALPHA = 2.0 * math.pi / SPR
FCLK = 1e6


def _move(steps: int, a: float, d: float, v: float, prescale: int = 1) -> ideal.IdealMove:
    """A move given in steps units (a, d in steps/s^2, v in steps/s)."""
    return ideal.ideal_move(steps, a * ALPHA, d * ALPHA, v * ALPHA, SPR, FCLK, prescale)


def test_c0_formula() -> None:
    # c0 = f_tick * sqrt(2 alpha / accel): accel 4 rad/s^2, alpha = 2 pi / 200, f_tick = 250 kHz
    expected = 250e3 * math.sqrt(2.0 * (2.0 * math.pi / 200.0) / 4.0)
    assert ideal.c0(4.0, 200.0, 1e6, 4) == pytest.approx(expected, rel=1e-15)
    assert ideal.cd0(4.0, 200.0, 1e6, 4) == pytest.approx(expected, rel=1e-15)


def test_first_interval_is_c0_for_long_accel() -> None:
    move = _move(1000, 5000.0, 5000.0, 4000.0)  # n_a = 1600 > L / 2: triangle, accel over ~500 steps
    c0 = FCLK * math.sqrt(2.0 / 5000.0)
    assert move.intervals()[0] == pytest.approx(c0, rel=1e-12)
    assert ideal.c0(5000.0 * ALPHA, SPR, FCLK) == pytest.approx(c0, rel=1e-12)


def test_accel_pulses_follow_sqrt_law() -> None:
    move = _move(500, 2000.0, 3000.0, 1000.0)  # n_a = 250 steps
    c0 = FCLK * math.sqrt(2.0 / 2000.0)
    t = move.pulse_times()
    for k in (0, 1, 2, 10, 100, 249):
        assert t[k] == pytest.approx(c0 * math.sqrt(k), rel=1e-12, abs=1e-9)


def test_last_interval_is_cd0_for_long_decel() -> None:
    move = _move(1000, 8000.0, 3000.0, 2000.0)
    cd0 = FCLK * math.sqrt(2.0 / 3000.0)
    assert move.intervals()[-1] == pytest.approx(cd0, rel=1e-9)


def test_cruise_intervals_are_the_period() -> None:
    move = _move(1000, 10000.0, 10000.0, 2000.0)  # n_a = n_d = 200
    assert not move.triangle
    period = FCLK / 2000.0
    cruise = move.intervals()[250:700]
    assert all(iv == pytest.approx(period, rel=1e-9) for iv in cruise)


def test_symmetric_move_is_symmetric() -> None:
    for steps, v in ((301, 1500.0), (300, 5000.0), (2, 100.0), (3, 100.0)):
        iv = _move(steps, 7000.0, 7000.0, v).intervals()
        for i in range(len(iv)):
            assert iv[i] == pytest.approx(iv[-1 - i], rel=1e-9)


def test_trapezoid_total_time_closed_form() -> None:
    for steps, a, d, v, prescale in ((1001, 3000.0, 7000.0, 1500.0, 1), (5000, 123.0, 4567.0, 100.0, 3)):
        move = _move(steps, a, d, v, prescale)
        length = steps - 1
        assert not move.triangle
        expected = (length / v + v / (2 * a) + v / (2 * d)) * FCLK / prescale
        assert move.pulse_times()[-1] == pytest.approx(expected, rel=1e-12)
        assert move.t_end * FCLK / prescale == pytest.approx(expected, rel=1e-12)


def test_triangle_peak_speed() -> None:
    a, d, v, steps = 3000.0, 1000.0, 5000.0, 801  # n_a + n_d = 4167 + 12500 > 800: triangle
    length = steps - 1
    move = _move(steps, a, d, v)
    assert move.triangle
    v_peak = math.sqrt(2.0 * a * d * length / (a + d))
    assert move.v_peak == pytest.approx(v_peak, rel=1e-12)
    assert v_peak < v
    assert ideal.peak_speed(steps, a * ALPHA, d * ALPHA, v * ALPHA, SPR) == pytest.approx(v_peak * ALPHA, rel=1e-12)
    # the peak is reached at x_p = L d / (a + d), at time v_peak / a; the move lasts v_peak (1/a + 1/d)
    assert move.x_a == pytest.approx(length * d / (a + d), rel=1e-12)
    assert move.time_at(move.x_a) == pytest.approx(v_peak / a * FCLK, rel=1e-12)
    assert move.pulse_times()[-1] == pytest.approx(v_peak * (1 / a + 1 / d) * FCLK, rel=1e-12)
    assert move.speed_at(move.x_a) == pytest.approx(v_peak, rel=1e-12)


def test_peak_speed_is_the_requested_one_when_reached() -> None:
    assert ideal.peak_speed(10000, 50.0, 80.0, 12.5, SPR) == pytest.approx(12.5, rel=1e-12)


def test_pulse_count_and_edge_cases() -> None:
    args = {"accel": 100.0, "decel": 100.0, "speed": 10.0, "spr": SPR, "fclk": FCLK}
    assert ideal.pulse_times(0, **args) == []
    assert ideal.pulse_times(1, **args) == [0.0]
    assert len(ideal.pulse_times(57, **args)) == 57
    assert ideal.pulse_times(-57, **args) == ideal.pulse_times(57, **args)
    t = ideal.pulse_times(500, **args)
    assert t[0] == 0.0
    assert all(t1 > t0 for t0, t1 in itertools.pairwise(t))


def test_two_step_move_single_interval() -> None:
    # L = 1: triangle peaking at x_p = d / (a + d); one interval = sqrt(2 x_p / a) + sqrt(2 (1 - x_p) / d)
    a, d = 400.0, 100.0
    move = _move(2, a, d, 1e6)
    x_p = d / (a + d)
    expected = (math.sqrt(2 * x_p / a) + math.sqrt(2 * (1 - x_p) / d)) * FCLK
    assert move.intervals() == [pytest.approx(expected, rel=1e-12)]


def test_speed_is_continuous() -> None:
    move = _move(2000, 3000.0, 1000.0, 1500.0)
    for x in (move.x_a, move.x_d):
        assert move.speed_at(x - 1e-9) == pytest.approx(move.speed_at(x + 1e-9), rel=1e-6)
