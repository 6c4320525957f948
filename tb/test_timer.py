# SPDX-License-Identifier: MIT
"""stepramp_timer: tick spacing for several PRESCALE values, a PRESCALE change while running, restart, and long
periods across the counter's width (G_WIDTH 5, 16 and 32).

The tick is sampled once per clock (these runs are a few thousand cycles long) and every edge after which it
is '1' is compared with the model's list.
"""

from __future__ import annotations

import pytest
from cocotb.triggers import ClockCycles, FallingEdge, First, ReadOnly, RisingEdge, Timer
from cocotb.utils import get_sim_time

from stepramp.models.blocks import timer_ticks
from stepramp.sim.clocking import Cycles, cycles
from stepramp.sim.runner import run_cocotb
from tbutil import build_dir, cocotb, now_cycles, start_clock_and_reset


async def pulse_restart(dut) -> int:
    """Pulse restart for one edge (from a falling edge to the next); returns that edge."""
    await FallingEdge(dut.clk)
    dut.restart.value = 1
    await RisingEdge(dut.clk)
    edge = now_cycles()
    await FallingEdge(dut.clk)
    dut.restart.value = 0
    return edge


async def record_ticks(dut, cycles: int, changes: dict[int, int] | None = None) -> tuple[int, list[int]]:
    """Pulse restart, then watch `cycles` edges; changes maps an edge offset to a new prescale value.

    Returns the restart edge and the edges after which tick was '1' (the restart edge included).
    """
    changes = changes or {}
    restart_edge = await pulse_restart(dut)
    # The restart edge itself is watched too: a restart is never a tick.
    ticks: list[int] = [restart_edge] if int(dut.tick.value) == 1 else []
    for offset in range(1, cycles + 1):
        if offset in changes:
            dut.prescale.value = changes[offset]  # sampled from edge restart + offset on
        await RisingEdge(dut.clk)
        await FallingEdge(dut.clk)
        if int(dut.tick.value) == 1:
            ticks.append(restart_edge + offset)
    return restart_edge, ticks


@cocotb.test(timeout_time=120, timeout_unit="us")  # measured 28 us
async def timer_spacing(dut) -> None:
    """For each PRESCALE: ticks at restart + P, + 2P, ... and nowhere else."""
    dut.restart.value = 0
    dut.prescale.value = 1
    await start_clock_and_reset(dut.clk, dut.rst)
    for prescale in (1, 2, 3, 7, 16, 100, 0):
        dut.prescale.value = prescale
        restart, ticks = await record_ticks(dut, 400)
        expected = timer_ticks([(restart, prescale)], restart, 400)
        assert ticks == expected, f"prescale {prescale}: ticks {ticks[:10]}..., expected {expected[:10]}..."
        assert len(ticks) == 400 // max(prescale, 1)


@cocotb.test(timeout_time=40, timeout_unit="us")  # measured 8.1 us
async def timer_prescale_change(dut) -> None:
    """A new PRESCALE takes effect at the next tick: the running period ends with the old value."""
    dut.restart.value = 0
    dut.prescale.value = 10
    await start_clock_and_reset(dut.clk, dut.rst)
    for change_at, old, new in ((25, 10, 3), (31, 3, 17), (5, 1, 4), (40, 8, 1)):
        dut.prescale.value = old
        restart, ticks = await record_ticks(dut, 200, {change_at: new})
        expected = timer_ticks([(restart, old), (restart + change_at, new)], restart, 200)
        assert ticks == expected, f"{old}->{new} at +{change_at}: {ticks[:12]} vs {expected[:12]}"


@cocotb.test(timeout_time=40, timeout_unit="us")  # measured 8.4 us
async def timer_restart_realigns(dut) -> None:
    """A restart in the middle of a period drops that period: the next tick is P clocks after the restart."""
    dut.restart.value = 0
    dut.prescale.value = 9
    await start_clock_and_reset(dut.clk, dut.rst)
    for skew in range(12):
        await record_ticks(dut, skew)  # leave the counter somewhere inside a period
        restart, ticks = await record_ticks(dut, 60)
        assert ticks == [restart + 9 * k for k in range(1, 7)], f"skew {skew}: {ticks}"


def long_periods(width: int) -> tuple[int, ...]:
    """PRESCALE values for timer_long_periods: above 16 bits, those whose down-count crosses from the low 16 bits
    into the bits above (reload 2^16 - 1, 2^16, 2^16 + 1, 2^17, ...); at 16 bits or fewer, the largest values."""
    if width > 16:
        return (65535, 65536, 65537, 65538, 70001, 131072, 131073)
    top = (1 << width) - 1
    return (top, top - 1, 3)


@cocotb.test(timeout_time=30, timeout_unit="ms")  # measured 12 ms at G_WIDTH 32
async def timer_long_periods(dut) -> None:
    """The counter's whole width (G_WIDTH from the port): for each PRESCALE of long_periods, the first two ticks after
    a restart at restart + P and + 2P, stamped at the tick's own rising edges (a tick any earlier fails)."""
    width = len(dut.prescale)
    dut.restart.value = 0
    dut.prescale.value = 3
    await start_clock_and_reset(dut.clk, dut.rst)
    for prescale in long_periods(width):
        dut.prescale.value = prescale
        at = await pulse_restart(dut)
        ticks = []
        for _ in range(2):
            await RisingEdge(dut.tick)
            ticks.append(now_cycles())
            await FallingEdge(dut.tick)
        assert ticks == timer_ticks([(at, prescale)], at, 2 * prescale), (
            f"G_WIDTH {width}, prescale {prescale}: ticks at restart + {[t - at for t in ticks]}"
        )


@cocotb.test(timeout_time=200, timeout_unit="us")  # measured 47 us
async def bench_cycles_is_clock_cycles(dut) -> None:
    """The benches' fast waits stepramp.sim.clocking.cycles(clk, n) and Cycles(clk, n) (alone and inside First) end
    at the same time as cocotb's ClockCycles(clk, n) started at the same moment, whatever the phase they are called
    in (at a rising or a falling edge, in ReadOnly, between edges) and whatever n."""
    dut.restart.value = 0
    dut.prescale.value = 1
    await start_clock_and_reset(dut.clk, dut.rst)

    async def ends(wait) -> int:
        await wait
        return get_sim_time("ps")

    phases = {
        "rising edge": lambda: RisingEdge(dut.clk),
        "falling edge": lambda: FallingEdge(dut.clk),
        "read-only": lambda: ReadOnly(),
        "3 ns after a falling edge": lambda: Timer(3, unit="ns"),
    }
    for phase, reach in phases.items():
        for n in (1, 2, 3, 4, 5, 17, 200, 1001):
            await FallingEdge(dut.clk)
            await reach()
            waits = {
                "cycles": cycles(dut.clk, n),
                "Cycles": Cycles(dut.clk, n),
                "First(Cycles, restart)": First(Cycles(dut.clk, n), RisingEdge(dut.restart)),
            }
            mine = {name: cocotb.start_soon(ends(w)) for name, w in waits.items()}
            want = await cocotb.start_soon(ends(ClockCycles(dut.clk, n)))
            for name, task in mine.items():
                got = await task
                assert got == want, f"{name}(clk, {n}) from the {phase}: ends at {got} ps, ClockCycles at {want} ps"


def test_timer() -> None:
    run_cocotb("stepramp_timer", "test_timer", build_dir("timer"), parameters={"G_WIDTH": 16})


@pytest.mark.parametrize("width", [5, 32])
def test_timer_widths(width: int) -> None:
    """The counter at a narrow width and at the widest (its 16-bit parts): timer_long_periods."""
    run_cocotb(
        "stepramp_timer",
        "test_timer",
        build_dir(f"timer_{width}"),
        parameters={"G_WIDTH": width},
        testcase="timer_long_periods",
    )
