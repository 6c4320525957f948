# SPDX-License-Identifier: MIT
"""The exact ramp (G_RAMP = 1, docs/algorithm.md "Exact step times") through both bus tops, against the model.

Every expected edge comes from stepramp.models.engine (plans whose ramp is RAMP_EXACT), whose arithmetic
sw/tests/test_exact.py holds within 1 tick of the ideal; the driver (stepramp.board.driver.StepRamp with
ramp=RAMP_EXACT) programs the core as MicroBlaze would.

* test_exact_profiles: the 64 profiles (EXACT_PROFILES: the same ticks at 1 to 4 times the clock and PRESCALE), three
  chunks per top, each with other stepping outputs and (chunks 1 and 2) bus idle cycles: every STEP edge equal to the
  model's, POSITION exact, no error. The core's ID has bit 15 set, and a driver for the AVR446 mode refuses it.
* test_exact_stops: soft and hard stops in ACCEL, RUN and DECEL of two profiles (a trapezoid and an asymmetric
  trapezoid), and a jog (an endless segment from START) ended by a soft stop in RUN (its c_sd), in ACCEL and
  by a hard stop: every edge as edges_with_stop / segment_edges say.
* test_exact_scripts: named command scripts in exact mode at 4 times the clock (PLB-like: a change in ACCEL, a retarget
  behind the motor: a soft stop and a queued move back, a jog through zero; AXI4-Lite: a change in DECEL, a queue
  in the same direction: two take-overs): every STEP edge and
  POSITION equal to stepramp.board.script.plan_script's, no error flagged.
"""

from __future__ import annotations

import functools
import json
import os

import pytest

from peripheral_tb import TOPS, PeripheralTb, check_stopped, stop_cases
from stepramp.board.driver import Outputs, StepRampError
from stepramp.board.plan import RAMP_EXACT, plan_move
from stepramp.board.regmap import ID_RAMP_BIT, ID_VALUE, offset
from stepramp.board.script import load_script, plan_script
from stepramp.models.engine import edges as model_edges
from stepramp.models.engine import last_edge, segment_edges
from stepramp.sim.clocking import CLK_PERIOD_NS
from stepramp.sim.profiles import EXACT_CLOCK_FACTOR, EXACT_PROFILES
from stepramp.sim.runner import run_cocotb
from stepramp.sim.script_sim import simulate_planned
from stepramp.sim.scripts import NAMED_SCRIPTS
from stepramp.tools.golden import exact_script
from tbutil import build_dir, cocotb, edges_differ, env_int

EXACT = {"G_RAMP": RAMP_EXACT}
BY_NAME = {p.name: p for p in EXACT_PROFILES}


def _limit_us(names: list[str]) -> int:
    """Twice the model's last edges plus 4000 clocks per move (bus, DIR timing), plus 200 us."""
    cycles = sum((last_edge(plan_move(**BY_NAME[n].args(), ramp=RAMP_EXACT)) or 0) + 4000 for n in names)
    return int(2 * cycles * CLK_PERIOD_NS / 1000) + 200


PROFILE_LIMIT_US = _limit_us(json.loads(os.environ.get("PROFILE_NAMES", "[]")))


@cocotb.test(timeout_time=PROFILE_LIMIT_US, timeout_unit="us")
async def exact_profiles(dut) -> None:
    """Every requested profile in exact mode, programmed by the driver, edge for edge as the model says."""
    names = json.loads(os.environ.get("PROFILE_NAMES", "[]"))
    tb = await PeripheralTb.started(dut, idle=bool(env_int("BUS_IDLE", 0)))
    await tb.configure(Outputs(**json.loads(os.environ.get("OUTPUTS", "{}"))), enable=True)
    raw = await tb.bus.read(offset("ID"))
    assert raw == ID_VALUE | 1 << ID_RAMP_BIT, f"ID reads {raw:#010x}"
    with pytest.raises(StepRampError, match="the core's ramp is exact"):
        await tb.driver().check_id()
    await tb.driver(ramp=RAMP_EXACT).check_id()
    problems: list[str] = []
    position = 0
    for name in names:
        prof = BY_NAME[name]
        drv = tb.driver(prof.args(), ramp=RAMP_EXACT)
        plan = drv.plan(prof.steps, prof.accel, prof.decel, prof.speed)
        assert plan.ramp == RAMP_EXACT
        edges, status = await tb.run_plan(drv, plan)
        position += prof.steps
        want = model_edges(plan)
        if edges != want:
            problems.append(f"{name}: {edges_differ(edges, want)}")
        if status.error or await drv.position() != position:
            problems.append(f"{name}: error={status.error} ({status.err_name}), position {await drv.position()}")
    assert not problems, "\n".join(problems)
    tb.finish()


#: (profile, pulses that land in ACCEL, RUN and DECEL)
STOP_PROFILES = (("trap_basic", (8, 100, 190)), ("trap_asym", (8, 60, 170)))


@cocotb.test(timeout_time=400, timeout_unit="ms")
async def exact_stops(dut) -> None:
    """Soft and hard stops in every phase of three moves, and a jog ended three ways, as the model says."""
    tb = await PeripheralTb.started(dut)
    await tb.configure(Outputs(mode="half", step_width=4, dir_setup=12, dir_hold=6), enable=True)
    stop_edges = tb.watch_stops()
    position = 0
    for name, pulses in STOP_PROFILES:
        prof = BY_NAME[name]
        drv = tb.driver(prof.args(), ramp=RAMP_EXACT)
        plan = drv.plan(prof.steps, prof.accel, prof.decel, prof.speed)
        for kind, wait, phase in stop_cases(pulses):

            async def start(drv=drv, plan=plan) -> None:  # type: ignore[no-untyped-def]
                await drv.program(plan)
                await drv.start()

            edges, request, _ = await tb.stop_after(drv, stop_edges, kind, wait, phase, start)
            check_stopped(plan, kind, phase, request, edges, wait)
            position += len(edges) * (-1 if plan.direction else 1)
            assert await drv.position() == position, f"{name} {kind} in {phase}: position"
    drv = tb.driver({"fclk": 4e6, "spr": 200.0, "prescale": 4}, ramp=RAMP_EXACT)
    for speed, kind, wait, phase in (
        (100.0, "soft", 20, "RUN"),
        (-100.0, "soft", 3, "ACCEL"),
        (60.0, "hard", 15, "RUN"),
    ):
        jog = functools.partial(drv.jog, speed, 20000.0, 15000.0)
        edges, request, seg = await tb.stop_after(drv, stop_edges, kind, wait, phase, jog)
        assert seg.ramp == RAMP_EXACT
        want = segment_edges(seg, drv.prescale, stop=(kind, request))
        assert edges == want, f"jog {speed}, {kind} stop in {phase}: {edges_differ(edges, want)}"
    tb.finish()


@pytest.mark.parametrize("chunk", range(3))
@pytest.mark.parametrize("top", TOPS)
def test_exact_profiles(top: str, chunk: int) -> None:
    outputs = [
        {"mode": "half", "step_width": 5, "dir_setup": 20, "dir_hold": 10},
        {"mode": "wave", "step_width": 10, "dir_setup": 7, "dir_hold": 3},  # PWM: the AVR446 profiles run it
        {"mode": "full", "step_width": 30},
    ][chunk]
    names = [p.name for p in EXACT_PROFILES[chunk::3]]
    run_cocotb(
        top,
        "test_exact_rtl",
        build_dir(f"exact_{top}_profiles_{chunk}"),
        parameters=EXACT,
        testcase="exact_profiles",
        extra_env={
            "PROFILE_NAMES": json.dumps(names),
            "BUS_IDLE": str(int(chunk > 0)),
            "OUTPUTS": json.dumps(outputs),
        },
    )


@pytest.mark.parametrize("top", TOPS)
def test_exact_stops(top: str) -> None:
    run_cocotb(top, "test_exact_rtl", build_dir(f"exact_{top}_stops"), parameters=EXACT, testcase="exact_stops")


#: The named scripts each top plays in exact mode (split between the tops: the simulation time of the regression).
EXACT_SCRIPTS = {
    "stepramp_plb": ("change_in_accel", "retarget_behind", "jog_through_zero"),
    "stepramp_axil": ("change_in_decel", "queue_same_direction"),
}


@pytest.mark.parametrize("top", TOPS)
def test_exact_scripts(top: str) -> None:
    names = EXACT_SCRIPTS[top]
    # each in exact mode at EXACT_CLOCK_FACTOR times the clock and PRESCALE (the same ticks, every clock count of the
    # script that many times larger)
    planned = [plan_script(load_script(exact_script(NAMED_SCRIPTS[n], EXACT_CLOCK_FACTOR))) for n in names]
    for name, p in zip(names, planned, strict=True):
        assert p.edges and not p.rejected and not p.errors, f"{name}: {p.rejected} {p.errors}"
    results = simulate_planned(planned, build_dir(f"exact_scripts_{top}"), top, ramp=RAMP_EXACT)
    for name, p, r in zip(names, planned, results, strict=True):
        assert [tuple(e) for e in r["core_errors"]] == p.errors, f"{name}: core errors {r['core_errors']}"
        assert r["edges"] == p.edges, f"{name}: STEP edges: {edges_differ(r['edges'], p.edges)}"
        assert r["positions"] == p.positions, f"{name}: positions differ from the model"
