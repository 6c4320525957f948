# SPDX-License-Identifier: MIT
"""Random soak: constrained-random bus sequences on both tops, the model as scoreboard, the monitors on.

One cocotb test, `soak`, plays operations drawn from a seeded generator through the driver, on stepramp_plb (IPIF)
or stepramp_axil (AXI4-Lite, with idle cycles and backpressure on every channel from the same seed):

* ``move``: a random move (steps, cruise period, ramp lengths, PRESCALE, direction): every STEP edge equal to
  stepramp.models.engine.edges, no error, POSITION the sum of the steps;
* ``stop``: a move with a soft or a hard stop after a random number of pulses: every edge as
  stepramp.models.engine.edges_with_stop says for the edge the engine sampled the strobe at, POSITION the pulses seen;
* ``busy_writes``: a move with one to four writes to random registers during it (every register, random values;
  CTRL only its enables, STATUS only 0): the move is unchanged, motion registers take the value (shadowed), the
  stepping configuration and POSITION ignore it with CFG_BUSY / POS_BUSY, the read-only registers ignore it;
* ``idle_writes``: writes to random registers while stopped, each read back against the register map (RW fields
  keep the value, read-only registers do not change, STATUS W1C clears what is written 1), POSITION presets;
* ``bad_value``: a valid trapezoid (ramps and a cruise, so that every motion register is used) with one bad register
  value (peripheral_tb.BAD_VALUES): its error code, no pulse, POSITION unchanged;
* ``reset``: the top's reset in the middle of a move: the edges before it are the model's first edges, no pulse
  after it, every register at its reset value;
* ``configure``: random stepping outputs (mode, widths, DIR timing, PWM period, ENABLE) through the driver, which
  restarts the monitors (STEP width, DIR setup/hold, windings) with them;
* ``change``: a move, and a take-over (CTRL.CHANGE) a few pulses after STEP_COUNT was read, to a new target, speed,
  accel and decel (stepramp.board.change.plan_change from the move's speed at that pulse): every edge as
  stepramp.models.engine.change_edges says, or, when the core refused it (the pulse had passed: the bus pauses make
  that happen), as the move alone; POSITION either way;
* ``queue``: a move and a second one queued during it (CTRL.QUEUE), either direction: both as the model says;
* ``jog_zero``: a jog, then the jog the other way through zero (SOFT_STOP with QUEUE in one write), ended by a hard
  stop: each jog's edges as stepramp.models.engine.segment_edges says with its stop;
* ``limit``: a move and the limit it runs towards switched on after a random number of pulses (random FILTER, soft
  or hard, sometimes after a bounce shorter than the filter): the edges as the model's stop committed at F + 1
  (docs/algorithm.md, "Machine inputs"), ERROR LIMIT when it came while the move was busy; a START towards the
  active limit refused, no pulse;
* ``estop``: ESTOP during a move, a jog or at rest: the edges as the model's hard stop sampled at F + 1, ERROR
  ESTOP, the fault latched and ENABLE low, a START refused; then the release, the clear and ENABLE again. An
  EstopMonitor runs through the whole soak: no STEP edge more than 2 clocks after a filtered ESTOP edge.

The same seed gives the same operations (and the same bus pauses), so a failing seed replays exactly:
`make soak SEED=S OPS=K` stops after the failing operation K. `make soak SECONDS=N SEED=S` runs for N seconds of
wall time per top and prints the counts; the regression runs a short one (`test_soak`, fixed seed, 25 operations
per top). Every operation has its own simulated-time limit from the model, so a hang fails at once.
"""

from __future__ import annotations

import dataclasses
import json
import os
import random
import time
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge, SimTimeoutError, with_timeout

from peripheral_tb import BAD_VALUES, TOPS, PeripheralTb, expect_rejected
from stepramp.board.change import Segment, plan_change, speed_at_pulse
from stepramp.board.driver import MODES, Outputs, StepRamp, StepRampError
from stepramp.board.plan import Plan, plan_move, plan_move_info
from stepramp.board.regmap import LIVE, REGISTERS, REGISTERS_BY_NAME, RW, STAGING, W1C, offset
from stepramp.models.engine import change_edges, edges_with_stop, segment_edges
from stepramp.models.engine import edges as model_edges
from stepramp.sim.monitors import EstopMonitor
from stepramp.sim.profiles import design_args
from stepramp.sim.runner import run_cocotb
from tbutil import build_dir, cocotb, edges_differ, env_int, now_cycles

MOTION = STAGING  # written at any time; the engine takes them at START
CONFIG = ("DRIVE", "STEP_WIDTH", "DIR_TIMING", "PWM_PERIOD", "STEP_SPACE", "INPUT_FILTER", "INPUT_CFG")
READ_ONLY = ("ID", "CUR_DELAY", "STEP_COUNT")
#: Operation weights.
OPS = {
    "move": 6,
    "stop": 4,
    "busy_writes": 3,
    "idle_writes": 3,
    "bad_value": 2,
    "reset": 1,
    "configure": 2,
    "change": 3,
    "queue": 2,
    "jog_zero": 2,
    "limit": 2,
    "estop": 1,
}
#: The soak's driver: a 1 MHz plan clock on a 200 steps/rev motor (the tick is one clock at PRESCALE 1).
FCLK, SPR = 1e6, 200.0
#: Simulated time one operation may take.
OP_LIMIT_MS = 10


def _ctrl(field: str) -> int:
    return REGISTERS_BY_NAME["CTRL"].field(field).mask


def rw_mask(name: str) -> int:
    return sum(f.mask for f in REGISTERS_BY_NAME[name].fields if f.access == RW)


class SoakError(AssertionError):
    """A scoreboard mismatch (an AssertionError, so that cocotb reports the test as failed)."""


class Soak:
    """The bench, the generator and the scoreboard (position, the registers' expected values, the counts)."""

    def __init__(self, tb: PeripheralTb, rng: random.Random) -> None:
        self.tb = tb
        self.rng = rng
        self.position = 0
        self.counts: Counter[str] = Counter()
        self.edges_checked = 0
        self.stop_edges: dict[str, list[int]] = {"soft": [], "hard": []}
        for kind, edges in self.stop_edges.items():
            cocotb.start_soon(tb.pins.watch(getattr(tb.dut.core_inst, f"{kind}_stop"), edges))

    # -- generators ---------------------------------------------------------------------------------------------
    def trapezoid(self) -> tuple[StepRamp, Plan]:
        """A random move that uses every motion register (ramps of 5 .. 15 steps, a cruise, 40 .. 160 steps): each
        of peripheral_tb.BAD_VALUES must then be rejected."""
        rng = self.rng
        steps = rng.randint(40, 160) * rng.choice((1, -1))
        args = design_args(steps, rng.uniform(70, 300), rng.uniform(5, 15), rng.uniform(5, 15))
        return self.tb.driver({"fclk": FCLK, "spr": SPR, "prescale": 1}), plan_move(**args)

    def plan(self, min_steps: int = 1) -> tuple[StepRamp, Plan]:
        """A random valid move: 1 .. 160 steps, cruise period 70 .. 300 ticks, ramps of 1 .. 60 steps, PRESCALE 1 .. 2.
        The shortest interval stays above the stepping configuration's pulse spacing (at most 60 clocks)."""
        rng = self.rng
        steps = rng.randint(min_steps, 160) * rng.choice((1, -1))
        prescale = rng.choice((1, 1, 2))
        args = design_args(steps, rng.uniform(70, 300), rng.uniform(1, 60), rng.uniform(1, 60), prescale=prescale)
        drv = self.tb.driver({"fclk": FCLK, "spr": SPR, "prescale": prescale})
        return drv, plan_move(**args)

    async def wait_done(self, drv: StepRamp) -> Any:
        return await drv.wait_done(idle=lambda: self.tb.irq_or(5_000))

    # -- checks -------------------------------------------------------------------------------------------------
    def check_edges(self, what: str, got: list[int], want: list[int]) -> None:
        if got != want:
            raise SoakError(f"{what}: {edges_differ(got, want)}")
        self.edges_checked += len(got)

    async def check_position(self, what: str) -> None:
        got = await self.tb.driver().position()
        if got != self.position:
            raise SoakError(f"{what}: POSITION {got}, expected {self.position}")

    # -- operations ---------------------------------------------------------------------------------------------
    async def op_move(self) -> None:
        drv, plan = self.plan()
        edges, status = await self.tb.run_plan(drv, plan)
        self.check_edges("move", edges, model_edges(plan))
        if status.error:
            raise SoakError(f"move: error {status.err_name}")
        self.position += -plan.steps if plan.direction else plan.steps
        await self.check_position("move")
        self.counts["moves"] += 1

    async def op_stop(self) -> None:
        drv, plan = self.plan(min_steps=8)
        kind = self.rng.choice(("soft", "hard"))
        wait = self.rng.randint(1, plan.steps - 2)
        tb = self.tb
        await drv.program(plan)
        n0, s0 = tb.pins.mark()
        k0 = len(self.stop_edges[kind])
        await drv.start()
        while len(tb.step_edges) < n0 + wait:
            await RisingEdge(tb.dut.step)
        await (drv.soft_stop() if kind == "soft" else drv.hard_stop())
        await self.wait_done(drv)
        edges = tb.edges_since(n0, s0)
        if len(self.stop_edges[kind]) <= k0:
            raise SoakError(f"{kind} stop: the strobe never reached the engine")
        request = self.stop_edges[kind][k0] + 1 - tb.start_edges[s0]  # the engine samples it one edge later
        self.check_edges(f"{kind} stop after {wait} pulses", edges, edges_with_stop(plan, kind, request))
        self.position += -len(edges) if plan.direction else len(edges)
        await self.check_position(f"{kind} stop")
        self.counts[f"{kind} stops"] += 1
        self.counts["moves"] += 1

    def new_values(self, prescale: int) -> tuple[float, float, float]:
        """Random accel, decel and speed (rad/s^2, rad/s) of the generator's ranges."""
        args = design_args(
            100, self.rng.uniform(70, 300), self.rng.uniform(1, 60), self.rng.uniform(1, 60), prescale=prescale
        )
        return args["accel"], args["decel"], args["speed"]

    async def op_change(self) -> None:
        rng, tb = self.rng, self.tb
        steps = rng.randint(40, 160) * rng.choice((1, -1))
        prescale = rng.choice((1, 1, 2))
        args = design_args(steps, rng.uniform(70, 300), rng.uniform(1, 60), rng.uniform(1, 60), prescale=prescale)
        plan, info = plan_move_info(**args)
        drv = tb.driver({"fclk": FCLK, "spr": SPR, "prescale": prescale})
        await drv.program(plan)
        n0, s0 = tb.pins.mark()
        await drv.start()
        while len(tb.step_edges) < n0 + rng.randint(2, plan.steps // 2):
            await RisingEdge(tb.dut.step)
        p = await drv.access.read(offset("STEP_COUNT")) + rng.randint(2, 6)
        change = plan_change(
            speed_at_pulse(info, p), rng.randint(1, 150), *self.new_values(prescale), SPR, FCLK, prescale
        )
        if change.back is not None or p >= plan.steps - 1:
            await self.wait_done(drv)  # (a target behind the stop: the scripts' reversal, not this op's)
            want, what = model_edges(plan), "move (no change)"
        else:
            await drv.change(change.segment, plan.direction, p)
            try:
                await self.wait_done(drv)
                want, what = change_edges(Segment.of_move(plan), p, change.segment, prescale), f"change at {p}"
                self.counts["changes"] += 1
            except StepRampError as exc:
                if "CHANGE" not in str(exc):
                    raise
                want, what = model_edges(plan), f"change at {p} refused"
                self.counts["changes refused"] += 1
        edges = tb.edges_since(n0, s0)
        self.check_edges(what, edges, want)
        self.position += -len(edges) if plan.direction else len(edges)
        await self.check_position(what)

    async def op_queue(self) -> None:
        tb = self.tb
        drv, first = self.plan(min_steps=30)
        drv2, second = self.plan()
        await drv.program(first)
        n0, s0 = tb.pins.mark()
        await drv.start()
        while len(tb.step_edges) < n0 + self.rng.randint(1, first.steps - 20):
            await RisingEdge(tb.dut.step)
        await drv2.queue(second)
        await self.wait_done(drv)
        busy = tb.dut.core_inst.busy
        while len(tb.start_edges) < s0 + 2:
            await RisingEdge(busy)
        # The queued move's end: the engine idle again (a short one may be over by now; its DONE then came with
        # the first move's, or after it, and is cleared here).
        if int(busy.value):
            await FallingEdge(busy)
        await ClockCycles(tb.clk, 4)
        status = await drv.status()
        if status.busy or status.error:
            raise SoakError(f"queued moves: {status}")
        await drv.clear_flags()
        edges = tb.edges_since(n0, s0)
        self.check_edges("the running move", edges[: first.steps], model_edges(first))
        self.check_edges("the queued move", tb.edges_since(n0 + first.steps, s0 + 1), model_edges(second))
        for plan in (first, second):
            self.position += -plan.steps if plan.direction else plan.steps
        await self.check_position("queued moves")
        self.counts["queued moves"] += 1

    async def op_jog_zero(self) -> None:
        tb = self.tb
        accel, decel, speed = self.new_values(1)
        speed *= self.rng.choice((1, -1))
        drv = tb.driver()
        k_soft, k_hard = len(self.stop_edges["soft"]), len(self.stop_edges["hard"])
        n0, s0 = tb.pins.mark()
        first = await drv.jog(speed, accel, decel)
        while len(tb.step_edges) < n0 + self.rng.randint(2, first.sa + 20):
            await RisingEdge(tb.dut.step)
        plan, regs, back = drv.plan_jog(-speed, accel, decel)
        await drv.program(plan, regs)
        await drv.access.write(offset("CTRL"), _ctrl("SOFT_STOP") | _ctrl("QUEUE"), strobe=0x1)
        while len(tb.start_edges) < s0 + 2:
            await RisingEdge(tb.dut.core_inst.busy)
        n1 = len(tb.step_edges)
        while len(tb.step_edges) < n1 + self.rng.randint(2, back.sa + 20):
            await RisingEdge(tb.dut.step)
        await drv.hard_stop()
        await self.wait_done(drv)
        soft = self.stop_edges["soft"][k_soft] + 1 - tb.start_edges[s0]
        hard = self.stop_edges["hard"][k_hard] + 1 - tb.start_edges[s0 + 1]
        ways = (
            (tb.edges_since(n0, s0)[: n1 - n0], segment_edges(first, 1, stop=("soft", soft)), speed),
            (tb.edges_since(n1, s0 + 1), segment_edges(back, 1, stop=("hard", hard)), -speed),
        )
        for got, want, way in ways:
            self.check_edges(f"jog {way:+.1f} rad/s", got, want)
            self.position += len(got) if way > 0 else -len(got)
        await self.check_position("jog through zero")
        self.counts["jogs through zero"] += 1

    async def op_busy_writes(self) -> None:
        tb, rng = self.tb, self.rng
        drv, plan = self.plan(min_steps=20)
        await drv.program(plan)
        n0, s0 = tb.pins.mark()
        await drv.start()
        await RisingEdge(tb.dut.step)
        expected_err: str | None = None
        written: dict[str, int] = {}
        for _ in range(rng.randint(1, 4)):
            name = rng.choice([r.name for r in REGISTERS])
            value = rng.getrandbits(32)
            ctrl = REGISTERS_BY_NAME["CTRL"]
            if name == "CTRL":  # enables only; ENABLE stays as configured
                value = value & (ctrl.field("IRQ_DONE_EN").mask | ctrl.field("IRQ_ERROR_EN").mask)
                value |= ctrl.field("ENABLE").mask if tb.enabled else 0
            elif name == "STATUS":
                value = 0
            busy = (await drv.status()).busy
            await tb.bus.write(offset(name), value)
            if not busy:
                break  # the move ended meanwhile: what follows is not a write while busy
            if name in CONFIG:
                expected_err = "CFG_BUSY"
            elif name == "POSITION":
                expected_err = "POS_BUSY"
            elif name in MOTION:
                written[name] = value & rw_mask(name)
            self.counts["busy writes"] += 1
        try:
            status = await self.wait_done(drv)
            err = None if not status.error else status.err_name
        except StepRampError:
            err = (await drv.status()).err_name
        self.check_edges("move with writes while busy", tb.edges_since(n0, s0), model_edges(plan))
        if expected_err is not None and err != expected_err:
            raise SoakError(f"writes while busy: error {err}, expected {expected_err}")
        if expected_err is None and err is not None:
            raise SoakError(f"writes while busy: unexpected error {err}")
        await drv.clear_flags()
        self.position += -plan.steps if plan.direction else plan.steps
        await self.check_position("writes while busy")
        for name, value in written.items():
            got = await tb.bus.read(offset(name))
            if got != value:
                raise SoakError(f"{name} written while busy reads {got:#x}, expected {value:#x} (shadowed)")
        self.counts["moves"] += 1

    async def op_idle_writes(self) -> None:
        tb, rng = self.tb, self.rng
        drv = tb.driver()
        for _ in range(rng.randint(1, 6)):
            name = rng.choice([n for n in (*MOTION, *READ_ONLY, "POSITION", "STATUS", "CTRL")])
            value = rng.getrandbits(32)
            addr = offset(name)
            if name in READ_ONLY:
                before = await tb.bus.read(addr)
                await tb.bus.write(addr, value)
                want = before
            elif name == "POSITION":
                await tb.bus.write(addr, value)
                self.position = value - (1 << 32) if value >> 31 else value
                want = value
            elif name == "STATUS":
                reg = REGISTERS_BY_NAME["STATUS"]
                before = await tb.bus.read(addr)
                await tb.bus.write(addr, value)
                cleared = sum(f.mask for f in reg.fields if f.access == W1C) & value
                want = before & ~cleared
            elif name == "CTRL":
                ctrl = REGISTERS_BY_NAME["CTRL"]
                value = value & (ctrl.field("IRQ_DONE_EN").mask | ctrl.field("IRQ_ERROR_EN").mask)
                value |= ctrl.field("ENABLE").mask if tb.enabled else 0
                await tb.bus.write(addr, value)
                want = value
            else:
                await tb.bus.write(addr, value)
                want = value & rw_mask(name)
            got = await tb.bus.read(addr)
            if got != want:
                raise SoakError(f"idle write {value:#x} to {name}: reads {got:#x}, expected {want:#x}")
            self.counts["idle writes"] += 1
        await self.check_position("idle writes")
        await drv.clear_flags()

    async def op_bad_value(self) -> None:
        tb = self.tb
        drv, good = self.trapezoid()
        label, change, cause = self.rng.choice(BAD_VALUES)
        await expect_rejected(tb, drv, dataclasses.replace(good, **change), f"bad value {label}", cause)
        await drv.clear_flags()
        await self.check_position(f"bad value {label}")
        self.counts["bad values"] += 1

    async def op_reset(self) -> None:
        tb = self.tb
        drv, plan = self.plan(min_steps=10)
        await drv.program(plan)
        n0, s0 = tb.pins.mark()
        await drv.start()
        want = model_edges(plan)
        await ClockCycles(tb.clk, self.rng.randint(1, max(2, want[-1])))
        tb.finish()  # the reset changes DIR and the windings at once, as documented: the monitors stop here
        await tb.reset_pulse()
        before = tb.edges_since(n0, s0)
        self.check_edges("edges before a reset", before, want[: len(before)])
        mark = tb.pins.mark()
        await ClockCycles(tb.clk, 2000)
        if tb.pins.mark()[0] != mark[0]:
            raise SoakError("a STEP pulse after the reset")
        for reg in REGISTERS:
            if reg.name in LIVE:
                continue  # the clock count
            got = await tb.bus.read(reg.offset)
            if got != reg.reset:
                raise SoakError(f"after a reset mid-move: {reg.name} reads {got:#x}, expected {reg.reset:#x}")
        self.position = 0
        tb.outputs, tb.enabled = Outputs(), False
        tb._start_monitors(position=0)
        await tb.driver().enable_irq(done=True, error=True)
        self.counts["resets"] += 1

    async def op_configure(self) -> None:
        rng = self.rng
        mode = rng.choice(list(MODES))
        outputs = Outputs(
            mode=mode,
            ustep_log2=rng.randint(0, 4) if mode == "pwm" else 0,
            step_width=rng.randint(1, 30),
            dir_setup=rng.randint(0, 60),
            dir_hold=rng.randint(0, 60),
            pwm_period=rng.randint(8, 64) if mode == "pwm" else 0,
            step_space=rng.randint(1, 20),
        )
        await self.tb.configure(outputs, enable=rng.random() < 0.9)
        self.counts["configurations"] += 1

    # -- the machine inputs (docs/algorithm.md, "Machine inputs") ----------------------------------------------------
    async def inputs(self, filter_clocks: int, hard: bool) -> int:
        """INPUT_FILTER and INPUT_CFG (limits on, soft or hard); returns N = max(FILTER, 1)."""
        cfg = REGISTERS_BY_NAME["INPUT_CFG"]
        await self.tb.bus.write(offset("INPUT_FILTER"), filter_clocks)
        word = cfg.field("LIMIT_EN").mask | (cfg.field("LIMIT_HARD").mask if hard else 0)
        await self.tb.bus.write(offset("INPUT_CFG"), word)
        return max(filter_clocks, 1)

    async def pin(self, name: str, level: int) -> int:
        """Drive a pin after the next falling edge; the last rising edge before the change (a)."""
        tb = self.tb
        await FallingEdge(tb.clk)
        getattr(tb.dut, name).value = level
        return now_cycles()

    async def bounce(self, name: str, n: int) -> None:
        """A bounce shorter than the filter (N >= 3): on for fewer than N clocks, off again, a pause."""
        if n >= 3 and self.rng.random() < 0.5:
            await self.pin(name, 1)
            await ClockCycles(self.tb.clk, self.rng.randint(1, n - 2))
            await self.pin(name, 0)
            await ClockCycles(self.tb.clk, self.rng.randint(1, n - 2))
            self.counts["bounces"] += 1

    async def refused_start(self, drv: StepRamp, plan: Plan, code: str) -> None:
        """A START that the core must refuse with `code`: no pulse."""
        tb = self.tb
        await drv.program(plan)
        k = len(tb.step_edges)
        await drv.start()
        status = await drv.status()
        for _ in range(200):
            if status.done:
                break
            await ClockCycles(tb.clk, 50)
            status = await drv.status()
        await ClockCycles(tb.clk, 500)
        if not status.error or status.err_name != code or len(tb.step_edges) != k:
            raise SoakError(f"a START during {code}: {status}, {len(tb.step_edges) - k} pulses")
        await drv.clear_flags()

    async def op_limit(self) -> None:
        tb, rng = self.tb, self.rng
        drv, plan = self.plan(min_steps=12)
        pin = "limit_neg" if plan.direction else "limit_pos"
        hard = rng.random() < 0.5
        n = await self.inputs(rng.choice((0, 1, 3, 20, 60)), hard)
        await drv.program(plan)
        n0, s0 = tb.pins.mark()
        await drv.start()
        while len(tb.step_edges) < n0 + rng.randint(1, plan.steps - 2):
            await RisingEdge(tb.dut.step)
        await self.bounce(pin, n)
        a = await self.pin(pin, 1)
        try:
            status = await self.wait_done(drv)
            err = None
        except StepRampError:
            status = await drv.status()
            err = status.err_name
            await drv.clear_flags()
        f = a + n + 2  # the filtered edge; the register file acts at f + 1, the engine samples the stop at f + 2
        start, want = tb.start_edges[s0], model_edges(plan)
        busy = f + 1 - start <= want[-1]
        if busy:
            want = edges_with_stop(plan, "hard" if hard else "soft", f + 2 - start)
        edges = tb.edges_since(n0, s0)
        self.check_edges(f"{pin} ({'hard' if hard else 'soft'}, FILTER N = {n})", edges, want)
        if err != ("LIMIT" if busy else None):
            raise SoakError(f"{pin}: error {err}, expected {'LIMIT' if busy else None}")
        self.position += -len(edges) if plan.direction else len(edges)
        await self.check_position(pin)
        await self.refused_start(drv, plan, "LIMIT")
        await self.pin(pin, 0)
        await ClockCycles(tb.clk, n + 8)
        events = REGISTERS_BY_NAME["STATUS"]
        await tb.bus.write(offset("STATUS"), events.field("LIMIT_NEG_EV").mask | events.field("LIMIT_POS_EV").mask)
        self.counts[f"limit stops ({'hard' if hard else 'soft'})" if busy else "limits after the move"] += 1
        self.counts["moves"] += 1

    async def op_estop(self) -> None:
        tb, rng = self.tb, self.rng
        n = await self.inputs(rng.choice((0, 1, 5, 40)), False)
        kind = rng.choice(("move", "move", "jog", "idle"))
        drv, plan = self.plan(min_steps=12)
        enabled = tb.enabled
        tb.finish()  # ENABLE drops: the winding monitors stop here (the STEP pin keeps its EstopMonitor)
        n0, s0 = tb.pins.mark()
        segment, forward = None, plan.direction == 0
        if kind == "move":
            await drv.program(plan)
            await drv.start()
        elif kind == "jog":
            accel, decel, speed = self.new_values(1)
            drv = tb.driver()
            speed *= rng.choice((1, -1))
            segment, forward = await drv.jog(speed, accel, decel), speed > 0
        if kind != "idle":
            while len(tb.step_edges) < n0 + rng.randint(1, 10 if segment is not None else plan.steps - 2):
                await RisingEdge(tb.dut.step)
        await self.bounce("estop", n)
        a = await self.pin("estop", 1)
        await ClockCycles(tb.clk, n + 10)
        status = await drv.status()
        for _ in range(200):
            if status.done or kind == "idle":
                break
            await ClockCycles(tb.clk, 50)
            status = await drv.status()
        f = a + n + 2  # the engine samples the ESTOP stop at f + 1
        if kind != "idle":
            request = f + 1 - tb.start_edges[s0]
            want = (
                edges_with_stop(plan, "hard", request)
                if segment is None
                else segment_edges(segment, 1, stop=("hard", request))
            )
            edges = tb.edges_since(n0, s0)
            self.check_edges(f"ESTOP in a {kind}", edges, want)
            self.position += len(edges) if forward else -len(edges)
        if not (status.error and status.err_name == "ESTOP" and status.estop_fault) or int(tb.dut.enable.value):
            raise SoakError(f"ESTOP in a {kind}: {status}, ENABLE {tb.dut.enable.value}")
        await drv.clear_flags()
        await self.refused_start(drv, plan, "ESTOP")
        await self.pin("estop", 0)
        await ClockCycles(tb.clk, n + 8)
        await drv.clear_estop(enable=enabled)
        await self.check_position("after ESTOP")
        await tb.configure(tb.outputs, enable=enabled)
        self.counts[f"ESTOP ({kind})"] += 1

    async def play(self, name: str) -> None:
        """One operation, within a simulated-time limit (a hang fails here, not at the test's limit): 10 ms, five
        times the longest move the generator makes (160 steps of 600 clocks, about 1 ms) plus its bus traffic."""
        await with_timeout(getattr(self, f"op_{name}")(), OP_LIMIT_MS, "ms")


SEED = env_int("SOAK_SEED", 1)
SECONDS = float(os.environ.get("SOAK_SECONDS", "0"))
OPS_LIMIT = env_int("SOAK_OPS", 25)
# The test's own limit: 20 ms of simulated time per operation, or per wall second of a timed run (GHDL
# simulates well under 20 ms of this design per second); each operation has a tighter limit of its own.
TEST_LIMIT_MS = max(OPS_LIMIT, SECONDS) * 20 + 10


@cocotb.test(timeout_time=TEST_LIMIT_MS, timeout_unit="ms")
async def soak(dut) -> None:
    """Random operations until SOAK_OPS of them (or SOAK_SECONDS of wall time) have passed."""
    tb = await PeripheralTb.started(dut, idle=True)
    rng = random.Random(SEED)
    soak = Soak(tb, rng)
    estop = EstopMonitor(dut.core_inst.estop_stop, [dut.step]).start()
    await tb.configure(Outputs(mode="half", step_width=5, dir_setup=20, dir_hold=10), enable=True)
    await tb.driver().enable_irq(done=True, error=True)
    t0 = time.monotonic()
    names, weights = list(OPS), list(OPS.values())
    ops = 0
    while ops < OPS_LIMIT or (SECONDS and time.monotonic() - t0 < SECONDS):
        if SECONDS and time.monotonic() - t0 >= SECONDS:
            break
        name = rng.choices(names, weights)[0]
        try:
            await soak.play(name)
        except (AssertionError, SimTimeoutError) as exc:
            raise SoakError(
                f"{tb.top} seed {SEED}, operation {ops + 1} ({name}): {exc}\n"
                f"  replay: make soak SEED={SEED} OPS={ops + 1}"
            ) from exc
        ops += 1
        soak.counts[f"op {name}"] += 1
    tb.finish()
    estop.stop()
    estop.check()
    summary = {
        "top": tb.top,
        "seed": SEED,
        "operations": ops,
        "edges_checked": soak.edges_checked,
        "wall_s": round(time.monotonic() - t0, 1),
        **dict(sorted(soak.counts.items())),
    }
    dut._log.info("soak: %s", json.dumps(summary))
    Path(os.environ.get("SOAK_RESULT", "soak.json")).write_text(json.dumps(summary) + "\n")


@pytest.mark.parametrize("top", TOPS)
def test_soak(top: str) -> None:
    """A short soak on each top (SOAK_SEED, default 1; SOAK_OPS, default 25; SOAK_SECONDS for a timed run): every
    operation checked against the model; prints the counts."""
    folder = build_dir(f"{top}_soak")
    result = folder / "soak.json"
    result.unlink(missing_ok=True)
    env = {"SOAK_RESULT": str(result), "BUS_SEED": str(SEED)}
    run_cocotb(top, "test_soak", folder, testcase="soak", extra_env=env)
    summary = json.loads(result.read_text())
    print(f"soak {top}: {json.dumps(summary)}")
    assert summary["operations"] >= (1 if SECONDS else OPS_LIMIT)
