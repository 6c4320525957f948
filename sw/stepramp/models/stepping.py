# SPDX-License-Identifier: MIT
"""Reference model of the stepping logic (stepramp_stepper): winding tables, PWM duty, STEP/DIR timing rules.

Written from the physics and from AVR446 Table 2-1, not from the RTL:

* The field angle of the two windings is theta = 90 degrees * e / m for an electrical position e of 4 * m
  positions per electrical cycle (m = 1 for wave and two-phase full step, 2 for half step, 2**ustep_log2 for
  microstepping). Winding A carries a current ~ cos(theta), winding B ~ sin(theta). Wave drive sits on the
  multiples of 90 degrees (one winding on), two-phase-on full step halfway between them (both windings on), half
  step interleaves the two: AVR446 Table 2-1 (its "full-stepping" row is the wave drive here).
* The electrical position is the position counter modulo the positions per cycle, so it cannot drift from it;
  a position counting up turns the field from A towards B (A+, A+B+, B+, ...), counting down the other way.
* PWM: magnitude |value| quantised to DUTY_BITS fractional bits, duty = |value| * pwm_period rounded to the
  nearest count; the sign selects the bridge input that carries the PWM.
* Timing: STEP high for max(step_width, 1) clocks; DIR never changes within dir_setup clocks before or dir_hold
  clocks after a STEP rising edge; the start gate holds the engine's start so that both hold.

Times are clock edges (integers): "edge e" is the e-th rising edge of clk, a signal "high after edge e" is '1' in the
cycle that follows it.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

# Modes (the `mode` input).
MODE_STEPDIR = 0
MODE_WAVE = 1
MODE_FULL = 2
MODE_HALF = 3
MODE_PWM = 4
MODE_NAMES: dict[int, str] = {
    MODE_STEPDIR: "stepdir",
    MODE_WAVE: "wave",
    MODE_FULL: "full",
    MODE_HALF: "half",
    MODE_PWM: "pwm",
}

#: Microstep resolutions the RTL accepts for G_MICROSTEPS (powers of two).
MICROSTEPS_RANGE = (1, 128)
DEFAULT_MICROSTEPS = 16
#: Fractional bits of the sine/cosine magnitude (G_DUTY_BITS).
DEFAULT_DUTY_BITS = 12
DUTY_BITS_RANGE = (4, 16)

#: AVR446 Table 2-1, half stepping: (winding A, winding B) current direction for the 8 positions of an electrical
#: cycle, +1 / -1 / 0 (off). Position 0 is A alone, positive; each position turns the field by 45 degrees.
HALF_STEP_TABLE: tuple[tuple[int, int], ...] = (
    (+1, 0),
    (+1, +1),
    (0, +1),
    (-1, +1),
    (-1, 0),
    (-1, -1),
    (0, -1),
    (+1, -1),
)
#: One winding on at a time (AVR446's "full-stepping" row): 0, 90, 180, 270 degrees.
WAVE_TABLE: tuple[tuple[int, int], ...] = HALF_STEP_TABLE[0::2]
#: Two-phase-on full step, both windings on: 45, 135, 225, 315 degrees (about 1.4 times the torque).
FULL_STEP_TABLE: tuple[tuple[int, int], ...] = HALF_STEP_TABLE[1::2]

# ----------------------------------------------------------------------------------------------------------------
# Timing constants (clock edges).
# ----------------------------------------------------------------------------------------------------------------
#: The engine's first pulse comes 2 clocks after the edge that samples its start (docs/stepramp_engine.md).
ENGINE_FIRST_PULSE_LATENCY = 2
#: STEP rises at the edge that samples eng_step = '1' (one register): 1 clock after eng_step goes high.
STEP_LATENCY = 1
#: From the edge that registers eng_start to the edge at which STEP rises for the engine's pulse 0.
START_TO_FIRST_STEP = 1 + ENGINE_FIRST_PULSE_LATENCY + STEP_LATENCY
#: A direction change: the first STEP rising edge comes max(dir_setup, this) clocks after the DIR change.
GATE_SETUP_MIN = START_TO_FIRST_STEP + 1


def pwm_round(duty_bits: int = DEFAULT_DUTY_BITS) -> int:
    """Clocks of one round of the RTL's serial duty multiplier: G_DUTY_BITS + 3."""
    return duty_bits + 3


def winding_latency(mode: int, duty_bits: int = DEFAULT_DUTY_BITS) -> int:
    """Clocks from the STEP rising edge (edge E) until the winding pins show the new position, at the latest.

    On/off modes: 0 (the pins change at edge E with STEP). PWM: the duty of the new position is computed by the
    next complete round of the serial multiplier and compared with the carrier one edge later: the pins show it
    from E + duty_bits + 4 to E + 2 * duty_bits + 6 at the latest (16 .. 30 clocks at 12 bits), well inside the
    shortest step interval (64 clocks).
    """
    if effective_mode(mode) != MODE_PWM:
        return 0
    return 1 + pwm_round(duty_bits) + duty_bits + 2


#: Shortest interval between engine pulses (the driver's MIN_INTERVAL_CLKS); step_width must be below it.
MIN_INTERVAL_CLKS = 64


def effective_mode(mode: int) -> int:
    """Mode values 5 .. 7 behave as 0 (STEP/DIR only)."""
    return mode if mode in MODE_NAMES else MODE_STEPDIR


def effective_ustep_log2(ustep_log2: int, microsteps: int = DEFAULT_MICROSTEPS) -> int:
    """Microsteps actually used are 2**ustep_log2, at most G_MICROSTEPS: larger values are clamped."""
    check_microsteps(microsteps)
    return min(ustep_log2, int(math.log2(microsteps)))


def check_microsteps(microsteps: int) -> None:
    """G_MICROSTEPS must be a power of two in MICROSTEPS_RANGE (the RTL asserts the same)."""
    lo, hi = MICROSTEPS_RANGE
    if not (lo <= microsteps <= hi and microsteps & (microsteps - 1) == 0):
        raise ValueError(f"microsteps must be a power of two in {lo} .. {hi}, not {microsteps}")


def positions_per_cycle(mode: int, ustep_log2: int = 0, microsteps: int = DEFAULT_MICROSTEPS) -> int:
    """Positions of one electrical cycle: 4 (wave, full), 8 (half), 4 * 2**ustep_log2 (PWM); 1 in STEP/DIR mode."""
    mode = effective_mode(mode)
    if mode in (MODE_WAVE, MODE_FULL):
        return 4
    if mode == MODE_HALF:
        return 8
    if mode == MODE_PWM:
        return 4 << effective_ustep_log2(ustep_log2, microsteps)
    return 1


def electrical_position(mode: int, position: int, ustep_log2: int = 0, microsteps: int = DEFAULT_MICROSTEPS) -> int:
    """Electrical position: the (signed) position counter modulo the positions per cycle."""
    return position % positions_per_cycle(mode, ustep_log2, microsteps)


def field_angle(mode: int, position: int, ustep_log2: int = 0, microsteps: int = DEFAULT_MICROSTEPS) -> float:
    """Field angle in degrees (0 .. 360) the windings are meant to produce; NaN in STEP/DIR mode."""
    mode = effective_mode(mode)
    e = electrical_position(mode, position, ustep_log2, microsteps)
    if mode == MODE_WAVE:
        return 90.0 * e
    if mode == MODE_FULL:
        return 45.0 + 90.0 * e
    if mode == MODE_HALF:
        return 45.0 * e
    if mode == MODE_PWM:
        return 360.0 * e / positions_per_cycle(mode, ustep_log2, microsteps)
    return math.nan


def winding_currents(mode: int, position: int, enable: bool = True) -> tuple[int, int]:
    """(A, B) current direction (+1, -1, 0) of the on/off modes; (0, 0) in STEP/DIR mode or when disabled.

    For the PWM mode use pwm_windings (the direction is the sign of cos / sin there).
    """
    mode = effective_mode(mode)
    if mode == MODE_PWM:
        raise ValueError("winding_currents is for the on/off modes; use pwm_windings for mode 4")
    if not enable or mode == MODE_STEPDIR:
        return (0, 0)
    e = electrical_position(mode, position)
    table = {MODE_WAVE: WAVE_TABLE, MODE_FULL: FULL_STEP_TABLE, MODE_HALF: HALF_STEP_TABLE}[mode]
    return table[e]


def bridge_inputs(current: int) -> tuple[int, int]:
    """(IN1, IN2) of a dual-input bridge: + -> (1, 0), - -> (0, 1), off -> (0, 0). Never (1, 1)."""
    if current > 0:
        return (1, 0)
    if current < 0:
        return (0, 1)
    return (0, 0)


def bridge_current(in1: int, in2: int) -> int:
    """Inverse of bridge_inputs; raises ValueError on (1, 1), which would short the supply (shoot-through)."""
    if in1 and in2:
        raise ValueError("IN1 and IN2 both '1': shoot-through")
    return 1 if in1 else -1 if in2 else 0


def winding_levels(mode: int, position: int, enable: bool = True) -> tuple[int, int, int, int]:
    """(a1, a2, b1, b2) of the on/off modes (0 .. 3, 5 .. 7)."""
    a, b = winding_currents(mode, position, enable)
    return (*bridge_inputs(a), *bridge_inputs(b))


# ----------------------------------------------------------------------------------------------------------------
# Sine/cosine PWM.
# ----------------------------------------------------------------------------------------------------------------
def quantise(value: float, bits: int = DEFAULT_DUTY_BITS) -> int:
    """|value| (0 .. 1) in units of 2**-bits, rounded to nearest (halves up): floor(2**bits * |value| + 0.5)."""
    return math.floor((1 << bits) * abs(value) + 0.5)


def sign(value: float, eps: float = 1e-12) -> int:
    """+1, -1, or 0 for a value that is 0 up to floating-point noise (cos(pi / 2) is 6e-17)."""
    return 1 if value > eps else -1 if value < -eps else 0


def cos_table(microsteps: int = DEFAULT_MICROSTEPS, bits: int = DEFAULT_DUTY_BITS) -> tuple[int, ...]:
    """The quarter-wave magnitude table: entry k = quantise(cos(pi * k / (2 * microsteps))), k = 0 .. microsteps."""
    check_microsteps(microsteps)
    table = [quantise(math.cos(math.pi * k / (2 * microsteps)), bits) for k in range(microsteps + 1)]
    table[microsteps] = 0  # cos(pi / 2) is zero, not 6e-17
    return tuple(table)


class Winding(NamedTuple):
    """One winding in PWM mode: current direction (+1, -1, 0), magnitude (units of 2**-bits) and duty (counts)."""

    polarity: int
    magnitude: int
    duty: int

    def levels(self) -> tuple[int, int]:
        """(IN1, IN2) while the PWM is on: the input of the polarity carries the PWM."""
        return bridge_inputs(self.polarity if self.duty > 0 else 0)


def duty_counts(magnitude: int, pwm_period: int, bits: int = DEFAULT_DUTY_BITS) -> int:
    """On-clocks per carrier period: magnitude * pwm_period / 2**bits rounded to nearest (halves up).

    pwm_period 0 or 1 holds the outputs off (duty 0). A magnitude of 2**bits gives pwm_period: always on.
    """
    if pwm_period < 2:
        return 0
    return (magnitude * pwm_period + (1 << (bits - 1))) >> bits


def pwm_windings(
    position: int,
    ustep_log2: int,
    pwm_period: int,
    microsteps: int = DEFAULT_MICROSTEPS,
    bits: int = DEFAULT_DUTY_BITS,
    enable: bool = True,
) -> tuple[Winding, Winding]:
    """Windings A (cos) and B (sin) at a position in PWM mode: theta = 2 pi e / (4 m), m = 2**ustep_log2."""
    m = 1 << effective_ustep_log2(ustep_log2, microsteps)
    theta = 2.0 * math.pi * (position % (4 * m)) / (4 * m)
    result: list[Winding] = []
    for value in (math.cos(theta), math.sin(theta)):
        mag = quantise(value, bits)
        duty = duty_counts(mag, pwm_period, bits) if enable else 0
        result.append(Winding(sign(value) if mag else 0, mag, duty))
    return result[0], result[1]


def pwm_levels(a: Winding, b: Winding, carrier: int) -> tuple[int, int, int, int]:
    """(a1, a2, b1, b2) at a carrier count: a winding is on while carrier < duty."""
    la = a.levels() if carrier < a.duty else (0, 0)
    lb = b.levels() if carrier < b.duty else (0, 0)
    return (*la, *lb)


# ----------------------------------------------------------------------------------------------------------------
# STEP / DIR timing and the start gate.
# ----------------------------------------------------------------------------------------------------------------
def step_pulse_width(step_width: int) -> int:
    """Clocks STEP is high per pulse: step_width, 0 behaves as 1."""
    return max(step_width, 1)


@dataclass(frozen=True)
class GateTiming:
    """What the start gate does with a start_req sampled at edge `request`.

    dir_edge: edge at which DIR changes (None: no change). start_edge: eng_start is '1' in the cycle after it.
    first_step_edge: edge at which STEP rises for the engine's pulse 0 (if the move has one).
    """

    request: int
    dir_edge: int | None
    start_edge: int
    first_step_edge: int

    @property
    def latency(self) -> int:
        """Clocks from start_req high to eng_start high (1 when the direction does not change)."""
        return self.start_edge - self.request + 1


def gate_timing(
    request: int,
    dir_changes: bool,
    last_step_edge: int | None,
    dir_hold: int,
    dir_setup: int,
    step_width: int = 1,
    step_space: int = 1,
) -> GateTiming:
    """The start gate's rule for one accepted start_req (sampled at edge `request`, gate idle, engine idle).

    Same direction: eng_start after edge request (1 clock after start_req). Direction change: DIR changes at
    D = max(request + 1, last_step_edge + max(dir_hold, 1)), eng_start after edge D + 1 + max(dir_setup - 5, 0),
    so that the first STEP rising edge comes max(dir_setup, 5) clocks after D. In both cases eng_start waits until
    the first STEP rising edge is at least min_gap = max(step_width, 1) + max(step_space, 1) clocks after
    last_step_edge (docs/algorithm.md, "Step spacing"). last_step_edge: the last edge that sampled eng_step = '1'
    (None: none since reset), which is also the edge the STEP pin rose.
    """
    gap = max(step_width, 1) + max(step_space, 1)
    earliest = None if last_step_edge is None else last_step_edge + gap - START_TO_FIRST_STEP
    if not dir_changes:
        s = request if earliest is None else max(request, earliest)
        return GateTiming(request, None, s, s + START_TO_FIRST_STEP)
    d = request + 1
    if last_step_edge is not None:
        d = max(d, last_step_edge + max(dir_hold, 1))
    s = d + 1 + max(dir_setup - GATE_SETUP_MIN, 0)
    if earliest is not None:
        s = max(s, earliest)
    return GateTiming(request, d, s, s + START_TO_FIRST_STEP)


def sync_gate_timing(gates: Sequence[GateTiming]) -> list[GateTiming]:
    """The start gates of the axes one SYNC_START starts (each axis's own gate_timing of the same request): every
    axis's eng_start after the latest start edge among them, so that pulse 0 of every axis comes on one clock edge
    (docs/algorithm.md, "Coordinated moves": the common start). DIR of an axis that changes direction still changes at
    its own edge (its setup is then longer than it needs). An axis that refuses the start (busy, ESTOP, bad STEPS, a
    limit) is not one of `gates`."""
    if not gates:
        return []
    s = max(g.start_edge for g in gates)
    return [GateTiming(g.request, g.dir_edge, s, s + START_TO_FIRST_STEP) for g in gates]


def check_step_widths(
    rises: Sequence[float], falls: Sequence[float], step_width: int, exact: bool = False
) -> list[str]:
    """STEP pulses (rise and fall times in clocks) against the programmed width: each at least max(step_width, 1)
    clocks high (exactly, with exact=True). A rise without a later fall is not judged. Returns the violations."""
    width = step_pulse_width(step_width)
    ordered = sorted(falls)
    problems: list[str] = []
    for r in rises:
        k = bisect.bisect_right(ordered, r)
        if k == len(ordered):
            continue
        high = ordered[k] - r
        if high < width or (exact and high != width):
            problems.append(f"STEP high {high} clocks from {r} (programmed {width})")
    return problems


def setup_ok(dir_change: float, step_rise: float, dir_setup: int) -> bool:
    """A STEP rising edge at or after a DIR change keeps the setup: step_rise - dir_change >= max(dir_setup, 1)."""
    return step_rise - dir_change >= max(dir_setup, 1)


def hold_ok(step_rise: float, dir_change: float, dir_hold: int) -> bool:
    """A DIR change at or after a STEP rising edge keeps the hold: dir_change - step_rise >= max(dir_hold, 1)."""
    return dir_change - step_rise >= max(dir_hold, 1)


def check_dir_timing(
    step_rises: Sequence[float], dir_changes: Sequence[float], dir_setup: int, dir_hold: int
) -> list[str]:
    """DIR changes against STEP rising edges (times in clocks): for a rise R and a change D, R >= D needs
    setup_ok(D, R) and D >= R needs hold_ok(R, D); they never coincide. Returns the violations."""
    problems: list[str] = []
    for d in dir_changes:
        for r in step_rises:
            if r >= d and not setup_ok(d, r, dir_setup):
                problems.append(f"DIR change at {d}, STEP rise at {r}: setup {r - d} < {max(dir_setup, 1)}")
            elif d >= r and not hold_ok(r, d, dir_hold):
                problems.append(f"STEP rise at {r}, DIR change at {d}: hold {d - r} < {max(dir_hold, 1)}")
    return problems


def step_positions(start: int, directions: Sequence[int]) -> list[int]:
    """Position after each STEP: +1 for DIR = 0, -1 for DIR = 1 (the engine's convention)."""
    out: list[int] = []
    pos = start
    for d in directions:
        pos += -1 if d else 1
        out.append(pos)
    return out


__all__ = [
    "DEFAULT_DUTY_BITS",
    "DEFAULT_MICROSTEPS",
    "DUTY_BITS_RANGE",
    "ENGINE_FIRST_PULSE_LATENCY",
    "FULL_STEP_TABLE",
    "GATE_SETUP_MIN",
    "HALF_STEP_TABLE",
    "MICROSTEPS_RANGE",
    "MIN_INTERVAL_CLKS",
    "MODE_FULL",
    "MODE_HALF",
    "MODE_NAMES",
    "MODE_PWM",
    "MODE_STEPDIR",
    "MODE_WAVE",
    "START_TO_FIRST_STEP",
    "STEP_LATENCY",
    "WAVE_TABLE",
    "GateTiming",
    "Winding",
    "bridge_current",
    "bridge_inputs",
    "check_dir_timing",
    "check_microsteps",
    "check_step_widths",
    "cos_table",
    "duty_counts",
    "effective_mode",
    "effective_ustep_log2",
    "electrical_position",
    "field_angle",
    "gate_timing",
    "hold_ok",
    "positions_per_cycle",
    "pwm_levels",
    "pwm_round",
    "pwm_windings",
    "quantise",
    "setup_ok",
    "sign",
    "step_positions",
    "step_pulse_width",
    "sync_gate_timing",
    "winding_currents",
    "winding_latency",
    "winding_levels",
]
