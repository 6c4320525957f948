# SPDX-License-Identifier: MIT
"""The multi-axis tops (stepramp_multi_plb, stepramp_multi_axil) at 3 axes, through their bus, with the driver
(stepramp.board.multi.MultiAxis and a StepRamp per axis window). docs/stepramp_multi.md.

GHDL's VPI does not see into the for-generate of the cores, so the bench observes only the top's ports: the STEP and
DIR vectors (every rising STEP edge of every axis, stamped with its clock edge), irq, and the bus. The clock edge at
which the slave sampled a write comes from the bus too: the edge of IP2Bus_WrAck (PLB-like), or the edge before
s_axil_bvalid rises (AXI4-Lite). Expected STEP edges are the bit-exact model's (stepramp.models.engine.edges) for
the axis's plan, placed by the start gate's rule (stepramp.models.stepping.gate_timing) from the edge that sampled
the START or SYNC_START write: START written at edge w reaches the gate at w + 1 (docs/stepramp_plb.md, "Start
timing").

Tests (one simulation per top):

* register_windows: the global window (ID with the axis count, IRQ_MASK, SYNC_START reads 0, AXES_STATUS after
  reset, read-only writes, word addresses), each axis's window (its ID, with bit 14: no winding outputs, the top's
  default; DRIVE.MODE reads 0 whatever is written and the driver refuses a winding mode; a register written with a
  value of its own and read back from every window: no aliasing), err on every unmapped global offset, on the
  unmapped offsets of each axis window and on the windows past the last axis; with idle cycles / backpressure;
* sync_start_same_clock: equal moves on axes 0 and 2 started by one SYNC_START: their STEP edges are the same clock
  edges, equal to the model's from the write's edge; axis 1 (programmed, not selected) does not move; AXES_STATUS and
  POSITION after;
* sync_group_is_the_named_axes: a SYNC_START of axis 0 (DIR change, setup 200) and, 40 clocks later, axis 1's own
  START (DIR change, setup 1,000): axis 0 starts at its own gate, not held by axis 1, which keeps its own timing;
* axes_status_and_irq: axis 0 started through its CTRL.START, then SYNC_START of all three (axis 0 is busy and
  ignores it); AXES_STATUS BUSY / DONE read while the moves run and end; irq with IRQ_MASK = axis 1 only rises one
  clock after axis 1's last STEP edge (the other axes' irq lines are up before, as AXES_STATUS.IRQ shows), follows
  the mask at once, and falls when the flags are cleared;
* coordinated_move: MultiAxis.move_coordinated of a 3-axis linear move (one axis backwards, so its DIR changes):
  the plans are stepramp.board.coord.plan_coordinated's, every STEP edge of every axis equals the model's, and the
  last pulses lie within max(2 ticks, 0.01 c0 of the slowest axis) of each other;
* coordinated_stop_on_the_line: MultiAxis.stop_coordinated (one CHANGE per axis, stepramp.board.coord
  .plan_coordinated_stop) of a 3-axis coordinated move in its ACCEL and of another in its RUN: every STEP edge of
  every axis equals change_edges of its plan and its take-over, every axis rests within half a step of the line;
* estop_stops_every_axis: the shared ESTOP pin raised while three axes run, each axis with its own INPUT_FILTER N:
  no STEP rising edge later than 2 clocks after the axis's filtered edge F = a + N + 2 (docs/algorithm.md, "Machine
  inputs"), every pulse before it as the model says, ERROR with ERR_CODE ESTOP, ENABLE low, and a SYNC_START during
  the fault refused; the fault clears once ESTOP is low.

The STEP width (exact) and DIR setup / hold of every axis are checked from the recorded pins in every motion test
(stepramp.models.stepping's checkers). test_axis_count_is_range_checked: G_AXES = 9 stops `ghdl synth` with the
generic's assertion, 8 passes.
"""

from __future__ import annotations

import dataclasses
import subprocess
from pathlib import Path
from typing import Any

import pytest
from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge, Timer
from cocotb.utils import get_sim_time

from peripheral_tb import AxilPort, BusError, BusPort, IpifPort
from stepramp.board.change import Segment
from stepramp.board.coord import CoordInfo, plan_coordinated_info, plan_coordinated_stop
from stepramp.board.driver import Outputs, StepRamp, plan_writes, segment_writes
from stepramp.board.multi import (
    AXIS_WINDOW,
    ID_MAGIC,
    ID_VERSION,
    REG_AXES_STATUS,
    REG_ID,
    REG_IRQ_MASK,
    REG_SYNC_SOFT_STOP,
    REG_SYNC_START,
    AxesStatus,
    MultiAxis,
    MultiAxisError,
    axis_base,
    soft_stop_line_bound,
)
from stepramp.board.plan import Plan, plan_move
from stepramp.board.regmap import ERROR_CODES, ID_VALUE, ID_WINDINGS_BIT, REGISTERS, REGISTERS_BY_NAME, offset
from stepramp.models import stepping as sm
from stepramp.models.engine import change_edges, edges_with_stop, phase_of, soft_stop_pulse
from stepramp.models.engine import edges as model_edges
from stepramp.sim.clocking import CLK_PERIOD_NS, CLK_PERIOD_PS, quiet_inputs, start_clock
from stepramp.sim.ipif import IpifMaster
from stepramp.sim.profiles import design_args
from stepramp.sim.runner import run_cocotb
from stepramp.tools.rtlcheck import analyse
from tbutil import build_dir, cocotb, edges_differ, env_int

#: The axis count the tops are built with here (G_AXES; MULTI_AXES in the simulation's environment).
AXES = 3
TOPS = ("stepramp_multi_plb", "stepramp_multi_axil")
PORTS: dict[str, type[BusPort]] = {"stepramp_multi_plb": IpifPort, "stepramp_multi_axil": AxilPort}

MAPPED = {r.offset for r in REGISTERS}
GLOBAL = (REG_ID, REG_SYNC_START, REG_AXES_STATUS, REG_IRQ_MASK, REG_SYNC_SOFT_STOP)
STATUS = REGISTERS_BY_NAME["STATUS"]
ESTOP_CODE = ERROR_CODES["ESTOP"][0]
#: The stepping outputs of the motion tests (STEP/DIR only): exact STEP width 4, the shortest DIR timing.
OUTPUTS = Outputs(step_width=4, dir_setup=0, dir_hold=0)


def _bits(value: Any) -> int | None:
    return int(value) if value.is_resolvable else None


class MultiTb:
    """A multi-axis top with its clock, reset, bus master, the driver, and the pins of every axis.

    Clock edges are numbered from this bench's clock start (edge 0); `write_edges` holds the edge at which the slave
    sampled each write, `rises[i]` / `falls[i]` / `dir_changes[i]` axis i's STEP rising and falling edges and DIR
    changes, `irq_rises` the edges after which irq is '1'.
    """

    def __init__(self, dut: Any, idle: bool = False) -> None:
        self.dut = dut
        self.top = dut._name
        self.axes = env_int("MULTI_AXES", AXES)
        self.port = PORTS[self.top](dut, env_int("BUS_SEED", 1) if idle else None)
        self.clk = self.port.clk
        self.t0 = get_sim_time("ps")
        start_clock(self.clk)
        quiet_inputs(dut)
        self.bus: Any = None
        self.write_edges: list[int] = []
        self.read_edges: list[int] = []
        self.rises: list[list[int]] = [[] for _ in range(self.axes)]
        self.falls: list[list[int]] = [[] for _ in range(self.axes)]
        self.dir_changes: list[list[int]] = [[] for _ in range(self.axes)]
        self.irq_rises: list[int] = []
        self.outputs = [Outputs() for _ in range(self.axes)]
        self.multi: MultiAxis

    @classmethod
    async def started(cls, dut: Any, idle: bool = False, fclk: float = 1e6, prescale: int = 1) -> MultiTb:
        tb = cls(dut, idle)
        tb.bus = await tb.port.reset()
        await ClockCycles(tb.clk, 2)
        tb.multi = MultiAxis(tb.bus, tb.axes, fclk=fclk, spr=200.0, prescale=prescale)
        for coro in (tb._watch_bus(), tb._watch_vector("step"), tb._watch_vector("dir"), tb._watch_irq()):
            cocotb.start_soon(coro)
        return tb

    def edge(self) -> int:
        """The rising edge now (at it, or in the half period after it)."""
        return round((get_sim_time("ps") - self.t0) / CLK_PERIOD_PS)

    def edge_before(self) -> int:
        """The last rising edge before now (at a falling edge: the one half a period ago)."""
        return int((get_sim_time("ps") - self.t0) // CLK_PERIOD_PS)

    async def _watch_bus(self) -> None:
        """The edge that sampled each access: PLB-like, the ack rises right after it; AXI4-Lite, the response valid
        rises one edge later (the slave registers the core's answer)."""
        if self.top.endswith("_plb"):
            wack, rack, late = self.dut.ip2bus_wrack, self.dut.ip2bus_rdack, 0
        else:
            wack, rack, late = self.dut.s_axil_bvalid, self.dut.s_axil_rvalid, 1

        async def watch(signal: Any, edges: list[int]) -> None:
            while True:
                await RisingEdge(signal)
                edges.append(self.edge() - late)

        cocotb.start_soon(watch(rack, self.read_edges))
        await watch(wack, self.write_edges)

    async def _watch_vector(self, name: str) -> None:
        signal = getattr(self.dut, name)
        prev = _bits(signal.value) or 0
        while True:
            await signal.value_change
            now = _bits(signal.value)
            if now is None:
                continue
            edge = self.edge()
            for i in range(self.axes):
                bit, was = now >> i & 1, prev >> i & 1
                if name == "dir" and bit != was:
                    self.dir_changes[i].append(edge)
                elif name == "step" and bit and not was:
                    self.rises[i].append(edge)
                elif name == "step" and was and not bit:
                    self.falls[i].append(edge)
            prev = now

    async def _watch_irq(self) -> None:
        while True:
            await RisingEdge(self.dut.irq)
            self.irq_rises.append(self.edge())

    def axis(self, i: int) -> StepRamp:
        return self.multi.axis(i)

    async def configure(self, outputs: Outputs = OUTPUTS, irq: bool = True) -> None:
        """Every axis: stepping outputs, ENABLE, interrupts on DONE and ERROR."""
        for i in range(self.axes):
            await self.axis(i).configure_outputs(outputs)
            await self.axis(i).set_enable(True)
            await self.axis(i).enable_irq(done=irq, error=irq)
            self.outputs[i] = outputs

    def pins_before(self) -> tuple[list[int], list[int | None], list[int]]:
        """Every axis's DIR now (0 after reset; the pins show each change), its last STEP rising edge (None: none since
        reset) and its count of STEP rising edges: what the edges of the next moves start from (expected_sync)."""
        dirs = [len(changes) % 2 for changes in self.dir_changes]
        lasts: list[int | None] = [r[-1] if r else None for r in self.rises]
        return dirs, lasts, [len(r) for r in self.rises]

    def expected(self, i: int, plan: Plan, write_edge: int, dir_before: int, last_rise: int | None) -> list[int]:
        """Axis i's STEP rising edges for `plan` started by a write sampled at `write_edge` (the gate's request one
        edge later), from DIR `dir_before` and its last STEP rising edge before (None: none since reset)."""
        o = self.outputs[i]
        gate = sm.gate_timing(
            write_edge + 1,
            plan.direction != dir_before,
            last_rise,
            o.dir_hold,
            o.dir_setup,
            o.step_width,
            o.step_space,
        )
        engine_edge0 = gate.start_edge + 1  # eng_start is '1' in the cycle after start_edge
        return [engine_edge0 + sm.STEP_LATENCY + e for e in model_edges(plan)]

    def expected_sync(
        self,
        plans: list[Plan],
        write_edge: int,
        dirs_before: list[int] | None = None,
        last_rises: list[int | None] | None = None,
    ) -> tuple[int, list[list[int]]]:
        """The engine's edge 0 and each axis's STEP rising edges (none for 0 steps) when one SYNC_START sampled at
        `write_edge` starts `plans`: each axis's start gate (gate_timing from its DIR and last STEP edge before), then
        the common start of the selected axes (stepramp.models.stepping.sync_gate_timing)."""
        dirs = dirs_before or [0] * len(plans)
        lasts = last_rises or [None] * len(plans)
        chosen = [i for i, plan in enumerate(plans) if plan.steps > 0]
        gates = []
        for i in chosen:
            o = self.outputs[i]
            gates.append(
                sm.gate_timing(
                    write_edge + 1,
                    plans[i].direction != dirs[i],
                    lasts[i],
                    o.dir_hold,
                    o.dir_setup,
                    o.step_width,
                    o.step_space,
                )
            )
        synced = sm.sync_gate_timing(gates)
        edge0 = synced[0].start_edge + 1
        out: list[list[int]] = [[] for _ in plans]
        for i in chosen:
            out[i] = [edge0 + sm.STEP_LATENCY + e for e in model_edges(plans[i])]
        return edge0, out

    def check_pins(self) -> None:
        """Exact STEP width and DIR setup / hold on every axis, from the recorded pins."""
        problems: list[str] = []
        for i in range(self.axes):
            o = self.outputs[i]
            problems += [
                f"axis {i}: {p}" for p in sm.check_step_widths(self.rises[i], self.falls[i], o.step_width, True)
            ]
            problems += [
                f"axis {i}: {p}"
                for p in sm.check_dir_timing(self.rises[i], self.dir_changes[i], o.dir_setup, o.dir_hold)
            ]
        assert not problems, "\n".join(problems[:10])

    async def wait_rises(self, i: int, count: int) -> None:
        """Until axis i has shown `count` STEP rising edges in all."""
        while len(self.rises[i]) < count:
            await RisingEdge(self.clk)

    async def idle(self, cycles: int) -> None:
        await Timer(cycles * CLK_PERIOD_NS, unit="ns")


def short_plan(steps: int, period: float, ramp: float, prescale: int = 1) -> Plan:
    """A short move designed in ticks (stepramp.sim.profiles.design_args): cruise period and ramp length in steps."""
    return plan_move(**design_args(steps, period, ramp, ramp, prescale=prescale))


async def expect_err(access: Any, kind: str, addr: int) -> None:
    try:
        await (access.read(addr) if kind == "rd" else access.write(addr, 0xFFFF_FFFF))
    except BusError:
        return
    raise AssertionError(f"{kind} at {addr:#05x}: no bus error")


# ---------------------------------------------------------------------------------------------------------------


@cocotb.test(timeout_time=400, timeout_unit="us")
async def register_windows(dut) -> None:
    """The global window, every axis window, no aliasing between them, err on every unmapped offset and window."""
    tb = await MultiTb.started(dut, idle=True)
    bus, axes = tb.bus, tb.axes
    writes0 = len(tb.write_edges)

    # Global window.
    assert await bus.read(REG_ID) == ID_MAGIC << 16 | ID_VERSION << 8 | axes
    assert await tb.multi.check_id() == ID_VERSION
    assert (await MultiAxis.probe(bus, 1e6, 200.0)).axes == axes
    all_axes = (1 << axes) - 1
    assert await bus.read(REG_IRQ_MASK) == all_axes, "IRQ_MASK resets to every axis"
    assert await bus.read(REG_AXES_STATUS) == 0, "AXES_STATUS after reset"
    assert await bus.read(REG_SYNC_START) == 0
    assert await bus.read(REG_SYNC_SOFT_STOP) == 0
    await bus.write(REG_IRQ_MASK, 0xFFFF_FFFF)
    assert await bus.read(REG_IRQ_MASK) == all_axes, "IRQ_MASK keeps a bit per axis only"
    await bus.write(REG_IRQ_MASK, 0b010, strobe=0b1110)  # byte lane 0 not enabled: no change
    assert await bus.read(REG_IRQ_MASK) == all_axes
    await tb.multi.set_irq_mask([0, 2])
    assert await tb.multi.irq_mask() == 0b101
    if tb.top.endswith("_plb"):  # (cocotbext-axi splits an unaligned read into two words)
        assert await bus.read(REG_IRQ_MASK + 3) == 0b101, "word address: bits 1:0 ignored"
    for reg in (REG_ID, REG_AXES_STATUS):  # read-only: acknowledged, no error, no change
        before = await bus.read(reg)
        await bus.write(reg, 0xFFFF_FFFF)
        assert await bus.read(reg) == before
    await bus.write(REG_SYNC_START, 0)  # selects no axis
    await bus.write(REG_SYNC_START, all_axes, strobe=0b1110)  # the mask's byte lane not enabled: no START
    await ClockCycles(tb.clk, 4)
    assert await bus.read(REG_AXES_STATUS) == 0, "SYNC_START without its byte lane started an axis"
    await tb.multi.sync_soft_stop(range(axes))  # idle axes: nothing to stop, no flag
    await ClockCycles(tb.clk, 4)
    assert await bus.read(REG_AXES_STATUS) == 0, "SYNC_SOFT_STOP of idle axes changed AXES_STATUS"
    await tb.multi.set_irq_mask(range(axes))

    # Every axis window: its own ID (bit 14: built without the winding outputs, the top's default G_WINDINGS),
    # STEPS written with a value of its own, read back from every window.
    for i in range(axes):
        assert await bus.read(axis_base(i) + offset("ID")) == ID_VALUE | 1 << ID_WINDINGS_BIT, f"axis {i}: ID"
        await bus.write(axis_base(i) + offset("STEPS"), 0x1000 + i)
        await bus.write(axis_base(i) + offset("SA"), 0x100 * (i + 1), strobe=0b0010)  # byte lane 1 only
    for i in range(axes):
        assert await bus.read(axis_base(i) + offset("STEPS")) == 0x1000 + i, f"axis {i}: STEPS"
        assert await bus.read(axis_base(i) + offset("SA")) == 0x100 * (i + 1), f"axis {i}: SA"
        assert (await tb.axis(i).status()).done is False

    # No windings: DRIVE.MODE reads 0 whatever is written (USTEP_LOG2 is kept), and the driver refuses a winding mode.
    drive = REGISTERS_BY_NAME["DRIVE"]
    pwm_mode = 4 << drive.field("MODE").lsb | 3 << drive.field("USTEP_LOG2").lsb
    await bus.write(axis_base(0) + offset("DRIVE"), pwm_mode)
    assert await bus.read(axis_base(0) + offset("DRIVE")) == 3 << drive.field("USTEP_LOG2").lsb, "DRIVE.MODE stored"
    await bus.write(axis_base(0) + offset("DRIVE"), 0)
    await tb.axis(0).check_id()
    assert tb.axis(0).windings is False
    with pytest.raises(ValueError, match="winding"):
        await tb.axis(0).configure_outputs(Outputs(mode="pwm"))

    # Unmapped: the rest of the global window, the unmapped offsets of each axis window, the windows past the axes.
    for addr in range(REG_SYNC_SOFT_STOP + 4, AXIS_WINDOW, 4):
        await expect_err(bus, "rd", addr)
        await expect_err(bus, "wr", addr)
    for i in range(axes):
        for off in (o for o in range(0, AXIS_WINDOW, 4) if o not in MAPPED):
            await expect_err(bus, "rd", axis_base(i) + off)
            await expect_err(bus, "wr", axis_base(i) + off)
    for window in range(axes + 1, 16):
        for off in (0x00, 0x04, offset("STEPS"), 0xFC):
            await expect_err(bus, "rd", window * AXIS_WINDOW + off)
            await expect_err(bus, "wr", window * AXIS_WINDOW + off)
    # The errors changed nothing.
    for i in range(axes):
        assert await bus.read(axis_base(i) + offset("STEPS")) == 0x1000 + i, f"axis {i}: STEPS after the errors"
    assert await bus.read(REG_IRQ_MASK) == all_axes
    assert len(tb.write_edges) > writes0, "no write response seen on the bus"
    assert not any(tb.rises), "a STEP pulse without a move"


@cocotb.test(timeout_time=300, timeout_unit="us")
async def sync_start_same_clock(dut) -> None:
    """Equal moves on axes 0 and 2 from one SYNC_START: every STEP edge on the same clock edge, as the model says;
    axis 1, programmed but not selected, does not move."""
    tb = await MultiTb.started(dut)
    await tb.configure()
    plan = short_plan(30, 100.0, 8.0)
    other = short_plan(12, 150.0, 4.0)
    await tb.axis(0).program(plan)
    await tb.axis(1).program(other)
    await tb.axis(2).program(plan)
    await tb.multi.sync_start([0, 2])
    w = tb.write_edges[-1]
    while len(tb.rises[0]) < 2:
        await RisingEdge(tb.clk)
    mid = await tb.multi.status()
    assert mid.busy == 0b101 and mid.done == 0, f"AXES_STATUS during the moves: {mid}"
    end = await tb.multi.wait_done([0, 2], idle=lambda: tb.idle(500))
    assert end.busy == 0 and end.done == 0b101, f"AXES_STATUS at the end: {end}"
    want = tb.expected(0, plan, w, 0, None)
    assert tb.rises[0] == want, f"axis 0: {edges_differ(tb.rises[0], want)}"
    assert tb.rises[2] == tb.rises[0], f"axes 0 and 2 differ: {edges_differ(tb.rises[2], tb.rises[0])}"
    assert tb.rises[1] == [], f"axis 1 was not selected and moved: {tb.rises[1][:5]}"
    assert [await tb.axis(i).position() for i in range(3)] == [30, 0, 30]
    after = await tb.multi.status()
    assert after.done == 0 and after.irq == 0, f"flags not cleared by wait_done: {after}"

    # The same again, now with DIR changing on both (a negative move): the gate holds both starts alike.
    back = short_plan(-20, 100.0, 6.0)
    last = tb.rises[0][-1]
    n0 = len(tb.rises[0])
    await tb.axis(0).program(back)
    await tb.axis(2).program(back)
    await tb.multi.sync_start([0, 2])
    w = tb.write_edges[-1]
    await tb.multi.wait_done([0, 2], idle=lambda: tb.idle(500))
    want = tb.expected(0, back, w, 0, last)
    assert tb.rises[0][n0:] == want, f"axis 0 back: {edges_differ(tb.rises[0][n0:], want)}"
    assert tb.rises[2] == tb.rises[0], "axes 0 and 2 differ on the way back"
    assert tb.rises[1] == []
    tb.check_pins()


@cocotb.test(timeout_time=800, timeout_unit="us")  # measured about 250 us
async def sync_group_is_the_named_axes(dut) -> None:
    """A SYNC_START's common start holds only the axes it names: axis 0 (named, DIR change, DIR setup 200) starts at
    its own gate although axis 1, idle at that SYNC_START and not named, is started 40 clocks later through its own
    CTRL.START with a DIR change and DIR setup 1,000; axis 1 keeps its own gate timing. Then a SYNC_START of both
    while axis 0 is in its DIR hold after a move: both start on axis 0's gate. A read of SYNC_SOFT_STOP during a move
    (PLB-like: with all ones left on the data lines) does not stop it. Each as the model says."""
    tb = await MultiTb.started(dut)
    await tb.configure()
    for i, setup in ((0, 200), (1, 1000)):
        out = Outputs(step_width=4, dir_setup=setup, dir_hold=0)
        await tb.axis(i).configure_outputs(out)
        tb.outputs[i] = out
    plan = short_plan(-12, 100.0, 4.0)
    await tb.axis(0).program(plan)
    await tb.axis(1).program(plan)
    await tb.multi.sync_start([0])
    w0 = tb.write_edges[-1]
    await ClockCycles(tb.clk, 40)
    await tb.axis(1).start()
    w1 = tb.write_edges[-1]
    await tb.multi.wait_done([0, 1], idle=lambda: tb.idle(500))
    _, wants = tb.expected_sync([plan, dataclasses.replace(plan, steps=0)], w0)
    assert tb.rises[0] == wants[0], f"axis 0 (named): {edges_differ(tb.rises[0], wants[0])}"
    want1 = tb.expected(1, plan, w1, 0, None)
    assert tb.rises[1] == want1, f"axis 1 (its own START): {edges_differ(tb.rises[1], want1)}"
    assert tb.rises[0][0] < tb.rises[1][0], "axis 0 waited for axis 1's gate"

    # ... and it waits for a named axis in its DIR hold: axis 0 reverses soon after a move (DIR hold 6,000 clocks),
    # axis 1 keeps its direction; both start on axis 0's gate.
    hold = Outputs(step_width=4, dir_setup=5, dir_hold=6000)
    await tb.axis(0).configure_outputs(hold)
    tb.outputs[0] = hold
    await tb.axis(0).program(short_plan(12, 100.0, 4.0))
    await tb.axis(0).start()
    await tb.multi.wait_done([0], idle=lambda: tb.idle(200))
    lasts: list[int | None] = [tb.rises[0][-1], tb.rises[1][-1]]
    n0 = [len(tb.rises[0]), len(tb.rises[1])]
    await tb.axis(0).program(plan)
    await tb.axis(1).program(plan)
    await tb.multi.sync_start([0, 1])
    w = tb.write_edges[-1]
    assert w < lasts[0] + 6000, "the SYNC_START came after axis 0's DIR hold"
    await tb.multi.wait_done([0, 1], idle=lambda: tb.idle(500))
    _, wants = tb.expected_sync([plan, plan], w, [0, 1], lasts)
    for i in range(2):
        got = tb.rises[i][n0[i] :]
        assert got == wants[i], f"axis {i} after the hold: {edges_differ(got, wants[i])}"
    assert wants[0][0] == wants[1][0], "the model's common start is not one edge"

    # SYNC_SOFT_STOP acts on its write only: read it (it reads 0; on the PLB-like bus with all ones left on
    # Bus2IP_Data, as a bus may leave a write's data) while axis 0 runs a move started through its CTRL (a write
    # whose bit 0 is set), then leave the bus alone: the move runs to its end.
    fwd = short_plan(12, 100.0, 4.0)
    k0 = len(tb.rises[0])
    last = tb.rises[0][-1]
    await tb.axis(0).program(fwd)
    await tb.axis(0).start()
    w = tb.write_edges[-1]
    want = tb.expected(0, fwd, w, 1, last)
    await tb.wait_rises(0, k0 + 3)
    if isinstance(tb.bus, IpifMaster):
        assert await tb.bus.read(REG_SYNC_SOFT_STOP, data_lines=0xFFFF_FFFF) == 0
    else:
        assert await tb.bus.read(REG_SYNC_SOFT_STOP) == 0
    await tb.idle(want[-1] - w + 200)
    got = tb.rises[0][k0:]
    assert got == want, f"axis 0 with a read of SYNC_SOFT_STOP: {edges_differ(got, want)}"
    await tb.multi.wait_done([0], idle=lambda: tb.idle(200))
    tb.check_pins()


@cocotb.test(timeout_time=400, timeout_unit="us")
async def axes_status_and_irq(dut) -> None:
    """AXES_STATUS BUSY / DONE while axes start and end at different times; SYNC_START ignored by a busy axis; one
    irq, the OR of the axes' irq lines under IRQ_MASK."""
    tb = await MultiTb.started(dut)
    await tb.configure()
    plans = [short_plan(24, 90.0, 6.0), short_plan(40, 100.0, 8.0), short_plan(10, 120.0, 3.0)]
    await tb.multi.set_irq_mask([1])
    # Axis 0 alone, through its own CTRL.START.
    await tb.axis(0).program(plans[0])
    await tb.axis(0).start()
    w0 = tb.write_edges[-1]
    await tb.wait_rises(0, 3)
    # All three by SYNC_START: axis 0 is busy and ignores it (axis 0's staging copy holds a move it must not run).
    await tb.axis(0).program(short_plan(5, 100.0, 2.0))
    await tb.axis(1).program(plans[1])
    await tb.axis(2).program(plans[2])
    await tb.multi.sync_start(range(3))
    w1 = tb.write_edges[-1]
    want = [tb.expected(0, plans[0], w0, 0, None)] + [tb.expected(i, plans[i], w1, 0, None) for i in (1, 2)]
    first = [w[0] for w in want]
    last = [w[-1] for w in want]
    assert first[1] == first[2] and last[2] < last[0] < last[1], f"the moves do not overlap as designed: {want}"

    async def status_at(label: str) -> None:
        """AXES_STATUS against the model's moves at the edge the read was sampled (not within 3 clocks of a start or
        an end of a move, where BUSY and DONE change)."""
        raw = await tb.bus.read(REG_AXES_STATUS)
        r = tb.read_edges[-1]
        starts = [w0 + 1, w1 + 1, w1 + 1]  # BUSY from the gate's request on
        near = [e for e in (*starts, *last) if abs(r - e) <= 3]
        assert not near, f"{label}: the read at edge {r} is too close to {near} to judge"
        busy = sum(1 << i for i in range(3) if starts[i] < r < last[i])
        done = sum(1 << i for i in range(3) if r > last[i])
        got = AxesStatus.decode(raw)
        assert (got.busy, got.done, got.irq) == (busy, done, done), f"{label}: {got} at edge {r}, model {busy=} {done=}"

    await tb.wait_rises(2, 2)
    await status_at("all three moving")
    await tb.wait_rises(2, len(want[2]))
    await tb.idle(20)
    await status_at("axis 2 done")
    await tb.wait_rises(0, len(want[0]))
    await tb.idle(20)
    await status_at("axes 0 and 2 done")
    assert tb.irq_rises == [], f"irq rose at {tb.irq_rises} with only axis 1 in IRQ_MASK"
    await tb.wait_rises(1, len(want[1]))
    await tb.idle(20)
    await status_at("all done")
    # The axis's irq is registered after DONE (one clock after its last STEP edge); the top ORs it at once.
    assert tb.irq_rises == [last[1] + 1], f"irq rises {tb.irq_rises}, axis 1's last STEP edge {last[1]}"
    for i in range(3):
        assert tb.rises[i] == want[i], f"axis {i}: {edges_differ(tb.rises[i], want[i])}"

    # The mask acts at once: off, irq low; axis 2 alone (its irq line is up), high again.
    await tb.multi.set_irq_mask([])
    await ClockCycles(tb.clk, 1)
    assert int(dut.irq.value) == 0, "irq with IRQ_MASK 0"
    await tb.multi.set_irq_mask([2])
    await ClockCycles(tb.clk, 1)
    assert int(dut.irq.value) == 1 and tb.irq_rises[-1] == tb.write_edges[-1], "irq does not follow IRQ_MASK"
    await tb.multi.wait_done(range(3))  # clears every axis's flags
    await ClockCycles(tb.clk, 2)
    assert int(dut.irq.value) == 0 and (await tb.multi.status()).irq == 0
    assert [await tb.axis(i).position() for i in range(3)] == [24, 40, 10]
    tb.check_pins()


#: The coordinated tests' PRESCALE (a tick of 2 clocks).
COORD_PRESCALE = 2


@dataclasses.dataclass(frozen=True)
class Lead:
    """The lead axis of the coordinated tests' moves, designed in ticks at COORD_PRESCALE (design_args: its steps,
    cruise period and ramp lengths): the path's accel, decel and speed (args), spr and fclk."""

    design: dict[str, Any]

    @classmethod
    def of(cls, steps: int, period: float, n_a: float, n_d: float) -> Lead:
        return cls(design_args(steps, period, n_a, n_d, prescale=COORD_PRESCALE))

    @property
    def args(self) -> tuple[float, float, float]:
        return self.design["accel"], self.design["decel"], self.design["speed"]

    def plan(self, steps: list[int]) -> tuple[list[Plan], CoordInfo]:
        """plan_coordinated_info of a coordinated move of `steps` at the lead's accel, decel and speed."""
        d = self.design
        return plan_coordinated_info(steps, *self.args, spr=d["spr"], fclk=d["fclk"], prescale=COORD_PRESCALE)


async def coordinated_bench(dut: Any, outputs: Outputs = OUTPUTS) -> MultiTb:
    """A started multi-axis bench at COORD_PRESCALE, every axis configured with `outputs`."""
    tb = await MultiTb.started(dut, prescale=COORD_PRESCALE)
    await tb.configure(outputs)
    return tb


@cocotb.test(timeout_time=600, timeout_unit="us")
async def coordinated_move(dut) -> None:
    """A coordinated linear move of three axes (one backwards) started by SYNC_START: every edge of every axis as the
    model says for its plan, and the last pulses within max(2 ticks, 0.01 c0 of the slowest axis) of each other."""
    tb = await coordinated_bench(dut)
    lead = Lead.of(48, 60.0, 10.0, 10.0)
    steps = [48, -29, 17]
    plans, info = lead.plan(steps)
    got = await tb.multi.move_coordinated(steps, *lead.args)
    assert got == plans, "the driver's plans are not plan_coordinated's"
    w = tb.write_edges[-1]
    await tb.multi.wait_done(range(3), idle=lambda: tb.idle(1000))
    _, wants = tb.expected_sync(plans, w)
    await check_coordinated_ends(tb, wants, steps, info)


async def check_coordinated_ends(tb: Any, wants: list[list[int]], steps: list[int], info: Any) -> None:
    """Every axis's edges as the model's (wants) and its POSITION, the last pulses within max(2 ticks, 0.01 c0 of the
    slowest axis) of each other, and the pins' checks."""
    for i in range(3):
        assert tb.rises[i] == wants[i], f"axis {i}: {edges_differ(tb.rises[i], wants[i])}"
        assert await tb.axis(i).position() == steps[i], f"axis {i}: POSITION"
    ends = [r[-1] for r in tb.rises]
    c0_slowest = max(move.c0 for move in info.infos)
    tolerance = max(2.0, 0.01 * c0_slowest) * COORD_PRESCALE  # clocks
    spread = max(ends) - min(ends)
    assert spread <= tolerance, f"last pulses at {ends}: {spread} clocks apart, more than {tolerance}"
    tb.check_pins()


@cocotb.test(timeout_time=400, timeout_unit="us")
async def coordinated_dir_changes(dut) -> None:
    """A coordinated 3-axis move in which two axes change DIR (DIR setup 60 clocks): SYNC_START gives every axis its
    pulse 0 on one clock edge, the latest gate among them (sync_gate_timing); every edge as the model says, the last
    pulses within max(2 ticks, 0.01 c0 of the slowest axis) of each other, DIR setup kept on the pins."""
    tb = await coordinated_bench(dut, Outputs(step_width=4, dir_setup=60, dir_hold=0))
    lead = Lead.of(40, 60.0, 8.0, 8.0)
    steps = [40, -23, -13]
    plans, info = lead.plan(steps)
    await tb.multi.move_coordinated(steps, *lead.args)
    w = tb.write_edges[-1]
    await tb.multi.wait_done(range(3), idle=lambda: tb.idle(1000))
    _, wants = tb.expected_sync(plans, w)
    assert len({want[0] for want in wants}) == 1, "the model's pulses 0 are not on one edge"
    await check_coordinated_ends(tb, wants, steps, info)


@cocotb.test(timeout_time=400, timeout_unit="us")
async def coordinated_soft_stop(dut) -> None:
    """SYNC_SOFT_STOP during a coordinated 3-axis move (in its ACCEL, then in a second move's RUN): every axis
    soft-stopped at the edge that samples the write, each edge as the model says (edges_with_stop of each plan at
    that edge), and each axis at rest within the documented distance of the line (the lead's stop point times
    L_i / L_lead, multi.soft_stop_line_bound)."""
    tb = await coordinated_bench(dut)
    lead = Lead.of(60, 60.0, 12.0, 12.0)
    position = [0, 0, 0]
    assert not any(tb.dir_changes)
    for steps, wait, phase in (([60, -37, 22], 6, "ACCEL"), ([-60, 41, -17], 25, "RUN")):
        plans, info = lead.plan(steps)
        dirs, lasts, n0 = tb.pins_before()
        await tb.axis(0).program(plans[0])
        await tb.axis(1).program(plans[1])
        await tb.axis(2).program(plans[2])
        await tb.multi.sync_start(range(3))
        w = tb.write_edges[-1]
        await tb.wait_rises(info.lead, n0[info.lead] + wait)
        await tb.multi.sync_soft_stop(range(3))
        s = tb.write_edges[-1]
        await tb.multi.wait_done(range(3), idle=lambda: tb.idle(1000))
        edge0, _ = tb.expected_sync(plans, w, dirs, lasts)
        request = s + 1 - edge0  # the engine samples the strobe one edge after the write's
        finals = []
        for i, plan in enumerate(plans):
            want = [edge0 + sm.STEP_LATENCY + e for e in edges_with_stop(plan, "soft", request)]
            got = tb.rises[i][n0[i] :]
            assert got == want, f"move {steps}, axis {i}: {edges_differ(got, want)}"
            finals.append(len(got) - 1)
            position[i] += (len(got)) * (1 if plan.direction == 0 else -1)
            assert await tb.axis(i).position() == position[i], f"axis {i}: POSITION"
        assert finals[info.lead] < abs(steps[info.lead]) - 1, "the stop did not shorten the lead's move"
        p_lead = soft_stop_pulse(plans[info.lead], request)
        assert p_lead is not None and phase_of(plans[info.lead], p_lead) == phase, f"not a stop in {phase}"
        bound = soft_stop_line_bound(plans[info.lead], p_lead)
        for i in range(3):
            off = abs(finals[i] - info.ratios[i] * finals[info.lead])
            assert off <= bound, f"axis {i} rests {off:.3f} steps off the line (bound {bound:.3f}), finals {finals}"
            dut._log.info(f"{phase} stop: axis {i} rests at {finals[i]}, {off:.3f} steps off the line (bound {bound})")
    tb.check_pins()


@cocotb.test(timeout_time=400, timeout_unit="us")
async def coordinated_stop_on_the_line(dut) -> None:
    """The coordinated stop on the line (MultiAxis.stop_coordinated of plan_coordinated_stop) of a 3-axis coordinated
    move in its ACCEL, then of another in its RUN: one CHANGE per axis, each committed no later than the edge its
    take-over pulse was named for; every STEP edge of every axis equals the model's (change_edges of its plan and its
    segment), and every axis rests on its T_i, within half a step of the line point k_i R_L of the lead's rest."""
    tb = await coordinated_bench(dut)
    lead = Lead.of(80, 40.0, 14.0, 10.0)
    position = [0, 0, 0]
    for steps, wait, phase in (([80, -53, 29], 4, "ACCEL"), ([-80, 61, -23], 35, "RUN")):
        plans, info = lead.plan(steps)
        dirs, lasts, n0 = tb.pins_before()
        for i in range(3):
            await tb.axis(i).program(plans[i])
        await tb.multi.sync_start(range(3))
        edge0, wants = tb.expected_sync(plans, tb.write_edges[-1], dirs, lasts)
        await tb.wait_rises(info.lead, n0[info.lead] + wait)
        now = tb.edge()
        commits = [now + 150 * (i + 1) for i in range(3)]  # (each axis's writes take well under 150 clocks)
        d = lead.design
        stop = plan_coordinated_stop(plans, info, wants, commits, *lead.args, d["spr"], d["fclk"], COORD_PRESCALE)
        assert stop.fallback is None and stop.changes == [0, 1, 2], f"{phase}: {stop}"
        p_lead = stop.axes[info.lead].pulse
        assert phase_of(plans[info.lead], p_lead) == phase, f"the lead takes over at {p_lead}, not in {phase}"
        seen = len(tb.write_edges)
        await tb.multi.stop_coordinated(stop, plans)
        await tb.multi.wait_done(range(3), idle=lambda: tb.idle(500))
        writes = tb.write_edges[seen:]
        k = 0
        for i in stop.changes:
            seg_plan, regs = stop.axes[i].change.segment.registers(plans[i].direction)
            k += len(plan_writes(seg_plan)) + len(segment_writes(regs)) + 2
            assert writes[k - 1] <= commits[i], f"axis {i}: CHANGE committed at {writes[k - 1]}, after {commits[i]}"
        for i, plan in enumerate(plans):
            axis = stop.axes[i]
            assert axis.change is not None
            model = change_edges(Segment.of_move(plan), axis.pulse, axis.change.segment, COORD_PRESCALE)
            want = [edge0 + sm.STEP_LATENCY + e for e in model]
            got = tb.rises[i][n0[i] :]
            assert got == want, f"{phase} stop, axis {i}: {edges_differ(got, want)}"
            assert len(got) - 1 == axis.target, f"axis {i}: rests at {len(got) - 1}, T_i = {axis.target}"
            off = abs(axis.target - info.ratios[i] * stop.rest)
            assert off <= 0.5, f"axis {i} rests {off:.3f} steps off the line"
            position[i] += len(got) * (1 if plan.direction == 0 else -1)
            assert await tb.axis(i).position() == position[i], f"axis {i}: POSITION"
            dut._log.info(
                f"{phase} stop: axis {i} takes over at {axis.pulse}, rests at {axis.target} "
                f"({off:.3f} steps off the line point {info.ratios[i] * stop.rest:.3f}; plan's end {plan.steps - 1})"
            )
        assert stop.rest < abs(steps[info.lead]) - 1, "the stop did not shorten the lead's move"
    tb.check_pins()


@cocotb.test(timeout_time=400, timeout_unit="us")
async def estop_stops_every_axis(dut) -> None:
    """The shared ESTOP raised during three moves: each axis stops by its own filtered edge F = a + N + 2 (no STEP
    rising edge after F + 2), errors with ESTOP, drops ENABLE and refuses a SYNC_START until the fault is cleared."""
    tb = await MultiTb.started(dut)
    await tb.configure()
    filters = [1, 6, 13][: tb.axes]
    for i, n in enumerate(filters):
        await tb.axis(i).access.write(offset("INPUT_FILTER"), n)
    plans = [short_plan(60, 70.0, 6.0), short_plan(-50, 80.0, 6.0), short_plan(40, 90.0, 6.0)]
    for i, plan in enumerate(plans):
        await tb.axis(i).program(plan)
    await tb.multi.sync_start(range(3))
    w = tb.write_edges[-1]
    _, want = tb.expected_sync(plans, w)  # (axis 1 changes DIR: the common start waits for it)
    await tb.wait_rises(0, 20)
    await FallingEdge(tb.clk)
    dut.estop.value = 1
    a = tb.edge_before()  # the pin changed after edge a
    with pytest.raises(MultiAxisError) as raised:
        await tb.multi.wait_done(range(3), idle=lambda: tb.idle(200))
    assert raised.value.axes == (0, 1, 2), f"axes that reported an error: {raised.value.axes}"
    await tb.idle(300)
    for i, n in enumerate(filters):
        f = a + n + 2
        seen, model = tb.rises[i], want[i]
        assert seen == model[: len(seen)], f"axis {i}: {edges_differ(seen, model)}"
        assert all(e <= f + 2 for e in seen), f"axis {i}: STEP at {seen[-1]} after F + 2 = {f + 2}"
        assert len(seen) >= sum(1 for e in model if e <= f), f"axis {i}: a pulse before F = {f} missing"
        assert any(e > f + 2 for e in model), f"axis {i}: the move would have ended before F anyway"
        status = await tb.axis(i).status()
        assert status.err_code == ESTOP_CODE, f"axis {i}: ERR_CODE {status.err_name}"
    raw_enable = int(dut.enable.value)
    assert raw_enable == 0, f"ENABLE pins {raw_enable:03b} during the fault"

    # A SYNC_START during the fault: DONE and ERROR (ESTOP) on every axis, nothing moves.
    counts = [len(r) for r in tb.rises]
    for i, plan in enumerate(plans):
        await tb.axis(i).program(plan)
    await tb.multi.sync_start(range(3))
    await ClockCycles(tb.clk, 5)
    refused = await tb.multi.status()
    assert refused.done == 0b111 and refused.busy == 0, f"SYNC_START during the fault: {refused}"
    for i in range(3):
        assert (await tb.axis(i).status()).err_code == ESTOP_CODE
    await tb.idle(200)
    assert [len(r) for r in tb.rises] == counts, "an axis moved during the fault"

    # ESTOP low: the fault clears (W1C) once the filtered level is low.
    await FallingEdge(tb.clk)
    dut.estop.value = 0
    await ClockCycles(tb.clk, max(filters) + 4)
    fault = 1 << STATUS.field("ESTOP_FAULT").lsb
    for i in range(3):
        await tb.axis(i).access.write(offset("STATUS"), fault | 0x30)
        assert not (await tb.axis(i).access.read(offset("STATUS"))) & fault, f"axis {i}: ESTOP_FAULT not cleared"
    tb.check_pins()


TESTS = [
    "register_windows",
    "sync_start_same_clock",
    "sync_group_is_the_named_axes",
    "axes_status_and_irq",
    "coordinated_move",
    "coordinated_dir_changes",
    "coordinated_soft_stop",
    "coordinated_stop_on_the_line",
    "estop_stops_every_axis",
]


def test_axis_count_is_range_checked(tmp_path: Path) -> None:
    """G_AXES outside 1 .. 8 stops elaboration (and synthesis) with the generic's assertion; 8 elaborates."""
    work = tmp_path / "work"
    assert not analyse("08", work)
    for axes, ok in ((9, False), (8, True)):
        res = subprocess.run(
            ["ghdl", "synth", "--std=08", f"--workdir={work}", f"-gG_AXES={axes}", "--out=none", "stepramp_multi"],
            cwd=work,
            capture_output=True,
            text=True,
            check=False,
        )
        assert (res.returncode == 0) == ok, f"G_AXES = {axes}: ghdl synth exit {res.returncode}"
        assert ("G_AXES must be in 1 .. 8" in res.stderr) != ok, f"G_AXES = {axes}: {res.stderr[-400:]}"


@pytest.mark.parametrize("top", TOPS)
def test_multi_rtl(top: str) -> None:
    """The multi-axis top at 3 axes through each bus: windows, SYNC_START, AXES_STATUS, irq, a coordinated move,
    ESTOP."""
    run_cocotb(
        top,
        "test_multi_rtl",
        build_dir(f"{top}_multi"),
        parameters={"G_AXES": AXES},
        extra_env={"MULTI_AXES": str(AXES)},
        testcase=TESTS,
    )
