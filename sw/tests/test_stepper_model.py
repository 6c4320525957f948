# SPDX-License-Identifier: MIT
"""The stepping-logic model against AVR446 Table 2-1, the sine/cosine definition and the timing rules."""

from __future__ import annotations

import math
from itertools import pairwise, product

import pytest

from stepramp.models import stepping as sm

MICROSTEPS = [1, 2, 4, 8, 16, 32, 64, 128]

# AVR446 Table 2-1, half stepping, written out as the application note prints it (positions 1 .. 8).
AVR446_WINDING_A = ["+", "+", "0", "-", "-", "-", "0", "+"]
AVR446_WINDING_B = ["0", "+", "+", "+", "0", "-", "-", "-"]
SIGN = {"+": 1, "-": -1, "0": 0}


def test_half_step_table_is_avr446_table_2_1() -> None:
    expected = [(SIGN[a], SIGN[b]) for a, b in zip(AVR446_WINDING_A, AVR446_WINDING_B, strict=True)]
    assert list(sm.HALF_STEP_TABLE) == expected


def test_wave_one_winding_full_two_windings_half_interleaves() -> None:
    assert all(abs(a) + abs(b) == 1 for a, b in sm.WAVE_TABLE)
    assert all(abs(a) == abs(b) == 1 for a, b in sm.FULL_STEP_TABLE)
    for k in range(4):
        assert sm.HALF_STEP_TABLE[2 * k] == sm.WAVE_TABLE[k]
        assert sm.HALF_STEP_TABLE[2 * k + 1] == sm.FULL_STEP_TABLE[k]
    # Every state of the cycle is distinct and each step changes exactly one winding by one level.
    assert len(set(sm.HALF_STEP_TABLE)) == 8
    for h in range(8):
        (a0, b0), (a1, b1) = sm.HALF_STEP_TABLE[h], sm.HALF_STEP_TABLE[(h + 1) % 8]
        assert abs(a1 - a0) + abs(b1 - b0) == 1


@pytest.mark.parametrize("mode", [sm.MODE_WAVE, sm.MODE_FULL, sm.MODE_HALF])
def test_field_turns_one_position_per_step(mode: int) -> None:
    """atan2(B, A) of the currents is the model's field angle and grows by 360 / n per position."""
    n = sm.positions_per_cycle(mode)
    for pos in range(-20, 20):
        a, b = sm.winding_currents(mode, pos)
        angle = math.degrees(math.atan2(b, a)) % 360
        assert angle == pytest.approx(sm.field_angle(mode, pos))
        nxt = sm.field_angle(mode, pos + 1)
        assert (nxt - sm.field_angle(mode, pos)) % 360 == pytest.approx(360 / n)


def test_electrical_position_is_position_mod_n() -> None:
    assert sm.positions_per_cycle(sm.MODE_WAVE) == 4
    assert sm.positions_per_cycle(sm.MODE_FULL) == 4
    assert sm.positions_per_cycle(sm.MODE_HALF) == 8
    assert sm.positions_per_cycle(sm.MODE_PWM, 4, 16) == 64
    assert sm.positions_per_cycle(sm.MODE_PWM, 7, 16) == 64  # clamped to G_MICROSTEPS
    assert sm.positions_per_cycle(sm.MODE_PWM, 0, 16) == 4
    assert sm.electrical_position(sm.MODE_HALF, -1) == 7
    assert sm.electrical_position(sm.MODE_FULL, -(2**31)) == 0
    assert sm.electrical_position(sm.MODE_PWM, -1, 3, 64) == 31
    # Wrapping the 32-bit counter keeps the electrical position (n divides 2^32).
    for mode, u in product([1, 2, 3, 4], range(8)):
        n = sm.positions_per_cycle(mode, u, 128)
        assert (2**31 - 1) % n == (2**31 - 1 - 2**32) % n


def test_stepdir_mode_other_modes_and_disable_are_all_off() -> None:
    for mode, pos in product([0, 5, 6, 7], range(-3, 9)):
        assert sm.winding_levels(mode, pos) == (0, 0, 0, 0)
    for mode, pos in product([1, 2, 3], range(8)):
        assert sm.winding_levels(mode, pos, enable=False) == (0, 0, 0, 0)
    a, b = sm.pwm_windings(3, 4, 100, enable=False)
    assert a.duty == b.duty == 0


def test_bridge_encoding_never_shoots_through() -> None:
    assert sm.bridge_inputs(1) == (1, 0)
    assert sm.bridge_inputs(-1) == (0, 1)
    assert sm.bridge_inputs(0) == (0, 0)
    for cur in (-1, 0, 1):
        assert sm.bridge_current(*sm.bridge_inputs(cur)) == cur
    with pytest.raises(ValueError, match="shoot-through"):
        sm.bridge_current(1, 1)
    for mode, pos in product(range(8), range(16)):
        if sm.effective_mode(mode) == sm.MODE_PWM:
            continue
        a1, a2, b1, b2 = sm.winding_levels(mode, pos)
        assert not (a1 and a2) and not (b1 and b2)


@pytest.mark.parametrize("microsteps", MICROSTEPS)
def test_cos_table(microsteps: int) -> None:
    t = sm.cos_table(microsteps, 12)
    assert len(t) == microsteps + 1
    assert t[0] == 4096 and t[-1] == 0
    assert all(x >= y for x, y in pairwise(t))
    if microsteps <= 64:  # at 128 the first two entries round to the same 12-bit value
        assert all(x > y for x, y in pairwise(t))
    if microsteps >= 2:
        assert t[microsteps // 2] == round(4096 / math.sqrt(2))  # 45 degrees: 2896


@pytest.mark.parametrize("bits", [4, 8, 12, 16])
def test_no_rounding_ties(bits: int) -> None:
    """No table value sits near a .5 boundary, so VHDL's and Python's cos (1 ulp apart at worst) round alike."""
    for k in range(129):
        x = (1 << bits) * math.cos(math.pi * k / 256)
        assert abs(x - math.floor(x) - 0.5) > 1e-6, (bits, k, x)


def test_microsteps_must_be_power_of_two() -> None:
    for bad in (0, 3, 12, 256):
        with pytest.raises(ValueError, match="power of two"):
            sm.cos_table(bad)


@pytest.mark.parametrize(("microsteps", "u"), [(g, u) for g in MICROSTEPS for u in range(8)])
def test_pwm_sine_cosine(microsteps: int, u: int) -> None:
    """Sum of squares ~ constant, quadrature, agreement with the quarter-wave table and the half-step table."""
    bits = 12
    m = 1 << sm.effective_ustep_log2(u, microsteps)
    n = 4 * m
    table = sm.cos_table(microsteps, bits)
    lg = int(math.log2(microsteps))
    for pos in range(-n, 2 * n):
        a, b = sm.pwm_windings(pos, u, 1000, microsteps, bits)
        # constant current vector: |(A, B)| = 2^bits within the rounding of both
        assert abs(math.hypot(a.magnitude, b.magnitude) - 4096) <= 1.0
        # quadrature: B(theta) = A(theta - 90 degrees)
        a_lag, _ = sm.pwm_windings(pos - m, u, 1000, microsteps, bits)
        assert (b.polarity, b.magnitude) == (a_lag.polarity, a_lag.magnitude)
        # the quarter-wave table with the index scaled to full resolution gives the same magnitudes
        e = (pos % n) << (lg - sm.effective_ustep_log2(u, microsteps))
        quad, f = divmod(e, microsteps)
        mag_a, mag_b = (table[f], table[microsteps - f]) if quad % 2 == 0 else (table[microsteps - f], table[f])
        assert (a.magnitude, b.magnitude) == (mag_a, mag_b), (pos, e)
        assert a.polarity in ((-1,) if quad in (1, 2) else (1,)) or a.magnitude == 0
        assert b.polarity in ((-1,) if quad in (2, 3) else (1,)) or b.magnitude == 0
        # at multiples of 45 degrees the polarities are the half-step table's
        if m >= 2 and (pos % n) % (m // 2) == 0:
            h = (pos % n) // (m // 2)
            assert (a.polarity, b.polarity) == sm.HALF_STEP_TABLE[h]


def test_fewer_microsteps_subsample_the_full_table() -> None:
    for u, pos in product(range(5), range(-70, 70)):
        coarse = sm.pwm_windings(pos, u, 777, 16)
        fine = sm.pwm_windings(pos << (4 - u), 4, 777, 16)
        assert coarse == fine


def test_duty_rounding() -> None:
    assert sm.duty_counts(4096, 1000) == 1000  # always on
    assert sm.duty_counts(0, 1000) == 0
    assert sm.duty_counts(4096, 1) == 0 and sm.duty_counts(4096, 0) == 0  # outputs held off
    assert sm.duty_counts(2048, 3) == 2  # 1.5 rounds up
    assert sm.duty_counts(2896, 100) == 71  # 70.7
    for mag, period in product(range(0, 4097, 7), (2, 3, 10, 99, 1000, 65535)):
        d = sm.duty_counts(mag, period)
        assert abs(d - mag * period / 4096) <= 0.5
        assert 0 <= d <= period
    for pos in range(64):
        a, b = sm.pwm_windings(pos, 4, 500)
        for w, v in ((a, math.cos(2 * math.pi * pos / 64)), (b, math.sin(2 * math.pi * pos / 64))):
            assert abs(w.duty - abs(v) * 500) <= 0.5 + 500 / 8192


def test_pwm_levels() -> None:
    a, b = sm.pwm_windings(40, 4, 100)  # 225 degrees: A-, B-
    assert a.polarity == b.polarity == -1 and a.duty == b.duty == 71
    assert sm.pwm_levels(a, b, 0) == (0, 1, 0, 1)
    assert sm.pwm_levels(a, b, 70) == (0, 1, 0, 1)
    assert sm.pwm_levels(a, b, 71) == (0, 0, 0, 0)
    a, b = sm.pwm_windings(0, 4, 100)
    assert (a.polarity, a.duty, b.polarity, b.duty) == (1, 100, 0, 0)
    assert sm.pwm_levels(a, b, 99) == (1, 0, 0, 0)


def test_step_width_rule() -> None:
    assert sm.step_pulse_width(0) == 1
    assert sm.step_pulse_width(7) == 7
    assert sm.check_step_widths([10, 100], [15, 105], 5, exact=True) == []
    assert sm.check_step_widths([10, 100], [15, 104], 5) != []
    assert sm.check_step_widths([10], [16], 5) == []
    assert sm.check_step_widths([10], [16], 5, exact=True) != []
    assert sm.check_step_widths([10], [11], 0, exact=True) == []
    assert sm.check_step_widths([10], [], 5) == []  # not finished: not judged


def test_dir_timing_rule() -> None:
    assert sm.check_dir_timing([100, 200], [150], 50, 50) == []
    assert len(sm.check_dir_timing([100, 200], [150], 51, 50)) == 1
    assert len(sm.check_dir_timing([100, 200], [150], 50, 51)) == 1
    assert len(sm.check_dir_timing([100], [100], 0, 0)) == 1  # never at the same edge
    assert sm.check_dir_timing([100], [101], 0, 0) == []
    assert sm.check_dir_timing([101], [100], 0, 0) == []


@pytest.mark.parametrize(("hold", "setup"), list(product([0, 1, 2, 3, 17, 300], [0, 1, 4, 5, 6, 9, 250])))
def test_gate_keeps_setup_and_hold(hold: int, setup: int) -> None:
    """The gate's own DIR change and first STEP keep the rules, as early as the rules allow."""
    for last, request in product([None, 0, 50, 99, 100], [100, 101, 140]):
        g = sm.gate_timing(request, True, last, hold, setup)
        assert g.dir_edge is not None
        rises = [] if last is None else [last]
        assert sm.check_dir_timing([*rises, g.first_step_edge], [g.dir_edge], setup, hold) == []
        assert g.first_step_edge - g.dir_edge == max(setup, sm.GATE_SETUP_MIN)
        earliest = request + 1 if last is None else max(request + 1, last + max(hold, 1))
        assert g.dir_edge == earliest
        assert g.start_edge >= g.dir_edge + 1
        same = sm.gate_timing(request, False, last, hold, setup)
        assert same.dir_edge is None and same.latency == 1
        assert same.first_step_edge == request + sm.START_TO_FIRST_STEP == request + 4


def test_step_positions() -> None:
    assert sm.step_positions(0, [0, 0, 1, 1, 1]) == [1, 2, 1, 0, -1]


def test_winding_latency() -> None:
    """On/off modes switch with STEP; PWM waits for one complete round of the serial duty multiplier."""
    for mode in (0, 1, 2, 3, 5, 6, 7):
        assert sm.winding_latency(mode) == 0
    assert sm.pwm_round(12) == 15
    assert sm.winding_latency(sm.MODE_PWM) == 30 == 2 * 12 + 6
    assert sm.winding_latency(sm.MODE_PWM, 16) == 38
    assert sm.winding_latency(sm.MODE_PWM, 16) < sm.MIN_INTERVAL_CLKS
