# SPDX-License-Identifier: MIT
"""A mechanical model of an axis for simulations: a carriage that follows STEP/DIR and switches it closes.

The carriage's position is in steps: +1 at every STEP rising edge with DIR '0', -1 with DIR '1' (DIR read at the
edge; POSITION counts the same way). Each `Switch` is active on one side of a fixed position (a home switch active
for position <= h, a limit beyond a travel end) and drives one of the core's input pins. When a step moves the
carriage across a switch edge, the pin changes after a short delay and bounces: it toggles back and forth a seeded
random number of times, at random intervals (in clocks, each shorter than the input filter so that the filter
removes it, some close to the filter's length), then settles at the new level (`bounce_intervals`). The toggles are
cocotb Timers; the carriage awaits STEP edges only, never every clock.

The bounce pattern generator is plain Python (sw/tests/test_mechanics.py); `Carriage` needs cocotb.

    carriage = Carriage(dut.step, dut.dir, {"home": dut.home}, [Switch("home", at=-200, side=-1)], position=37,
                        bounce=Bounce(filter_clocks=100), seed=5, period_ps=10_000)
    carriage.start()
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class Switch:
    """A switch on the axis: active on `side` of position `at` (side -1: for position <= at; +1: for position >= at),
    driving the input pin `pin` ("home", "limit_neg", "limit_pos"); the pin reads 0 when active if active_low."""

    pin: str
    at: int
    side: int = -1
    active_low: bool = False

    def active(self, position: int) -> bool:
        return position <= self.at if self.side < 0 else position >= self.at

    @property
    def first_off(self) -> int:
        """The first position off the switch, leaving it: the switch edge lies between `at` and this."""
        return self.at - self.side

    def level(self, active: bool) -> int:
        """The pin level for a switch state."""
        return int(active) ^ int(self.active_low)


@dataclass(frozen=True)
class Bounce:
    """How switches bounce: after a crossing, up to max_bounces returns to the old level (each a pair of toggles), the
    intervals between toggles in [min_clocks, filter_clocks - 1.5] clocks; `near` is the share of patterns whose
    intervals at the new level lie within 3 clocks of that bound, and `clean` the share without bounce. lag_clocks: the
    pin's delay after the STEP edge, drawn in [0, lag_clocks)."""

    filter_clocks: int
    max_bounces: int = 4
    min_clocks: float = 1.5
    near: float = 0.3
    clean: float = 0.1
    lag_clocks: float = 1.0

    @property
    def max_interval(self) -> float:
        """The longest interval between two toggles: an interval of d clocks is sampled by at most ceil(d) clock
        edges, so d < N - 1 keeps every bounce below the filter's N samples."""
        return self.filter_clocks - 1.5

    @property
    def settle_clocks(self) -> int:
        """The longest time from a STEP edge to the pin's last change: the lag and 2 max_bounces intervals."""
        return math.ceil(self.lag_clocks + 2 * self.max_bounces * self.max_interval)

    def check(self) -> None:
        if self.filter_clocks < 4:
            raise ValueError(f"bounce needs a filter of at least 4 clocks, got {self.filter_clocks}")
        if not 1.0 <= self.min_clocks <= self.max_interval:
            raise ValueError(f"min_clocks must be in 1 .. {self.max_interval}, got {self.min_clocks}")
        if self.max_bounces < 0 or not 0 <= self.near <= 1 or not 0 <= self.clean <= 1 or self.lag_clocks < 0:
            raise ValueError(f"invalid bounce settings {self}")


def bounce_intervals(rng: random.Random, bounce: Bounce) -> list[float]:
    """One crossing's bounce: the intervals, in clocks, between the pin's first change and each following toggle
    (an even count, so that the pin ends at its new level). Every interval lies in [min_clocks, max_interval]: at
    least one clock, so each level in the pattern is sampled and two bounces never merge into one run the filter
    would take; below N - 1, so the filter never takes a bounce."""
    bounce.check()
    if rng.random() < bounce.clean or bounce.max_bounces == 0:
        return []
    pairs = rng.randint(1, bounce.max_bounces)
    near = rng.random() < bounce.near
    hi = bounce.max_interval
    lo_near = max(bounce.min_clocks, hi - 3.0)
    out: list[float] = []
    for _ in range(pairs):
        # at the new level (the filter counts these), then back at the old one
        out.append(rng.uniform(lo_near, hi) if near else rng.uniform(bounce.min_clocks, hi))
        out.append(rng.uniform(bounce.min_clocks, hi))
    return out


@dataclass
class Crossing:
    """A switch edge the carriage crossed: the STEP edge's time (ps), the pin, the new switch state, the position
    after the step, the bounce intervals (clocks), and the time from the STEP edge to the pin's last change (ps: the
    lag and every interval, as the Timers wait them)."""

    time_ps: int
    pin: str
    active: bool
    position: int
    intervals: list[float] = field(default_factory=list)
    settle_ps: int = 0

    @property
    def last_change_ps(self) -> int:
        """When the pin settled at its new level (ps)."""
        return self.time_ps + self.settle_ps


class Carriage:
    """The carriage and its switches in a running simulation (cocotb): follows `step` / `direction` from start() on
    and drives the pins (handles by pin name) of `switches`."""

    def __init__(
        self,
        step: Any,
        direction: Any,
        pins: dict[str, Any],
        switches: list[Switch],
        position: int,
        bounce: Bounce,
        seed: int,
        period_ps: int,
    ) -> None:
        bounce.check()
        self.step, self.direction, self.pins = step, direction, pins
        self.switches = switches
        self.position = position
        self.bounce = bounce
        self.rng = random.Random(seed)
        self.period_ps = period_ps
        self.crossings: list[Crossing] = []
        self.steps = 0
        self._state = {sw.pin: sw.active(position) for sw in switches}
        self._bouncing: dict[str, Any] = {}
        self._task: Any = None

    def start(self) -> None:
        """Drive every pin to its switch's level now (no bounce) and follow the STEP pin from here on."""
        import cocotb

        for sw in self.switches:
            self.pins[sw.pin].value = sw.level(self._state[sw.pin])
        self._task = cocotb.start_soon(self._follow())

    def stop(self) -> None:
        for task in [self._task, *self._bouncing.values()]:
            if task is not None and not task.done():
                task.cancel()

    def place(self, position: int) -> None:
        """Put the carriage somewhere else by hand (the motor off): the pins follow at once, without bounce."""
        self.position = position
        for sw in self.switches:
            self._set(sw, sw.active(position))

    async def _follow(self) -> None:
        from cocotb.triggers import RisingEdge
        from cocotb.utils import get_sim_time

        while True:
            await RisingEdge(self.step)
            self.position += -1 if int(self.direction.value) else 1
            self.steps += 1
            for sw in self.switches:
                active = sw.active(self.position)
                if active != self._state[sw.pin]:
                    crossing = Crossing(int(get_sim_time("ps")), sw.pin, active, self.position)
                    self.crossings.append(crossing)
                    self._set(sw, active, crossing)

    def _set(self, sw: Switch, active: bool, crossing: Crossing | None = None) -> None:
        """The switch's new state: at once (crossing None), or with the lag and a bounce pattern, recorded in the
        crossing."""
        import cocotb

        self._state[sw.pin] = active
        running = self._bouncing.pop(sw.pin, None)
        if running is not None and not running.done():
            running.cancel()  # a crossing back during a bounce: the new one starts from the pin's level now
        if crossing is None:
            self.pins[sw.pin].value = sw.level(active)
            return
        crossing.intervals = bounce_intervals(self.rng, self.bounce)
        delays = [self._ps(self.rng.uniform(0.0, self.bounce.lag_clocks)), *map(self._ps, crossing.intervals)]
        crossing.settle_ps = sum(delays)
        self._bouncing[sw.pin] = cocotb.start_soon(self._bounce(sw, active, delays))

    def _ps(self, clocks: float) -> int:
        """A delay in ps for a time in clocks, at least 1 ps."""
        return max(1, round(clocks * self.period_ps))

    async def _bounce(self, sw: Switch, active: bool, delays: list[int]) -> None:
        """The pin's new level after delays[0] ps, then a toggle after each further delay."""
        from cocotb.triggers import Timer

        pin = self.pins[sw.pin]
        level = sw.level(not active)
        for d in delays:
            await Timer(d, unit="ps")
            level ^= 1
            pin.value = level
        # an even number of toggles: the pin ends at its new level
        assert level == sw.level(active), "bounce pattern with an odd number of toggles"


__all__ = ["Bounce", "Carriage", "Crossing", "Switch", "bounce_intervals"]
