# SPDX-License-Identifier: MIT
"""stepramp_stepper alone: winding sequences per mode in both directions, PWM duty, STEP width, the start gate's DIR
setup/hold timing, enable, mode changes while stopped, and monitors that fail when told a wrong setting.

A fake engine in Python plays the ramp engine's side with its documented timing (docs/stepramp_engine.md): it
takes eng_start at the next edge (edge 0), raises busy, emits pulse 0 two clocks later and then one pulse every
`interval` clocks (>= 64), updating the electrical position (`eng_elec_pos`, the pulses counted modulo 512) in the
cycle of each pulse and dropping busy in the cycle of the last. The bench may also set `eng_elec_pos` directly, to
reach any electrical position at once (the real engine only counts pulses).
Expected values come from stepramp.models.stepping; the pins are also watched by stepramp.sim.monitors.

Edge numbers: edge e is the rising edge at e * CLK_PERIOD_NS; inputs are driven at the falling edge after edge
e - 1 (so edge e samples them); "high after edge e" is the cycle after it.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import pytest
from cocotb.triggers import ClockCycles, Event, FallingEdge, ReadOnly, RisingEdge, Timer
from cocotb.utils import get_sim_time

from stepramp.board.driver import MODES, Outputs
from stepramp.models import stepping as sm
from stepramp.sim import coverage
from stepramp.sim.clocking import reset_held, start_clock
from stepramp.sim.monitors import (
    DirTimingMonitor,
    ElectricalMonitor,
    MotionMonitors,
    ShootThroughMonitor,
    StepWidthMonitor,
)
from stepramp.sim.runner import run_cocotb
from tbutil import CLK_PERIOD_NS, build_dir, cocotb, env_int

MICROSTEPS = env_int("STEPPER_G_MICROSTEPS", sm.DEFAULT_MICROSTEPS)
LG = MICROSTEPS.bit_length() - 1
DUTY_BITS = env_int("STEPPER_G_DUTY_BITS", sm.DEFAULT_DUTY_BITS)
PWM_LATENCY = sm.winding_latency(sm.MODE_PWM, DUTY_BITS)  # 30 clocks at G_DUTY_BITS = 12


# The cocotb tests of this module run one after the other in one simulation, each starting its own clock: edge
# numbers count from the rising edge at which the current test's clock started.
_CLOCK_T0_PS = [0]
_PERIOD_PS = CLK_PERIOD_NS * 1000


def edge_now() -> int:
    """Index of the most recent rising edge (also during the cycle that follows it)."""
    return int((get_sim_time("ps") - _CLOCK_T0_PS[0]) // _PERIOD_PS)


async def after_edge(e: int) -> None:
    """Wait until the falling edge after rising edge e (drive there to be sampled by edge e + 1)."""
    target = _CLOCK_T0_PS[0] + e * _PERIOD_PS + _PERIOD_PS // 2
    now = round(get_sim_time("ps"))
    if target <= now:
        raise RuntimeError(f"after_edge({e}) asked at {now} ps (edge {edge_now()})")
    await Timer(target - now, unit="ps")


def levels(dut: Any) -> tuple[int, int, int, int]:
    return (int(dut.a1.value), int(dut.a2.value), int(dut.b1.value), int(dut.b2.value))


@dataclass
class Move:
    steps: int
    interval: int = 64  # clocks between pulses (>= 64 as the engine guarantees)


@dataclass
class FakeEngine:
    """The engine's side of the interface, driven from Python with the engine's documented timing."""

    dut: Any
    position: int = 0
    dir_override: int | None = None  # drive eng_dir differently from eng_direction (dir_fault test)
    moves: list[Move] = field(default_factory=list)
    start_edges: list[int] = field(default_factory=list)  # edge 0 of every accepted start
    step_edges: list[int] = field(default_factory=list)  # edges after which eng_step is '1'
    eng_start_edges: list[int] = field(default_factory=list)  # every edge after which eng_start is '1'
    busy: bool = False
    ignored: int = 0
    cancelled: int = 0  # starts that came with eng_hard_stop
    last_pulse: Event = field(default_factory=Event)
    done: Event = field(default_factory=Event)

    def start(self) -> FakeEngine:
        self.dut.eng_step.value = 0
        self.dut.eng_busy.value = 0
        self.dut.eng_dir.value = 0
        self.set_position(self.position)
        cocotb.start_soon(self._run())
        return self

    def set_position(self, pos: int) -> None:
        """Jump to electrical position pos (a bench shortcut): eng_elec_pos takes pos modulo 512."""
        self.position = pos
        self.dut.eng_elec_pos.value = pos & 0x1FF

    async def _run(self) -> None:
        dut = self.dut
        while True:
            await RisingEdge(dut.eng_start)
            s = edge_now()
            self.eng_start_edges.append(s)
            if self.busy:
                self.ignored += 1  # the engine ignores a start while busy
                continue
            await ReadOnly()
            if int(dut.eng_hard_stop.value):  # start with hard_stop: the engine accepts and ends it, no pulse
                if self.moves:
                    self.moves.pop(0)
                self.cancelled += 1
                self.done.set()
                continue
            move = self.moves.pop(0) if self.moves else Move(0)
            self.busy = True
            cocotb.start_soon(self._play(s + 1, move))

    async def _play(self, e0: int, move: Move) -> None:
        dut = self.dut
        await RisingEdge(dut.clk)  # edge 0 samples eng_start
        direction = int(dut.eng_direction.value) if self.dir_override is None else self.dir_override
        self.last_pulse.clear()
        self.done.clear()
        self.start_edges.append(e0)
        await after_edge(e0)
        dut.eng_busy.value = 1
        dut.eng_dir.value = direction
        pulse_edge = e0 + sm.ENGINE_FIRST_PULSE_LATENCY
        for k in range(move.steps):
            await after_edge(pulse_edge)
            self.set_position(self.position + (-1 if direction else 1))
            dut.eng_step.value = 1
            self.step_edges.append(pulse_edge)
            if k == move.steps - 1:  # done cycle: busy '0' with the last pulse
                dut.eng_busy.value = 0
                self.busy = False
                self.last_pulse.set()
                self.done.set()
            await after_edge(pulse_edge + 1)
            dut.eng_step.value = 0
            pulse_edge += move.interval
        if move.steps == 0:
            await after_edge(pulse_edge)
            dut.eng_busy.value = 0
            self.busy = False
            self.done.set()

    def arm(self) -> None:
        """Forget the previous move's last_pulse / done before requesting the next one."""
        self.last_pulse.clear()
        self.done.clear()


#: The stepping outputs (the driver's configuration of DRIVE .. STEP_SPACE) where a test does not say otherwise.
OUTPUTS = Outputs(mode="half", ustep_log2=LG, step_width=10, dir_setup=20, dir_hold=20, pwm_period=64)


def apply(dut: Any, cfg: Outputs, enable: int = 1, mode: int | None = None) -> None:
    """Drive the stepper's configuration inputs: the stepping outputs and CTRL.ENABLE. mode, when given, is a raw
    DRIVE.MODE value in place of cfg.mode (the tests that step through mode values pass it, the reserved 5 .. 7 that
    act as 0 included, which Outputs has no name for)."""
    dut.mode.value = MODES[cfg.mode] if mode is None else mode
    dut.ustep_log2.value = cfg.ustep_log2
    dut.step_width.value = cfg.step_width
    dut.dir_setup.value = cfg.dir_setup
    dut.dir_hold.value = cfg.dir_hold
    dut.pwm_period.value = cfg.pwm_period
    dut.ctrl_enable.value = enable
    dut.step_space.value = cfg.step_space


async def setup(dut: Any, cfg: Outputs, position: int = 0, enable: int = 1) -> FakeEngine:
    apply(dut, cfg, enable)
    dut.start_req.value = 0
    dut.new_dir.value = 0
    dut.hard_stop.value = 0
    dut.soft_stop.value = 0
    dut.start_hold.value = 0
    eng = FakeEngine(dut, position=position).start()
    _CLOCK_T0_PS[0] = round(get_sim_time("ps"))
    start_clock(dut.clk)
    async with reset_held(dut.clk, dut.rst):
        await ReadOnly()  # in reset (docs/stepramp_stepper.md): no start held, no fault
        held = (int(dut.gate_busy.value), int(dut.dir_fault.value))
        assert held == (0, 0), f"gate_busy, dir_fault in reset: {held}"
    await ClockCycles(dut.clk, 4)
    coverage.watch_stepper(dut)
    return eng


async def request_start(dut: Any, new_dir: int) -> int:
    """start_req high for one clock with new_dir; returns the edge Q that samples it."""
    await FallingEdge(dut.clk)
    dut.start_req.value = 1
    dut.new_dir.value = new_dir
    q = edge_now() + 1
    await RisingEdge(dut.clk)
    await FallingEdge(dut.clk)
    dut.start_req.value = 0
    return q


async def wait_move(dut: Any, eng: FakeEngine, n_before: int, budget: int = 100_000) -> None:
    """Wait until the engine has accepted a start after n_before starts and finished that move."""
    for _ in range(budget):
        if len(eng.start_edges) > n_before and eng.done.is_set():
            return
        await RisingEdge(dut.clk)
    raise AssertionError(f"no move finished within {budget} clocks (starts {eng.start_edges})")


async def run_move(dut: Any, eng: FakeEngine, steps: int, direction: int, interval: int = 64) -> int:
    """Queue one move, request it, wait for its end (plus a few clocks). Returns the request edge."""
    eng.moves.append(Move(steps, interval))
    n = len(eng.start_edges)
    eng.arm()
    q = await request_start(dut, direction)
    await wait_move(dut, eng, n)
    await ClockCycles(dut.clk, 4)
    while int(dut.step.value) == 1:  # let the last STEP pulse end
        await FallingEdge(dut.step)
    await ClockCycles(dut.clk, 2)
    return q


# --------------------------------------------------------------------------------------------------------------
# Winding sequences of the on/off modes.
# --------------------------------------------------------------------------------------------------------------
class StepRecorder:
    """Windings `latency` clocks after each STEP rising edge, and DIR at the edge."""

    def __init__(self, dut: Any, latency: int) -> None:
        self.dut = dut
        self.latency = latency
        self.samples: list[tuple[int, tuple[int, int, int, int]]] = []
        self.task = cocotb.start_soon(self._watch())

    async def _watch(self) -> None:
        while True:
            await RisingEdge(self.dut.step)
            d = int(self.dut.dir.value)
            if self.latency:
                await ClockCycles(self.dut.clk, self.latency)
            await ReadOnly()
            self.samples.append((d, levels(self.dut)))

    def stop(self) -> None:
        self.task.cancel()


@cocotb.test(timeout_time=500, timeout_unit="us")  # measured 118 us
async def windings_follow_steps(dut) -> None:
    """Modes 0 .. 3 (and 5 .. 7 = 0): the state after every step is the model's for position mod n, forwards,
    backwards and across reversals, starting from positive and negative positions."""
    cfg = replace(OUTPUTS, step_width=8, dir_setup=12, dir_hold=9)
    eng = await setup(dut, cfg)
    for mode, start in ((1, 0), (2, 5), (3, -3), (0, 2), (3, 512 - 3), (6, 1)):
        apply(dut, cfg, mode=mode)
        eng.set_position(start)
        await ClockCycles(dut.clk, 3)
        mons = MotionMonitors(
            dut, mode=mode, step_width=cfg.step_width, dir_setup=cfg.dir_setup, dir_hold=cfg.dir_hold, position=start
        ).start()
        rec = StepRecorder(dut, 0)
        plan = [(11, 0, 64), (5, 1, 70), (1, 0, 64), (1, 1, 64), (13, 1, 65), (3, 0, 64)]
        for steps, direction, interval in plan:
            await run_move(dut, eng, steps, direction, interval)
        rec.stop()
        mons.stop()
        mons.check()
        dirs = [d for d, _ in rec.samples]
        expected = [sm.winding_levels(mode, p) for p in sm.step_positions(start, dirs)]
        got = [lv for _, lv in rec.samples]
        assert dirs == [d for steps, d, _ in plan for _ in range(steps)], f"mode {mode}: DIR per step {dirs}"
        assert got == expected, f"mode {mode}: windings {got[:10]}..., expected {expected[:10]}..."
        assert mons.electrical.checked == len(got) + 1 and mons.width.pulses == len(got)
        assert eng.position == start + 11 - 5 + 1 - 1 - 13 + 3
        # From 509 the 9-bit eng_elec_pos wraps at 512 and the electrical position goes on.
        dut._log.info("mode %d: %d steps checked from position %d", mode, len(got), start)


# --------------------------------------------------------------------------------------------------------------
# PWM.
# --------------------------------------------------------------------------------------------------------------
async def measure_duty(dut: Any, period: int) -> tuple[int, int, int, int]:
    """On-clocks of a1, a2, b1, b2 over one carrier period."""
    counts = [0, 0, 0, 0]
    for _ in range(period):
        await RisingEdge(dut.clk)
        await ReadOnly()
        for k, v in enumerate(levels(dut)):
            counts[k] += v
    await FallingEdge(dut.clk)
    return (counts[0], counts[1], counts[2], counts[3])


def expected_counts(a: sm.Winding, b: sm.Winding) -> tuple[int, int, int, int]:
    def pair(w: sm.Winding) -> tuple[int, int]:
        return (w.duty, 0) if w.polarity > 0 else (0, w.duty) if w.polarity < 0 else (0, 0)

    return (*pair(a), *pair(b))


def pwm_cases() -> list[tuple[int, int, list[int]]]:
    """(ustep_log2, pwm_period, positions) for the generic under test."""
    cases: list[tuple[int, int, list[int]]] = []
    for u in sorted({LG, LG // 2, 0}):
        n = 4 << u
        stride = max(1, n // 64)  # every position up to 64; pwm_table_matches_model covers the rest
        cases.append((u, 37, list(range(-2, n + 2, stride))))
    cases.append((7, 37, [1, 2, (4 << LG) - 1]))  # ustep_log2 beyond G_MICROSTEPS: clamped
    cases.append((LG, 256, list(range(0, 4 << LG, max(1, (4 << LG) // 16)))))
    cases.append((LG, 1000, [0, 1, 3 << LG, (4 << LG) - 1, -(1 << LG) - 1]))
    cases.append((LG, 2, list(range(4 << LG))[:16]))
    cases.append((LG, 3, [0, 1, 2, 5, 9]))
    return cases


# Limit: 4x the clocks it waits (per position the PWM latency and one carrier period), which vary with the generics.
PWM_DUTY_LIMIT_US = math.ceil(
    4 * (sum(len(ps) * (PWM_LATENCY + period + 1) for _, period, ps in pwm_cases()) + 100) * CLK_PERIOD_NS / 1000
)


@cocotb.test(timeout_time=PWM_DUTY_LIMIT_US, timeout_unit="us")  # 692 us at the defaults, measured 170 us
async def pwm_duty_per_position(dut) -> None:
    """Mode 4: on-clocks of each bridge input over a carrier period equal the model's duty and polarity (exactly)
    for several ustep_log2 and pwm_period values, positions around the whole cycle and negative ones."""
    cfg = replace(OUTPUTS, mode="pwm")
    eng = await setup(dut, cfg)
    checked = 0
    for u, period, positions in pwm_cases():
        cfg = replace(cfg, ustep_log2=u, pwm_period=period)
        apply(dut, cfg)
        for pos in positions:
            eng.set_position(pos)
            await ClockCycles(dut.clk, PWM_LATENCY)
            got = await measure_duty(dut, period)
            a, b = sm.pwm_windings(pos, u, period, MICROSTEPS, DUTY_BITS)
            assert got == expected_counts(a, b), f"u={u} P={period} position {pos}: {got} vs {a}, {b}"
            checked += 1
    dut._log.info("%d PWM positions measured", checked)


# Limit: 4x the clocks it waits (the PWM latency per position, 2 periods x 4 * G_MICROSTEPS positions).
PWM_TABLE_LIMIT_US = math.ceil(4 * (2 * (4 << LG) * (PWM_LATENCY + 1) + 100) * CLK_PERIOD_NS / 1000)


@cocotb.test(timeout_time=PWM_TABLE_LIMIT_US, timeout_unit="us")  # 163 us at the defaults, measured 39 us
async def pwm_table_matches_model(dut) -> None:
    """The elaborated table (ieee.math_real) equals the model's for every electrical position: with
    pwm_period = 2^G_DUTY_BITS the duty register is the magnitude itself; with 65535 the multiplier's full range."""
    cfg = replace(OUTPUTS, mode="pwm", ustep_log2=LG)
    eng = await setup(dut, cfg)
    table = sm.cos_table(MICROSTEPS, DUTY_BITS)
    assert len(table) == MICROSTEPS + 1
    unit = min(1 << DUTY_BITS, 1 << 15)  # pwm_period is 16 bits
    for period in (unit, 65535):
        cfg = replace(cfg, pwm_period=period)
        apply(dut, cfg)
        for pos in range(4 << LG):
            eng.set_position(pos)
            await ClockCycles(dut.clk, PWM_LATENCY)  # the latest edge the duty may change
            await ReadOnly()
            a, b = sm.pwm_windings(pos, LG, period, MICROSTEPS, DUTY_BITS)
            got = (int(dut.duty_a.value), int(dut.neg_a.value), int(dut.duty_b.value), int(dut.neg_b.value))
            want = (a.duty, int(a.polarity < 0), b.duty, int(b.polarity < 0))
            if period == 1 << DUTY_BITS:
                assert (a.duty, b.duty) == (a.magnitude, b.magnitude)
            # polarity is don't-care where the magnitude is 0
            if a.duty == 0:
                got, want = (got[0], 0, *got[2:]), (want[0], 0, *want[2:])
            if b.duty == 0:
                got, want = (*got[:3], 0), (*want[:3], 0)
            assert got == want, f"P={period} position {pos}: duty_a neg_a duty_b neg_b {got}, expected {want}"
            await FallingEdge(dut.clk)


@cocotb.test(timeout_time=1, timeout_unit="ms")  # measured 217 us at every generic set
async def pwm_motion_with_monitors(dut) -> None:
    """Mode 4 moves in both directions with every monitor on (polarity at each step, duty now and then)."""
    eng: FakeEngine | None = None
    for u, period, interval in ((LG, 64, 150), (min(2, LG), 40, 100)):
        cfg = replace(OUTPUTS, mode="pwm", ustep_log2=u, pwm_period=period, step_width=5, dir_setup=7, dir_hold=7)
        if eng is None:
            eng = await setup(dut, cfg, position=-5)
        else:
            apply(dut, cfg)
            eng.set_position(-5)
        await ClockCycles(dut.clk, PWM_LATENCY + 1)
        mons = MotionMonitors(
            dut,
            mode=sm.MODE_PWM,
            step_width=5,
            dir_setup=7,
            dir_hold=7,
            position=-5,
            ustep_log2=u,
            pwm_period=period,
            microsteps=MICROSTEPS,
            duty_bits=DUTY_BITS,
            pwm_every=3,
        ).start()
        for steps, direction in ((40, 0), (17, 1), (2, 0), (30, 1)):
            await run_move(dut, eng, steps, direction, interval)
        await ClockCycles(dut.clk, 2 * period)
        mons.stop()
        mons.check()
        el = mons.electrical
        assert el.steps == 89 and el.duty_measured >= 25, (el.steps, el.duty_measured, el.duty_skipped)
        assert mons.shoot.edges > 50


# --------------------------------------------------------------------------------------------------------------
# Mode and enable changes while stopped.
# --------------------------------------------------------------------------------------------------------------
@cocotb.test(timeout_time=40, timeout_unit="us")  # measured 8.6 us
async def mode_changes_while_stopped(dut) -> None:
    """Every mode value at several positions: the pins show the model's state one clock after the change (PWM:
    after its pipeline), and mode 0 / 5 .. 7 switch everything off."""
    cfg = replace(OUTPUTS, pwm_period=50)
    eng = await setup(dut, cfg)
    for pos in (0, 1, 6, -3, 12345):
        eng.set_position(pos)
        for mode in (3, 0, 1, 4, 2, 5, 7, 3, 4, 6):
            apply(dut, cfg, mode=mode)
            await RisingEdge(dut.clk)
            await ReadOnly()
            if sm.effective_mode(mode) != sm.MODE_PWM:
                assert levels(dut) == sm.winding_levels(mode, pos), f"mode {mode} position {pos}: {levels(dut)}"
                await FallingEdge(dut.clk)
            else:
                await ClockCycles(dut.clk, PWM_LATENCY)
                got = await measure_duty(dut, cfg.pwm_period)
                want = expected_counts(*sm.pwm_windings(pos, cfg.ustep_log2, 50, MICROSTEPS, DUTY_BITS))
                assert got == want, f"mode {mode} position {pos}: {got}, expected {want}"


@cocotb.test(timeout_time=80, timeout_unit="us")  # measured 20 us
async def enable_gates_windings(dut) -> None:
    """enable is ctrl_enable one clock later; with ctrl_enable = 0 every winding input is 0 in every mode (PWM and
    pwm_period <= 1 too) while STEP/DIR keep working; switching back restores the state of the position."""
    cfg = replace(OUTPUTS, mode="half")
    eng = await setup(dut, cfg, position=1, enable=0)
    assert int(dut.enable.value) == 0
    for mode in (1, 2, 3, 4):
        apply(dut, cfg, enable=0, mode=mode)
        mons = MotionMonitors(
            dut,
            mode=mode,
            step_width=cfg.step_width,
            dir_setup=cfg.dir_setup,
            dir_hold=cfg.dir_hold,
            position=eng.position,
            pwm_period=cfg.pwm_period,
            microsteps=MICROSTEPS,
            duty_bits=DUTY_BITS,
            ustep_log2=cfg.ustep_log2,
            enable=False,
            pwm_every=1,
        )
        await ClockCycles(dut.clk, 1)
        mons.start()
        await run_move(dut, eng, 6, mode % 2, 80)
        mons.stop()
        mons.check()
        assert mons.width.pulses == 6
        # enable on: registered one clock later, windings at the current position
        await FallingEdge(dut.clk)
        dut.ctrl_enable.value = 1
        await RisingEdge(dut.clk)
        e = edge_now()
        await ReadOnly()
        assert int(dut.enable.value) == 1, "enable one clock after ctrl_enable"
        if mode != sm.MODE_PWM:
            assert levels(dut) == sm.winding_levels(mode, eng.position)
        await FallingEdge(dut.clk)
        dut.ctrl_enable.value = 0
        await RisingEdge(dut.clk)
        assert edge_now() == e + 1
        await ReadOnly()
        assert int(dut.enable.value) == 0 and levels(dut) == (0, 0, 0, 0)
        await FallingEdge(dut.clk)
    # PWM with the carrier held off (pwm_period 0 and 1): outputs off although enabled
    for period in (0, 1):
        cfg = replace(cfg, mode="pwm", pwm_period=period)
        apply(dut, cfg, enable=1)
        eng.set_position(0)  # A at full scale
        await ClockCycles(dut.clk, 4)
        assert await measure_duty(dut, 100) == (0, 0, 0, 0), f"pwm_period {period}"


# --------------------------------------------------------------------------------------------------------------
# STEP width.
# --------------------------------------------------------------------------------------------------------------
@cocotb.test(timeout_time=80, timeout_unit="us")  # measured 17 us
async def step_width_exact(dut) -> None:
    """step rises one clock after eng_step and stays high exactly max(step_width, 1) clocks."""
    cfg = replace(OUTPUTS, mode="full")
    eng = await setup(dut, cfg)
    for width in (0, 1, 2, 5, 37, 63):
        cfg = replace(cfg, step_width=width)
        apply(dut, cfg)
        mon = StepWidthMonitor(dut.step, width, exact=True).start()
        rises: list[int] = []

        async def watch(rises: list[int] = rises) -> None:
            while True:
                await RisingEdge(dut.step)
                rises.append(edge_now())

        task = cocotb.start_soon(watch())
        n0 = len(eng.step_edges)
        await run_move(dut, eng, 5, 0, 64)
        task.cancel()
        mon.stop()
        mon.check()
        assert mon.pulses == 5 and mon.widths == [sm.step_pulse_width(width)] * 5
        assert rises == [e + sm.STEP_LATENCY for e in eng.step_edges[n0:]], (rises, eng.step_edges[n0:])


@cocotb.test(timeout_time=12, timeout_unit="us")  # measured 3.0 us
async def step_overlap_restarts_width(dut) -> None:
    """A pulse that comes while STEP is still high (step_width > interval: the driver never programs this)
    restarts the width: one STEP pulse, high until step_width clocks after the later pulse."""
    cfg = replace(OUTPUTS, mode="full", step_width=100)
    eng = await setup(dut, cfg)
    mon = StepWidthMonitor(dut.step, 100).start()
    await run_move(dut, eng, 2, 0, 64)
    await ClockCycles(dut.clk, 120)
    mon.stop()
    mon.check()
    assert mon.pulses == 1 and mon.widths == [64 + 100]


# --------------------------------------------------------------------------------------------------------------
# Start gate.
# --------------------------------------------------------------------------------------------------------------
class GateRecorder:
    """Edges of DIR changes, eng_start pulses and step rising edges."""

    def __init__(self, dut: Any) -> None:
        self.dut = dut
        self.dir_edges: list[int] = []
        self.start_edges: list[int] = []
        self.step_rises: list[int] = []
        self.tasks = [
            cocotb.start_soon(self._watch(dut.dir.value_change, self.dir_edges)),
            cocotb.start_soon(self._watch_rise(dut.eng_start, self.start_edges)),
            cocotb.start_soon(self._watch_rise(dut.step, self.step_rises)),
        ]

    async def _watch(self, trigger: Any, out: list[int]) -> None:
        while True:
            await trigger
            out.append(edge_now())

    async def _watch_rise(self, sig: Any, out: list[int]) -> None:
        while True:
            await RisingEdge(sig)
            out.append(edge_now())

    def stop(self) -> None:
        for t in self.tasks:
            t.cancel()


@cocotb.test(timeout_time=800, timeout_unit="us")  # measured 185 us
async def start_gate_timing(dut) -> None:
    """eng_start 1 clock after start_req when DIR stays; on a change DIR waits for dir_hold after the last STEP
    rising edge, eng_start for max(dir_setup, 5) clocks to the first STEP rising edge; either way the first STEP
    rising edge keeps STEP_WIDTH + STEP_SPACE from the last one: measured edge for edge against
    stepramp.models.stepping.gate_timing, with the DIR monitor on."""
    cfg = replace(OUTPUTS, mode="half", step_width=4)
    eng = await setup(dut, cfg)
    cases = [
        # (dir_setup, dir_hold, new_dir, gap, step_width, step_space): gap = clocks between the last pulse's
        # eng_step and start_req (0: start_req in the engine's done cycle, the last pulse's own cycle)
        (20, 20, 0, 30, 4, 1),
        (20, 20, 1, 30, 4, 1),
        (20, 20, 1, 100, 4, 1),
        (0, 0, 0, 5, 4, 1),
        (1, 1, 1, 0, 4, 1),
        (5, 1, 0, 0, 4, 1),
        (6, 3, 1, 0, 4, 1),
        (9, 40, 0, 0, 4, 1),
        (9, 40, 1, 12, 4, 1),
        (300, 200, 0, 3, 4, 1),
        (4, 64, 1, 63, 4, 1),
        (64, 7, 0, 7, 4, 1),
        (64, 7, 0, 8, 4, 1),
        (2, 1000, 1, 0, 4, 1),
        # STEP spacing across moves holds the start (same direction, and after a DIR change)
        (0, 0, 0, 0, 1, 1),
        (0, 0, 0, 0, 2, 1),
        (0, 0, 0, 0, 2, 2),
        (0, 0, 0, 0, 40, 30),
        (0, 0, 0, 2, 40, 30),
        (0, 0, 0, 66, 40, 30),
        (0, 0, 0, 67, 40, 30),
        (0, 0, 0, 3, 0, 0),
        (5, 1, 1, 0, 40, 30),
        (30, 20, 1, 10, 40, 30),
        (80, 20, 1, 10, 40, 30),
        (5, 1, 1, 0, 1000, 5000),
    ]
    for setup_clks, hold, new_dir, gap, width, space in cases:
        cfg = replace(cfg, dir_setup=setup_clks, dir_hold=hold, step_width=width, step_space=space)
        apply(dut, cfg)
        # a previous move ends with a pulse at a known edge
        eng.moves.append(Move(3, 64))
        prev_dir = int(dut.dir.value)
        eng.arm()
        await request_start(dut, prev_dir)
        await eng.last_pulse.wait()
        last_eng_step = eng.step_edges[-1]  # eng_step high after this edge
        last_rise = last_eng_step + sm.STEP_LATENCY
        mon = DirTimingMonitor(dut.step, dut.dir, setup_clks, hold).start()
        rec = GateRecorder(dut)
        eng.moves.append(Move(2, 64))
        busy_trace: list[int] = []
        # start_req in the cycle after edge last_eng_step + gap: sampled at q
        q = last_eng_step + gap + 1
        if q > edge_now() + 1:
            await after_edge(q - 1)
        dut.start_req.value = 1
        dut.new_dir.value = new_dir
        assert edge_now() == q - 1
        await after_edge(q)
        dut.start_req.value = 0
        # busy as the register file sees it (gate_busy or eng_busy) from the cycle after q until the move ends
        for _ in range(10_000):
            await ReadOnly()
            busy_trace.append(int(dut.gate_busy.value) | int(dut.eng_busy.value))
            if eng.done.is_set() and len(eng.start_edges) >= 2 and eng.start_edges[-1] > q:
                break
            await FallingEdge(dut.clk)
        await ClockCycles(dut.clk, 2 * hold + 2 * setup_clks + 20)
        rec.stop()
        mon.stop()
        want = sm.gate_timing(q, new_dir != prev_dir, last_rise, hold, setup_clks, width, space)
        got_dir = rec.dir_edges[0] if rec.dir_edges else None
        msg = f"setup {setup_clks} hold {hold} width {width} space {space} dir {prev_dir}->{new_dir} gap {gap}: "
        msg += f"q={q}, want {want}, got "
        msg += f"dir {rec.dir_edges} eng_start {rec.start_edges} step rises {rec.step_rises}"
        assert got_dir == want.dir_edge and len(rec.dir_edges) <= 1, msg
        assert rec.start_edges == [want.start_edge], msg
        rises = [r for r in rec.step_rises if r > last_rise]
        assert rises and rises[0] == want.first_step_edge, msg
        assert eng.start_edges[-1] == want.start_edge + 1, msg
        spacing = max(width, 1) + max(space, 1)
        assert rises[0] - last_rise >= spacing, msg
        if want.dir_edge is not None:
            assert want.first_step_edge - want.dir_edge >= max(setup_clks, sm.GATE_SETUP_MIN), msg
            if rises[0] - last_rise > spacing:
                assert want.first_step_edge - want.dir_edge == max(setup_clks, sm.GATE_SETUP_MIN), msg
        assert all(busy_trace[:-1]), f"busy dropped during the start: {busy_trace}"
        mon.check()
        assert int(dut.dir.value) == new_dir and int(dut.dir_fault.value) == 0
        dut._log.info(
            "setup %d hold %d %d->%d gap %d: eng_start after %d clocks, first STEP %d clocks after DIR",
            setup_clks,
            hold,
            prev_dir,
            new_dir,
            gap,
            want.latency,
            0 if want.dir_edge is None else want.first_step_edge - want.dir_edge,
        )


@cocotb.test(timeout_time=20, timeout_unit="us")  # measured 4.5 us
async def start_dropped_while_busy(dut) -> None:
    """A start_req while the engine is busy or while the gate holds a start is dropped: no eng_start, no DIR change."""
    cfg = replace(OUTPUTS, mode="half", dir_setup=50, dir_hold=50)
    eng = await setup(dut, cfg)
    rec = GateRecorder(dut)
    # engine busy: a request with the other direction in the middle of a move
    eng.moves.append(Move(6, 64))
    await request_start(dut, 0)
    await ClockCycles(dut.clk, 100)
    assert eng.busy
    await request_start(dut, 1)
    await request_start(dut, 0)
    await wait_move(dut, eng, 0)
    await ClockCycles(dut.clk, 10)
    assert rec.dir_edges == [] and len(rec.start_edges) == 1 and eng.ignored == 0
    # gate busy: a direction change waits for hold, a second request meanwhile is dropped
    eng.moves.append(Move(1, 64))
    q = await request_start(dut, 1)
    assert int(dut.gate_busy.value) == 1
    await request_start(dut, 0)
    await request_start(dut, 0)
    await wait_move(dut, eng, 1)
    await ClockCycles(dut.clk, 20)
    rec.stop()
    assert len(rec.dir_edges) == 1 and len(rec.start_edges) == 2, (rec.dir_edges, rec.start_edges)
    assert rec.dir_edges[0] > q and int(dut.dir.value) == 1 and int(dut.gate_busy.value) == 0


@cocotb.test(timeout_time=80, timeout_unit="us")  # measured 19 us
async def hard_stop_cancels_a_held_start(dut) -> None:
    """hard_stop while the gate holds a start (DIR hold, DIR setup) or with the start_req it accepts: eng_start and
    eng_hard_stop together after that edge (the engine accepts and ends the move at once), no DIR change from then
    on."""
    cfg = replace(OUTPUTS, mode="half", dir_setup=200, dir_hold=100)
    eng = await setup(dut, cfg)
    rec = GateRecorder(dut)
    stops: list[int] = []

    async def watch_stop() -> None:
        while True:
            await RisingEdge(dut.eng_hard_stop)
            await ReadOnly()
            assert int(dut.eng_start.value) == 1, "eng_hard_stop without eng_start"
            stops.append(edge_now())

    watcher = cocotb.start_soon(watch_stop())

    async def request_with_stop(new_dir: int, strobe: Any) -> int:
        """start_req and a stop strobe high in the same cycle; returns the edge Q that samples both."""
        await FallingEdge(dut.clk)
        dut.start_req.value = 1
        dut.new_dir.value = new_dir
        strobe.value = 1
        q = edge_now() + 1
        await after_edge(q)
        dut.start_req.value = 0
        strobe.value = 0
        return q

    async def stop_at(h: int, kind: str = "hard") -> None:
        strobe = dut.hard_stop if kind == "hard" else dut.soft_stop
        await after_edge(h - 1)
        strobe.value = 1
        await after_edge(h)
        strobe.value = 0

    # A normal move in direction 0 first: eng_hard_stop stays low.
    await run_move(dut, eng, 2, 0)
    assert stops == []
    # DIR hold: direction 1 requested right after the last pulse waits for dir_hold; stopped meanwhile.
    n_starts = len(rec.start_edges)
    eng.moves.append(Move(3))  # what the engine would play if the cancel failed
    q = await request_start(dut, 1)
    assert int(dut.gate_busy.value) == 1
    await stop_at(q + 20)
    await ClockCycles(dut.clk, 400)
    assert stops == [q + 20] and rec.start_edges[n_starts:] == [q + 20], (stops, rec.start_edges)
    assert rec.dir_edges == [] and int(dut.dir.value) == 0, "DIR changed after a stop during its hold"
    assert int(dut.gate_busy.value) == 0
    # DIR setup: DIR changes at once (no pulse for a while), the start waits 195 clocks; stopped meanwhile.
    eng.moves.append(Move(3))  # what the engine would play if the cancel failed
    q = await request_start(dut, 1)
    await stop_at(q + 50)
    await ClockCycles(dut.clk, 400)
    assert stops[-1] == q + 50 and rec.start_edges[-1] == q + 50
    assert rec.dir_edges == [q + 1] and int(dut.dir.value) == 1
    # A soft stop during DIR setup cancels the start the same way (at rest there is nothing to decelerate).
    eng.moves.append(Move(3))
    q = await request_start(dut, 0)
    await stop_at(q + 30, "soft")
    await ClockCycles(dut.clk, 400)
    assert stops[-1] == q + 30 and rec.start_edges[-1] == q + 30
    assert rec.dir_edges[-1] == q + 1 and int(dut.dir.value) == 0
    n_dir = len(rec.dir_edges)
    # start_req and hard_stop at one edge, with a direction change: no DIR change, eng_start with eng_hard_stop.
    eng.moves.append(Move(3))
    q = await request_with_stop(1, dut.hard_stop)
    await ClockCycles(dut.clk, 400)
    assert stops[-1] == q and rec.start_edges[-1] == q
    assert len(rec.dir_edges) == n_dir and int(dut.dir.value) == 0
    # A soft stop with the start_req it accepts is not a cancel: the engine decides it (it ignores a soft stop at
    # its start edge), so eng_start comes alone.
    n_stops = len(stops)
    q = await request_with_stop(0, dut.soft_stop)
    await ClockCycles(dut.clk, 100)
    assert len(stops) == n_stops and rec.start_edges[-1] == q
    assert eng.cancelled == 4 and not eng.moves
    assert len(eng.step_edges) == 2, "only the first move pulsed"
    watcher.cancel()
    rec.stop()


@cocotb.test(timeout_time=4, timeout_unit="us")  # measured 0.9 us
async def dir_fault_flags_engine_direction(dut) -> None:
    """An engine pulse whose direction differs from DIR (engine started around the gate) sets dir_fault until the
    next accepted start_req."""
    cfg = replace(OUTPUTS, mode="full")
    eng = await setup(dut, cfg)
    eng.dir_override = 1
    await run_move(dut, eng, 2, 0)
    assert int(dut.dir_fault.value) == 1
    eng.dir_override = None
    eng.arm()
    await request_start(dut, 0)
    await ClockCycles(dut.clk, 2)
    assert int(dut.dir_fault.value) == 0
    await eng.done.wait()
    await ClockCycles(dut.clk, 2)
    assert int(dut.dir_fault.value) == 0


# --------------------------------------------------------------------------------------------------------------
# The monitors fail when given a wrong setting.
# --------------------------------------------------------------------------------------------------------------
def assert_fails(dut: Any, mon: Any, what: str) -> None:
    try:
        mon.check()
    except AssertionError as exc:
        dut._log.info("%s fails as it should: %s", what, str(exc).splitlines()[0])
        return
    raise AssertionError(f"{what}: the monitor did not fail")


@cocotb.test(timeout_time=35, timeout_unit="us")  # measured 7.7 us
async def monitors_fail_on_wrong_settings(dut) -> None:
    """Each monitor, told a setting other than the one programmed, reports violations (and passes with the right
    one on the same run): width + 1, exact width - 1, setup + 1, hold + 1, a position off by one, the wrong mode, the
    wrong ustep_log2 for the PWM duty, and a bridge whose inputs are both '1'; and MotionMonitors, whose one STEP
    coroutine does the width, DIR and position work, with the right settings and with each of four wrong ones."""
    cfg = replace(OUTPUTS, mode="half", step_width=9, dir_setup=30, dir_hold=25)
    eng = await setup(dut, cfg)
    await run_move(dut, eng, 3, 0)
    w, s, h = cfg.step_width, cfg.dir_setup, cfg.dir_hold
    right = [
        StepWidthMonitor(dut.step, w, exact=True),
        DirTimingMonitor(dut.step, dut.dir, s, h),
        ElectricalMonitor(dut.clk, dut.step, dut.dir, (dut.a1, dut.a2, dut.b1, dut.b2), 3, position=3),
    ]
    wrong = {
        "width + 1": StepWidthMonitor(dut.step, w + 1),
        "exact width - 1": StepWidthMonitor(dut.step, w - 1, exact=True),
        "setup + 1": DirTimingMonitor(dut.step, dut.dir, s + 1, 0),
        "hold + 1": DirTimingMonitor(dut.step, dut.dir, 0, h + 1),
        "position + 1": ElectricalMonitor(dut.clk, dut.step, dut.dir, (dut.a1, dut.a2, dut.b1, dut.b2), 3, position=4),
        "mode full instead of half": ElectricalMonitor(
            dut.clk, dut.step, dut.dir, (dut.a1, dut.a2, dut.b1, dut.b2), 2, position=3
        ),
    }
    # the same checks through MotionMonitors, whose one STEP coroutine does the width, DIR and position work
    hub = functools.partial(MotionMonitors, dut, mode=3)
    right += [hub(step_width=w, dir_setup=s, dir_hold=h, position=3)]
    wrong |= {
        "all four, width + 1": hub(step_width=w + 1, dir_setup=s, dir_hold=h, position=3),
        "all four, setup + 1": hub(step_width=w, dir_setup=s + 1, dir_hold=h, position=3),
        "all four, hold + 1": hub(step_width=w, dir_setup=s, dir_hold=h + 1, position=3),
        "all four, position + 1": hub(step_width=w, dir_setup=s, dir_hold=h, position=4),
    }
    for m in [*right, *wrong.values()]:
        m.start()
    # reverse right after the end of a move (start_req in the done cycle): hold and setup are exactly as programmed
    eng.moves.append(Move(4, 64))
    n = len(eng.start_edges)
    eng.arm()
    await request_start(dut, 0)
    await eng.last_pulse.wait()
    dut.start_req.value = 1
    dut.new_dir.value = 1
    await after_edge(edge_now() + 1)
    dut.start_req.value = 0
    eng.moves.append(Move(5, 64))
    await wait_move(dut, eng, n + 1)
    await ClockCycles(dut.clk, 4)
    for m in [*right, *wrong.values()]:
        m.stop()
    for m in right:
        m.check()
    for what, m in wrong.items():
        assert_fails(dut, m, what)
    # PWM: the duty measured against a wrong ustep_log2 (same polarities at this position, other duties)
    cfg = replace(cfg, mode="pwm", pwm_period=60)
    apply(dut, cfg)
    eng.set_position(5)
    await ClockCycles(dut.clk, PWM_LATENCY + 1)
    pins = (dut.a1, dut.a2, dut.b1, dut.b2)
    ok = ElectricalMonitor(dut.clk, dut.step, dut.dir, pins, 4, position=5, ustep_log2=LG, pwm_period=60)
    bad = ElectricalMonitor(dut.clk, dut.step, dut.dir, pins, 4, position=5, ustep_log2=LG - 1, pwm_period=60)
    a_ok, b_ok = ok.expected_pwm(5)
    a_bad, b_bad = bad.expected_pwm(5)
    assert (a_ok.polarity, b_ok.polarity) == (a_bad.polarity, b_bad.polarity) and a_ok.duty != a_bad.duty
    ok.start()
    bad.start()
    await ClockCycles(dut.clk, 70)
    ok.stop()
    bad.stop()
    ok.check()
    assert ok.duty_measured == bad.duty_measured == 1
    assert_fails(dut, bad, "ustep_log2 - 1 (duty)")
    # shoot-through: two inputs the test drives, both '1'
    shoot = ShootThroughMonitor([(dut.new_dir, dut.start_req)]).start()
    await FallingEdge(dut.clk)
    dut.new_dir.value = 1
    await FallingEdge(dut.clk)
    dut.eng_busy.value = 1  # so that the start_req below is dropped
    dut.start_req.value = 1
    await FallingEdge(dut.clk)
    dut.start_req.value = 0
    dut.eng_busy.value = 0
    await ClockCycles(dut.clk, 2)
    shoot.stop()
    assert_fails(dut, shoot, "shoot-through on (new_dir, start_req)")


# --------------------------------------------------------------------------------------------------------------
# pytest entry points: one simulation per generic set.
# --------------------------------------------------------------------------------------------------------------
ALL_TESTS: Sequence[str] = (
    "windings_follow_steps",
    "pwm_duty_per_position",
    "pwm_table_matches_model",
    "pwm_motion_with_monitors",
    "mode_changes_while_stopped",
    "enable_gates_windings",
    "step_width_exact",
    "step_overlap_restarts_width",
    "start_gate_timing",
    "start_dropped_while_busy",
    "hard_stop_cancels_a_held_start",
    "dir_fault_flags_engine_direction",
    "monitors_fail_on_wrong_settings",
)
PWM_TESTS: Sequence[str] = ("pwm_duty_per_position", "pwm_table_matches_model", "pwm_motion_with_monitors")


def test_stepper() -> None:
    """Everything at the default G_MICROSTEPS = 16."""
    run_cocotb("stepramp_stepper", "test_stepper", build_dir("stepper"), testcase=list(ALL_TESTS))


@pytest.mark.parametrize(("microsteps", "duty_bits"), [(1, 12), (2, 12), (64, 12), (128, 16), (8, 4)])
def test_stepper_pwm_generics(microsteps: int, duty_bits: int) -> None:
    """The PWM tests at other table sizes and resolutions: the smallest, the 64 microsteps the spec asks for, the
    largest table with 16-bit magnitudes, and the coarsest 4-bit table."""
    run_cocotb(
        "stepramp_stepper",
        "test_stepper",
        build_dir(f"stepper_g{microsteps}_b{duty_bits}"),
        parameters={"G_MICROSTEPS": microsteps, "G_DUTY_BITS": duty_bits},
        extra_env={"STEPPER_G_MICROSTEPS": str(microsteps), "STEPPER_G_DUTY_BITS": str(duty_bits)},
        testcase=list(PWM_TESTS),
    )
