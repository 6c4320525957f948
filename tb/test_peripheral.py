# SPDX-License-Identifier: MIT
"""The peripheral through its bus, played the way MicroBlaze would, with the driver: both tops.

stepramp_plb (PLB-like IPIF, stepramp/ipif.py master) and stepramp_axil (AXI4-Lite, cocotbext-axi master with idle
cycles and backpressure on every channel) run the same tests: register behaviour (reset values, read/write, byte
enables, bus errors, W1C, interrupt, shadowing, bad values) against the register map (stepramp.board.regmap), and motion
(every profile, programmed through the bus by stepramp.board.driver.StepRamp) against the bit-exact model.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import os
import random

import pytest
from cocotb.triggers import ClockCycles, FallingEdge, ReadOnly, RisingEdge

from peripheral_tb import (
    BAD_VALUES,
    TOPS,
    BusError,
    PeripheralTb,
    check_stopped,
    expect_rejected,
    profiles_limit_us,
    stop_cases,
)
from stepramp.board.change import Segment, plan_change
from stepramp.board.driver import Outputs, StepRampError, plan_writes
from stepramp.board.plan import Plan, plan_move
from stepramp.board.regmap import ADDR_BITS, ERROR_CODES, ID_VALUE, LIVE, REGISTERS, REGISTERS_BY_NAME, RW, offset
from stepramp.models import stepping as sm
from stepramp.models.engine import change_edges, segment_edges
from stepramp.models.engine import edges as model_edges
from stepramp.sim.profiles import PROFILES, PROFILES_BY_NAME, design_args
from stepramp.sim.runner import run_cocotb
from tbutil import build_dir, cocotb, edges_differ, env_int

ERR = {name: code for name, (code, _) in ERROR_CODES.items()}
MAPPED = {r.offset for r in REGISTERS}


def valid_plan() -> Plan:
    return plan_move(**PROFILES_BY_NAME["trap_basic"].args())


@cocotb.test(timeout_time=15, timeout_unit="us")  # measured 4 us (the slower top)
async def reset_values_and_id(dut) -> None:
    """Every register reads its documented reset value."""
    tb = await PeripheralTb.started(dut)
    for reg in REGISTERS:
        if reg.name in LIVE:
            continue  # the clock count: below
        got = await tb.bus.read(reg.offset)
        assert got == reg.reset, f"{reg.name}: {got:#x} after reset, expected {reg.reset:#x}"
    # TIME counts clocks: two reads N clocks apart differ by N (TIME_HI holds bits 63:32 as the read of TIME_LO saw).
    first = await tb.bus.read(offset("TIME_LO"))
    await ClockCycles(tb.clk, 200)
    second = await tb.bus.read(offset("TIME_LO"))
    per_read = second - first - 200
    third = await tb.bus.read(offset("TIME_LO"))
    assert 0 < per_read < 20 and third - second == per_read, f"TIME_LO: {first}, {second}, {third}"
    assert await tb.bus.read(offset("TIME_HI")) == 0
    assert await tb.bus.read(offset("ID")) == ID_VALUE
    if tb.top == "stepramp_plb":
        await ipif_data_and_first_access(tb)
    else:
        await axil_quiet_in_reset(tb)


async def ipif_data_and_first_access(tb: PeripheralTb) -> None:
    """IPIF (docs/stepramp_plb.md, "Bus timing"): ip2bus_data is 0 outside a read acknowledge (buses OR the slaves'
    data); one acknowledge per access, also when bus2ip_cs is still high at the edge after the acknowledge; an
    access whose bus2ip_cs rises with the release of reset is acknowledged one clock later, as any."""
    dut, clk = tb.dut, tb.clk
    await tb.bus.write(offset("STEPS"), 0xFFFF_FFFF)  # returns at the edge after the ack, CS still sampled high
    for cycle in range(6):  # the cycles from there on: no data on the bus, no second acknowledge, no error
        if cycle:
            await RisingEdge(clk)
        await ReadOnly()
        assert int(dut.ip2bus_data.value) == 0, "ip2bus_data is not 0 outside a read acknowledge"
        acks = (int(dut.ip2bus_rdack.value), int(dut.ip2bus_wrack.value), int(dut.ip2bus_error.value))
        assert acks == (0, 0, 0), f"idle cycle {cycle} after a write: rdack, wrack, error = {acks}"
    await FallingEdge(clk)
    dut.rst.value = 1
    await ClockCycles(clk, 3)
    await FallingEdge(clk)
    dut.rst.value = 0
    dut.bus2ip_addr.value, dut.bus2ip_rnw.value, dut.bus2ip_be.value = offset("ID"), 1, 0xF
    dut.bus2ip_cs.value = 1
    await RisingEdge(clk)
    await ReadOnly()
    acked = int(dut.ip2bus_rdack.value)
    data = int(dut.ip2bus_data.value)
    await FallingEdge(clk)
    dut.bus2ip_cs.value = 0
    assert acked == 1, "the first access after reset was not acknowledged one clock after bus2ip_cs"
    assert data == ID_VALUE


async def axil_quiet_in_reset(tb: PeripheralTb) -> None:
    """AXI4-Lite (the protocol's reset rule): from the first edge of reset on, BVALID and RVALID are low and stay low
    after it until an access asks for a response; the address and data channels are ready. Then the tie rule from
    reset on, and after a read alone."""
    dut, clk = tb.dut, tb.clk
    await tb.bus.write(offset("STEPS"), 5)  # a response channel used before the reset
    await FallingEdge(clk)
    dut.aresetn.value = 0
    for cycle in range(6):
        await RisingEdge(clk)
        await ReadOnly()
        if cycle == 3:
            await FallingEdge(clk)
            dut.aresetn.value = 1
            continue
        valid = (int(dut.s_axil_bvalid.value), int(dut.s_axil_rvalid.value))
        ready = (int(dut.s_axil_awready.value), int(dut.s_axil_wready.value), int(dut.s_axil_arready.value))
        assert valid == (0, 0), f"cycle {cycle} of the reset: BVALID, RVALID = {valid}"
        assert ready == (1, 1, 1), f"cycle {cycle} of the reset: AWREADY, WREADY, ARREADY = {ready}"
    # The first accesses after the reset: a write and a read of STEPS presented in the same clock, three times. "On
    # a tie the kind that did not go last goes first" (docs/stepramp_plb.md) starts as if a write went last: the
    # read goes first and reads the old value; the write then went last, so each later tie goes the same way.
    reads = []
    for value in (0x11, 0x22, 0x33):
        write = cocotb.start_soon(tb.bus.write(offset("STEPS"), value))
        read = cocotb.start_soon(tb.bus.read(offset("STEPS")))
        await write
        reads.append(await read)
    assert reads == [0, 0x11, 0x22], f"reads tied with writes of 0x11, 0x22, 0x33 after reset gave {reads}"
    # After a read alone (a read went last), a tie lets the write go first: the tied read sees the new value.
    assert await tb.bus.read(offset("STEPS")) == 0x33
    write = cocotb.start_soon(tb.bus.write(offset("STEPS"), 0x44))
    read = cocotb.start_soon(tb.bus.read(offset("STEPS")))
    await write
    assert await read == 0x44, "a tie after a read: the read went first (the write should, a read went last)"


@cocotb.test(timeout_time=60, timeout_unit="us")  # measured 14 us (the slower top)
async def read_write_every_register(dut) -> None:
    """RW fields keep what is written (bits outside fields read 0); RO registers ignore writes without error."""
    tb = await PeripheralTb.started(dut, idle=True)
    rng = random.Random(11)
    for reg in REGISTERS:
        if reg.name in LIVE:  # the clock count ignores the write and goes on counting
            before = await tb.bus.read(reg.offset)
            await tb.bus.write(reg.offset, 0xA5A5_5A5A)
            after = await tb.bus.read(reg.offset)
            assert 0 < after - before < 200, f"{reg.name}: {before:#x}, then {after:#x} after a write"
            continue
        if reg.name in ("CTRL", "STATUS", "POSITION"):
            continue  # commands and flags: tested below
        rw_mask = sum(f.mask for f in reg.fields if f.access == RW)
        before = await tb.bus.read(reg.offset)
        for pattern in (0xFFFF_FFFF, 0, 0xA5A5_5A5A, rng.getrandbits(32)):
            await tb.bus.write(reg.offset, pattern)
            got = await tb.bus.read(reg.offset)
            want = pattern & rw_mask if rw_mask else before
            assert got == want, f"{reg.name}: wrote {pattern:#x}, read {got:#x}, expected {want:#x}"


@cocotb.test(timeout_time=50, timeout_unit="us")  # measured 10 us (the slower top)
async def byte_enables(dut) -> None:
    """Each byte lane of a write changes only its byte."""
    tb = await PeripheralTb.started(dut)
    for name in ("STEPS", "CRUISE_HI", "STOP_RATIO", "C_FIRST_LO"):
        addr = offset(name)
        for be in range(16):
            await tb.bus.write(addr, 0x1122_3344)
            await tb.bus.write(addr, 0xAABB_CCDD, strobe=be)
            got = await tb.bus.read(addr)
            want = 0
            for b in range(4):
                src = 0xAABB_CCDD if be >> b & 1 else 0x1122_3344
                want |= src & (0xFF << (8 * b))
            assert got == want, f"{name} be={be:04b}: {got:#x} expected {want:#x}"


@cocotb.test(timeout_time=5, timeout_unit="us")  # measured 1.2 us (the slower top)
async def concurrent_reads_and_writes(dut) -> None:
    """Reads and writes issued at the same time from several coroutines (on AXI they overlap on the channels,
    with idle cycles and backpressure): every write lands, every read returns its register's value."""
    tb = await PeripheralTb.started(dut, idle=True)
    rng = random.Random(5)
    targets = [offset(n) for n in ("STEPS", "C_FIRST_LO", "CRUISE_LO", "CRUISE_HI", "STOP_RATIO", "SA", "SD")]
    values = {addr: rng.getrandbits(31) for addr in targets}

    async def writer(addr: int) -> None:
        for _ in range(3):
            await tb.bus.write(addr, values[addr])

    async def reader(results: list[int]) -> None:
        for _ in range(6):
            results.append(await tb.bus.read(offset("ID")))

    reads: list[int] = []
    tasks = [cocotb.start_soon(writer(a)) for a in targets] + [cocotb.start_soon(reader(reads)) for _ in range(3)]
    for task in tasks:
        await task
    assert reads == [ID_VALUE] * 18, "a read overlapping writes returned something else"
    for addr in targets:
        assert await tb.bus.read(addr) == values[addr], f"write to {addr:#x} lost or corrupted"


@cocotb.test(timeout_time=8, timeout_unit="us")  # measured 1.8 us (the slower top)
async def unmapped_offsets_answer_with_error(dut) -> None:
    """Every offset of the register window that is not a register answers with IP2Bus_Error / SLVERR."""
    tb = await PeripheralTb.started(dut)
    for addr in range(0, 1 << ADDR_BITS, 4):
        if addr in MAPPED:
            await tb.bus.read(addr)  # no error
            continue
        for access in ("read", "write"):
            try:
                if access == "read":
                    await tb.bus.read(addr)
                else:
                    await tb.bus.write(addr, 0xFFFF_FFFF)
            except BusError:
                continue
            raise AssertionError(f"{access} at unmapped offset {addr:#x} did not answer with a bus error")
    # The bus still works after errors.
    assert await tb.bus.read(offset("ID")) == ID_VALUE


@cocotb.test(timeout_time=8, timeout_unit="us")  # measured 2.0 us (the slower top)
async def w1c_flags_and_interrupt(dut) -> None:
    """DONE/ERROR are sticky until written 1; irq follows them when enabled."""
    tb = await PeripheralTb.started(dut)
    drv = tb.driver()
    await drv.program(plan_move(0, 100.0, 100.0, 10.0, 200.0, 1e6))  # N = 0: done at once
    await drv.start()
    await ClockCycles(tb.clk, 10)
    status = await drv.status()
    assert status.done and not status.error
    assert int(dut.irq.value) == 0, "irq without enable"
    await drv.enable_irq(done=True, error=False)
    await ClockCycles(tb.clk, 3)
    assert int(dut.irq.value) == 1, "irq must follow DONE once enabled"
    await tb.bus.write(offset("STATUS"), 0)  # writing 0 clears nothing
    assert (await drv.status()).done
    await tb.bus.write(offset("STATUS"), 1 << REGISTERS_BY_NAME["STATUS"].field("DONE").lsb)
    assert not (await drv.status()).done
    await ClockCycles(tb.clk, 3)
    assert int(dut.irq.value) == 0
    # An error with only the error interrupt enabled.
    await drv.enable_irq(done=False, error=True)
    await tb.bus.write(offset("PRESCALE"), 0)
    await drv.start()
    await ClockCycles(tb.clk, 10)
    status = await drv.status()
    assert status.error and status.done and status.err_code == ERR["PRESCALE"]
    assert int(dut.irq.value) == 1
    await drv.clear_flags()
    await ClockCycles(tb.clk, 3)
    assert int(dut.irq.value) == 0
    status = await drv.status()
    assert not status.error and status.err_code == ERR["PRESCALE"], "ERR_CODE keeps the last cause"
    # CTRL reads back its enables only; the command bits read 0.
    assert await tb.bus.read(offset("CTRL")) == 1 << REGISTERS_BY_NAME["CTRL"].field("IRQ_ERROR_EN").lsb


@cocotb.test(timeout_time=2500, timeout_unit="us")  # measured 618 us (the slower top)
async def bad_register_values_flag_an_error(dut) -> None:
    """Each bad register value: ERROR with its cause, DONE, not a single step pulse, and the core still works."""
    tb = await PeripheralTb.started(dut)
    drv = tb.driver()
    good = valid_plan()
    for label, change, cause in BAD_VALUES:
        await expect_rejected(tb, drv, dataclasses.replace(good, **change), label, cause)
        assert await drv.position() == 0
    # STEPS = -2^31 (all ones would be -1: a valid 1-step move) is rejected by the register file.
    await drv.program(good)
    await tb.bus.write(offset("STEPS"), 0x8000_0000)
    await drv.start()
    with pytest.raises(StepRampError, match="STEPS"):
        await drv.wait_done(idle=lambda: ClockCycles(tb.clk, 5), polls=50)
    assert await drv.position() == 0
    # And a good move afterwards runs normally.
    edges, _ = await tb.run_plan(drv, good)
    assert edges == model_edges(good)
    tb.finish()


@cocotb.test(timeout_time=2500, timeout_unit="us")  # measured 552 us (the slower top)
async def position_register(dut) -> None:
    """POSITION is written while stopped; a write during a move is ignored and flagged POS_BUSY."""
    tb = await PeripheralTb.started(dut)
    drv = tb.driver()
    await drv.set_position(-123456)
    assert await drv.position() == -123456
    plan = valid_plan()
    await drv.program(plan)
    await drv.start()
    await ClockCycles(tb.clk, 50)
    await drv.set_position(777)
    # wait_done returns at DONE: the move ends normally, the ignored write has left ERROR = POS_BUSY.
    with pytest.raises(StepRampError, match="POS_BUSY"):
        await drv.wait_done(idle=lambda: tb.irq_or(5_000))
    assert await drv.position() == -123456 + plan.steps
    tb.finish()


@cocotb.test(timeout_time=3, timeout_unit="ms")
async def position_preset_keeps_the_field(dut) -> None:
    """A POSITION write while stopped (homing) leaves the windings where they are: the electrical position counts
    pulses only (docs/algorithm.md, "Electrical position"), so the next move goes on from the same field angle
    (half step, the electrical monitor on across the presets; found by `make soak SECONDS=600 SEED=11`)."""
    tb = await PeripheralTb.started(dut)
    await tb.configure(Outputs(mode="half", step_width=4, dir_setup=12, dir_hold=6), enable=True)
    drv = tb.driver()
    plan = valid_plan()
    await tb.run_plan(drv, plan)
    pins = (dut.a1, dut.a2, dut.b1, dut.b2)
    field = sm.winding_levels(sm.MODE_HALF, plan.steps)
    for value in (plan.steps + 1, plan.steps + 4, -7, 2**31 - 1):
        await drv.set_position(value)
        await ClockCycles(tb.clk, 5)
        await ReadOnly()
        got = tuple(int(p.value) for p in pins)
        assert got == field, f"POSITION := {value}: windings {got}, expected {field} (unchanged)"
        await FallingEdge(tb.clk)
        assert await drv.position() == value
    await tb.run_plan(drv, plan)
    await ReadOnly()
    got = tuple(int(p.value) for p in pins)
    assert got == sm.winding_levels(sm.MODE_HALF, 2 * plan.steps), f"after the next move: windings {got}"
    await FallingEdge(tb.clk)
    assert await drv.position() == ((2**31 - 1 + plan.steps) & 0xFFFF_FFFF) - 2**32
    assert tb.monitors is not None and tb.monitors.electrical.checked >= 2 * plan.steps
    tb.finish()


@cocotb.test(timeout_time=3, timeout_unit="ms")  # measured 723 us (the slower top)
async def motion_registers_are_shadowed(dut) -> None:
    """Writing the next move's registers during a move does not disturb it; the next START uses them."""
    tb = await PeripheralTb.started(dut, idle=True)
    drv = tb.driver()
    first = valid_plan()
    second = plan_move(**PROFILES_BY_NAME["triangle_negative"].args())
    await drv.program(first)
    n0, s0 = len(tb.step_edges), len(tb.start_edges)
    await drv.start()
    await ClockCycles(tb.clk, 2000)
    await drv.program(second)  # during the move
    await drv.wait_done(idle=lambda: tb.irq_or(5_000))
    assert tb.edges_since(n0, s0) == model_edges(first)
    # The second move was programmed during the first: just START it.
    n1, s1 = len(tb.step_edges), len(tb.start_edges)
    await drv.start()
    await drv.wait_done(idle=lambda: tb.irq_or(5_000))
    assert tb.edges_since(n1, s1) == model_edges(second)
    assert await drv.position() == first.steps - second.steps
    tb.finish()


@cocotb.test(timeout_time=2500, timeout_unit="us")  # measured 548 us (the slower top)
async def start_while_busy_is_ignored(dut) -> None:
    """A second START during a move changes nothing, even with other motion registers written since the first."""
    tb = await PeripheralTb.started(dut)
    drv = tb.driver()
    plan = valid_plan()
    await drv.program(plan)
    n0, s0 = len(tb.step_edges), len(tb.start_edges)
    await drv.start()
    await drv.program(plan_move(**PROFILES_BY_NAME["triangle_negative"].args()))  # staged for the next START
    for _ in range(3):
        await ClockCycles(tb.clk, 1500)
        await drv.start()
    await drv.wait_done(idle=lambda: tb.irq_or(5_000))
    assert tb.edges_since(n0, s0) == model_edges(plan)
    assert len(tb.start_edges) == s0 + 1, "a START during the move restarted the engine"
    await ClockCycles(tb.clk, 100)
    assert not (await drv.status()).busy
    tb.finish()


@cocotb.test(timeout_time=2500, timeout_unit="us")  # measured 560 us
async def every_register_written_while_busy(dut) -> None:
    """Every register written during a move: the move runs as the model says; the motion registers take the value
    (for the next START), the stepping configuration and POSITION ignore it and flag CFG_BUSY / POS_BUSY (the last
    cause stays in ERR_CODE), ID does not change, STATUS written 0 clears nothing, CTRL's enables take it."""
    tb = await PeripheralTb.started(dut)
    drv = tb.driver()
    plan = valid_plan()
    await drv.program(plan)
    n0, s0 = tb.pins.mark()
    await drv.start()
    await RisingEdge(dut.step)
    ctrl = REGISTERS_BY_NAME["CTRL"]
    enables = ctrl.field("IRQ_DONE_EN").mask | ctrl.field("IRQ_ERROR_EN").mask
    rng = random.Random(3)
    want: dict[str, int] = {}
    assert (await drv.status()).busy
    for reg in REGISTERS:  # offset order: POSITION before DRIVE .. STEP_SPACE, so CFG_BUSY is the last cause
        before = await tb.bus.read(reg.offset)
        value = {"CTRL": enables, "STATUS": 0}.get(reg.name, rng.getrandbits(32))
        await tb.bus.write(reg.offset, value)
        if reg.name == "CTRL" or offset("STEPS") <= reg.offset <= offset("STOP_RATIO"):
            want[reg.name] = value & sum(f.mask for f in reg.fields if f.access == RW)
        elif reg.name in ("ID", "DRIVE", "STEP_WIDTH", "DIR_TIMING", "PWM_PERIOD", "STEP_SPACE"):
            want[reg.name] = before
    assert (await drv.status()).busy, "the move ended before the last write: not every write was while busy"
    with pytest.raises(StepRampError, match="CFG_BUSY"):
        await drv.wait_done(idle=lambda: tb.irq_or(5_000))
    assert tb.edges_since(n0, s0) == model_edges(plan), "a write while busy changed the move"
    assert await drv.position() == plan.steps, "POSITION written while busy: the write must be ignored"
    for name, value in want.items():
        got = await tb.bus.read(offset(name))
        assert got == value, f"{name} written while busy reads {got:#x}, expected {value:#x}"
    tb.finish()


#: (kind, pulses to wait before the command, the phase it then lands in) on trap_long_cruise (ramps of ~40 steps).
STOP_CASES = stop_cases((10, 300, 1175))


@cocotb.test(timeout_time=12, timeout_unit="ms")  # measured 2.6 ms (the slower top)
async def soft_and_hard_stop(dut) -> None:
    """SOFT_STOP and HARD_STOP through the bus in ACCEL, RUN and DECEL: every edge as the model predicts, position
    equal to the pulses seen, a soft stop ending at the slow end of a decel ramp, no pulse after a hard stop."""
    tb = await PeripheralTb.started(dut)
    await tb.configure(Outputs(mode="half", step_width=4, dir_setup=12, dir_hold=6), enable=True)
    stop_edges = tb.watch_stops()
    prof = PROFILES_BY_NAME["trap_long_cruise"]
    drv = tb.driver(prof.args())
    plan = drv.plan(prof.steps, prof.accel, prof.decel, prof.speed)
    position = 0
    for kind, wait_pulses, phase in STOP_CASES:
        await drv.program(plan)
        edges, request, _ = await tb.stop_after(drv, stop_edges, kind, wait_pulses, phase, drv.start)
        check_stopped(plan, kind, phase, request, edges, wait_pulses)
        position += -len(edges) if plan.direction else len(edges)
        assert await drv.position() == position, f"{kind} stop in {phase}: position is not the pulses seen"
    tb.finish()


@cocotb.test(timeout_time=1500, timeout_unit="us")  # measured 343 us (the slower top)
async def hard_stop_cancels_a_held_start(dut) -> None:
    """HARD_STOP or SOFT_STOP while the stepping logic holds a START for DIR setup, or HARD_STOP in the same CTRL
    write as START: DONE without error, no STEP pulse, POSITION unchanged; the next move runs as the model says."""
    tb = await PeripheralTb.started(dut)
    await tb.configure(Outputs(mode="half", step_width=4, dir_setup=3000, dir_hold=10), enable=True)
    drv = tb.driver()
    backwards = plan_move(**{**PROFILES_BY_NAME["trap_basic"].args(), "steps": -40})
    assert backwards.direction == 1 and int(dut.dir.value) == 0
    # 1: a direction change: DIR changes, then the start waits 3000 clocks for DIR setup; stop it meanwhile.
    await drv.program(backwards)
    n0 = len(tb.step_edges)
    await drv.start()
    await ClockCycles(tb.clk, 200)
    assert (await drv.status()).busy, "the held start shows as BUSY"
    await drv.hard_stop()
    status = await drv.wait_done(idle=lambda: tb.irq_or(500))
    assert not status.error and not status.busy
    await ClockCycles(tb.clk, 4000)
    assert len(tb.step_edges) == n0, "a STEP pulse after the hard stop cancelled the held start"
    assert await drv.position() == 0
    assert int(dut.dir.value) == 1, "DIR had changed before the stop; it stays"
    # 1b: the same with SOFT_STOP (the motor is at rest: nothing to decelerate), back to direction 0.
    await drv.program(valid_plan())
    await drv.start()
    await ClockCycles(tb.clk, 200)
    assert (await drv.status()).busy
    await drv.soft_stop()
    status = await drv.wait_done(idle=lambda: tb.irq_or(500))
    assert not status.error
    await ClockCycles(tb.clk, 4000)
    assert len(tb.step_edges) == n0 and await drv.position() == 0
    assert int(dut.dir.value) == 0
    # 2: START and HARD_STOP in one write: the stop wins.
    forwards = valid_plan()
    await drv.program(forwards)
    ctrl = REGISTERS_BY_NAME["CTRL"]
    await tb.bus.write(offset("CTRL"), ctrl.field("START").mask | ctrl.field("HARD_STOP").mask, strobe=0x1)
    status = await drv.wait_done(idle=lambda: tb.irq_or(500))
    assert not status.error
    await ClockCycles(tb.clk, 4000)
    assert len(tb.step_edges) == n0 and await drv.position() == 0
    # 3: the core goes on: the backwards move, edge for edge.
    await tb.configure(Outputs(mode="half", step_width=4, dir_setup=20, dir_hold=10), enable=True)
    edges, status = await tb.run_plan(drv, backwards)
    assert edges == model_edges(backwards) and not status.error
    assert await drv.position() == -40
    tb.finish()


@cocotb.test(timeout_time=2, timeout_unit="ms")  # measured 408 us (the slower top)
async def stepping_configuration(dut) -> None:
    """ENABLE follows CTRL.ENABLE and gates the windings; DRIVE .. PWM_PERIOD are written only while stopped."""
    tb = await PeripheralTb.started(dut)
    half = Outputs(mode="half", step_width=12, dir_setup=30, dir_hold=8)
    await tb.configure(half, enable=True)
    await ClockCycles(tb.clk, 3)
    assert int(dut.enable.value) == 1
    assert (await tb.bus.read(offset("DRIVE"))) == 3
    drv = tb.driver()
    plan = plan_move(**PROFILES_BY_NAME["trap_negative"].args())
    await drv.program(plan)
    await drv.start()
    await ClockCycles(tb.clk, 300)
    for name in ("DRIVE", "STEP_WIDTH", "DIR_TIMING", "PWM_PERIOD"):
        await tb.bus.write(offset(name), 0x4)  # during the move: ignored, flagged
    with pytest.raises(StepRampError, match="CFG_BUSY"):
        await drv.wait_done(idle=lambda: tb.irq_or(5_000))
    assert (await tb.bus.read(offset("DRIVE"))) == 3
    assert (await tb.bus.read(offset("STEP_WIDTH"))) == 12
    assert (await tb.bus.read(offset("DIR_TIMING"))) == 30 | 8 << 16
    assert await drv.position() == -plan.steps
    await ClockCycles(tb.clk, 20)
    levels = [int(getattr(dut, pin).value) for pin in ("a1", "a2", "b1", "b2")]
    assert any(levels), "half step: the windings are on while enabled"
    await tb.configure(half, enable=False)
    await ClockCycles(tb.clk, 3)
    assert int(dut.enable.value) == 0
    assert [int(getattr(dut, pin).value) for pin in ("a1", "a2", "b1", "b2")] == [0, 0, 0, 0]
    tb.finish()


# Limit: from the profiles this run is given (PROFILE_NAMES), as the model says they last (about 2x the measured time).
PROFILES_LIMIT_US = profiles_limit_us(json.loads(os.environ.get("PROFILE_NAMES", "[]")))


@cocotb.test(timeout_time=PROFILES_LIMIT_US, timeout_unit="us")
async def profiles_through_the_bus(dut) -> None:
    """Every requested profile, programmed by the driver from physical units, matches the model edge for edge."""
    names = json.loads(os.environ.get("PROFILE_NAMES", "[]"))
    if not names:
        return
    tb = await PeripheralTb.started(dut, idle=bool(env_int("BUS_IDLE", 0)))
    await tb.configure(Outputs(**json.loads(os.environ.get("OUTPUTS", "{}"))), enable=True)
    await tb.driver().enable_irq(done=True, error=True)
    problems: list[str] = []
    position = 0
    for name in names:
        prof = PROFILES_BY_NAME[name]
        drv = tb.driver(prof.args())
        plan = drv.plan(prof.steps, prof.accel, prof.decel, prof.speed)
        edges, status = await tb.run_plan(drv, plan)
        position += prof.steps
        if edges != model_edges(plan):
            problems.append(f"{name}: {edges_differ(edges, model_edges(plan))}")
        if status.error or await drv.position() != position:
            problems.append(f"{name}: error={status.error} position {await drv.position()} expected {position}")
    assert not problems, "\n".join(problems)
    tb.finish()


@cocotb.test(timeout_time=3000, timeout_unit="us")
async def jog_through_the_bus(dut) -> None:
    """Jog (an endless segment, docs/algorithm.md "Changes while moving") through the bus with the driver: forwards
    ended by SOFT_STOP in RUN, backwards by SOFT_STOP in ACCEL, and by HARD_STOP; every edge as
    stepramp.models.engine.segment_edges says, POSITION the pulses seen; a plain move after them runs as the model
    says (the driver cleared the segment registers)."""
    tb = await PeripheralTb.started(dut)
    await tb.configure(Outputs(mode="half", step_width=4, dir_setup=12, dir_hold=6), enable=True)
    stop_edges = tb.watch_stops()
    drv = tb.driver()
    position = 0
    jogs = ((100.0, "soft", 20, "RUN"), (-100.0, "soft", 3, "ACCEL"), (60.0, "hard", 15, "RUN"))
    for speed, kind, wait, phase in jogs:
        jog = functools.partial(drv.jog, speed, 20000.0, 15000.0)
        edges, request, seg = await tb.stop_after(drv, stop_edges, kind, wait, phase, jog)
        want = segment_edges(seg, drv.prescale, stop=(kind, request))
        assert edges == want, f"jog {speed}, {kind} stop: {edges_differ(edges, want)}"
        position += -len(edges) if speed < 0 else len(edges)
        assert await drv.position() == position, f"jog {speed}: position is not the pulses seen"
    plan = valid_plan()
    edges, status = await tb.run_plan(drv, plan)
    assert edges == model_edges(plan), f"the move after the jogs: {edges_differ(edges, model_edges(plan))}"
    assert not status.error
    tb.finish()


@cocotb.test(timeout_time=40, timeout_unit="ms")
async def change_and_queue_refusals(dut) -> None:
    """CTRL.CHANGE and CTRL.QUEUE refused (docs/algorithm.md, "The take-over, the queue and the script contract"):
    while idle (ERROR with code CHANGE, nothing moves); a CHANGE for a pulse already past and one against the running
    direction (code CHANGE, the motion goes on exactly as the model says); a staging write while a QUEUE is pending
    (code STAGED: the register keeps the staged value, STATUS.PENDING is set) and the queued move, which then starts
    when the first ends and runs as the model says; POSITION the sum of both."""
    tb = await PeripheralTb.started(dut)
    drv = tb.driver()
    plan = valid_plan()
    ctrl = offset("CTRL")
    for bit in ("CHANGE", "QUEUE"):
        await drv.clear_flags()
        await drv.access.write(ctrl, REGISTERS_BY_NAME["CTRL"].field(bit).mask, strobe=0x1)
        st = await drv.status()
        assert (st.error, st.err_name, st.busy, st.pending) == (True, "CHANGE", False, False), f"{bit} while idle: {st}"
    n0, s0 = len(tb.step_edges), len(tb.start_edges)
    await drv.clear_flags()
    await drv.program(plan)
    await drv.start()
    while len(tb.step_edges) < n0 + 5:
        await RisingEdge(dut.step)
    prof = PROFILES_BY_NAME["trap_basic"]
    seg = plan_change(0.0, 10, prof.accel, prof.decel, prof.speed, prof.spr, prof.fclk, prof.prescale).segment
    for pulse, direction, what in ((2, 0, "a pulse already past"), (plan.steps - 2, 1, "the other direction")):
        await drv.clear_flags()
        await drv.change(seg, direction, pulse)
        await ClockCycles(tb.clk, 4)  # the engine answers two clocks after the register file's strobe
        st = await drv.status()
        assert (st.error, st.err_name, st.busy) == (True, "CHANGE", True), f"CHANGE for {what}: {st}"
    back = dataclasses.replace(plan, direction=1)
    await drv.clear_flags()
    await drv.queue(back)
    st = await drv.status()
    assert (st.error, st.pending) == (False, True), f"QUEUE while moving: {st}"
    await drv.access.write(offset("STEPS"), 5)
    st = await drv.status()
    assert (st.error, st.err_name, st.pending) == (True, "STAGED", True), f"a staging write while pending: {st}"
    assert await drv.access.read(offset("STEPS")) == -back.steps & 0xFFFF_FFFF, "the refused write changed STEPS"
    await drv.clear_flags()
    while len(tb.start_edges) < s0 + 2:
        await RisingEdge(dut.core_inst.busy)
    await drv.clear_flags()  # the first move's DONE
    await drv.wait_done(idle=lambda: tb.irq_or(2000))
    first, second = tb.edges_since(n0, s0)[: plan.steps], tb.edges_since(n0 + plan.steps, s0 + 1)
    assert first == model_edges(plan), f"the move under refused changes: {edges_differ(first, model_edges(plan))}"
    assert second == model_edges(back), f"the queued move: {edges_differ(second, model_edges(back))}"
    assert await drv.position() == 0, "POSITION after a move and the queued move back"
    tb.finish()


@cocotb.test(timeout_time=400, timeout_unit="us")  # measured 60 us
async def change_past_the_last_pulse_is_refused(dut) -> None:
    """A CHANGE naming a pulse past the running motion's last pulse L (CHANGE_AT = L + 1) is refused at the engine's
    answer (docs/algorithm.md, "The take-over, the queue and the script contract": `P <= L`): ERROR with code CHANGE
    and PENDING low four clocks after the write, the staging free (a later staging write sets no STAGED), the motion
    exactly the model's. CHANGE_AT = L is accepted (PENDING) and taken over at pulse L: every edge the model's."""
    tb = await PeripheralTb.started(dut)
    drv = tb.driver()
    args = design_args(60, 70.0, 6.0, 6.0)
    plan = plan_move(**args)
    last = plan.steps - 1
    keys = ("accel", "decel", "speed", "spr", "fclk", "prescale")
    seg = plan_change(0.0, 10, *(args[k] for k in keys)).segment
    for pulse in (last + 1, last):
        await drv.clear_flags()
        await drv.program(plan)
        n0, s0 = len(tb.step_edges), len(tb.start_edges)
        await drv.start()
        while len(tb.step_edges) < n0 + 6:
            await RisingEdge(dut.step)
        await drv.change(seg, plan.direction, pulse)
        await ClockCycles(tb.clk, 4)  # the engine answers two clocks after the register file's strobe
        st = await drv.status()
        if pulse > last:
            assert (st.error, st.err_name, st.pending, st.busy) == (True, "CHANGE", False, True), f"P = L + 1: {st}"
            await drv.clear_flags()
            await drv.access.write(offset("STEPS"), plan.steps)  # the staging is free: no STAGED
            st = await drv.status()
            assert (st.error, st.pending) == (False, False), f"a staging write after the refusal: {st}"
            want = model_edges(plan)
        else:
            assert (st.error, st.pending, st.busy) == (False, True, True), f"P = L: {st}"
            want = change_edges(Segment.of_move(plan), pulse, seg, args["prescale"])
        st = await drv.wait_done(idle=lambda: tb.irq_or(5_000))
        got = tb.edges_since(n0, s0)
        assert got == want, f"CHANGE_AT = {pulse} (L = {last}): {edges_differ(got, want)}"
    tb.finish()


#: The queued start's window (docs/stepramp_plb.md, STATUS.BUSY): the read or write train's phases, enough to put one
#: access on every clock of a bus access period.
QUEUE_PHASES = 6


@cocotb.test(timeout_time=4, timeout_unit="ms")  # measured 0.9 ms
async def queued_start_is_never_idle(dut) -> None:
    """A move queued behind a running one starts as a START written at the engine's done: no STATUS read between the
    QUEUE and the queued move's end shows the core idle (BUSY and PENDING both 0), and no POSITION write in that window
    is taken (POS_BUSY; POSITION ends at the sum of both moves). Each run sends a train of back-to-back reads, or
    POSITION writes, across the first move's last pulse, its phase moved by one clock per run (QUEUE_PHASES runs), in
    the same and in the other direction with DIR setup 500 and hold 6 (the held start)."""
    tb = await PeripheralTb.started(dut)
    await tb.configure(Outputs(dir_setup=500, dir_hold=6))
    drv = tb.driver()
    args = design_args(40, 70.0, 6.0, 6.0)
    first = plan_move(**args)
    first_edges = model_edges(first)
    gap = first_edges[-1] - first_edges[-2]
    position = 0
    for what in ("read", "write"):
        for back in (False, True):
            second = plan_move(**{**args, "steps": -30 if back else 30})
            for phase in range(QUEUE_PHASES):
                await drv.clear_flags()
                await drv.program(first)
                n0 = len(tb.step_edges)
                await drv.start()
                await drv.queue(second)
                assert (await drv.status()).pending, "the QUEUE was not taken"
                while len(tb.step_edges) < n0 + first.steps - 1:
                    await RisingEdge(dut.step)
                await ClockCycles(tb.clk, gap - 12 + phase)
                for k in range(12):
                    if what == "read":
                        st = await drv.status()
                        assert st.busy or st.pending, f"phase {phase}, read {k}: the core looks idle: {st}"
                    else:
                        await drv.access.write(offset("POSITION"), 1000)
                await drv.clear_flags()
                while (await drv.status()).busy:
                    await tb.irq_or(500)
                position += first.steps + (-30 if back else 30)
                got = await drv.position()
                assert got == position, f"{what} phase {phase}: POSITION {got}, expected {position}"
    tb.finish()


REGISTER_TESTS = [
    "reset_values_and_id",
    "read_write_every_register",
    "byte_enables",
    "concurrent_reads_and_writes",
    "unmapped_offsets_answer_with_error",
    "w1c_flags_and_interrupt",
    "bad_register_values_flag_an_error",
    "position_register",
    "position_preset_keeps_the_field",
    "motion_registers_are_shadowed",
    "start_while_busy_is_ignored",
    "every_register_written_while_busy",
    "stepping_configuration",
    "soft_and_hard_stop",
    "hard_stop_cancels_a_held_start",
    "jog_through_the_bus",
    "change_and_queue_refusals",
    "change_past_the_last_pulse_is_refused",
    "queued_start_is_never_idle",
]


@pytest.mark.parametrize("top", TOPS)
def test_registers(top: str) -> None:
    """Register behaviour through each top (the masters insert idle cycles / backpressure in some tests)."""
    run_cocotb(top, "test_peripheral", build_dir(f"{top}_registers"), testcase=REGISTER_TESTS)


#: Stepping outputs per chunk of profiles: every mode is used in a motion test, with the monitors on.
CHUNK_OUTPUTS = [
    {"mode": "half", "step_width": 5, "dir_setup": 20, "dir_hold": 10},
    {"mode": "pwm", "ustep_log2": 4, "step_width": 10, "dir_setup": 7, "dir_hold": 3, "pwm_period": 40},
    {"mode": "full", "step_width": 30},
]
CHUNKS = len(CHUNK_OUTPUTS)


@pytest.mark.parametrize("chunk", range(CHUNKS))
@pytest.mark.parametrize("top", TOPS)
def test_profiles(top: str, chunk: int) -> None:
    """All profiles through each top and the driver; chunk 0 without bus idle, the others with idle/backpressure."""
    names = [p.name for p in PROFILES[chunk::CHUNKS]]
    run_cocotb(
        top,
        "test_peripheral",
        build_dir(f"{top}_profiles_{chunk}"),
        testcase="profiles_through_the_bus",
        extra_env={
            "PROFILE_NAMES": json.dumps(names),
            "BUS_IDLE": str(int(chunk > 0)),
            "BUS_SEED": str(chunk),
            "OUTPUTS": json.dumps(CHUNK_OUTPUTS[chunk]),
        },
    )


def test_plan_writes_cover_every_motion_register() -> None:
    """The driver writes each motion register exactly once (no simulator needed)."""
    addrs = [a for a, _ in plan_writes(valid_plan())]
    motion = [r.offset for r in REGISTERS if offset("STEPS") <= r.offset <= offset("STOP_RATIO")]
    assert sorted(addrs) == motion
