# SPDX-License-Identifier: MIT
"""The ideal continuous trapezoid / triangle: the judge of the driver, the model and the RTL.

Written plainly with square roots (docs/algorithm.md, "The ideal trajectory"). Times are in ticks
(``f_tick = f_clk / prescale``), positions in steps. An ``N``-step move covers ``L = N - 1`` steps and
pulse ``k`` is emitted when the trajectory reaches position ``k`` (pulse 0 at ``t = 0``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # numpy only for time_chunk
    import numpy as np
    from numpy.typing import NDArray


def step_angle(spr: float) -> float:
    """Step angle alpha = 2*pi/spr in rad."""
    return 2.0 * math.pi / spr


def c0(accel: float, spr: float, fclk: float, prescale: int = 1) -> float:
    """First interval of an acceleration from rest, in ticks: f_tick * sqrt(2 * alpha / accel)."""
    return fclk / prescale * math.sqrt(2.0 * step_angle(spr) / accel)


def cd0(decel: float, spr: float, fclk: float, prescale: int = 1) -> float:
    """Last interval of a deceleration to rest, in ticks: f_tick * sqrt(2 * alpha / decel)."""
    return c0(decel, spr, fclk, prescale)


@dataclass(frozen=True)
class IdealMove:
    """A rest-to-rest move of ``length`` steps; a, d in steps/s^2, v and v_peak in steps/s."""

    length: int
    a: float
    d: float
    v: float
    f_tick: float
    x_a: float
    x_d: float
    v_peak: float
    triangle: bool

    @property
    def t_a(self) -> float:
        """End of the acceleration, in s."""
        return self.v_peak / self.a

    @property
    def t_d(self) -> float:
        """Start of the deceleration, in s."""
        return self.t_a + (self.x_d - self.x_a) / self.v_peak if self.length > 0 else 0.0

    @property
    def t_end(self) -> float:
        """Duration of the move, in s."""
        return self.t_d + self.v_peak / self.d if self.length > 0 else 0.0

    def time_at(self, x: float) -> float:
        """Time (ticks) at which the trajectory reaches position x (0 <= x <= length)."""
        if self.length <= 0 or x <= 0.0:
            return 0.0
        if x <= self.x_a:
            t = math.sqrt(2.0 * x / self.a)
        elif x <= self.x_d:
            t = self.t_a + (x - self.x_a) / self.v_peak
        else:
            t = self.t_end - math.sqrt(2.0 * max(self.length - x, 0.0) / self.d)
        return t * self.f_tick

    def speed_at(self, x: float) -> float:
        """Speed (steps/s) at position x."""
        if self.length <= 0:
            return 0.0
        if x <= self.x_a:
            return math.sqrt(2.0 * self.a * max(x, 0.0))
        if x <= self.x_d:
            return self.v_peak
        return math.sqrt(2.0 * self.d * max(self.length - x, 0.0))

    def pulse_times(self) -> list[float]:
        """Ideal pulse times t_k (ticks), k = 0 .. length."""
        return [self.time_at(float(k)) for k in range(self.length + 1)]

    def time_chunk(self, start: int, stop: int) -> NDArray[np.float64]:
        """time_at(k) for k = start .. stop - 1 as a numpy array, bit-identical to time_at (the same double
        operations in the same order, per region), so that long moves can be judged chunk by chunk."""
        import numpy as np

        x = np.arange(start, stop, dtype=np.float64)
        out = np.zeros(len(x))
        if self.length <= 0 or len(x) == 0:
            return out

        def index(k: int) -> int:  # position in the chunk of pulse k, clamped
            return min(max(k - start, 0), len(x))

        # for an integer k >= 1: k <= x_a <=> k <= floor(x_a), likewise for x_d (x_a <= x_d)
        first = index(1)
        end_a = max(index(math.floor(self.x_a) + 1), first)
        end_c = max(index(math.floor(self.x_d) + 1), end_a)
        part = 2.0 * x[first:end_a]  # sqrt(2.0 * x / a)
        part /= self.a
        np.sqrt(part, out=out[first:end_a])
        part = np.subtract(x[end_a:end_c], self.x_a)  # t_a + (x - x_a) / v_peak; in place, the same operations
        part /= self.v_peak
        np.add(self.t_a, part, out=out[end_a:end_c])
        part = np.subtract(float(self.length), x[end_c:])  # t_end - sqrt(2.0 * max(length - x, 0.0) / d)
        np.maximum(part, 0.0, out=part)
        part *= 2.0
        part /= self.d
        np.sqrt(part, out=part)
        np.subtract(self.t_end, part, out=out[end_c:])
        out *= self.f_tick
        return out

    def intervals(self) -> list[float]:
        """Ideal intervals t_i - t_{i-1} (ticks), i = 1 .. length."""
        t = self.pulse_times()
        return [t[i] - t[i - 1] for i in range(1, len(t))]


def ideal_move(
    steps: int, accel: float, decel: float, speed: float, spr: float, fclk: float, prescale: int = 1
) -> IdealMove:
    """The ideal trajectory of a move given in physical units (sign of steps ignored)."""
    alpha = step_angle(spr)
    a, d, v = accel / alpha, decel / alpha, speed / alpha
    length = max(abs(steps) - 1, 0)
    n_a = v * v / (2.0 * a)
    n_d = v * v / (2.0 * d)
    if n_a + n_d <= length:
        x_a, x_d, v_peak, triangle = n_a, length - n_d, v, False
    else:
        x_p = length * d / (a + d)
        x_a, x_d, v_peak, triangle = x_p, x_p, math.sqrt(2.0 * a * x_p), True
    return IdealMove(length, a, d, v, fclk / prescale, x_a, x_d, v_peak, triangle)


def pulse_times(
    steps: int, accel: float, decel: float, speed: float, spr: float, fclk: float, prescale: int = 1
) -> list[float]:
    """Ideal pulse times t_k in ticks for k = 0 .. N-1 (empty for N = 0)."""
    if steps == 0:
        return []
    return ideal_move(steps, accel, decel, speed, spr, fclk, prescale).pulse_times()


def peak_speed(steps: int, accel: float, decel: float, speed: float, spr: float) -> float:
    """Highest speed of the move in rad/s: the requested speed, or the triangle's peak."""
    move = ideal_move(steps, accel, decel, speed, spr, 1.0)
    return move.v_peak * step_angle(spr)


@dataclass(frozen=True)
class IdealSegment:
    """The ideal motion after a change (docs/algorithm.md, "Changes while moving"): from speed u at position 0 (the
    pulse of the change), to speed v (up at a, or down at d), then at v, then down at d to rest at ``length``, or
    at v for ever (``length`` None). a, d, u, v in steps/s^2 and steps/s; times in ticks from the change.

    Written plainly from the kinematics: the peak w of a move that cannot reach v solves
    (w^2 - u^2) / (2 a) + w^2 / (2 d) = length; u must allow a stop at the target (u^2 <= 2 d length)."""

    u: float
    a: float
    d: float
    v: float
    length: int | None
    f_tick: float

    @property
    def peak(self) -> float:
        """The cruise speed (steps/s): v, or lower when the distance does not allow it."""
        if self.length is None or self.u >= self.v:
            return self.v
        w2 = (self.u * self.u / (2.0 * self.a) + self.length) / (1.0 / (2.0 * self.a) + 1.0 / (2.0 * self.d))
        return min(self.v, math.sqrt(w2))

    def time_at(self, x: float) -> float:
        """Time (ticks) at which the motion reaches position x (0 <= x <= length)."""
        u, w = self.u, self.peak
        rate = self.a if w >= u else self.d  # the first ramp: up at a, or down at d
        x1 = abs(w * w - u * u) / (2.0 * rate)
        if x <= x1:
            s = math.sqrt(u * u + 2.0 * rate * x) if w >= u else math.sqrt(u * u - 2.0 * rate * x)
            return abs(s - u) / rate * self.f_tick
        t1 = abs(w - u) / rate
        x2 = self.length - w * w / (2.0 * self.d) if self.length is not None else math.inf
        if x <= x2:
            return (t1 + (x - x1) / w) * self.f_tick
        t2 = t1 + (x2 - x1) / w
        return (t2 + (w - math.sqrt(max(w * w - 2.0 * self.d * (x - x2), 0.0))) / self.d) * self.f_tick

    def pulse_times(self, count: int) -> list[float]:
        """Ideal times of the pulses 0 .. count (pulse 0 is the change's pulse, at 0)."""
        return [self.time_at(float(k)) for k in range(count + 1)]
