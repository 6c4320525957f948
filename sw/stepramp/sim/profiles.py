# SPDX-License-Identifier: MIT
"""Named move profiles shared by the pure-Python tests and the RTL (cocotb/GHDL) tests.

The RTL simulator runs ~0.4 M clock cycles/s, so every profile is kept short: each move lasts well
under 300,000 clock cycles (most under 100,000) and all of them together under ~4 M cycles. Most
profiles are designed in the tick domain with :func:`_design` (cruise period in ticks and the length of
each ramp in steps) and converted to the physical units that :func:`stepramp.board.plan.plan_move` takes.
"""

from __future__ import annotations

import dataclasses
import math
import random
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from stepramp.board.plan import MIN_INTERVAL_CLKS, RAMP_EXACT, Plan, plan_move


@dataclass(frozen=True)
class Profile:
    """One move: signed steps, accel/decel in rad/s^2, speed in rad/s, spr steps/rev, fclk in Hz."""

    name: str
    steps: int
    accel: float
    decel: float
    speed: float
    spr: float
    fclk: float
    prescale: int = 1

    def args(self) -> dict[str, Any]:
        """Keyword arguments for plan_move / ideal_move."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "name"}


def design_args(
    steps: int, period: float, n_a: float, n_d: float, spr: float = 200.0, fclk: float = 1e6, prescale: int = 1
) -> dict[str, Any]:
    """plan_move keyword arguments from tick-domain design values.

    period: cruise period in ticks; n_a, n_d: steps needed to reach / leave the cruise speed
    (a triangle when n_a + n_d > steps - 1, with its peak at (steps - 1) * n_a / (n_a + n_d)).
    """
    alpha = 2.0 * math.pi / spr
    v = fclk / prescale / period  # steps/s
    accel, decel = alpha * v * v / (2.0 * n_a), alpha * v * v / (2.0 * n_d)
    return dict(steps=steps, accel=accel, decel=decel, speed=alpha * v, spr=spr, fclk=fclk, prescale=prescale)


def _design(
    name: str,
    steps: int,
    period: float,
    n_a: float,
    n_d: float,
    *,
    spr: float = 200.0,
    fclk: float = 1e6,
    prescale: int = 1,
) -> Profile:
    """A profile from tick-domain design values (design_args)."""
    return Profile(name, **design_args(steps, period, n_a, n_d, spr, fclk, prescale))


NAMED_PROFILES: list[Profile] = [
    # --- trapezoids: STOP -> ACCEL -> RUN -> DECEL -> STOP ---------------------------------------
    _design("trap_basic", 200, 200.0, 30.3, 30.3),
    _design("trap_asym", 180, 150.7, 20.5, 45.7),
    _design("trap_fractional_period", 300, 100.37, 25.6, 17.2),
    _design("trap_long_cruise", 1200, 70.25, 40.4, 40.4),
    _design("trap_microstep_3200", 400, 120.0, 60.7, 35.2, spr=3200.0, fclk=4e6),
    _design("trap_negative", -150, 180.0, 22.7, 31.9),
    _design("trap_speed_limit_edge", 600, 64.0, 50.5, 50.5),  # floor(64) * 1 == MIN_INTERVAL_CLKS
    _design("trap_cruise_one_interval", 60, 300.0, 20.2, 20.9),  # x_a, x_d in the same interval
    _design("trap_cruise_two_intervals", 60, 300.0, 20.2, 37.9),  # sd == sa + 1: no cruise value
    _design("trap_m0_zero", 80, 250.0, 10.5, 1.5),  # sd == L - 1: decel recurrence unused
    _design("trap_m0_one", 80, 250.0, 10.5, 2.5),  # sd == L - 2: one decel recurrence value
    _design("trap_run_to_stop", 90, 250.0, 12.5, 0.6),  # sd == L: from RUN straight to the last interval
    _design("trap_sa_two", 70, 250.0, 1.5, 8.5),  # sa == 2: no accel recurrence value
    _design("trap_sa_three", 70, 250.0, 2.5, 8.5),  # sa == 3: one accel recurrence value (A_1)
    # --- PRESCALE > 1 -------------------------------------------------------------------------------
    _design("trap_prescale_4", 250, 60.5, 24.3, 28.8, fclk=4e6, prescale=4),
    _design("trap_prescale_100", 150, 3.3, 12.4, 15.6, fclk=10e6, prescale=100),
    _design("trap_prescale_1000_neg", -40, 1.6, 4.6, 5.3, fclk=10e6, prescale=1000),
    _design("trap_prescale_7_avr_clock", 320, 40.5, 35.3, 35.3, fclk=3.6864e6, prescale=7),
    _design("triangle_prescale_3_neg", -121, 30.0, 90.0, 70.0, fclk=3e6, prescale=3),
    # --- triangles: ACCEL -> DECEL ----------------------------------------------------------------
    _design("triangle_sym", 101, 80.0, 80.0, 80.0),
    _design("triangle_asym", 90, 90.0, 40.0, 90.0),
    _design("triangle_negative", -75, 100.0, 60.0, 45.0),
    _design("triangle_long_ramp", 801, 64.5, 600.0, 600.0),  # remainder not carried into decel
    _design("triangle_sa_sd_one", 3, 200.0, 0.3, 30.0),  # peak inside interval 1: sa == sd == 1
    _design("triangle_peak_last_interval", 10, 150.0, 50.0, 0.5),  # sa == sd == L
    # --- start directly in RUN (sa == 1) --------------------------------------------------------------
    _design("run_start", 120, 150.0, 0.4, 15.3),
    _design("run_start_short_ramps", 80, 150.0, 0.6, 0.6),  # sa == 1 and sd == L
    _design("run_start_negative", -100, 140.0, 0.25, 9.7),
    _design("run_start_prescale_5", 110, 25.5, 0.9, 20.1, fclk=5e6, prescale=5),
    # --- accel >> decel and decel >> accel (ratio 50 .. 100) ---------------------------------------
    _design("ratio_accel_50", 300, 90.0, 2.2, 110.0),
    _design("ratio_decel_50", 300, 90.0, 110.0, 2.2),
    _design("ratio_accel_100_triangle", 120, 64.0, 20.0, 2000.0),
    _design("ratio_decel_100_triangle", -120, 64.0, 2000.0, 20.0),
    # --- 0, 1, 2 and 3 step moves -----------------------------------------------------------------------
    _design("steps_0", 0, 200.0, 20.0, 20.0),
    _design("steps_1", 1, 200.0, 20.0, 20.0),
    _design("steps_neg_1", -1, 200.0, 20.0, 20.0),
    _design("steps_2", 2, 200.0, 20.0, 20.0),
    _design("steps_neg_2_asym", -2, 200.0, 5.0, 50.0),
    _design("steps_3", 3, 200.0, 20.0, 20.0),
    _design("steps_3_run", 3, 200.0, 0.3, 0.3),  # sa == 1, sd == 2: all three intervals exact
    _design("steps_neg_3_prescale_2", -3, 150.0, 10.0, 3.0, fclk=2e6, prescale=2),
    # --- delays above 2^16 ticks (32-bit integer parts) ---------------------------------------------
    _design("long_first_delay", 4, 1000.0, 1100.0, 11.0),  # c0 ~ 66,300 ticks > 2^16
    # --- integer and near-integer boundaries ------------------------------------------------------
    # x_a == 20.0 exactly in the driver's double arithmetic (accel nudged by ulps): sa == 21
    Profile("boundary_x_a_integer", 120, 19634.95408493621, 12875.379727827023, 157.07963267948966, 200.0, 1e6),
    # x_d == 80.0 exactly: sd == 81
    Profile("boundary_x_d_integer", 120, 19156.052765791424, 10069.20722304421, 157.07963267948966, 200.0, 1e6),
    # triangle with its peak at x_p == 30.0 exactly: sa == sd == 31
    Profile("boundary_triangle_integer", 61, 31415.926535897936, 31415.926535897936, 314.1592653589793, 200.0, 1e6),
    _design("boundary_x_a_just_below", 120, 200.0, 20.0 - 1e-9, 30.5),
    _design("boundary_x_a_just_above", 120, 200.0, 20.0 + 1e-9, 30.5),
    _design("boundary_x_d_just_below", 120, 200.0, 20.5, 39.0 + 1e-9),
    _design("boundary_x_d_just_above", 120, 200.0, 20.5, 39.0 - 1e-9),
    # --- the AVR446 demo default ----------------------------------------------------------------------
    # spr 400, accel = decel = 40 rad/s^2, speed 20 rad/s, 400 steps: a triangle (peak ~1008 steps/s)
    # of ~0.79 s. f_clk = 100 kHz is the slowest round clock that meets MIN_INTERVAL_CLKS
    # (floor(99.2) = 99 clocks at the peak); the move costs ~79,000 clock cycles.
    Profile("avr446_demo", 400, 40.0, 40.0, 20.0, 400.0, 100e3),
]


def _random_profiles(seed: int, count: int) -> list[Profile]:
    """Random valid profiles from a fixed seed, each lasting under ~100,000 clock cycles."""
    rng = random.Random(seed)
    out: list[Profile] = []
    while len(out) < count:
        prescale = rng.choice((1, 1, 1, 2, 3, 8, 16))
        fclk = rng.choice((1e6, 2e6, 2.5e6, 4e6, 10e6))
        spr = rng.choice((48.0, 200.0, 400.0, 1600.0, 3200.0))
        period = math.ceil(MIN_INTERVAL_CLKS / prescale) + rng.uniform(0.0, 150.0 / prescale)
        n_a = math.exp(rng.uniform(math.log(0.2), math.log(200.0)))
        n_d = n_a * math.exp(rng.uniform(-math.log(60.0), math.log(60.0)))
        steps = rng.randint(2, 500) * rng.choice((1, -1))
        profile = _design(f"random_{len(out):02d}", steps, period, n_a, n_d, spr=spr, fclk=fclk, prescale=prescale)
        if _estimated_cycles(profile) < 100_000:
            out.append(profile)
    return out


def _estimated_cycles(p: Profile) -> float:
    """Ideal duration of the move in clock cycles (closed form, trapezoid or triangle)."""
    alpha = 2.0 * math.pi / p.spr
    a, d, v = p.accel / alpha, p.decel / alpha, p.speed / alpha
    length = max(abs(p.steps) - 1, 0)
    if v * v / (2 * a) + v * v / (2 * d) <= length:
        t = length / v + v / (2 * a) + v / (2 * d)
    else:
        v_p = math.sqrt(2 * a * length * d / (a + d))
        t = v_p / a + v_p / d
    return t * p.fclk


RANDOM_SEED = 446
RANDOM_PROFILES: list[Profile] = _random_profiles(RANDOM_SEED, 14)

PROFILES: list[Profile] = NAMED_PROFILES + RANDOM_PROFILES
"""Every valid profile, named ones first."""

PROFILES_BY_NAME: dict[str, Profile] = {p.name: p for p in PROFILES}

_OK: dict[str, Any] = {
    "steps": 100,
    "accel": 1000.0,
    "decel": 1000.0,
    "speed": 50.0,
    "spr": 200.0,
    "fclk": 1e6,
    "prescale": 1,
}


def _bad(**changes: Any) -> dict[str, Any]:
    return {**_OK, **changes}


INVALID_INPUTS: list[tuple[dict[str, Any], str]] = [
    (_bad(accel=0.0), "accel must be finite and > 0"),
    (_bad(accel=-5.0), "accel must be finite and > 0"),
    (_bad(decel=math.inf), "decel must be finite and > 0"),
    (_bad(decel=0.0), "decel must be finite and > 0"),
    (_bad(speed=math.nan), "speed must be finite and > 0"),
    (_bad(speed=-1.0), "speed must be finite and > 0"),
    (_bad(spr=0.0), "spr must be finite and > 0"),
    (_bad(fclk=-1e6), "fclk must be finite and > 0"),
    (_bad(fclk=math.inf), "fclk must be finite and > 0"),
    (_bad(prescale=0), "prescale must be an integer in 1 .. 65535"),
    (_bad(prescale=65536), "prescale must be an integer in 1 .. 65535"),
    (_bad(prescale=2.0), "prescale must be an integer"),
    (_bad(steps=2**31), "|steps| must be <= 2^31 - 1"),
    (_bad(steps=-(2**31)), "|steps| must be <= 2^31 - 1"),
    (_bad(steps=1.5), "steps must be an integer"),
    # a very slow acceleration: c0 = 1e6 * sqrt(2 * 0.0314 / 1e-8) ~ 2.5e9 ticks is fine, 1e-12 is not
    (_bad(accel=1e-12), "overflows its register"),
    # a very slow speed: cruise period ~ 6.4e9 ticks > 2^32
    (_bad(speed=5e-6, accel=1e-6, decel=1e-6, steps=3), "overflows its register"),
    # peak faster than one step per tick
    (_bad(speed=1e5, accel=1e9, decel=1e9), "interval shorter than 1 tick"),
    # peak interval 63.x ticks at prescale 1 < MIN_INTERVAL_CLKS
    (
        _bad(speed=2 * math.pi / 200 * 1e6 / 63.5, accel=1e6, decel=1e6),
        "speed too high for the hardware to compute the next delay in time",
    ),
    # 40 clocks per step: 20 ticks at prescale 2, 20 * 2 < 64
    (_bad(speed=2 * math.pi / 200 * 1e6 / 40.0, accel=1e6, decel=1e6, prescale=2), "speed too high for the hardware"),
]
"""Invalid plan_move keyword arguments and a substring of the expected ValueError message."""


def exact_plan(
    steps: int, prescale: int, first: float, cruise: float = 100.0, last: float = 100.0, direction: int = 0
) -> Plan:
    """A hand-made move whose intervals are all exact values (no recurrence), in ticks: interval 1 = `first`,
    intervals 2 .. L - 1 = `cruise` (Q32.32, so a fraction alternates the tick counts), interval L = `last`
    (sa = 1, sd = L). The driver never plans intervals this short; the step-spacing tests need them."""
    length = steps - 1
    return Plan(
        steps=steps,
        direction=direction,
        prescale=prescale,
        c_first=round(first * 2**16),
        c_last=round(last * 2**16) if length >= 2 else 0,
        sa=1 if length >= 1 else 0,
        c_sa=0,
        sd=length,
        c_sd=0,
        accel_seed=0,
        decel_seed=0,
        cruise=round(cruise * 2**32) if length >= 3 else 0,
        stop_ratio=0,
    )


EXACT_CLOCK_FACTOR = 4
"""The largest factor exact_profile needs: the fastest profiles' 64-clock intervals times 4 keep the exact mode's
MIN_INTERVAL_CLKS_EXACT = 256."""


def exact_factor(profile: Profile) -> int:
    """The smallest k in 1 .. EXACT_CLOCK_FACTOR for which the exact mode takes the profile at k times its clock and
    PRESCALE (the same ticks, every interval k times as many clocks); ValueError when none does."""
    for k in range(1, EXACT_CLOCK_FACTOR + 1):
        try:
            plan_move(**_scaled(profile, k).args(), ramp=RAMP_EXACT)
        except ValueError:
            continue
        return k
    raise ValueError(f"{profile.name}: not an exact-mode move at up to {EXACT_CLOCK_FACTOR} times its clock")


def _scaled(profile: Profile, k: int) -> Profile:
    return dataclasses.replace(profile, fclk=profile.fclk * k, prescale=profile.prescale * k)


def exact_profile(profile: Profile) -> Profile:
    """The profile as the exact mode runs it: at exact_factor times its clock and PRESCALE (the same ticks and the
    same plan but PRESCALE), so that its shortest interval keeps MIN_INTERVAL_CLKS_EXACT, and no slower than that
    (simulation time)."""
    return _scaled(profile, exact_factor(profile))


EXACT_PROFILES: list[Profile] = [exact_profile(p) for p in PROFILES]
"""The 64 profiles in exact mode (exact_profile; plan them with ramp=RAMP_EXACT)."""


SPRS = (24.0, 200.0, 400.0, 1000.0, 1600.0, 3200.0, 25600.0, 51200.0)
"""The steps per revolution random_design_moves draws from (each also times 1.37)."""


@dataclass(frozen=True)
class MoveRanges:
    """What random_design_moves draws from: a cruise period of min_clks / PRESCALE ticks plus up to period_span more,
    long_steps steps for the first moves and short_steps for the others, the steps per revolution sprs."""

    min_clks: int
    period_span: float
    long_steps: tuple[int, int]
    short_steps: tuple[int, int]
    sprs: tuple[float, ...] = SPRS


def random_design_moves(
    seed: int, count: int, long_moves: int, ranges: MoveRanges, plan: Callable[[dict[str, Any]], object]
) -> list[dict[str, Any]]:
    """count random plan_move arguments (design_args), the ones plan takes without a ValueError: PRESCALE 1 .. 8,
    spr from ranges.sprs (times 1 or 1.37), f_clk 100 kHz .. 200 MHz (log-uniform), the cruise period of ranges,
    ramps of 0.05 .. 30,000 steps to reach it and a deceleration ratio up to 100 both ways; the first long_moves of
    ranges.long_steps steps, the others of ranges.short_steps, either direction."""
    min_clks, period_span, long_steps, short_steps, sprs = dataclasses.astuple(ranges)
    rng = random.Random(seed)
    out: list[dict[str, Any]] = []
    while len(out) < count:
        prescale = rng.randint(1, 8)
        spr = rng.choice(sprs) * rng.choice((1, 1.37))
        fclk = math.exp(rng.uniform(math.log(1e5), math.log(2e8)))
        period = math.ceil(min_clks / prescale) + math.exp(rng.uniform(0.0, math.log(period_span)))
        n_a = math.exp(rng.uniform(math.log(0.05), math.log(3e4)))
        n_d = n_a * math.exp(rng.uniform(-math.log(100.0), math.log(100.0)))
        steps = rng.randint(*long_steps) if len(out) < long_moves else rng.randint(*short_steps)
        args = design_args(steps * rng.choice((1, -1)), period, n_a, n_d, spr, fclk, prescale)
        try:
            plan(args)
        except ValueError:
            continue
        out.append(args)
    return out


def random_exact_moves(seed: int, count: int, long_moves: int) -> list[dict[str, Any]]:
    """Random moves the exact mode takes (sw/tests/test_exact.py, scripts/exact_check.py): random_design_moves with
    cruise intervals from 256 clocks, the first long_moves of 20,000 .. 100,000 steps, the others 1 .. 3,000."""
    ranges = MoveRanges(256, 1e4, (20_000, 100_000), (1, 3000))
    return random_design_moves(seed, count, long_moves, ranges, lambda args: plan_move(**args, ramp=RAMP_EXACT))
