# SPDX-License-Identifier: MIT
"""stepramp_core alone, through its native register port, programmed by the driver as on a board (issue 12).

The two bus tops only adapt a bus to stepramp_core's register port (docs/stepramp_plb.md: one-cycle wr / rd strobes
with addr, wdata and be; ack, with err for an unmapped offset and rdata for a read, one clock later). CoreMaster
below is a master for that port with the driver's async read / write interface, so stepramp.board.driver.StepRamp
programs the core exactly as it programs a board; the master checks the port's timing on every access (no answer in
the strobe's own cycle, ack in the next one, ack for one clock only) and watches ack and err for answers nobody
asked for. Expected values come from stepramp.board.regmap (registers), stepramp.models.engine (every STEP edge, stops),
stepramp.models.stepping (windings, through the motion monitors of stepramp.sim.monitors) and the rules of
docs/stepramp_plb.md, never from the RTL.

Tests (one simulation, one after the other):

* register_port_timing: a scripted sequence of strobes, back to back and with gaps, sampled every cycle: ack exactly
  one clock after each strobe, err with it for an unmapped offset, rdata of ID and of a register written the cycle
  before (byte enables, word addresses); then through the master: ID, every register's reset value, err on every
  unmapped offset;
* motion_profiles: a trapezoid, a triangle, negative moves with a DIR change and DIR_TIMING set, PRESCALE 3 and 5,
  programmed with the driver: every STEP rising edge equal to stepramp.models.engine.edges, STATUS during the move,
  POSITION and STEP_COUNT after it, DONE and irq (irq two clocks after the engine's busy falls, low one clock after
  the W1C clear, never without its enable);
* soft_and_hard_stop: SOFT_STOP and HARD_STOP through CTRL in ACCEL, RUN and DECEL against
  stepramp.models.engine.edges_with_stop;
* windings: wave, full and half step follow the STEP pulses (1-step moves through two electrical periods and back),
  not POSITION writes; ENABLE off switches them off; half-step and PWM moves with the electrical-position monitor on.

The motion monitors (STEP width, DIR setup / hold, shoot-through, windings against stepramp.models.stepping) run in
every motion test. About 4 ms of simulated time at a 10 ns clock.
"""

from __future__ import annotations

from typing import Any

from cocotb.triggers import ClockCycles, FallingEdge, Lock, ReadOnly, RisingEdge, Timer
from cocotb.utils import get_sim_time

from peripheral_tb import MotionBench, check_stopped, stop_cases
from stepramp.board.driver import MODES, Outputs, StepRamp
from stepramp.board.plan import Plan, plan_move
from stepramp.board.regmap import (
    ADDR_BITS,
    ID_VALUE,
    LIVE,
    REGISTERS,
    REGISTERS_BY_NAME,
    VERSION_MAJOR,
    VERSION_MINOR,
    offset,
)
from stepramp.models import stepping as sm
from stepramp.models.engine import edges as model_edges
from stepramp.sim.clocking import CLK_PERIOD_PS, apply_reset, quiet_inputs, start_clock
from stepramp.sim.coverage import watch_coverage
from stepramp.sim.monitors import MotionMonitors, StepWidthMonitor
from stepramp.sim.profiles import PROFILES_BY_NAME
from stepramp.sim.runner import run_cocotb
from stepramp.sim.stepwatch import StepWatch
from tbutil import build_dir, cocotb, edges_differ

WINDOW = 1 << ADDR_BITS
WORD = 0xFFFF_FFFF
MAPPED = {r.offset for r in REGISTERS}
UNMAPPED = [a for a in range(0, WINDOW, 4) if a not in MAPPED]
CTRL = REGISTERS_BY_NAME["CTRL"]


class CoreBusError(Exception):
    """The core answered err: the offset is not a register."""


class PortTimingError(AssertionError):
    """The register port did not answer one clock after the strobe, for one clock."""


def _bit(signal: Any) -> int:
    return 1 if str(signal.value) == "1" else 0


class CoreMaster:
    """The driver's register access (async read / write) over stepramp_core's native register port.

    An access drives wr or rd with addr, wdata and be at a falling edge for one clock; the rising edge that follows
    samples it (the strobe edge), and ack (with err, and rdata for a read) must be '1' in the cycle after that edge,
    for that cycle only, and '0' in the strobe's own cycle. A write with a strobe other than 0xF uses it as be. The
    accesses of several coroutines are serialised; one idle cycle separates two accesses. Every rising edge of ack
    must be a strobe edge and err may only rise with ack; violations are collected and raised by check().
    """

    def __init__(self, dut: Any, t0_ps: float) -> None:
        self.dut = dut
        self.clk = dut.clk
        self.t0_ps = t0_ps
        self.e0 = round(t0_ps / CLK_PERIOD_PS)  # edges numbered as stepramp.sim.stepwatch.StepWatch numbers them
        self.lock = Lock()
        self.strobe_edges: set[int] = set()
        self.last_edge = -1  # strobe edge of the last access
        self.accesses = 0
        self.violations: list[str] = []
        self.idle()
        dut.addr.value = 0
        dut.waddr.value = 0
        dut.wdata.value = 0
        dut.be.value = 0
        self._tasks = [cocotb.start_soon(self._watch_ack()), cocotb.start_soon(self._watch_err())]

    def cycles(self) -> float:
        """Now in clock periods: rising edge e at e.0, the falling edge after it at e.5 (the clock starts at t0_ps
        with a rising edge, numbered as StepWatch numbers it)."""
        return (get_sim_time("ps") - self.t0_ps) / CLK_PERIOD_PS + self.e0

    def idle(self) -> None:
        self.dut.wr.value = 0
        self.dut.rd.value = 0

    def drive(self, kind: str | None, addr: int = 0, wdata: int = 0, be: int = 0xF) -> int | None:
        """At a falling edge: a strobe ("wr" or "rd") for the coming cycle, or nothing (None). Returns the number of
        the rising edge that samples it."""
        if kind is None:
            self.idle()
            return None
        self.dut.wr.value = int(kind == "wr")
        self.dut.rd.value = int(kind == "rd")
        self.dut.addr.value = addr & (WINDOW - 1)
        self.dut.waddr.value = addr & (WINDOW - 1)  # one address for both, as on the PLB-like top
        self.dut.wdata.value = wdata & WORD
        self.dut.be.value = be & 0xF
        edge = int(self.cycles()) + 1
        self.strobe_edges.add(edge)
        return edge

    def answer(self) -> tuple[int, int, int]:
        """(ack, err, rdata) now (call in ReadOnly)."""
        rdata = self.dut.rdata.value
        return _bit(self.dut.ack), _bit(self.dut.err), int(rdata) if rdata.is_resolvable else -1

    async def _access(self, kind: str, addr: int, wdata: int, be: int) -> int:
        what = f"{kind} {addr:#04x}"
        async with self.lock:
            await FallingEdge(self.clk)
            edge = self.drive(kind, addr, wdata, be)
            await ReadOnly()
            if self.answer()[0]:
                raise PortTimingError(f"{what}: ack in the strobe's own cycle (before edge {edge})")
            await RisingEdge(self.clk)
            await ReadOnly()
            ack, err, rdata = self.answer()
            if not ack:
                raise PortTimingError(f"{what}: no ack in the cycle after the strobe edge {edge}")
            await FallingEdge(self.clk)
            self.idle()
            await RisingEdge(self.clk)
            await ReadOnly()
            if self.answer()[0] or self.answer()[1]:
                raise PortTimingError(f"{what}: ack or err still '1' two clocks after the strobe edge {edge}")
            await Timer(1, unit="ps")  # out of the ReadOnly phase, so that the caller may drive and trigger
            self.accesses += 1
            self.last_edge = edge
        if err:
            raise CoreBusError(f"{what}: err")
        return rdata

    async def read(self, addr: int) -> int:
        return await self._access("rd", addr, 0, 0xF)

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None:
        await self._access("wr", addr, value, strobe)

    async def _watch_ack(self) -> None:
        while True:
            await RisingEdge(self.dut.ack)
            now = self.cycles()
            if abs(now - round(now)) > 1e-6 or round(now) not in self.strobe_edges:
                self.violations.append(f"ack rose at clock {now:.2f} without a strobe sampled there")

    async def _watch_err(self) -> None:
        while True:
            await RisingEdge(self.dut.err)
            await ReadOnly()
            if not _bit(self.dut.ack):
                self.violations.append(f"err rose at clock {self.cycles():.2f} without ack")

    def check(self) -> None:
        if self.violations:
            raise PortTimingError("register port: " + "; ".join(self.violations[:10]))


class CoreTb(MotionBench):
    """stepramp_core with its clock, the register-port master, the STEP / engine-start watch and the monitors."""

    def __init__(self, dut: Any) -> None:
        self.dut = dut
        self.clk = dut.clk
        self.t0_ps = get_sim_time("ps")
        start_clock(self.clk)
        quiet_inputs(dut)
        self.master = CoreMaster(dut, self.t0_ps)
        self.bus = self.master  # the driver's register access
        self.pins: StepWatch | None = None
        self.irq_rises: list[int] = []
        self.irq_falls: list[int] = []
        self.busy_falls: list[int] = []
        self.outputs = Outputs()
        self.enabled = False
        self.monitors: MotionMonitors | None = None
        self.exact_width: StepWidthMonitor | None = None

    async def reset(self) -> None:
        await apply_reset(self.clk, self.dut.rst, settle=2)
        # The engine's busy rises at the edge that samples its start: the model's edge 0 (as in tb/peripheral_tb.py).
        self.pins = StepWatch(self.dut.step, self.dut.busy, CLK_PERIOD_PS)
        cocotb.start_soon(self._watch(RisingEdge, self.dut.irq, self.irq_rises))
        cocotb.start_soon(self._watch(FallingEdge, self.dut.irq, self.irq_falls))
        cocotb.start_soon(self._watch(FallingEdge, self.dut.busy, self.busy_falls))
        self.count_steps()
        self._start_monitors(position=0)
        self.bus = watch_coverage(self.dut, self.bus)

    def edge(self) -> int:
        """The most recent rising clock edge (the master's and StepWatch's numbering)."""
        return round(self.master.cycles())

    async def _watch(self, trigger: Any, signal: Any, edges: list[int]) -> None:
        while True:
            await trigger(signal)
            edges.append(self.edge())

    def _start_monitors(self, position: int) -> None:
        o = self.outputs
        self.monitors = MotionMonitors.for_outputs(self.dut, o, self.enabled, position)
        # STEP_WIDTH is the exact pulse width (docs/stepramp_plb.md), not only a minimum.
        self.exact_width = StepWidthMonitor(self.dut.step, o.step_width, exact=True, name="exact STEP width").start()

    def finish(self) -> None:
        """Stop the monitors and raise what they, or the register-port master, saw."""
        if self.monitors is not None and self.exact_width is not None:
            self.monitors.stop()
            self.exact_width.stop()
            self.monitors.check()
            self.exact_width.check()
            self.monitors = self.exact_width = None
        self.master.check()

    def mark(self) -> tuple[int, int]:
        assert self.pins is not None, "reset() first"
        return self.pins.mark()

    def edges_since(self, mark: tuple[int, int]) -> list[int]:
        assert self.pins is not None, "reset() first"
        return self.pins.since(*mark)

    def windings(self) -> tuple[int, ...]:
        return tuple(_bit(getattr(self.dut, p)) for p in ("a1", "a2", "b1", "b2"))


def plan_of(tb: CoreTb, name: str) -> tuple[StepRamp, Plan]:
    """The driver for a named profile's clock and motor, and the plan it computes from the physical units."""
    prof = PROFILES_BY_NAME[name]
    drv = tb.driver(prof.args())
    return drv, drv.plan(prof.steps, prof.accel, prof.decel, prof.speed)


def signed_steps(plan: Plan) -> int:
    return -plan.steps if plan.direction else plan.steps


# ---------------------------------------------------------------------------------------------------------------
# The register port.


@cocotb.test(timeout_time=1, timeout_unit="ms")
async def register_port_timing(dut) -> None:
    """ack exactly one clock after each strobe (back to back and with gaps), err with it for an unmapped offset,
    rdata of ID and of a register written the cycle before; then ID, reset values and err through the master."""
    tb = CoreTb(dut)
    await tb.reset()
    steps, id_, status = offset("STEPS"), offset("ID"), offset("STATUS")
    merged = 0x1234_5678 & 0xFF00_FF00 | 0xAABB_CCDD & 0x00FF_00FF  # be = 0b0101 over 0x12345678
    # (strobe, addr, wdata, be, rdata expected one clock later or None)
    script: list[tuple[str | None, int, int, int, int | None]] = [
        (None, 0, 0, 0, None),
        ("rd", id_, 0, 0xF, ID_VALUE),
        (None, 0, 0, 0, None),
        ("wr", steps, 0x1234_5678, 0xF, None),
        ("rd", steps, 0, 0xF, 0x1234_5678),  # back to back: the write of the cycle before is there
        ("rd", UNMAPPED[0], 0, 0xF, None),
        ("wr", UNMAPPED[-1], WORD, 0xF, None),
        ("wr", steps, 0xAABB_CCDD, 0b0101, None),
        ("rd", steps + 3, 0, 0xF, merged),  # word address: bits 1:0 ignored
        ("wr", id_, 0, 0xF, None),  # RO: acknowledged, no error, no change
        ("rd", id_ + 1, 0, 0xF, ID_VALUE),
        ("rd", status, 0, 0xF, 0),
        (None, 0, 0, 0, None),
        (None, 0, 0, 0, None),
        ("wr", steps, 0, 0b0010, None),  # clears byte 1 only
        (None, 0, 0, 0, None),
        ("rd", steps, 0, 0xF, merged & 0xFFFF_00FF),
        (None, 0, 0, 0, None),
        (None, 0, 0, 0, None),
    ]
    seen: list[tuple[int, int, int]] = []
    for kind, addr, wdata, be, _ in [*script, (None, 0, 0, 0, None)]:
        await FallingEdge(tb.clk)
        tb.master.drive(kind, addr, wdata, be)
        await ReadOnly()
        seen.append(tb.master.answer())  # the answer in this cycle: to the strobe of the cycle before
    problems = []
    for k, (kind, addr, _, _, rdata) in enumerate(script):
        ack, err, got = seen[k + 1]
        want_ack = int(kind is not None)
        want_err = int(kind is not None and addr & ~3 not in MAPPED)
        if (ack, err) != (want_ack, want_err):
            problems.append(
                f"cycle {k} ({kind} {addr:#x}): ack, err = {ack}, {err} a clock later, want {want_ack}, {want_err}"
            )
        if rdata is not None and got != rdata:
            problems.append(f"cycle {k} (rd {addr:#x}): rdata {got:#x}, want {rdata:#x}")
    assert seen[0][:2] == (0, 0), "ack or err without a strobe"
    assert not problems, "\n".join(problems)

    # Through the master, as the driver uses it.
    drv = tb.driver()
    assert await drv.check_id() == VERSION_MAJOR << 8 | VERSION_MINOR
    await tb.master.write(steps, 0)
    for reg in REGISTERS:
        got = await tb.master.read(reg.offset)
        assert reg.name in LIVE or got == reg.reset, f"{reg.name}: not its reset value"  # (TIME_LO: the clock count)
    for addr in UNMAPPED:
        for kind in ("rd", "wr"):
            try:
                await (tb.master.read(addr) if kind == "rd" else tb.master.write(addr, WORD))
            except CoreBusError:
                continue
            raise AssertionError(f"{kind} at offset {addr:#x}: no err")
    await tb.master.write(offset("SA"), 0x7FFF_FFFF)
    assert await tb.master.read(offset("SA")) == 0x7FFF_FFFF
    assert tb.master.accesses == 1 + 1 + len(REGISTERS) + 2 * len(UNMAPPED) + 2
    tb.finish()


# ---------------------------------------------------------------------------------------------------------------
# Motion, programmed with the driver.


#: (profile, what it covers); the moves run back to back, so each sign change is a DIR change.
MOVES = [
    ("trap_basic", "trapezoid"),
    ("trap_negative", "negative trapezoid, DIR change"),
    ("triangle_sym", "triangle, DIR change"),
    ("triangle_prescale_3_neg", "negative triangle at PRESCALE 3, DIR change"),
    ("run_start_prescale_5", "PRESCALE 5, starts in RUN, DIR change"),
]


@cocotb.test(timeout_time=5, timeout_unit="ms")
async def motion_profiles(dut) -> None:
    """Moves programmed with the driver: every STEP edge equal to the model, STATUS during the move, POSITION and
    STEP_COUNT after it, DONE and irq; the motion monitors on."""
    tb = CoreTb(dut)
    await tb.reset()
    await tb.configure(Outputs(mode="full", step_width=5, dir_setup=20, dir_hold=10), enable=True)
    await tb.driver().enable_irq(done=True, error=True)
    position = 0
    problems: list[str] = []
    for name, what in MOVES:
        drv, plan = plan_of(tb, name)
        mark = tb.mark()
        irq0, busy0 = len(tb.irq_rises), len(tb.busy_falls)
        assert int(dut.irq.value) == 0, f"{name}: irq before the move"
        await drv.program(plan)
        await drv.start()
        # During the move: BUSY, not DONE, a ramp state, the move's direction, STEP_COUNT counting.
        await RisingEdge(dut.step)
        during = await drv.status()
        count = await tb.master.read(offset("STEP_COUNT"))
        if not (during.busy and not during.done and during.state != "STOP" and during.direction == plan.direction):
            problems.append(f"{name}: STATUS during the move {during}")
        if not 1 <= count < plan.steps:
            problems.append(f"{name}: STEP_COUNT {count} after the first pulse of {plan.steps}")
        status = await drv.wait_done(idle=lambda: tb.irq_or(20_000))
        clear_edge = tb.master.last_edge
        edges = tb.edges_since(mark)
        want = model_edges(plan)
        position += signed_steps(plan)
        if edges != want:
            problems.append(f"{name} ({what}): {edges_differ(edges, want)}")
        if status.error or status.busy or status.state != "STOP" or status.direction != plan.direction:
            problems.append(f"{name}: STATUS at DONE {status}")
        if await drv.position() != position:
            problems.append(f"{name}: POSITION {await drv.position()}, want {position}")
        if await tb.master.read(offset("STEP_COUNT")) != plan.steps:
            problems.append(f"{name}: STEP_COUNT {await tb.master.read(offset('STEP_COUNT'))}, want {plan.steps}")
        if int(dut.dir.value) != plan.direction:
            problems.append(f"{name}: DIR pin {dut.dir.value} after the move")
        # irq: one rise per move, two clocks after the engine's busy fell with its last pulse (DONE one clock after
        # BUSY, irq registered one more), so one clock after the last STEP edge (the pin is the pulse registered);
        # low one clock after the edge that samples the W1C clear of the flags.
        rises, falls = tb.irq_rises[irq0:], tb.busy_falls[busy0:]
        assert tb.pins is not None
        last_step = tb.pins.step_edges[-1]
        if len(rises) != 1 or len(falls) != 1 or rises[0] != falls[0] + 2 or rises[0] != last_step + 1:
            problems.append(f"{name}: irq rises {rises}, busy falls {falls}, last STEP edge {last_step}")
        elif tb.irq_falls[-1] != clear_edge + 1 or int(dut.irq.value) != 0:
            problems.append(f"{name}: irq fell at {tb.irq_falls[-1]}, the clear was sampled at {clear_edge}")
    assert not problems, "\n".join(problems)

    # DONE without its interrupt enable: DONE is set, irq stays low until the enable, then follows DONE.
    await drv.enable_irq(done=False, error=True)
    drv, plan = plan_of(tb, "steps_neg_3_prescale_2")
    mark, irq0 = tb.mark(), len(tb.irq_rises)
    await drv.program(plan)
    await drv.start()
    status = await drv.status()
    while not status.done:
        await ClockCycles(tb.clk, 200)
        status = await drv.status()
    assert not status.error and tb.edges_since(mark) == model_edges(plan)
    assert await drv.position() == position - plan.steps
    assert len(tb.irq_rises) == irq0 and int(dut.irq.value) == 0, "irq without IRQ_DONE_EN"
    await drv.enable_irq(done=True, error=False)
    await ClockCycles(tb.clk, 2)
    assert int(dut.irq.value) == 1, "irq must follow DONE once enabled"
    assert await tb.master.read(offset("CTRL")) == CTRL.field("IRQ_DONE_EN").mask | CTRL.field("ENABLE").mask
    await drv.clear_flags()
    await ClockCycles(tb.clk, 2)
    assert int(dut.irq.value) == 0 and not (await drv.status()).done
    tb.finish()


# ---------------------------------------------------------------------------------------------------------------
# Soft and hard stop through CTRL.

#: (kind, pulses to wait before the command, the phase it then lands in) on trap_negative (ACCEL 22, RUN 95,
#: DECEL 32 intervals).
STOP_CASES = stop_cases((10, 60, 135))


@cocotb.test(timeout_time=5, timeout_unit="ms")
async def soft_and_hard_stop(dut) -> None:
    """SOFT_STOP and HARD_STOP written to CTRL in ACCEL, RUN and DECEL: every edge as
    stepramp.models.engine.edges_with_stop predicts for the edge the engine samples the request, POSITION and
    STEP_COUNT equal to the pulses seen."""
    tb = CoreTb(dut)
    await tb.reset()
    await tb.configure(Outputs(mode="half", step_width=4, dir_setup=12, dir_hold=6), enable=True)
    await tb.driver().enable_irq(done=True, error=True)
    assert tb.pins is not None
    stop_edges: dict[str, list[int]] = {"soft": [], "hard": []}
    for kind in stop_edges:  # the register file's strobes inside the core
        cocotb.start_soon(tb.pins.watch(getattr(dut, f"{kind}_stop"), stop_edges[kind]))
    drv, plan = plan_of(tb, "trap_negative")
    position = 0
    for kind, wait_pulses, phase in STOP_CASES:
        what = f"{kind} stop in {phase}"
        await drv.program(plan)
        mark, k0 = tb.mark(), len(stop_edges[kind])
        await drv.start()
        while len(tb.pins.step_edges) < mark[0] + wait_pulses:
            await RisingEdge(dut.step)
        assert (await drv.status()).state == phase, f"{what}: not in {phase} after {wait_pulses} pulses"
        await (drv.soft_stop() if kind == "soft" else drv.hard_stop())
        status = await drv.wait_done(idle=lambda: tb.irq_or(20_000))
        assert not status.error, f"{what}: error {status.err_name}"
        edges = tb.edges_since(mark)
        assert len(stop_edges[kind]) == k0 + 1, f"{what}: {len(stop_edges[kind]) - k0} stop strobes"
        # The register file's strobe is high after the edge that samples the write; the engine samples it one later.
        check_stopped(plan, kind, phase, stop_edges[kind][k0] + 1 - tb.pins.start_edges[mark[1]], edges, wait_pulses)
        position -= len(edges)
        assert await drv.position() == position, f"{what}: POSITION is not the pulses seen"
        assert await tb.master.read(offset("STEP_COUNT")) == len(edges), f"{what}: STEP_COUNT"
    tb.finish()


# ---------------------------------------------------------------------------------------------------------------
# Windings.


@cocotb.test(timeout_time=3, timeout_unit="ms")
async def windings(dut) -> None:
    """The winding outputs follow the electrical position, the STEP pulses counted from the pins (docs/algorithm.md,
    "Electrical position"; stepramp.models.stepping): in wave, full and half step, 1-step moves forwards through two
    electrical periods and back past 0, POSITION presets that move nothing, off with ENABLE off; then half-step and PWM
    moves with the electrical-position monitor on."""
    tb = CoreTb(dut)
    await tb.reset()
    drv = tb.driver()
    one_step = {**PROFILES_BY_NAME["trap_basic"].args(), "steps": 1}
    for mode in ("wave", "full", "half"):
        await tb.configure(Outputs(mode=mode, step_width=4, dir_setup=10, dir_hold=5), enable=True)
        for steps in [1] * 9 + [-1] * 12:
            mark = tb.mark()
            await drv.program(plan_move(**{**one_step, "steps": steps}))
            await drv.start()
            await drv.wait_done(idle=lambda: tb.irq_or(500))
            assert len(tb.edges_since(mark)) == 1, f"{mode}: a 1-step move of {steps} gave no single pulse"
            want = sm.winding_levels(MODES[mode], tb.elec_pos, True)
            assert tb.windings() == want, f"{mode}, {tb.elec_pos} steps: a1 a2 b1 b2 = {tb.windings()}, want {want}"
        for p in (12345, -(2**31), 2**31 - 1, 0):
            await drv.set_position(p)
            await ClockCycles(tb.clk, 3)
            assert tb.windings() == want, f"{mode}: POSITION {p} moved the windings to {tb.windings()}"
        await drv.set_enable(False)
        await ClockCycles(tb.clk, 3)
        assert tb.windings() == (0, 0, 0, 0) and int(dut.enable.value) == 0, f"{mode}: windings on with ENABLE off"
    tb.finish()

    # Half-step moves from an odd electrical position, forwards and back (a DIR change), the monitors following every
    # STEP.
    assert tb.elec_pos % 2 == 1, f"electrical position {tb.elec_pos} is even"
    await tb.configure(Outputs(mode="half", step_width=4, dir_setup=10, dir_hold=5), enable=True)
    position = 0
    for name in ("triangle_sym", "triangle_negative"):
        drv, plan = plan_of(tb, name)
        mark = tb.mark()
        await drv.program(plan)
        await drv.start()
        await drv.wait_done(idle=lambda: tb.irq_or(2_000))
        position += signed_steps(plan)
        assert tb.edges_since(mark) == model_edges(plan), f"{name}: edges"
        assert await drv.position() == position, f"{name}: POSITION"
        assert tb.windings() == sm.winding_levels(sm.MODE_HALF, tb.elec_pos, True), f"{name}: windings at the end"
    assert tb.monitors is not None and tb.monitors.electrical.checked >= 101 + 75
    tb.finish()

    # Sine/cosine PWM (16 microsteps per full step): polarity at every step, duty over a carrier period now and then.
    await tb.configure(
        Outputs(mode="pwm", ustep_log2=4, step_width=10, dir_setup=7, dir_hold=3, pwm_period=40), enable=True
    )
    drv, plan = plan_of(tb, "triangle_sym")
    mark = tb.mark()
    await drv.program(plan)
    await drv.start()
    await drv.wait_done(idle=lambda: tb.irq_or(2_000))
    assert tb.edges_since(mark) == model_edges(plan)
    assert await drv.position() == position + plan.steps
    assert tb.monitors is not None and tb.monitors.electrical.duty_measured >= 3
    tb.finish()


TESTS = ["register_port_timing", "motion_profiles", "soft_and_hard_stop", "windings"]


def test_core() -> None:
    """stepramp_core alone through its register port, programmed by the driver, against the model."""
    run_cocotb("stepramp_core", "test_core", build_dir("core"), testcase=TESTS)
