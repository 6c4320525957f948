# SPDX-License-Identifier: MIT
"""Reusable cocotb monitors for the motor pins of every motion test (stepper alone, engine + stepper, tops).

Each monitor is given the settings the test programmed (so that a test can pass a wrong one on purpose and see the
monitor fail), watches the pins from start() on, records every violation as (time in ns, message) and raises
AssertionError listing them in check(). They wait on edges of the signals they watch, not on every clock; only the
PWM duty measurement samples the pins clock by clock, for one carrier period now and then.

* StepWidthMonitor: every STEP pulse is high at least max(step_width, 1) clocks (exactly, with exact=True).
* DirTimingMonitor: no DIR change within dir_setup clocks before or dir_hold clocks after a STEP rising edge.
* ShootThroughMonitor: IN1 and IN2 of a bridge are never '1' together.
* EstopMonitor: no STEP rising edge more than 2 clocks after the filtered ESTOP edge, while the ESTOP stop holds.
* ElectricalMonitor: after every STEP rising edge the windings show the model's state for the position counted
  from the STEP pulses and DIR (so the electrical position follows the step count in both directions); in PWM mode
  the polarity at every step and the duty measured over a carrier period now and then.

The rules come from stepramp.models.stepping (the model), never from the RTL. Times are converted to clock periods
(stepramp.sim.clocking.CLK_PERIOD_NS unless told otherwise).
"""

from __future__ import annotations

from collections.abc import Coroutine, Iterable, Sequence
from typing import TYPE_CHECKING, Any, ClassVar, TypedDict

import cocotb
from cocotb.triggers import ReadOnly, RisingEdge
from cocotb.utils import get_sim_time

from stepramp.models import stepping as sm
from stepramp.sim.clocking import CLK_PERIOD_NS, cycles, now_periods

if TYPE_CHECKING:  # (typing.Unpack from Python 3.11 on)
    from typing_extensions import Unpack


def _bit(signal: Any) -> int:
    """A 1-bit signal as 0 / 1 (X, Z, U read as 0, with the raw value kept out of the arithmetic)."""
    value = signal.value
    return 1 if str(value) == "1" else 0


def _name(signal: Any) -> str:
    return str(getattr(signal, "_name", signal))


class MonitorOptions(TypedDict, total=False):
    """The keyword options every monitor takes: its clock period (times are counted in clock periods) and the name
    its violations are reported under (default: the class's `title`)."""

    clk_period_ns: float
    name: str


class Monitor:
    """Base: a list of violations, start / stop of the watching coroutines, check()."""

    title = "monitor"

    def __init__(self, *, clk_period_ns: float = CLK_PERIOD_NS, name: str | None = None) -> None:
        self.name = self.title if name is None else name
        self.clk_period_ns = clk_period_ns
        self.violations: list[tuple[float, str]] = []
        self._tasks: list[Any] = []

    def _coroutines(self) -> Iterable[Coroutine[Any, Any, None]]:
        raise NotImplementedError

    def start(self) -> Monitor:
        """Start watching (call after reset). Returns self, so `mon = XMonitor(...).start()` works."""
        self._tasks = [cocotb.start_soon(c) for c in self._coroutines()]
        return self

    def stop(self) -> None:
        """Stop watching (for example before the settings change); the violations are kept."""
        for task in self._tasks:
            if not task.done():
                task.cancel()
        self._tasks = []

    def now(self) -> float:
        """Simulation time in clock periods, to a thousandth: a test that starts a time step late (cocotb starts each
        test of a simulation one step after the previous one ends) must not make a 4-clock pulse 3.9999999 long."""
        return round(now_periods(self.clk_period_ns * 1000), 3)

    def violation(self, message: str) -> None:
        self.violations.append((get_sim_time("ns"), message))

    def check(self) -> None:
        """Raise AssertionError listing the violations (at most 20 shown)."""
        if self.violations:
            lines = [f"  {t:.0f} ns: {msg}" for t, msg in self.violations[:20]]
            more = len(self.violations) - 20
            if more > 0:
                lines.append(f"  ... and {more} more")
            raise AssertionError(f"{self.name}: {len(self.violations)} violation(s)\n" + "\n".join(lines))


class StepWidthMonitor(Monitor):
    """STEP high for at least max(step_width, 1) clocks per pulse (exactly that with exact=True)."""

    title = "STEP width"

    def __init__(self, step: Any, step_width: int, *, exact: bool = False, **options: Unpack[MonitorOptions]) -> None:
        super().__init__(**options)
        self.step = step
        self.step_width = step_width
        self.exact = exact
        self.pulses = 0
        self.widths: list[float] = []

    def _coroutines(self) -> Iterable[Coroutine[Any, Any, None]]:
        return [self._watch()]

    async def _watch(self) -> None:
        while True:
            await RisingEdge(self.step)
            rise = self.now()
            await self.step.falling_edge
            self.pulse(rise, self.now())

    def pulse(self, rise: float, fall: float) -> None:
        """One pulse seen, from its rising edge to its falling edge (clock periods)."""
        self.pulses += 1
        self.widths.append(fall - rise)
        for problem in sm.check_step_widths([rise], [fall], self.step_width, exact=self.exact):
            self.violation(problem)


class DirTimingMonitor(Monitor):
    """No DIR change within dir_setup clocks before or dir_hold clocks after a STEP rising edge (never both at once).

    Each STEP rising edge is checked against the latest DIR change, each DIR change against the latest rising edge.
    """

    title = "DIR setup/hold"

    def __init__(
        self, step: Any, direction: Any, dir_setup: int, dir_hold: int, **options: Unpack[MonitorOptions]
    ) -> None:
        super().__init__(**options)
        self.step = step
        self.direction = direction
        self.dir_setup = dir_setup
        self.dir_hold = dir_hold
        self.last_rise: float | None = None
        self.last_change: float | None = None
        self.rises = 0
        self.changes: list[float] = []

    def _coroutines(self) -> Iterable[Coroutine[Any, Any, None]]:
        return [self._watch_step(), self._watch_dir()]

    async def _watch_step(self) -> None:
        while True:
            await RisingEdge(self.step)
            self.rise(self.now())

    def rise(self, t: float) -> None:
        """A STEP rising edge at t (clock periods), against the latest DIR change."""
        self.rises += 1
        if self.last_change is not None and not sm.setup_ok(self.last_change, t, self.dir_setup):
            self.violation(
                f"STEP rise {t - self.last_change:.0f} clocks after the DIR change (setup {max(self.dir_setup, 1)})"
            )
        self.last_rise = t

    async def _watch_dir(self) -> None:
        while True:
            await self.direction.value_change
            t = self.now()
            self.changes.append(t)
            if self.last_rise is not None and not sm.hold_ok(self.last_rise, t, self.dir_hold):
                self.violation(
                    f"DIR change {t - self.last_rise:.0f} clocks after a STEP rise (hold {max(self.dir_hold, 1)})"
                )
            self.last_change = t


class ShootThroughMonitor(Monitor):
    """IN1 and IN2 of each bridge never '1' together. bridges: pairs (in1, in2), e.g. [(a1, a2), (b1, b2)]."""

    title = "shoot-through"

    def __init__(self, bridges: Sequence[tuple[Any, Any]], **options: Unpack[MonitorOptions]) -> None:
        super().__init__(**options)
        self.bridges = list(bridges)
        self.edges = 0

    def _coroutines(self) -> Iterable[Coroutine[Any, Any, None]]:
        # One watcher per input (cocotb 2.1's First() does not survive Task.cancel() cleanly).
        out: list[Coroutine[Any, Any, None]] = []
        for k, (in1, in2) in enumerate(self.bridges):
            out += [self._watch(k, in1, in2), self._watch(k, in2, in1)]
        return out

    async def _watch(self, k: int, rising: Any, other: Any) -> None:
        while True:
            await RisingEdge(rising)
            await ReadOnly()
            self.edges += 1
            if _bit(other):
                self.violation(f"bridge {k} ({_name(rising)}, {_name(other)}): both inputs '1'")


class ElectricalMonitor(Monitor):
    """The windings follow the step count: after each STEP rising edge, the position (start value +1 per STEP with
    DIR = 0, -1 with DIR = 1) gives the expected winding state from stepramp.models.stepping.

    Every check is made `settle` clocks after the STEP rising edge (default: stepramp.models.stepping.winding_latency: 0
    for the on/off modes, 2 * duty_bits + 6 for PWM). On/off modes (0 .. 3, 5 .. 7): a1, a2, b1, b2 equal the
    model's levels. PWM mode (4): at every step the polarity (the input of the wrong sign is '0', an input with a
    duty of the full period is '1'); and after every `pwm_every`-th step (and at start) the on-clocks of each input
    are counted over one carrier period and compared with the model's duty within duty_tolerance counts (a
    measurement that a
    STEP interrupts is dropped and counted in duty_skipped). Every STEP rising edge is counted (the count never
    misses one); a check whose settle time a newer STEP interrupts (steps closer than `settle`, as between two
    moves) is left to the newer one and counted in `superseded`. pins: (a1, a2, b1, b2).
    """

    title = "electrical position"

    def __init__(
        self,
        clk: Any,
        step: Any,
        direction: Any,
        pins: Sequence[Any],
        mode: int,
        *,
        position: int = 0,
        ustep_log2: int = 0,
        pwm_period: int = 0,
        microsteps: int = sm.DEFAULT_MICROSTEPS,
        duty_bits: int = sm.DEFAULT_DUTY_BITS,
        enable: bool = True,
        settle: int | None = None,
        pwm_every: int = 16,
        duty_tolerance: int = 1,
        **options: Unpack[MonitorOptions],
    ) -> None:
        super().__init__(**options)
        if len(pins) != 4:
            raise ValueError("pins must be (a1, a2, b1, b2)")
        self.clk = clk
        self.step = step
        self.direction = direction
        self.pins = list(pins)
        self.mode = sm.effective_mode(mode)
        self.position = position
        self.ustep_log2 = ustep_log2
        self.pwm_period = pwm_period
        self.microsteps = microsteps
        self.duty_bits = duty_bits
        self.enable = enable
        self.settle = sm.winding_latency(self.mode, duty_bits) if settle is None else settle
        self.pwm_every = max(pwm_every, 1)
        self.duty_tolerance = duty_tolerance
        self.steps = 0
        self.checked = 0
        self.duty_measured = 0
        self.duty_skipped = 0
        self.superseded = 0
        self._measuring = False

    def _coroutines(self) -> Iterable[Coroutine[Any, Any, None]]:
        return [self._watch()]

    def levels(self) -> tuple[int, int, int, int]:
        return tuple(_bit(p) for p in self.pins)  # type: ignore[return-value]

    def expected_pwm(self, position: int) -> tuple[sm.Winding, sm.Winding]:
        return sm.pwm_windings(
            position, self.ustep_log2, self.pwm_period, self.microsteps, self.duty_bits, enable=self.enable
        )

    def _spawn(self, coro: Coroutine[Any, Any, None]) -> None:
        self._tasks = [t for t in self._tasks if not t.done()]
        self._tasks.append(cocotb.start_soon(coro))

    async def _watch(self) -> None:
        self._spawn(self._check_after(self.position, self.steps, initial=True))
        while True:
            await RisingEdge(self.step)
            self.step_seen()
            self._spawn(self._check_after(self.position, self.steps))

    def step_seen(self) -> None:
        """A STEP rising edge, now: the position moves by one in DIR's direction."""
        self.position += -1 if _bit(self.direction) else 1
        self.steps += 1

    async def _check_after(self, pos: int, steps: int, initial: bool = False) -> None:
        """settle clocks after a STEP rising edge (at once for the initial check): compare, unless a newer STEP
        came meanwhile (then that one's check covers it; counted in `superseded`)."""
        if self.settle and not initial:
            await cycles(self.clk, self.settle, round(self.clk_period_ns * 1000))
        await ReadOnly()
        if self.steps != steps:
            self.superseded += 1
            return
        self._check_position(pos, initial)

    def _check_position(self, pos: int, initial: bool = False) -> None:
        """Compare the pins now (in ReadOnly) with the model at pos; start a duty measurement now and then."""
        self.checked += 1
        got = self.levels()
        if self.mode != sm.MODE_PWM:
            want = sm.winding_levels(self.mode, pos, self.enable)
            if got != want:
                self.violation(
                    f"position {pos} ({sm.MODE_NAMES[self.mode]}, e = {sm.electrical_position(self.mode, pos)}): "
                    f"a1 a2 b1 b2 = {got}, expected {want}"
                )
            return
        for k, w in enumerate(self.expected_pwm(pos)):
            in1, in2 = got[2 * k], got[2 * k + 1]
            act1, act2 = w.levels()
            winding = "AB"[k]
            if (in1 and not act1) or (in2 and not act2):
                self.violation(
                    f"position {pos}: winding {winding} inputs ({in1}, {in2}) but polarity {w.polarity:+d} "
                    f"(duty {w.duty})"
                )
            if w.duty >= self.pwm_period >= 2 and (in1, in2) != (act1, act2):
                self.violation(f"position {pos}: winding {winding} at full duty but inputs ({in1}, {in2})")
        if not self._measuring and (initial or self.steps % self.pwm_every == 0):
            self._measuring = True
            self._spawn(self._measure(pos, self.steps))

    async def measure(self, pos: int) -> tuple[list[int], bool]:
        """On-clocks of a1, a2, b1, b2 over one carrier period from the next clock edge; flag: a STEP interrupted."""
        steps = self.steps
        counts = [0, 0, 0, 0]
        for _ in range(max(self.pwm_period, 1)):
            await RisingEdge(self.clk)
            await ReadOnly()
            for k, p in enumerate(self.pins):
                counts[k] += _bit(p)
        return counts, self.steps != steps

    async def _measure(self, pos: int, steps: int) -> None:
        try:
            counts, interrupted = await self.measure(pos)
        finally:
            self._measuring = False
        if interrupted or self.steps != steps:
            self.duty_skipped += 1
            return
        self.duty_measured += 1
        for k, w in enumerate(self.expected_pwm(pos)):
            on1, on2 = counts[2 * k], counts[2 * k + 1]
            want1, want2 = (w.duty, 0) if w.polarity > 0 else (0, w.duty) if w.polarity < 0 else (0, 0)
            if abs(on1 - want1) > self.duty_tolerance or abs(on2 - want2) > self.duty_tolerance:
                self.violation(
                    f"position {pos}: winding {'AB'[k]} on-clocks ({on1}, {on2}) per {self.pwm_period}, "
                    f"expected ({want1}, {want2})"
                )


class EstopMonitor(Monitor):
    """No STEP rising edge more than `bound` clocks after the filtered ESTOP edge (docs/algorithm.md, "Machine inputs":
    2 clocks), for as long as the ESTOP stop holds. `stop` is the signal that rises at the filtered edge F and stays
    high while the stop holds (stepramp_core's estop_stop: the filtered level or the latched fault); `steps` the STEP
    pins it guards. latencies: for every ESTOP edge, the last STEP rising edge after it minus F (clocks; none if no
    pulse came after F)."""

    title = "ESTOP"

    def __init__(self, stop: Any, steps: Sequence[Any], bound: int = 2, **options: Unpack[MonitorOptions]) -> None:
        super().__init__(**options)
        self.stop_signal = stop
        self.steps = list(steps)
        self.bound = bound
        self.since: float | None = None
        self.edges: list[float] = []
        self.latencies: list[float] = []

    def _coroutines(self) -> Iterable[Coroutine[Any, Any, None]]:
        return [self._watch_stop(), *(self._watch_step(step) for step in self.steps)]

    async def _watch_stop(self) -> None:
        while True:
            await RisingEdge(self.stop_signal)
            self.since = self.now()
            self.edges.append(self.since)
            await self.stop_signal.falling_edge
            self.since = None

    async def _watch_step(self, step: Any) -> None:
        while True:
            await RisingEdge(step)
            t, since = self.now(), self.since
            if since is None:
                continue
            if t > since + self.bound:
                self.violation(f"{_name(step)} rose {t - since:g} clocks after the filtered ESTOP edge")
            self.latencies.append(t - since)


class MotionMonitors:
    """All four monitors on one set of pins, with one check(). names maps step, dir, a1, a2, b1, b2 to the
    pins' names on the dut (default: the pin names step, dir, a1, a2, b1, b2 that stepramp_stepper, stepramp_core and
    both tops share)."""

    DEFAULT_NAMES: ClassVar[dict[str, str]] = {
        "clk": "clk",
        "step": "step",
        "dir": "dir",
        "a1": "a1",
        "a2": "a2",
        "b1": "b1",
        "b2": "b2",
    }

    def __init__(
        self,
        dut: Any,
        *,
        step_width: int,
        dir_setup: int,
        dir_hold: int,
        names: dict[str, str] | None = None,
        clk_period_ns: float = CLK_PERIOD_NS,
        **electrical: Any,
    ) -> None:
        """electrical: ElectricalMonitor's settings by keyword (mode, required; position, ustep_log2, pwm_period,
        microsteps, duty_bits, enable, pwm_every ...)."""
        n = {**self.DEFAULT_NAMES, **(names or {})}
        sig = {k: getattr(dut, v) for k, v in n.items()}
        pins = (sig["a1"], sig["a2"], sig["b1"], sig["b2"])
        self.width = StepWidthMonitor(sig["step"], step_width, clk_period_ns=clk_period_ns)
        self.dir = DirTimingMonitor(sig["step"], sig["dir"], dir_setup, dir_hold, clk_period_ns=clk_period_ns)
        self.shoot = ShootThroughMonitor([pins[:2], pins[2:]], clk_period_ns=clk_period_ns)
        self.electrical = ElectricalMonitor(
            sig["clk"], sig["step"], sig["dir"], pins, clk_period_ns=clk_period_ns, **electrical
        )
        self.all: list[Monitor] = [self.width, self.dir, self.shoot, self.electrical]
        self._hub: Any = None

    def start(self) -> MotionMonitors:
        """Start watching. The STEP edges wake one coroutine (_step_edges) that does the STEP work of the width, DIR
        and electrical monitors, the same checks at the same instants as their own watchers would make, with three
        wakes per pulse instead of six and a task; DIR changes and the bridges keep their own watchers."""
        self.shoot.start()
        self.dir._tasks = [cocotb.start_soon(self.dir._watch_dir())]
        el = self.electrical
        el._spawn(el._check_after(el.position, el.steps, initial=True))
        self._hub = cocotb.start_soon(self._step_edges())
        return self

    async def _step_edges(self) -> None:
        step, el = self.width.step, self.electrical
        while True:
            await RisingEdge(step)
            rise = self.width.now()
            self.dir.rise(rise)
            el.step_seen()
            if el.settle:
                el._spawn(el._check_after(el.position, el.steps))
            else:  # (what _check_after does with no settle time, without a task)
                await ReadOnly()
                el._check_position(el.position)
            await step.falling_edge
            self.width.pulse(rise, self.width.now())

    @classmethod
    def for_outputs(
        cls, dut: Any, outputs: Any, enable: bool, position: int, names: dict[str, str] | None = None
    ) -> MotionMonitors:
        """Started monitors for a stepramp.board.driver.Outputs configuration (mode by name) and the current position,
        on a top's pins (STEP and DIR are `step` and `dir` there; `names` may rename more)."""
        from stepramp.board.driver import MODES

        return cls(
            dut,
            mode=MODES[outputs.mode],
            step_width=outputs.step_width,
            dir_setup=outputs.dir_setup,
            dir_hold=outputs.dir_hold,
            position=position,
            ustep_log2=outputs.ustep_log2,
            pwm_period=outputs.pwm_period,
            enable=enable,
            names={"step": "step", "dir": "dir", **(names or {})},
        ).start()

    def stop(self) -> None:
        if self._hub is not None and not self._hub.done():
            self._hub.cancel()
        self._hub = None
        for m in self.all:
            m.stop()

    def check(self) -> None:
        """Raise one AssertionError with the violations of every monitor."""
        problems: list[str] = []
        for m in self.all:
            try:
                m.check()
            except AssertionError as exc:
                problems.append(str(exc))
        if problems:
            raise AssertionError("\n".join(problems))


__all__ = [
    "DirTimingMonitor",
    "ElectricalMonitor",
    "Monitor",
    "MonitorOptions",
    "MotionMonitors",
    "ShootThroughMonitor",
    "StepWidthMonitor",
]
