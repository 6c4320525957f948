# SPDX-License-Identifier: MIT
"""Driver setup math: a move in physical units -> the engine's registers (docs/algorithm.md).

Everything is computed in double precision and each register value is rounded once. The exact
intervals are computed piecewise (accel / cruise / decel part of each one-step interval) with
cancellation-free square-root differences, so they stay accurate for moves of up to 2^31 - 1 steps.
Plan itself, the register widths and the ramp kinds are in stepramp.spec (imported here too).
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass

from stepramp.models.exact import ramp_constant
from stepramp.spec import (
    FRAC_CRUISE,
    FRAC_RAMP,
    MAX_PRESCALE,
    MAX_STEPS,
    RAMP_AVR446,
    RAMP_EXACT,
    REG_WIDTHS,
    Plan,
    check_ramp,
)
from stepramp.spec import check_widths as check_widths

MIN_INTERVAL_CLKS = 64
"""Shortest interval, in clocks, that leaves the engine time to compute the next value."""
MIN_INTERVAL_CLKS_EXACT = 256
"""The same in exact mode (G_RAMP = 1), for a move whose ramp constants are below 2^48 (c0 and cd0 below 2^20 ticks):
a ramp value there takes one or two square roots (docs/stepramp_engine.md, "Latency budget in exact mode")."""
MIN_INTERVAL_CLKS_EXACT_WIDE = 304
"""The same for a move with a ramp constant of 2^48 or more (wider square roots)."""
RAMPS = {"avr446": RAMP_AVR446, "exact": RAMP_EXACT}
"""The ramp modes by name (the CLI's --ramp)."""
SEED_FACTOR = math.gamma(0.75) / (2.0 * math.gamma(1.25))
"""Gamma(3/4) / (2 Gamma(5/4)) = 0.67597824...: recurrence value at index 0, in units of c0."""
_LGAMMA_RATIO_0 = math.lgamma(1.25) - math.lgamma(0.75)
_PRODUCT_LOOP_MAX = 256


def exact_narrow(c0_ticks: float) -> bool:
    """Whether the ramp constant of c0 (exact.ramp_constant) is below 2^48: round(c0^2 * 2^8) < 2^48, without
    rounding (and False for a square that is not finite)."""
    return c0_ticks * c0_ticks * 256.0 < 2.0**48 - 0.5


def min_interval_clks(ramp: int, *c0_ticks: float) -> int:
    """The shortest interval in clocks the core built with G_RAMP = ramp computes the next value in time for; in exact
    mode for a move whose ramps have the first intervals c0_ticks (MIN_INTERVAL_CLKS_EXACT when all their ramp
    constants are below 2^48, else MIN_INTERVAL_CLKS_EXACT_WIDE)."""
    if ramp != RAMP_EXACT:
        return MIN_INTERVAL_CLKS
    return MIN_INTERVAL_CLKS_EXACT if all(exact_narrow(c) for c in c0_ticks) else MIN_INTERVAL_CLKS_EXACT_WIDE


@dataclass(frozen=True)
class MoveInfo:
    """Informative values of a planned move (not registers); a, d, v in steps/s^2 and steps/s."""

    f_tick: float
    length: int
    a: float
    d: float
    v: float
    x_a: float
    x_d: float
    v_peak: float
    triangle: bool
    c0: float
    cd0: float
    m0: int
    min_interval: float
    """Shortest interval of the move, f_tick / v_peak, in ticks (inf when there is no interval)."""


def decel_product(m: int) -> float:
    """prod_{k=1..m} (4k-1)/(4k+1) = Gamma(m+3/4) Gamma(5/4) / (Gamma(m+5/4) Gamma(3/4)).

    A plain product for small m; above, the Stirling series of the log ratio arranged without the
    cancellation of two large lgamma values (which would cost ~1e-6 relative at m ~ 1e9).
    """
    if m <= _PRODUCT_LOOP_MAX:
        p = 1.0
        for k in range(1, m + 1):
            p *= (4 * k - 1) / (4 * k + 1)
        return p
    z1 = m + 0.75
    z2 = m + 1.25
    log_ratio = (m + 0.25) * math.log1p(-0.5 / z2) - 0.5 * math.log(z2) + 0.5

    def series(z: float) -> float:
        zi2 = 1.0 / (z * z)
        return (1.0 / 12.0 - zi2 * (1.0 / 360.0 - zi2 / 1260.0)) / z

    return math.exp(log_ratio + series(z1) - series(z2) + _LGAMMA_RATIO_0)


def _check_positive(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    if not math.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    return float(value)


def _check_int(name: str, value: int) -> int:
    if isinstance(value, bool):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    try:
        return operator.index(value)
    except TypeError:
        raise ValueError(f"{name} must be an integer, got {value!r}") from None


def _to_fixed(name: str, ticks: float, frac: int, width: int) -> int:
    """Round a delay in ticks to an unsigned fixed-point register value, or raise ValueError."""
    scaled = ticks * (1 << frac)  # a huge finite delay overflows to inf here
    value = round(scaled) if math.isfinite(scaled) else 1 << width
    if value >= 1 << width:
        raise ValueError(
            f"{name} = {ticks:.6g} ticks overflows its register (integer part >= 2^{width - frac}): "
            "delay too long; use a larger accel/decel/speed, a lower f_clk or a larger prescale"
        )
    return value


class _Ramp:
    """Piecewise exact trajectory used by the driver (distinct code from ideal.py on purpose)."""

    def __init__(self, length: int, a: float, d: float, v: float, f_tick: float) -> None:
        self.length = length
        n_a = v * v / (2.0 * a)
        n_d = v * v / (2.0 * d)
        x_d = length - n_d
        if math.isfinite(x_d) and n_a <= x_d:
            self.triangle = False
            self.x_a, self.x_d, self.n_d, self.v_peak = n_a, x_d, n_d, v
        else:
            self.triangle = True
            x_p = length * (d / (a + d))
            self.x_a = self.x_d = x_p
            self.n_d = length * (a / (a + d))
            self.v_peak = math.sqrt(2.0 * a * x_p)
        self.k_a = f_tick * math.sqrt(2.0 / a)  # c0: ticks per unit of sqrt(position)
        self.k_d = f_tick * math.sqrt(2.0 / d)  # cd0
        self.k_c = f_tick / self.v_peak if self.v_peak > 0 else math.inf

    def boundary(self, x: float) -> int:
        """Index of the interval containing position x: floor(x) + 1 clamped to [1, L]."""
        return min(max(math.floor(x) + 1, 1), self.length)

    def interval(self, i: int) -> float:
        """Exact interval i (from position i-1 to i) in ticks."""
        p = i - 1
        q = self.length - i
        ov_a = min(max(self.x_a - p, 0.0), 1.0)  # part of [p, p+1] in the acceleration
        ov_d = min(max(self.n_d - q, 0.0), 1.0)  # part of [p, p+1] in the deceleration
        ov_c = max(1.0 - ov_a - ov_d, 0.0)
        t = 0.0
        if ov_a > 0.0:
            t += self.k_a * ov_a / (math.sqrt(p + ov_a) + math.sqrt(p))
        if ov_c > 0.0 and not self.triangle:
            t += self.k_c * ov_c
        if ov_d > 0.0:
            t += self.k_d * ov_d / (math.sqrt(q + ov_d) + math.sqrt(q))
        return t


def accel_truncation(n: int) -> float:
    """The accel recurrence's mean truncation (Q32.16 LSB): by how much its integer values A_1 .. A_n (remainder
    carried) exceed the continuous ones A_0 P(j) in sum, n - (P(1) + .. + P(n)) = n - (2 (n + 3/4) P(n) - 3/2).

    A_j = A_(j-1) - q_j, (4j + 1) q_j + r_j = 2 A_(j-1) + r_(j-1): A_j is the continuous value plus E_j with
    E_j = E_(j-1) (4j - 1) / (4j + 1) + (r_j - r_(j-1)) / (4j + 1). With the remainders uniform (mean 2 j, r_0 = 0)
    the mean of E_j is 1 - P(j): about one LSB per value (docs/algorithm.md, "Recurrence deficit").
    """
    return n - (2.0 * (n + 0.75) * decel_product(n) - 1.5)


def register_doubles(ramp: _Ramp, sa: int, sd: int, m0: int) -> dict[str, float]:
    """The unrounded values (ticks) of the ramp registers: the exact intervals and the seeds, with the recurrences'
    time deficits put back (docs/algorithm.md, "Recurrence deficit"). The C driver computes the same doubles.

    The recurrence values are A_j = A_0 P(j) (accel) and D_m = D_m0 P(m) / P(m0) (decel), P = decel_product, and their
    sums telescope (sum_{j<=n} Gamma(j + 3/4) / Gamma(j + 5/4) = 2 (Gamma(n + 7/4) / Gamma(n + 5/4) - Gamma(7/4) /
    Gamma(5/4))): A_1 + .. + A_n = A_0 (2 (n + 3/4) P(n) - 3/2). The ideal time of the same intervals is
    c0 (sqrt(n + 1) - 1). Half of each deficit (about 0.007 c0 on a long ramp) goes into the ramp's seed, spread over
    its recurrence values; the other half into interval 1 for the accel ramp (c_first) and nowhere for the decel ramp
    (c_last stays exact), which halves the largest error again. c_sa and c_sd stay exact: a soft stop starts from c_sa.
    The accel seed also loses the integer recurrence's mean truncation, accel_truncation(n) LSB over its n values
    (docs/algorithm.md, "Recurrence deficit"), which would otherwise make a long ramp n / 2^16 ticks late.
    """
    c0 = ramp.k_a
    cd0 = ramp.k_d
    seed_a = SEED_FACTOR * c0
    seed_d = SEED_FACTOR * cd0 * decel_product(m0) if m0 >= 1 else 0.0
    first_extra = 0.0
    n_a = sa - 2  # intervals 2 .. sa-1 take the accel recurrence values A_1 .. A_n
    if n_a >= 1:
        unit_a = 2.0 * (n_a + 0.75) * decel_product(n_a) - 1.5  # (A_1 + .. + A_n) / A_0
        half_a = (c0 * (math.sqrt(n_a + 1.0) - 1.0) - seed_a * unit_a) / 2.0
        first_extra = half_a
        seed_a = seed_a + half_a / unit_a - accel_truncation(n_a) / unit_a / (1 << FRAC_RAMP)
    if m0 >= 1:  # intervals sd+1 .. L-1 take the decel recurrence values D_m0 .. D_1
        unit_d = 2.0 * (m0 + 0.75) - 1.5 / decel_product(m0)  # (D_1 + .. + D_m0) / D_m0
        half_d = (cd0 * (math.sqrt(m0 + 1.0) - 1.0) - seed_d * unit_d) / 2.0
        seed_d = seed_d + half_d / unit_d
    return {
        "t_first": ramp.interval(1) + first_extra,
        "t_last": ramp.interval(ramp.length),
        "t_sa": ramp.interval(sa),
        "t_sd": ramp.interval(sd),
        "t_accel_seed": seed_a,
        "t_decel_seed": seed_d,
    }


def _cruise(f_tick: float, v: float) -> int:
    """round(f_tick / v * 2^32): the cruise period in Q32.32, from the same doubles as every other field.

    32 fraction bits leave no drift from truncation (2^-33 tick per step at most). What remains is the double
    quotient's own rounding, a few 1e-16 relative, the precision the speed was given in: over 2^31 steps it
    stays under a tick for periods up to about 1e6 ticks (a move of 2^31 steps at such a period lasts decades).
    Plain doubles keep the C driver bit-identical to this one.
    """
    period = f_tick / v
    scaled = period * (1 << FRAC_CRUISE)
    value = round(scaled) if math.isfinite(scaled) else 1 << REG_WIDTHS["cruise"]
    if value >= 1 << REG_WIDTHS["cruise"]:
        raise ValueError(
            f"cruise = {period:.6g} ticks overflows its register (integer part >= 2^32): "
            "delay too long; use a larger speed, a lower f_clk or a larger prescale"
        )
    return value


def _stop_ratio(accel: float, decel: float) -> int:
    """accel / decel in Q16.16, rounded, saturated at 2^32 - 1 (also when the quotient overflows a double)."""
    ratio = accel / decel * (1 << 16)
    top = (1 << REG_WIDTHS["stop_ratio"]) - 1
    return round(ratio) if ratio < top else top


def check_motion_args(
    accel: float, decel: float, speed: float, spr: float, fclk: float, prescale: int
) -> tuple[float, float, float, float, float, int]:
    """The physical arguments checked in this order (finite and > 0, prescale an integer 1 .. MAX_PRESCALE), as
    floats; ValueError with the reason for the first that is not."""
    values = (accel, decel, speed, spr, fclk)
    checked = [_check_positive(name, value) for name, value in zip(_MOTION, values, strict=True)]
    prescale = _check_int("prescale", prescale)
    if not 1 <= prescale <= MAX_PRESCALE:
        raise ValueError(f"prescale must be an integer in 1 .. {MAX_PRESCALE}, got {prescale}")
    return checked[0], checked[1], checked[2], checked[3], checked[4], prescale


def steps_units(
    accel: float, decel: float, speed: float, spr: float, fclk: float, prescale: int, squares: bool = False
) -> tuple[float, float, float, float]:
    """(f_tick, a, d, v) in ticks/s and steps units, each finite and > 0 (with squares, its square too: a segment
    squares them), or ValueError with the reason."""
    f_tick = fclk / prescale
    alpha = 2.0 * math.pi / spr
    a, d, v = accel / alpha, decel / alpha, speed / alpha
    for name, value in (("accel", a), ("decel", d), ("speed", v), ("f_tick", f_tick)):
        ok = math.isfinite(value) and value > 0.0
        if not ok or (squares and not (math.isfinite(value * value) and value * value > 0.0)):
            raise ValueError(f"{name} in steps units is out of range ({value!r}); check spr and the units")
    return f_tick, a, d, v


_MOTION = ("accel", "decel", "speed", "spr", "fclk")


def plan_move_info(
    steps: int,
    accel: float,
    decel: float,
    speed: float,
    spr: float,
    fclk: float,
    prescale: int = 1,
    ramp: int = RAMP_AVR446,
) -> tuple[Plan, MoveInfo]:
    """Like plan_move, also returning the informative MoveInfo."""
    ramp = check_ramp(ramp)
    steps = _check_int("steps", steps)
    accel, decel, speed, spr, fclk, prescale = check_motion_args(accel, decel, speed, spr, fclk, prescale)
    if abs(steps) > MAX_STEPS:
        raise ValueError(f"|steps| must be <= 2^31 - 1 = {MAX_STEPS}, got {steps}")

    n = abs(steps)
    direction = 1 if steps < 0 else 0
    length = n - 1
    f_tick, a, d, v = steps_units(accel, decel, speed, spr, fclk, prescale)

    if length < 1:  # N = 0 or 1: no interval, nothing for the engine to compute
        info = MoveInfo(f_tick, max(length, 0), a, d, v, 0.0, 0.0, 0.0, True, 0.0, 0.0, 0, math.inf)
        return Plan(n, direction, prescale, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, ramp), info

    curve = _Ramp(length, a, d, v, f_tick)
    min_interval = curve.k_c
    if not math.isfinite(min_interval):
        raise ValueError("peak speed underflows: the delays would overflow their registers")
    if not min_interval >= 1.0:
        raise ValueError(
            f"interval shorter than 1 tick ({min_interval:.6g} ticks at the peak speed): "
            "lower the speed or raise f_clk / lower the prescale"
        )
    least = min_interval_clks(ramp, curve.k_a, curve.k_d)
    if math.floor(min_interval) * prescale < least:
        raise ValueError(
            f"speed too high for the hardware to compute the next delay in time: shortest interval "
            f"floor({min_interval:.6g}) ticks * prescale {prescale} < {least} clocks"
        )

    sa = curve.boundary(curve.x_a)
    sd = curve.boundary(curve.x_d)
    m0 = length - sd - 1
    c0 = curve.k_a
    cd0 = curve.k_d
    q16 = FRAC_RAMP
    w48 = REG_WIDTHS["c_first"]
    info = MoveInfo(
        f_tick, length, a, d, v, curve.x_a, curve.x_d, curve.v_peak, curve.triangle, c0, cd0, m0, min_interval
    )
    if ramp == RAMP_EXACT:
        return _exact_plan(n, direction, prescale, curve, sa, sd, accel, decel, f_tick, v), info
    raw = register_doubles(curve, sa, sd, m0)
    plan = Plan(
        steps=n,
        direction=direction,
        prescale=prescale,
        c_first=_to_fixed("c_first", raw["t_first"], q16, w48),
        c_last=_to_fixed("c_last", raw["t_last"], q16, w48),
        sa=sa,
        c_sa=_to_fixed("c_sa", raw["t_sa"], q16, w48),
        sd=sd,
        c_sd=_to_fixed("c_sd", raw["t_sd"], q16, w48),
        accel_seed=_to_fixed("accel_seed", raw["t_accel_seed"], q16, w48),
        decel_seed=_to_fixed("decel_seed", raw["t_decel_seed"], q16, w48) if m0 >= 1 else 0,
        cruise=_cruise(f_tick, v),
        # accel / decel in Q16.16 (rounded, saturated): sizes the decel ramp of a soft stop
        stop_ratio=_stop_ratio(accel, decel),
    )
    return plan, info


def _exact_plan(
    n: int,
    direction: int,
    prescale: int,
    curve: _Ramp,
    sa: int,
    sd: int,
    accel: float,
    decel: float,
    f_tick: float,
    v: float,
) -> Plan:
    """The registers of an exact-mode move (docs/algorithm.md, "Exact step times"): the exact intervals as in the
    AVR446 mode but without the recurrence deficit, and the ramp constants C = round(c0^2 * 2^8) in the seeds (seed
    words: exact.ramp_constant)."""
    q16 = FRAC_RAMP
    w48 = REG_WIDTHS["c_first"]
    return Plan(
        steps=n,
        direction=direction,
        prescale=prescale,
        c_first=_to_fixed("c_first", curve.interval(1), q16, w48),
        c_last=_to_fixed("c_last", curve.interval(curve.length), q16, w48),
        sa=sa,
        c_sa=_to_fixed("c_sa", curve.interval(sa), q16, w48),
        sd=sd,
        c_sd=_to_fixed("c_sd", curve.interval(sd), q16, w48),
        accel_seed=ramp_constant(curve.k_a),
        decel_seed=ramp_constant(curve.k_d),
        cruise=_cruise(f_tick, v),
        stop_ratio=_stop_ratio(accel, decel),
        ramp=RAMP_EXACT,
    )


def plan_move(
    steps: int,
    accel: float,
    decel: float,
    speed: float,
    spr: float,
    fclk: float,
    prescale: int = 1,
    ramp: int = RAMP_AVR446,
) -> Plan:
    """Plan a move: signed step count, accel/decel in rad/s^2, speed in rad/s, spr steps/rev, fclk Hz, for the
    ramp arithmetic of the core (RAMP_AVR446, or RAMP_EXACT for a core built with G_RAMP = 1).

    Raises ValueError with the reason when the move is not valid for the engine.
    """
    return plan_move_info(steps, accel, decel, speed, spr, fclk, prescale, ramp)[0]
