# SPDX-License-Identifier: MIT
"""Testbench for the peripheral tops (stepramp_plb, stepramp_axil): clock, reset, a bus master, monitors.

The bus master is stepramp/ipif.py's IpifMaster for the PLB-like top, or cocotbext-axi's AxiLiteMaster (wrapped to the
driver's read/write interface) for the AXI4-Lite top; with `idle` the masters insert idle cycles and, on AXI,
backpressure on every channel. The engine's own start edge (edge 0 of the model) is taken from the rising edge of
the core's (engine's) busy, so step edges are compared with stepramp.models.engine whatever the bus timing and whatever
time the stepping logic holds a start back for DIR setup/hold.
"""

from __future__ import annotations

import itertools
import math
import random
from collections.abc import Iterator
from typing import Any

from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, FallingEdge, First, RisingEdge, Timer

from monitors import MotionMonitors
from stepramp.board.driver import Outputs, Status, StepRamp
from stepramp.board.plan import Plan, plan_move
from stepramp.models.engine import last_edge
from stepramp.sim.ipif import IpifError, IpifMaster
from stepramp.sim.profiles import PROFILES_BY_NAME
from stepramp.sim.stepwatch import StepWatch
from stepramp.sim.waves import LAYOUTS, missing_in, signal_paths
from tbutil import CLK_PERIOD_NS


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


class PeripheralTb:
    """One of the two tops, with its bus master, a STEP monitor and the engine-start monitor."""

    def __init__(self, dut: Any, top: str, idle: bool = False, seed: int = 1) -> None:
        self.dut = dut
        self.top = top
        self.idle = idle
        self.seed = seed
        self.clk = dut.aclk if top == "stepramp_axil" else dut.clk
        Clock(self.clk, CLK_PERIOD_NS, unit="ns").start()
        self.bus: Any = None
        self.pins: StepWatch | None = None
        self.step_edges: list[int] = []  # the pins' records once reset
        self.start_edges: list[int] = []
        self.outputs = Outputs()
        self.enabled = False
        self.monitors: MotionMonitors | None = None

    async def reset(self) -> None:
        if self.top == "stepramp_axil":
            self.dut.aresetn.value = 0
            await ClockCycles(self.clk, 3)
            from cocotbext.axi import AxiLiteBus, AxiLiteMaster

            master = AxiLiteMaster(AxiLiteBus.from_prefix(self.dut, "s_axil"), self.clk, self.dut.aresetn, False)
            self.bus = AxilAccess(master, seed=self.seed if self.idle else None)
            await FallingEdge(self.clk)
            self.dut.aresetn.value = 1
        else:
            self.bus = IpifMaster(self.dut, self.clk, CLK_PERIOD_NS, idle=pauses(self.seed) if self.idle else None)
            self.dut.rst.value = 1
            await ClockCycles(self.clk, 3)
            await FallingEdge(self.clk)
            self.dut.rst.value = 0
        await ClockCycles(self.clk, 2)
        missing = missing_in(self.dut, signal_paths(LAYOUTS[self.top]))
        assert not missing, f"the GTKWave layout names signals {self.top} does not have: {missing}"
        self.pins = StepWatch(self.dut.step, self.dut.core_inst.busy, CLK_PERIOD_NS * 1000)
        self.step_edges, self.start_edges = self.pins.step_edges, self.pins.start_edges
        self._start_monitors(position=0)

    def _start_monitors(self, position: int) -> None:
        """STEP width, DIR setup/hold, shoot-through and electrical position monitors for the current settings."""
        clk = "aclk" if self.top == "stepramp_axil" else "clk"
        self.monitors = MotionMonitors.for_outputs(self.dut, self.outputs, self.enabled, position, names={"clk": clk})

    async def configure(self, outputs: Outputs, enable: bool = True) -> None:
        """Program the stepping outputs (while stopped) and restart the monitors with the new settings."""
        await reconfigure(self, outputs, enable)

    def finish(self) -> None:
        """Stop the monitors and raise if any of them saw a violation (call at the end of every motion test)."""
        if self.monitors is not None:
            self.monitors.stop()
            self.monitors.check()
            self.monitors = None

    def driver(self, plan_args: dict[str, Any] | None = None) -> StepRamp:
        args = plan_args or {"fclk": 1e6, "spr": 200.0, "prescale": 1}
        drv = StepRamp(self.bus, fclk=args["fclk"], spr=args["spr"], prescale=args["prescale"])
        drv.outputs = self.outputs
        return drv

    async def irq_or(self, cycles: int) -> None:
        """Idle between status polls: until irq rises, or at most `cycles` clocks."""
        await First(RisingEdge(self.dut.irq), Timer(cycles * CLK_PERIOD_NS, unit="ns"))

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


async def reconfigure(tb: Any, outputs: Outputs, enable: bool) -> None:
    """A bench's configure (PeripheralTb, tb/test_core.py's CoreTb): stop and check its monitors, program the stepping
    outputs through its driver (while stopped), and restart the monitors with the new settings."""
    tb.finish()
    drv = tb.driver()
    await drv.configure_outputs(outputs)
    await drv.set_enable(enable)
    tb.outputs, tb.enabled = outputs, enable
    # The PWM duty follows a new mode after the serial multipliers (stepramp.models.stepping.winding_latency, < 40
    # clocks): let the outputs settle before the monitors look at them.
    await ClockCycles(tb.clk, 100)
    tb._start_monitors(position=await drv.position())


def profiles_limit_us(names: list[str]) -> int:
    """Sim-time limit for playing these profiles back to back: twice their model last edges plus 2000 clocks each
    (bus accesses, DIR setup), plus 100 us for reset and configuration."""
    cycles = sum((last_edge(plan_move(**PROFILES_BY_NAME[name].args())) or 0) + 2000 for name in names)
    return math.ceil(2 * cycles * CLK_PERIOD_NS / 1000) + 100


__all__ = ["AxilAccess", "AxilError", "BusError", "PeripheralTb", "pauses", "profiles_limit_us", "reconfigure"]
