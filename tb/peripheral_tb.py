# SPDX-License-Identifier: MIT
"""Testbench for the peripheral tops (stepramp_plb, stepramp_axil): clock, reset, a bus master, monitors.

What differs between the tops is in one small BusPort class per top (PORTS): IpifPort (clk, rst, stepramp.sim.ipif's
IpifMaster) for the PLB-like top, AxilPort (aclk, aresetn, cocotbext-axi's AxiLiteMaster wrapped to the driver's
read/write interface by AxilAccess) for the AXI4-Lite top; with `idle` the masters insert idle cycles and, on AXI,
backpressure on every channel. The engine's own start edge (edge 0 of the model) is taken from the rising edge of
the core's (engine's) busy, so step edges are compared with stepramp.models.engine whatever the bus timing and whatever
time the stepping logic holds a start back for DIR setup/hold.
"""

from __future__ import annotations

import itertools
import math
import os
import random
from collections.abc import Iterator
from typing import Any

import cocotb
from cocotb.triggers import ClockCycles, FallingEdge, First, RisingEdge, Timer

from stepramp.board.driver import Outputs, Status, StepRamp, StepRampError
from stepramp.board.plan import Plan, plan_move
from stepramp.board.regmap import ERROR_CODES
from stepramp.models.engine import edges as edges_of
from stepramp.models.engine import edges_with_stop, last_edge
from stepramp.sim.clocking import (
    CLK_PERIOD_NS,
    CLK_PERIOD_PS,
    Cycles,
    apply_reset,
    quiet_inputs,
    reset_held,
    start_clock,
)
from stepramp.sim.coverage import watch_coverage
from stepramp.sim.ipif import IpifError, IpifMaster
from stepramp.sim.monitors import MotionMonitors
from stepramp.sim.profiles import PROFILES_BY_NAME
from stepramp.sim.stepwatch import StepWatch
from stepramp.sim.waves import LAYOUTS, missing_in, signal_paths
from tbutil import edges_differ, env_int


class AxilError(Exception):
    """The AXI4-Lite slave answered SLVERR (or DECERR)."""


class AxilAccess:
    """The driver's register access over cocotbext-axi's AxiLiteMaster (strobes as runs of byte writes).

    With `seed`, every channel gets random idle / backpressure cycles while an access is in flight (the pause
    generators run a coroutine per clock, so they are switched off between accesses: long moves stay fast).
    """

    def __init__(self, master: Any, seed: int | None = None) -> None:
        self.master = master
        self.seed = seed
        self.in_flight = 0
        self.channels = [
            master.write_if.aw_channel,
            master.write_if.w_channel,
            master.write_if.b_channel,
            master.read_if.ar_channel,
            master.read_if.r_channel,
        ]

    def _pauses(self, on: bool) -> None:
        if self.seed is None:
            return
        self.in_flight += 1 if on else -1
        if on and self.in_flight == 1:
            for i, ch in enumerate(self.channels):
                ch.set_pause_generator(pauses(self.seed + i))
        elif not on and self.in_flight == 0:
            for ch in self.channels:
                ch.set_pause_generator(None)

    async def read(self, addr: int) -> int:
        self._pauses(True)
        try:
            resp = await self.master.read(addr, 4)
        finally:
            self._pauses(False)
        if int(resp.resp) != 0:
            raise AxilError(f"read {addr:#x}: resp {int(resp.resp)}")
        return int.from_bytes(resp.data, "little")

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None:
        data = (value & 0xFFFF_FFFF).to_bytes(4, "little")
        lanes = [b for b in range(4) if strobe >> b & 1]
        # Contiguous runs of enabled lanes, each one AXI write with the matching WSTRB.
        runs: list[list[int]] = []
        for b in lanes:
            if runs and runs[-1][-1] == b - 1:
                runs[-1].append(b)
            else:
                runs.append([b])
        for run in runs:
            self._pauses(True)
            try:
                resp = await self.master.write(addr + run[0], data[run[0] : run[-1] + 1])
            finally:
                self._pauses(False)
            if int(resp.resp) != 0:
                raise AxilError(f"write {addr:#x}: resp {int(resp.resp)}")


BusError = (IpifError, AxilError)


def pauses(seed: int) -> Iterator[int]:
    """A reproducible pause pattern: 1 = idle / not ready this cycle."""
    rng = random.Random(seed)
    return itertools.cycle([int(rng.random() < 0.35) for _ in range(97)])


class BusPort:
    """A top's side of the bench: its clock, its reset and the bus master the driver talks through."""

    clk_name = "clk"
    rst_name = "rst"
    rst_active = 1

    def __init__(self, dut: Any, idle_seed: int | None) -> None:
        self.dut = dut
        self.clk = getattr(dut, self.clk_name)
        self.rst = getattr(dut, self.rst_name)
        self.idle_seed = idle_seed  # None: no idle cycles, no backpressure

    async def reset(self) -> Any:
        """Reset the top (the clock runs) and return its bus master, ready once the reset is released."""
        raise NotImplementedError


class IpifPort(BusPort):
    """stepramp_plb: clk, rst (active high) and stepramp.sim.ipif's IpifMaster, idle cycles between accesses from
    `pauses` when given a seed."""

    async def reset(self) -> IpifMaster:
        """The master (driving an idle bus from now on), then the reset."""
        idle = None if self.idle_seed is None else pauses(self.idle_seed)
        master = IpifMaster(self.dut, self.clk, CLK_PERIOD_NS, idle=idle)
        await apply_reset(self.clk, self.rst)
        return master


class AxilPort(BusPort):
    """stepramp_axil: aclk, aresetn (active low) and cocotbext-axi's AxiLiteMaster behind AxilAccess, idle cycles and
    backpressure on every channel when given a seed."""

    clk_name = "aclk"
    rst_name = "aresetn"
    rst_active = 0

    async def reset(self) -> AxilAccess:
        """The reset, with the master created while it is held (so it starts out of reset)."""
        from cocotbext.axi import AxiLiteBus, AxiLiteMaster

        async with reset_held(self.clk, self.rst, active=self.rst_active):
            master = AxiLiteMaster(AxiLiteBus.from_prefix(self.dut, "s_axil"), self.clk, self.rst, False)
        return AxilAccess(master, seed=self.idle_seed)


#: The bench's side of each top, by the top's name.
PORTS: dict[str, type[BusPort]] = {"stepramp_plb": IpifPort, "stepramp_axil": AxilPort}
TOPS = tuple(PORTS)


class MotionBench:
    """What the benches that program a core with the driver share (PeripheralTb; tb/test_core.py's CoreTb): a driver
    over the bench's register access `bus`, the wait for irq, and the stepping configuration with the motion monitors
    (which each bench starts in its _start_monitors and stops and checks in its finish)."""

    dut: Any
    clk: Any
    bus: Any
    outputs: Outputs
    enabled: bool
    # The electrical position the pins have shown since the last reset: +1 per STEP rising edge with DIR '0', -1 with
    # DIR '1' (docs/algorithm.md "Electrical position": a POSITION write does not move it).
    elec_pos: int = 0
    _counting: bool = False
    pins: StepWatch | None = None

    def _start_monitors(self, position: int) -> None:
        raise NotImplementedError

    def count_steps(self) -> None:
        """Count the electrical position from the pins from now on (at reset: elec_pos = 0); once per bench, after
        its StepWatch (`pins`) is made: counted at each STEP rising edge the StepWatch records."""
        self.elec_pos = 0
        if not self._counting:
            self._counting = True
            assert self.pins is not None, "count_steps: the bench's StepWatch first"
            self.pins.on_step.append(self._count_step)

    def _count_step(self) -> None:
        self.elec_pos += -1 if int(self.dut.dir.value) else 1

    def finish(self) -> None:
        raise NotImplementedError

    def driver(self, plan_args: dict[str, Any] | None = None, ramp: int = 0) -> StepRamp:
        """The driver for a clock and motor (plan_args: fclk, spr, prescale; default 1 MHz, 200 steps/rev, 1) and the
        core's ramp arithmetic (G_RAMP)."""
        args = plan_args or {"fclk": 1e6, "spr": 200.0, "prescale": 1}
        drv = StepRamp(self.bus, fclk=args["fclk"], spr=args["spr"], prescale=args["prescale"], ramp=ramp)
        drv.outputs = self.outputs
        return drv

    async def irq_or(self, cycles: int) -> None:
        """Idle between status polls: until irq rises, or at most `cycles` clocks."""
        await First(RisingEdge(self.dut.irq), Timer(cycles * CLK_PERIOD_NS, unit="ns"))

    async def configure(self, outputs: Outputs, enable: bool = True) -> None:
        """Stop and check the monitors, program the stepping outputs through the driver (while stopped), and restart
        the monitors with the new settings."""
        self.finish()
        drv = self.driver()
        await drv.configure_outputs(outputs)
        await drv.set_enable(enable)
        self.outputs, self.enabled = outputs, enable
        # The PWM duty follows a new mode after the serial multipliers (stepramp.models.stepping.winding_latency, < 40
        # clocks): let the outputs settle before the monitors look at them.
        await Cycles(self.clk, 100)
        self._start_monitors(position=self.elec_pos)


class PeripheralTb(MotionBench):
    """One of the two tops, with its bus master, a STEP monitor and the engine-start monitor."""

    def __init__(self, dut: Any, top: str, idle: bool = False, seed: int = 1) -> None:
        self.dut = dut
        self.top = top
        self.port = PORTS[top](dut, seed if idle else None)
        self.clk = self.port.clk
        start_clock(self.clk)
        quiet_inputs(dut)
        self.bus: Any = None
        self.pins: StepWatch | None = None
        self.step_edges: list[int] = []  # the pins' records once reset
        self.start_edges: list[int] = []
        self.outputs = Outputs()
        self.enabled = False
        self.monitors: MotionMonitors | None = None

    @classmethod
    async def started(cls, dut: Any, idle: bool = False) -> PeripheralTb:
        """The bench of the top under test (dut._name), reset; idle cycles from the seed in BUS_SEED (1)."""
        tb = cls(dut, dut._name, idle=idle, seed=env_int("BUS_SEED", 1))
        await tb.reset()
        tb.bus = watch_coverage(dut.core_inst, tb.bus)
        return tb

    async def reset(self) -> None:
        self.bus = await self.port.reset()
        await ClockCycles(self.clk, 2)
        # The waveform layout names RTL signals; a netlist (STEPRAMP_NETLIST) keeps only some of them.
        missing = [] if os.environ.get("STEPRAMP_NETLIST") else missing_in(self.dut, signal_paths(LAYOUTS[self.top]))
        assert not missing, f"the GTKWave layout names signals {self.top} does not have: {missing}"
        self.pins = StepWatch(self.dut.step, self.dut.core_inst.busy, CLK_PERIOD_PS)
        self.step_edges, self.start_edges = self.pins.step_edges, self.pins.start_edges
        self.count_steps()
        self._start_monitors(position=0)

    async def reset_pulse(self) -> None:
        """The top's reset again (rst, or aresetn low), as at the start, from the next falling edge."""
        await FallingEdge(self.clk)
        await apply_reset(self.clk, self.port.rst, active=self.port.rst_active)
        self.elec_pos = 0

    def _start_monitors(self, position: int) -> None:
        """STEP width, DIR setup/hold, shoot-through and electrical position monitors for the current settings."""
        self.monitors = MotionMonitors.for_outputs(
            self.dut, self.outputs, self.enabled, position, names={"clk": self.port.clk_name}
        )

    def finish(self) -> None:
        """Stop the monitors and raise if any of them saw a violation (call at the end of every motion test)."""
        if self.monitors is not None:
            self.monitors.stop()
            self.monitors.check()
            self.monitors = None

    def watch_stops(self) -> dict[str, list[int]]:
        """The clock edges at which the register file raises its soft_stop and hard_stop strobes, from now on (the
        engine samples a strobe at the edge after)."""
        assert self.pins is not None, "reset() first"
        edges: dict[str, list[int]] = {"soft": [], "hard": []}
        for kind, seen in edges.items():
            cocotb.start_soon(self.pins.watch(getattr(self.dut.core_inst, f"{kind}_stop"), seen))
        return edges

    async def stop_after(
        self, drv: StepRamp, stop_edges: dict[str, list[int]], kind: str, pulses: int, phase: str, start: Any
    ) -> tuple[list[int], int, Any]:
        """Start a move (`start`: a coroutine function, its result returned last), wait for `pulses` STEP pulses, check
        that the engine is in `phase`, then SOFT_STOP or HARD_STOP (`kind`) and wait for done. Returns the move's
        edges, the edge of the move's numbering at which the engine sampled the stop (stop_edges: watch_stops), and
        what `start` returned."""
        n0, s0, k0 = len(self.step_edges), len(self.start_edges), len(stop_edges[kind])
        started = await start()
        while len(self.step_edges) < n0 + pulses:
            await RisingEdge(self.dut.step)
        assert (await drv.status()).state == phase, f"{kind} stop: not in {phase} after {pulses} pulses"
        await (drv.soft_stop() if kind == "soft" else drv.hard_stop())
        await drv.wait_done(idle=lambda: self.irq_or(5_000))
        # The register file's strobe is high after edge w; the engine samples it at w + 1.
        request = stop_edges[kind][k0] + 1 - self.start_edges[s0]
        return self.edges_since(n0, s0), request, started

    def edges_since(self, first_step: int, first_start: int) -> list[int]:
        """STEP pin edges of a move in the model's convention (stepramp.sim.stepwatch.StepWatch.since)."""
        assert self.pins is not None, "reset() first"
        return self.pins.since(first_step, first_start)

    async def run_plan(self, drv: StepRamp, plan: Plan) -> tuple[list[int], Status]:
        """Program, start, wait for done (interrupt-driven); step edges counted from the engine's start edge."""
        await drv.program(plan)
        n_steps, n_starts = len(self.step_edges), len(self.start_edges)
        await drv.start()
        status = await drv.wait_done(idle=lambda: self.irq_or(20_000))
        return self.edges_since(n_steps, n_starts), status


def check_stopped(plan: Plan, kind: str, phase: str, request: int, edges: list[int], wait_pulses: int) -> None:
    """A move stopped through CTRL, SOFT_STOP or HARD_STOP (`kind`) sampled by the engine at edge `request` of the
    move, `wait_pulses` pulses into it, in `phase`: every edge as stepramp.models.engine.edges_with_stop says; no pulse
    at or after a hard stop; a soft stop changes nothing in DECEL, and in ACCEL or RUN ends the move early on a decel
    ramp (the speed never rises after the pulse that decides it, the last interval is at the slow end: the plan's
    c_last)."""
    what = f"{kind} stop in {phase}"
    want = edges_with_stop(plan, kind, request)
    assert edges == want, f"{what}: {edges_differ(edges, want)}"
    normal = edges_of(plan)
    if kind == "hard":
        assert all(e < request for e in edges) and len(edges) < len(normal), f"{what}: a pulse at or after it"
    elif phase == "DECEL":
        assert edges == normal, f"{what}: changes the move"
    else:
        assert len(edges) < len(normal), f"{what}: does not end the move early"
        # the request comes before pulse wait_pulses (q), the stop is decided at pulse q + 1 (docs/algorithm.md)
        tail = [b - a for a, b in itertools.pairwise(edges[wait_pulses + 1 :])]
        slow_end = (plan.c_last >> 16) * plan.prescale
        assert tail[-1] >= 0.95 * slow_end, f"{what}: last interval {tail[-1]}, not at the slow end {slow_end}"
        assert all(b >= a - plan.prescale for a, b in itertools.pairwise(tail)), f"{what}: the speed rose"


def stop_cases(pulses: tuple[int, int, int]) -> list[tuple[str, int, str]]:
    """(kind, pulses to wait before the command, the phase it then lands in): a soft and a hard stop after each of
    `pulses`, pulse counts that land in ACCEL, RUN and DECEL of the move."""
    return [
        (kind, wait, phase)
        for kind in ("soft", "hard")
        for wait, phase in zip(pulses, ("ACCEL", "RUN", "DECEL"), strict=True)
    ]


def profiles_limit_us(names: list[str]) -> int:
    """Sim-time limit for playing these profiles back to back: twice their model last edges plus 2000 clocks each
    (bus accesses, DIR setup), plus 100 us for reset and configuration."""
    cycles = sum((last_edge(plan_move(**PROFILES_BY_NAME[name].args())) or 0) + 2000 for name in names)
    return math.ceil(2 * cycles * CLK_PERIOD_NS / 1000) + 100


#: Register corruptions of a valid plan and the error each must give (no motion, no hang).
BAD_VALUES: list[tuple[str, dict[str, int], str]] = [
    ("zero prescale", {"prescale": 0}, "PRESCALE"),
    ("zero c_first", {"c_first": 0}, "C_FIRST"),
    ("c_first below one tick", {"c_first": 0xFFFF}, "C_FIRST"),
    ("zero c_last", {"c_last": 0}, "C_LAST"),
    ("zero accel seed", {"accel_seed": 0}, "ACCEL_SEED"),
    ("zero cruise", {"cruise": 0}, "CRUISE"),
    ("cruise below one tick", {"cruise": 0xFFFF_FFFF}, "CRUISE"),
    ("zero decel seed", {"decel_seed": 0}, "DECEL_SEED"),
    ("all-ones sa", {"sa": 0x7FFF_FFFF}, "BOUNDS"),
    ("all-ones sd", {"sd": 0x7FFF_FFFF}, "BOUNDS"),
    ("sa after sd", {"sa": 150, "sd": 20}, "BOUNDS"),
    ("zero sa", {"sa": 0}, "BOUNDS"),
]


async def expect_rejected(tb: PeripheralTb, drv: StepRamp, plan: Plan, label: str, cause: str) -> None:
    """START a plan with a bad value: the core must answer with ERROR and error code `cause`, DONE, no STEP pulse."""
    code = ERROR_CODES[cause][0]
    await drv.program(plan)
    before = len(tb.step_edges)
    await drv.start()
    try:
        await drv.wait_done(idle=lambda: ClockCycles(tb.clk, 5), polls=200)
    except StepRampError:
        pass
    else:
        raise AssertionError(f"{label}: no error")
    status = await drv.status()
    assert status.err_code == code, f"{label}: error {status.err_name}, expected {cause} ({code})"
    assert len(tb.step_edges) == before, f"{label}: the core moved"


__all__ = [
    "BAD_VALUES",
    "PORTS",
    "TOPS",
    "AxilAccess",
    "AxilError",
    "AxilPort",
    "BusError",
    "BusPort",
    "IpifPort",
    "MotionBench",
    "PeripheralTb",
    "check_stopped",
    "expect_rejected",
    "pauses",
    "profiles_limit_us",
    "stop_cases",
]
