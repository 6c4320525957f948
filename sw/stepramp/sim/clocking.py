# SPDX-License-Identifier: MIT
"""Inside a simulation (cocotb): the clock and reset every bench starts with, and simulated time in clock edges.

One place for the timing every bench shares, so that the step edges they compare with the bit-exact model count from
the same clock: the benches' clock period, starting a clock, a synchronous reset held for a number of rising edges and
released at the falling edge after them (the inputs change away from the edges that sample them), and the index of
the most recent rising edge of a clock started at time 0. Used by the testbenches in tb/, `stepramp.sim.engine_bench`,
`stepramp.sim.session` and `stepramp.sim.stepwatch`.
"""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator
from typing import Any

from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge, Timer
from cocotb.utils import get_sim_time

#: The benches' clock period (100 MHz); the session and the demo run the clock the driver is given instead.
CLK_PERIOD_NS = 10
CLK_PERIOD_PS = CLK_PERIOD_NS * 1000

#: Rising edges a reset is held for.
RESET_CYCLES = 3


def start_clock(clk: Any, period_ps: int = CLK_PERIOD_PS) -> None:
    """Start a clock on clk (cocotb's GPI clock): a rising edge now, then one every period_ps."""
    Clock(clk, period_ps, unit="ps").start()


@contextlib.asynccontextmanager
async def reset_held(clk: Any, rst: Any, *, active: int = 1, cycles: int = RESET_CYCLES) -> AsyncIterator[None]:
    """Drive rst to `active` and wait `cycles` rising edges of clk; the body runs there, with the reset still on;
    then release rst at the next falling edge."""
    rst.value = active
    await ClockCycles(clk, cycles)
    yield
    await FallingEdge(clk)
    rst.value = 1 - active


async def apply_reset(clk: Any, rst: Any, *, active: int = 1, cycles: int = RESET_CYCLES, settle: int = 0) -> None:
    """Hold rst at `active` for `cycles` rising edges, release it at the falling edge after them, then wait `settle`
    rising edges."""
    async with reset_held(clk, rst, active=active, cycles=cycles):
        pass
    if settle:
        await ClockCycles(clk, settle)


async def start_clock_and_reset(
    clk: Any, rst: Any, *, period_ps: int = CLK_PERIOD_PS, cycles: int = RESET_CYCLES, settle: int = 0
) -> None:
    """start_clock, then apply_reset (active high); the caller drives the other inputs."""
    start_clock(clk, period_ps)
    await apply_reset(clk, rst, cycles=cycles, settle=settle)


#: The machine inputs of the tops and of stepramp_core (and the core's multi-axis start), held at 0 unless a test
#: drives them: an undriven top-level input would read 'U'.
QUIET_INPUTS = ("limit_neg", "limit_pos", "home", "estop", "sync_start", "sync_soft_stop", "sync_hold")


def quiet_inputs(dut: Any) -> None:
    """Drive every machine input a top has (QUIET_INPUTS) to 0."""
    for name in QUIET_INPUTS:
        try:
            handle = getattr(dut, name)
        except AttributeError:
            continue
        handle.value = 0


async def cycles(clk: Any, n: int, period_ps: int = CLK_PERIOD_PS) -> None:
    """Return just after the n-th rising edge of clk from now, as `await ClockCycles(clk, n)` does, but waking the
    simulation's Python three times instead of n: the first edge, a Timer to the middle of the cycle before the n-th,
    then the n-th edge. For a clock of period period_ps that keeps running (start_clock's)."""
    if n <= 3:
        await ClockCycles(clk, n)
        return
    await RisingEdge(clk)
    await Timer((n - 2) * period_ps + period_ps // 2, unit="ps")
    await RisingEdge(clk)


class Cycles(ClockCycles):
    """ClockCycles(clk, n) (rising edges) that waits as `cycles` does: a Trigger-like awaitable that First() takes too.
    For a clock of period period_ps that keeps running (start_clock's)."""

    def __init__(self, clk: Any, n: int, period_ps: int = CLK_PERIOD_PS) -> None:
        super().__init__(clk, n)
        self.period_ps = period_ps

    async def _wait(self) -> Cycles:
        await cycles(self.signal, self.num_cycles, self.period_ps)
        return self


def now_periods(period_ps: float = CLK_PERIOD_PS) -> float:
    """Simulation time in clock periods, not rounded (rising edge e of a clock started at time 0 is at e.0)."""
    return get_sim_time("ps") / period_ps


def now_cycles(period_ps: float = CLK_PERIOD_PS) -> int:
    """Simulation time in clock periods, rounded: the index of the nearest rising edge of a clock started at time 0
    (the most recent one, at that edge's own time step and in the first half of the cycle after it)."""
    return round(now_periods(period_ps))


__all__ = [
    "CLK_PERIOD_NS",
    "CLK_PERIOD_PS",
    "QUIET_INPUTS",
    "RESET_CYCLES",
    "Cycles",
    "apply_reset",
    "cycles",
    "now_cycles",
    "now_periods",
    "quiet_inputs",
    "reset_held",
    "start_clock",
    "start_clock_and_reset",
]
