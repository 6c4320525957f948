# SPDX-License-Identifier: MIT
"""The cocotb side of `make bench`'s simulation speed (stepramp.tools.simbench): one move on a top, timed.

Not a test module of the regression (no test_ prefix): it measures. Each run plays one long move on the top it is
started on, with the regression's own bench for that top, everything on as in the tests:

* stepramp_engine: stepramp.sim.engine_bench's player (the engine's inputs driven, every STEP edge stamped);
* stepramp_plb, stepramp_axil: tb/peripheral_tb.py's PeripheralTb (its bus master, the driver, the STEP / DIR /
  winding monitors, the step counter), the move programmed from physical units and waited for on irq;
* stepramp_multi_plb, stepramp_multi_axil: tb/test_multi_rtl.py's MultiTb, the same move on its three axes from one
  SYNC_START (every axis's pins recorded).

Wall time (perf_counter) and the simulator process's CPU time (process_time: the simulation and the Python in it,
not the other processes of a loaded machine) are taken from the start of the move to its end; simulated clocks from
the simulated time. The edges are compared with the model's, so a figure is only printed for a move that ran right.
Writes {"top", "clocks", "wall_s", "cpu_s", "steps"} as JSON to $STEPRAMP_SPEED_RESULT.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time
from pathlib import Path
from typing import Any

import cocotb
from cocotb.utils import get_sim_time

from stepramp.board.driver import Outputs
from stepramp.board.plan import plan_move
from stepramp.models.engine import edges as model_edges
from stepramp.sim.clocking import CLK_PERIOD_NS
from stepramp.sim.profiles import EXACT_PROFILES, PROFILES_BY_NAME
from tbutil import edges_differ

#: The move every bench plays (about 90,000 clocks: 1,200 steps with a long cruise).
PROFILE = os.environ.get("SPEED_PROFILE", "trap_long_cruise")
#: The ramp arithmetic (G_RAMP of the engine and the bus tops: 0 AVR446, 1 exact: the move of EXACT_PROFILES, the same
#: ticks at 4 times the clock and PRESCALE, as the exact tests play it).
RAMP = int(os.environ.get("SPEED_RAMP", "0"))
MOVE = {p.name: p for p in EXACT_PROFILES}[PROFILE] if RAMP else PROFILES_BY_NAME[PROFILE]


class _Clock:
    """Wall and CPU time and simulated clocks from construction to stop()."""

    def __init__(self) -> None:
        self.sim0 = get_sim_time("ns")
        self.wall0, self.cpu0 = time.perf_counter(), time.process_time()

    def stop(self, top: str, steps: int) -> None:
        result = {
            "top": top,
            "clocks": round((get_sim_time("ns") - self.sim0) / CLK_PERIOD_NS),
            "wall_s": time.perf_counter() - self.wall0,
            "cpu_s": time.process_time() - self.cpu0,
            "steps": steps,
        }
        Path(os.environ["STEPRAMP_SPEED_RESULT"]).write_text(json.dumps(result))


async def _engine(dut: Any) -> None:
    from stepramp.sim import coverage
    from stepramp.sim.clocking import start_clock_and_reset
    from stepramp.sim.engine_bench import INPUTS, SEGMENT_INPUTS, _play
    from stepramp.sim.engine_sim import timeout_cycles

    plan = plan_move(**MOVE.args(), ramp=RAMP)
    for name in ("start", "load", "soft_stop", "hard_stop", "change", "change_at", "pos_load", "pos_value"):
        getattr(dut, name).value = 0
    for name in (*INPUTS, *SEGMENT_INPUTS):
        getattr(dut, name).value = 0
    dut.min_gap.value = 2
    await start_clock_and_reset(dut.clk, dut.rst, settle=2)
    coverage.watch_engine(dut)
    clock = _Clock()
    result = await _play(dut, {"registers": dataclasses.asdict(plan), "timeout_cycles": timeout_cycles(plan)})
    clock.stop(dut._name, len(result["edges"]))
    assert result["edges"] == model_edges(plan), edges_differ(result["edges"], model_edges(plan))


async def _bus_top(dut: Any) -> None:
    from peripheral_tb import PeripheralTb

    prof = MOVE
    tb = await PeripheralTb.started(dut)
    await tb.configure(Outputs(mode="half", step_width=5, dir_setup=20, dir_hold=10), enable=True)
    await tb.driver().enable_irq(done=True, error=True)
    drv = tb.driver(prof.args(), ramp=RAMP)
    plan = drv.plan(prof.steps, prof.accel, prof.decel, prof.speed)
    clock = _Clock()
    edges, status = await tb.run_plan(drv, plan)
    clock.stop(dut._name, len(edges))
    assert edges == model_edges(plan), edges_differ(edges, model_edges(plan))
    assert not status.error
    tb.finish()


async def _multi_top(dut: Any) -> None:
    from test_multi_rtl import MultiTb

    prof = MOVE
    tb = await MultiTb.started(dut, fclk=prof.fclk, prescale=prof.prescale)
    await tb.configure()
    plans = [plan_move(**prof.args()) for _ in range(tb.axes)]
    clock = _Clock()
    await tb.multi.program_sync(plans)
    w = tb.write_edges[-1]
    await tb.multi.wait_done(range(tb.axes), idle=lambda: tb.idle(1000))
    clock.stop(dut._name, sum(len(r) for r in tb.rises))
    _, wants = tb.expected_sync(plans, w)
    for i in range(tb.axes):
        assert tb.rises[i] == wants[i], f"axis {i}: {edges_differ(tb.rises[i], wants[i])}"
    tb.check_pins()


@cocotb.test(timeout_time=20, timeout_unit="ms")
async def speed_of_a_move(dut) -> None:
    """Play one move on the top, timed (see the module's docstring)."""
    top = dut._name
    if top == "stepramp_engine":
        await _engine(dut)
    elif top.startswith("stepramp_multi"):
        await _multi_top(dut)
    else:
        await _bus_top(dut)
