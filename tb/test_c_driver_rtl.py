# SPDX-License-Identifier: MIT
"""The C driver (sw/c/src/stepramp.c) itself against the RTL, both tops.

build/libstepramp_cb.so is the driver compiled for a host whose bus is a set of callbacks
(sw/c/host/stepramp_cbbus.c); stepramp.sim.cdriver.CDriver attaches those callbacks to the bench's bus master and runs
every C call in a thread bridged into the simulation (cocotb's bridge/resume). So each register access, byte lane and
polling loop of the C code reaches the core as a MicroBlaze program's would, and the core's answer is checked
against the bit-exact model (stepramp.models.engine) and the register map (stepramp.board.regmap), never against the
driver's own view:

- c_driver_moves_by_polling: stepramp_init, stepramp_move and stepramp_wait_done per profile (a trapezoid, a
  triangle with negative steps, a move starting in RUN, PRESCALE 4): every STEP edge as the model's, the position;
- c_driver_isr: stepramp_isr on the irq line: nothing pending (ENOIRQ), a move's end (OK, irq drops), a POSITION
  write during a move (ECORE(POS_BUSY) while the move goes on, then OK at its end), a plan with PRESCALE 0
  (ECORE(PRESCALE), no pulse);
- c_driver_stops: stepramp_soft_stop and stepramp_hard_stop in RUN, edges as stepramp.models.engine.edges_with_stop;
- c_driver_status_fields: stepramp_status in the middle of ACCEL, RUN and DECEL: its fields equal the register map's
  decoding of the raw word, the state is the model's phase there;
- c_driver_jog: stepramp_jog forwards ended by stepramp_soft_stop, backwards by stepramp_hard_stop, both in RUN:
  edges as stepramp.models.engine.segment_edges of change.py's segment; a stepramp_move after them as the model's;
- c_driver_change_and_queue: stepramp_change_to in RUN at pulse STEP_COUNT + 4 (faster, to a new target), then
  stepramp_queue_move back while it runs: edges as stepramp.models.engine.change_edges, then the queued move's as the
  model's from its own start, which the start gate gives at the first motion's last pulse; STATUS.PENDING; POSITION.
- c_driver_exact (test_c_driver_exact_mode, stepramp_plb with G_RAMP = 1): stepramp_init refuses the exact core,
  stepramp_init_ramp takes it; two exact moves and a jog stopped in RUN, every edge as the model's exact plans.
"""

from __future__ import annotations

import ctypes
import dataclasses
import os
from pathlib import Path
from typing import Any

import pytest
from cocotb.triggers import ClockCycles, First, RisingEdge

from peripheral_tb import TOPS, PeripheralTb, profiles_limit_us
from stepramp.board.change import Segment, plan_change, speed_at_pulse
from stepramp.board.plan import RAMP_EXACT, Plan, plan_move, plan_move_info
from stepramp.board.regmap import ERROR_CODES, ID_VALUE, REGISTERS_BY_NAME, offset
from stepramp.models.engine import change_edges, edges_with_stop, phase_of, segment_edges
from stepramp.models.engine import edges as model_edges
from stepramp.models.stepping import gate_timing
from stepramp.sim.cdriver import CDriver
from stepramp.sim.clocking import Cycles
from stepramp.sim.profiles import EXACT_PROFILES, PROFILES_BY_NAME, Profile
from tbutil import build_dir, cocotb, edges_differ, run_with_c_lib

#: A trapezoid, a triangle with negative steps, a move starting in RUN, and one with PRESCALE > 1.
POLLED = ("trap_basic", "triangle_negative", "run_start", "trap_prescale_4")

#: The driver's results (stepramp.h): STEPRAMP_OK, STEPRAMP_ENOIRQ, STEPRAMP_ECORE(code) = 128 + code.
OK, ENOIRQ, ECORE_BASE = 0, 67, 128
EID = 64
EXACT_BY_NAME = {p.name: p for p in EXACT_PROFILES}
ERR = {name: code for name, (code, _) in ERROR_CODES.items()}
STATE_CODES = {"STOP": 0, "ACCEL": 1, "RUN": 2, "DECEL": 3}


async def c_bench(dut: Any, prof: Profile) -> tuple[PeripheralTb, CDriver]:
    """The top, reset, with the C driver on its bus master, initialised for a profile's clock and motor (the driver's
    STEPRAMP_IDLE() waits 200 clocks)."""
    tb = await PeripheralTb.started(dut)
    cdrv = CDriver(Path(os.environ["STEPRAMP_C_CB_LIB"]), tb.bus, idle=lambda: Cycles(tb.clk, 200))
    await c_init(cdrv, prof)
    return tb, cdrv


async def c_init(cdrv: CDriver, prof: Profile) -> None:
    rc = await cdrv.dev_call("stepramp_init", cdrv.base, prof.fclk, prof.spr, prof.prescale)
    assert rc == OK, f"stepramp_init: {await cdrv.call('stepramp_strresult', rc)}"
    assert cdrv.dev.version == ID_VALUE & 0xFFFF, f"stepramp_init read version {cdrv.dev.version:#x}"


async def c_move(cdrv: CDriver, prof: Profile) -> None:
    rc = await cdrv.dev_call("stepramp_move", prof.steps, prof.accel, prof.decel, prof.speed)
    assert rc == OK, f"{prof.name}: stepramp_move: {await cdrv.call('stepramp_strresult', rc)}"


async def c_isr(cdrv: CDriver) -> int:
    return int(await cdrv.dev_call("stepramp_isr", ctypes.byref(cdrv.status)))


async def until_pulses(tb: PeripheralTb, count: int) -> None:
    while len(tb.step_edges) < count:
        await RisingEdge(tb.dut.step)


async def irq_dropped(tb: PeripheralTb) -> None:
    """irq is low after the handler's clearing write: it follows the flags one clock later (docs/stepramp_plb.md)."""
    await ClockCycles(tb.clk, 2)
    assert not int(tb.dut.irq.value), "irq still high two clocks after stepramp_isr cleared the flags"


async def irq_within(tb: PeripheralTb, cycles: int) -> bool:
    if not int(tb.dut.irq.value):
        await First(RisingEdge(tb.dut.irq), Cycles(tb.clk, cycles))
    return bool(int(tb.dut.irq.value))


# Limit: the polled profiles as the model says they last (measured 1.64 ms).
@cocotb.test(timeout_time=profiles_limit_us(list(POLLED)), timeout_unit="us")
async def c_driver_moves_by_polling(dut) -> None:
    """stepramp_move then stepramp_wait_done per profile: edges of the model's plan, POSITION the steps' sum."""
    tb, cdrv = await c_bench(dut, PROFILES_BY_NAME[POLLED[0]])
    problems: list[str] = []
    position = 0
    for name in POLLED:
        prof = PROFILES_BY_NAME[name]
        await c_init(cdrv, prof)
        n0, s0, idles0 = len(tb.step_edges), len(tb.start_edges), cdrv.idles
        await c_move(cdrv, prof)
        rc = await cdrv.dev_call("stepramp_wait_done", 100_000)
        edges = tb.edges_since(n0, s0)
        want = model_edges(plan_move(**prof.args()))
        position += prof.steps
        dut._log.info("%s: %d edges, %d STATUS polls", name, len(edges), cdrv.idles - idles0 + 1)
        if rc != OK:
            problems.append(f"{name}: stepramp_wait_done: {await cdrv.call('stepramp_strresult', rc)}")
        if edges != want:
            problems.append(f"{name}: {edges_differ(edges, want)}")
        if cdrv.idles == idles0:
            problems.append(f"{name}: wait_done never ran STEPRAMP_IDLE() (DONE before the first poll?)")
        got = await cdrv.dev_call("stepramp_position")
        if got != position:
            problems.append(f"{name}: stepramp_position {got}, expected {position}")
    assert not problems, "\n".join(problems)
    tb.finish()


@cocotb.test(timeout_time=4, timeout_unit="ms")  # measured 1.06 ms
async def c_driver_isr(dut) -> None:
    """stepramp_isr as the irq handler: ENOIRQ, OK at a move's end, ECORE(POS_BUSY) during a move, ECORE(PRESCALE)."""
    prof = PROFILES_BY_NAME["trap_basic"]
    tb, cdrv = await c_bench(dut, prof)
    await cdrv.dev_call("stepramp_enable_irq", 1, 1)
    assert await c_isr(cdrv) == ENOIRQ, "stepramp_isr with nothing pending is not ENOIRQ"
    assert not cdrv.status.done and not cdrv.status.error
    # 1: a move ends; the handler reports OK and irq drops.
    n0 = len(tb.step_edges)
    await c_move(cdrv, prof)
    assert await irq_within(tb, 200_000), "no irq at the end of the move"
    assert len(tb.step_edges) - n0 == prof.steps
    assert await c_isr(cdrv) == OK
    assert cdrv.status.done and not cdrv.status.error and not cdrv.status.busy
    await irq_dropped(tb)
    # 2: a POSITION write during a move: ERROR (POS_BUSY) raises irq while the move goes on; then DONE without error.
    n0 = len(tb.step_edges)
    await c_move(cdrv, prof)
    await until_pulses(tb, n0 + 20)
    await cdrv.dev_call("stepramp_set_position", 12345)
    assert await irq_within(tb, 20), "no irq for the POSITION write during the move"
    rc = await c_isr(cdrv)
    assert rc == ECORE_BASE + ERR["POS_BUSY"], f"isr returned {rc}"
    assert cdrv.status.busy and not cdrv.status.done, "the move did not go on after the refused POSITION write"
    assert (await cdrv.call("stepramp_corename", cdrv.status.err_code)) == "POS_BUSY"
    await irq_dropped(tb)
    assert await irq_within(tb, 200_000), "no irq at the end of the move"
    rc = await c_isr(cdrv)
    await irq_dropped(tb)
    assert rc == OK, f"isr at the end of the move returned {rc}: {await cdrv.call('stepramp_strresult', rc)}"
    assert len(tb.step_edges) - n0 == prof.steps
    assert await cdrv.dev_call("stepramp_position") == 2 * prof.steps, "the refused POSITION write moved POSITION"
    # 3: a plan with PRESCALE 0, programmed and started: rejected, nothing moves.
    plan = cdrv.plan_t()
    rc = await cdrv.dev_call("stepramp_plan", ctypes.byref(plan), prof.steps, prof.accel, prof.decel, prof.speed)
    assert rc == OK
    plan.prescale = 0
    assert await cdrv.dev_call("stepramp_program", ctypes.byref(plan)) == OK
    n0 = len(tb.step_edges)
    await cdrv.dev_call("stepramp_start")
    assert await irq_within(tb, 1_000), "no irq for a rejected start"
    rc = await c_isr(cdrv)
    assert rc == ECORE_BASE + ERR["PRESCALE"], f"isr returned {rc}"
    assert cdrv.status.done and cdrv.status.error
    await irq_dropped(tb)
    await Cycles(tb.clk, 2_000)
    assert len(tb.step_edges) == n0, "a rejected move pulsed STEP"
    tb.finish()


@cocotb.test(timeout_time=4, timeout_unit="ms")  # measured 0.96 ms
async def c_driver_stops(dut) -> None:
    """stepramp_soft_stop and stepramp_hard_stop in RUN: the edges of the model's stop at the request's edge."""
    prof = PROFILES_BY_NAME["trap_long_cruise"]
    tb, cdrv = await c_bench(dut, prof)
    plan = plan_move(**prof.args())
    requests: dict[str, list[int]] = {"soft": [], "hard": []}
    assert tb.pins is not None
    for kind in requests:
        cocotb.start_soon(tb.pins.watch(getattr(dut.core_inst, f"{kind}_stop"), requests[kind]))
    wait_pulses = (plan.sa + plan.sd) // 2
    assert phase_of(plan, wait_pulses) == "RUN"
    position = 0
    for kind in requests:
        n0, s0, k0 = len(tb.step_edges), len(tb.start_edges), len(requests[kind])
        await c_move(cdrv, prof)
        await until_pulses(tb, n0 + wait_pulses)
        await cdrv.dev_call(f"stepramp_{kind}_stop")
        rc = await cdrv.dev_call("stepramp_wait_done", 100_000)
        assert rc == OK, f"{kind} stop: {await cdrv.call('stepramp_strresult', rc)}"
        edges = tb.edges_since(n0, s0)
        # The register file's strobe is high after edge w; the engine samples it at w + 1.
        request = requests[kind][k0] + 1 - tb.start_edges[s0]
        want = edges_with_stop(plan, kind, request)
        assert edges == want, f"{kind} stop: {edges_differ(edges, want)}"
        position += len(edges)
        assert await cdrv.dev_call("stepramp_position") == position
    tb.finish()


def status_fields(raw: int) -> dict[str, int]:
    """STATUS decoded with the register map's field table."""
    reg = REGISTERS_BY_NAME["STATUS"]
    return {f.name: (raw >> f.lsb) & ((1 << f.width) - 1) for f in reg.fields}


@cocotb.test(timeout_time=2, timeout_unit="ms")  # measured 0.52 ms
async def c_driver_status_fields(dut) -> None:
    """stepramp_status in the middle of each phase of a negative trapezoid: its fields are the register map's
    decoding of the raw word; state, busy and direction are those of the model's plan at that pulse."""
    prof = PROFILES_BY_NAME["trap_basic"]
    tb, cdrv = await c_bench(dut, prof)
    backwards = dataclasses.replace(prof, name="trap_basic_negative", steps=-prof.steps)
    plan: Plan = plan_move(**backwards.args())
    samples = [plan.sa // 2, (plan.sa + plan.sd) // 2, (plan.sd + plan.steps) // 2]
    assert [phase_of(plan, k) for k in samples] == ["ACCEL", "RUN", "DECEL"], f"plan {plan}"
    n0 = len(tb.step_edges)
    await c_move(cdrv, backwards)
    st = cdrv.status
    for k in samples:
        await until_pulses(tb, n0 + k)
        raw = int(await cdrv.dev_call("stepramp_status", ctypes.byref(st)))
        fields = status_fields(raw)
        decoded = {
            "STATE": st.state,
            "BUSY": st.busy,
            "DIR": st.dir,
            "DONE": st.done,
            "ERROR": st.error,
            "ERR_CODE": st.err_code,
        }
        assert st.raw == raw
        assert decoded == {name: fields[name] for name in decoded}, f"pulse {k}: C {decoded}, map {fields}"
        assert (st.state, st.busy, st.dir) == (STATE_CODES[phase_of(plan, k)], 1, 1), f"pulse {k}: {decoded}"
    rc = await cdrv.dev_call("stepramp_wait_done", 100_000)
    assert rc == OK
    st_raw = int(await cdrv.dev_call("stepramp_status", ctypes.byref(st)))
    assert (st.state, st.busy, st.dir, st.done) == (0, 0, 1, 0), f"after the move: {status_fields(st_raw)}"
    tb.finish()


@cocotb.test(timeout_time=8, timeout_unit="ms")
async def c_driver_jog(dut) -> None:
    """stepramp_jog forwards ended by stepramp_soft_stop, backwards by stepramp_hard_stop, both in RUN: every edge as
    segment_edges says of change.py's segment (the C driver writes its registers), POSITION the pulses seen; then a
    stepramp_move runs as the model says (the driver cleared the segment registers)."""
    prof = PROFILES_BY_NAME["trap_long_cruise"]
    tb, cdrv = await c_bench(dut, prof)
    cdrv.so.stepramp_jog.argtypes = [ctypes.POINTER(cdrv.dev_t), *(ctypes.c_double,) * 3]
    cdrv.so.stepramp_jog.restype = ctypes.c_int
    requests: dict[str, list[int]] = {"soft": [], "hard": []}
    assert tb.pins is not None
    for kind in requests:
        cocotb.start_soon(tb.pins.watch(getattr(dut.core_inst, f"{kind}_stop"), requests[kind]))
    position = 0
    for speed, kind in ((prof.speed, "soft"), (-prof.speed, "hard")):
        seg = plan_change(0.0, None, prof.accel, prof.decel, abs(speed), prof.spr, prof.fclk, prof.prescale).segment
        n0, s0, k0 = len(tb.step_edges), len(tb.start_edges), len(requests[kind])
        rc = await cdrv.dev_call("stepramp_jog", speed, prof.accel, prof.decel)
        assert rc == OK, f"stepramp_jog({speed}): {await cdrv.call('stepramp_strresult', rc)}"
        await until_pulses(tb, n0 + seg.sa + 10)
        await cdrv.dev_call("stepramp_status", ctypes.byref(cdrv.status))
        assert cdrv.status.state == STATE_CODES["RUN"], f"jog {speed}: state {cdrv.status.state} after sa + 10 pulses"
        await cdrv.dev_call(f"stepramp_{kind}_stop")
        rc = await cdrv.dev_call("stepramp_wait_done", 100_000)
        assert rc == OK, f"jog {speed}, {kind} stop: {await cdrv.call('stepramp_strresult', rc)}"
        edges = tb.edges_since(n0, s0)
        # The register file's strobe is high after edge w; the engine samples it at w + 1.
        request = requests[kind][k0] + 1 - tb.start_edges[s0]
        want = segment_edges(seg, prof.prescale, stop=(kind, request))
        assert edges == want, f"jog {speed}, {kind} stop: {edges_differ(edges, want)}"
        position += -len(edges) if speed < 0 else len(edges)
        assert await cdrv.dev_call("stepramp_position") == position, f"jog {speed}: position is not the pulses seen"
    assert cdrv.dev.segment_dirty == 1
    n0, s0 = len(tb.step_edges), len(tb.start_edges)
    await c_move(cdrv, prof)
    assert cdrv.dev.segment_dirty == 0
    rc = await cdrv.dev_call("stepramp_wait_done", 100_000)
    assert rc == OK, f"the move after the jogs: {await cdrv.call('stepramp_strresult', rc)}"
    edges, want = tb.edges_since(n0, s0), model_edges(plan_move(**prof.args()))
    assert edges == want, f"the move after the jogs: {edges_differ(edges, want)}"
    tb.finish()


@cocotb.test(timeout_time=3, timeout_unit="ms")  # measured 0.98 ms
async def c_driver_change_and_queue(dut) -> None:
    """stepramp_change_to in RUN, at pulse P = STEP_COUNT + 4, to a faster speed and a new target: every edge of the
    motion as change_edges says of change.py's segment for the same u (the C plan is bit-identical); while it runs,
    stepramp_queue_move back: it starts at the motion's last pulse (through the start gate: DIR changes), its edges
    the model's from its own start edge; STATUS.PENDING while each is pending; POSITION the sum."""
    prof = PROFILES_BY_NAME["trap_basic"]
    tb, cdrv = await c_bench(dut, prof)
    plan, info = plan_move_info(**prof.args())
    st = cdrv.status
    n0, s0 = len(tb.step_edges), len(tb.start_edges)
    await c_move(cdrv, prof)
    await until_pulses(tb, n0 + plan.sa + 10)
    await cdrv.dev_call("stepramp_status", ctypes.byref(st))
    assert st.state == STATE_CODES["RUN"] and not st.pending, f"state {st.state}, pending {st.pending} in the cruise"
    # the change: faster, harder accel, softer decel, to a target `remaining` steps past pulse P
    p = await tb.bus.read(offset("STEP_COUNT")) + 4
    u = speed_at_pulse(info, p)
    accel, decel, speed, remaining = 1.2 * prof.accel, 0.7 * prof.decel, 1.5 * prof.speed, 250
    change = plan_change(u, remaining, accel, decel, speed, prof.spr, prof.fclk, prof.prescale)
    assert change.back is None and change.segment.length == remaining
    pulses_before = len(tb.step_edges) - n0
    rc = await cdrv.dev_call("stepramp_change_to", p, u, remaining, accel, decel, speed)
    assert rc == OK, f"stepramp_change_to: {await cdrv.call('stepramp_strresult', rc)}"
    dut._log.info("change at pulse %d: the C call ran from pulse %d to %d", p, pulses_before, len(tb.step_edges) - n0)
    await cdrv.dev_call("stepramp_status", ctypes.byref(st))
    assert st.pending and st.busy and not st.error, f"the change was not accepted: {status_fields(st.raw)}"
    # PENDING falls two clocks after pulse P - 1's engine edge: by pulse P's STEP edge
    await until_pulses(tb, n0 + p + 1)
    await cdrv.dev_call("stepramp_status", ctypes.byref(st))
    assert not st.pending and st.busy and not st.error, f"after pulse {p}: {status_fields(st.raw)}"
    # the queued move back, staged while the changed motion runs
    back = dataclasses.replace(prof, name="trap_basic_back", steps=-120)
    rc = await cdrv.dev_call("stepramp_queue_move", back.steps, back.accel, back.decel, back.speed)
    assert rc == OK, f"stepramp_queue_move: {await cdrv.call('stepramp_strresult', rc)}"
    await cdrv.dev_call("stepramp_status", ctypes.byref(st))
    assert st.pending and st.busy and not st.error, f"the queue was not accepted: {status_fields(st.raw)}"
    assert cdrv.dev.segment_dirty == 0, "stepramp_queue_move left the change's segment registers set"
    for which in ("the changed motion", "the queued move"):
        rc = await cdrv.dev_call("stepramp_wait_done", 100_000)
        assert rc == OK, f"{which}: stepramp_wait_done: {await cdrv.call('stepramp_strresult', rc)}"
    await cdrv.dev_call("stepramp_status", ctypes.byref(st))
    assert not st.busy and not st.pending and st.dir == 1, f"after the queued move: {status_fields(st.raw)}"
    # the changed motion: intervals 1 .. P of the move, then the segment's, one accumulator
    want = change_edges(Segment.of_move(plan), p, change.segment, prof.prescale)
    assert len(want) == p + 1 + remaining
    edges = tb.edges_since(n0, s0)[: len(want)]
    assert edges == want, f"the change at pulse {p}: {edges_differ(edges, want)}"
    # the queued move: its own start, after the first motion's last pulse, as the start gate times a START whose
    # request is sampled one clock after that STEP edge (DIR changes: hold, then setup, at their reset values)
    assert len(tb.start_edges) == s0 + 2, f"{len(tb.start_edges) - s0} engine starts, expected 2"
    n1 = n0 + len(want)
    last = tb.step_edges[n1 - 1]
    gate = gate_timing(last + 1, True, last, dir_hold=0, dir_setup=0)
    assert tb.step_edges[n1] == gate.first_step_edge, (
        f"the queued move's first STEP edge is {tb.step_edges[n1] - last} clocks after the last one, expected "
        f"{gate.first_step_edge - last}"
    )
    assert tb.pins is not None
    edges, want = tb.pins.since(n1, s0 + 1), model_edges(plan_move(**back.args()))
    assert edges == want, f"the queued move: {edges_differ(edges, want)}"
    position = p + 1 + remaining + back.steps
    assert await cdrv.dev_call("stepramp_position") == position, f"POSITION is not {position}"
    tb.finish()


@cocotb.test(timeout_time=60, timeout_unit="ms")
async def c_driver_exact(dut) -> None:
    """A core built with G_RAMP = 1: stepramp_init refuses it (ID bit 15, STEPRAMP_EID), stepramp_init_ramp with
    STEPRAMP_RAMP_EXACT takes it; then stepramp_move of two exact profiles and a stepramp_jog ended by
    stepramp_soft_stop in RUN: every edge as the model says of the Python driver's exact plans (the C plans are
    bit-identical), POSITION the pulses seen."""
    tb = await PeripheralTb.started(dut)
    cdrv = CDriver(Path(os.environ["STEPRAMP_C_CB_LIB"]), tb.bus, idle=lambda: Cycles(tb.clk, 200))
    prof = EXACT_BY_NAME["trap_basic"]
    rc = await cdrv.dev_call("stepramp_init", cdrv.base, prof.fclk, prof.spr, prof.prescale)
    assert rc == EID, f"stepramp_init on an exact core: {await cdrv.call('stepramp_strresult', rc)}"
    position = 0
    for name in ("trap_basic", "triangle_negative"):
        prof = EXACT_BY_NAME[name]
        rc = await cdrv.dev_call("stepramp_init_ramp", cdrv.base, prof.fclk, prof.spr, prof.prescale, RAMP_EXACT)
        assert rc == OK, f"stepramp_init_ramp: {await cdrv.call('stepramp_strresult', rc)}"
        n0, s0 = len(tb.step_edges), len(tb.start_edges)
        await c_move(cdrv, prof)
        rc = await cdrv.dev_call("stepramp_wait_done", 1_000_000)
        assert rc == OK, f"{name}: {await cdrv.call('stepramp_strresult', rc)}"
        edges, want = tb.edges_since(n0, s0), model_edges(plan_move(**prof.args(), ramp=RAMP_EXACT))
        assert edges == want, f"{name} (exact): {edges_differ(edges, want)}"
        position += prof.steps
    prof = EXACT_BY_NAME["trap_basic"]
    rc = await cdrv.dev_call("stepramp_init_ramp", cdrv.base, prof.fclk, prof.spr, prof.prescale, RAMP_EXACT)
    assert rc == OK, f"stepramp_init_ramp: {await cdrv.call('stepramp_strresult', rc)}"
    cdrv.so.stepramp_jog.argtypes = [ctypes.POINTER(cdrv.dev_t), *(ctypes.c_double,) * 3]
    cdrv.so.stepramp_jog.restype = ctypes.c_int
    requests: list[int] = []
    assert tb.pins is not None
    cocotb.start_soon(tb.pins.watch(dut.core_inst.soft_stop, requests))
    seg = plan_change(0.0, None, prof.accel, prof.decel, prof.speed, prof.spr, prof.fclk, prof.prescale, RAMP_EXACT)
    n0, s0 = len(tb.step_edges), len(tb.start_edges)
    rc = await cdrv.dev_call("stepramp_jog", prof.speed, prof.accel, prof.decel)
    assert rc == OK, f"stepramp_jog: {await cdrv.call('stepramp_strresult', rc)}"
    await until_pulses(tb, n0 + seg.segment.sa + 5)
    await cdrv.dev_call("stepramp_soft_stop")
    rc = await cdrv.dev_call("stepramp_wait_done", 1_000_000)
    assert rc == OK, f"jog, soft stop: {await cdrv.call('stepramp_strresult', rc)}"
    edges = tb.edges_since(n0, s0)
    want = segment_edges(seg.segment, prof.prescale, stop=("soft", requests[0] + 1 - tb.start_edges[s0]))
    assert edges == want, f"jog (exact), soft stop in RUN: {edges_differ(edges, want)}"
    position += len(edges)
    assert await cdrv.dev_call("stepramp_position") == position
    tb.finish()


C_TESTS = [
    "c_driver_moves_by_polling",
    "c_driver_isr",
    "c_driver_stops",
    "c_driver_status_fields",
    "c_driver_jog",
    "c_driver_change_and_queue",
]


@pytest.mark.parametrize("top", TOPS)
def test_c_driver_on_rtl(top: str) -> None:
    """The C driver's calls against each top (the library is built here: make -C sw/c lib)."""
    run_with_c_lib(top, "test_c_driver_rtl", build_dir(f"{top}_c_driver"), testcase=C_TESTS)


def test_c_driver_exact_mode() -> None:
    """The C driver against stepramp_plb built with G_RAMP = 1 (the exact ramp)."""
    run_with_c_lib(
        "stepramp_plb",
        "test_c_driver_rtl",
        build_dir("plb_c_driver_exact"),
        testcase="c_driver_exact",
        parameters={"G_RAMP": RAMP_EXACT},
    )
