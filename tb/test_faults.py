# SPDX-License-Identifier: MIT
"""The faults that adversarial tests found (issue 11), through both tops, each against an independent expectation:

* a START held by the stepping logic (DIR hold / setup) runs the move of the moment START was written, whatever is
  written during the hold, and the STEPS = -2^31 and PRESCALE = 0 checks judge those values (stepramp.models.engine);
* pulses never merge on the STEP pin: a pulse closer than STEP_WIDTH + STEP_SPACE to the previous one stops the move
  with error STEP_SPACE (stepramp.models.engine.first_space_fault names it), and a start is held until its first pulse
  keeps that distance from the previous move's last one;
* a reset during a move never cuts a STEP pulse short, and what it does to DIR, ENABLE, the windings and POSITION is
  what docs/stepramp_plb.md says;
* the core decodes word addresses: the low two address bits pick nothing (docs/registers.md).
"""

from __future__ import annotations

import itertools

import pytest
from cocotb.triggers import ClockCycles, FallingEdge, ReadOnly, RisingEdge

from peripheral_tb import TOPS, PeripheralTb
from stepramp.board.driver import Outputs, StepRamp, StepRampError, plan_writes
from stepramp.board.plan import Plan, plan_move
from stepramp.board.regmap import LIVE, REGISTERS, offset
from stepramp.models.engine import edges as model_edges
from stepramp.models.engine import first_space_fault, min_gap
from stepramp.sim.profiles import PROFILES_BY_NAME, exact_plan
from stepramp.sim.runner import run_cocotb
from tbutil import build_dir, cocotb, now_cycles

TIMEOUT_MS = 40


def trap(steps: int) -> Plan:
    return plan_move(**{**PROFILES_BY_NAME["trap_basic"].args(), "steps": steps})


async def idle(tb: PeripheralTb) -> None:
    await tb.irq_or(2_000)


async def program(tb: PeripheralTb, plan: Plan) -> None:
    """Write a plan's registers as they are (also plans the driver would refuse)."""
    for addr, value in plan_writes(plan):
        await tb.bus.write(addr, value)


async def held(tb: PeripheralTb, drv: StepRamp) -> None:
    """START is held by the stepping logic: STATUS.BUSY, but the engine has not started."""
    assert (await drv.status()).busy, "the held start shows as BUSY"
    assert int(tb.dut.core_inst.busy.value) == 0, "the engine started: the start was not held"


@cocotb.test(timeout_time=TIMEOUT_MS, timeout_unit="ms")
async def held_start_keeps_its_move(dut) -> None:
    """DIR_TIMING setup 2000 / hold 10, a move of -75 steps, START; while the start is held for DIR setup, the
    next move (+80) is programmed. The held start runs -75 steps edge for edge; the next START runs +80."""
    tb = await PeripheralTb.started(dut)
    await tb.configure(Outputs(mode="half", step_width=4, dir_setup=2000, dir_hold=10), enable=True)
    drv = tb.driver()
    backwards, forwards = trap(-75), trap(80)
    await drv.program(backwards)
    first = tb.pins.mark()
    await drv.start()
    await ClockCycles(tb.clk, 100)
    await held(tb, drv)
    await drv.program(forwards)  # the register map allows it: the staging copy
    await held(tb, drv)
    await drv.wait_done(idle=lambda: idle(tb))
    assert tb.edges_since(*first) == model_edges(backwards), "the held start did not run the move it was given"
    assert await drv.position() == -75
    second = tb.pins.mark()
    await drv.start()
    await drv.wait_done(idle=lambda: idle(tb))
    assert tb.edges_since(*second) == model_edges(forwards), "the staged move did not run at the next START"
    assert await drv.position() == 5
    tb.finish()


@cocotb.test(timeout_time=TIMEOUT_MS, timeout_unit="ms")
async def bad_values_written_during_a_held_start(dut) -> None:
    """STEPS = -2^31 or PRESCALE = 0 written while a start is held: the held move runs as it was written at START
    (edge for edge), and the next START, which takes the bad value, is rejected with STEPS or PRESCALE."""
    tb = await PeripheralTb.started(dut)
    await tb.configure(Outputs(mode="half", step_width=4, dir_setup=2000, dir_hold=10), enable=True)
    drv = tb.driver()
    position = 0
    for plan, register, bad, cause in (
        (trap(-40), "STEPS", 0x8000_0000, "STEPS"),
        (trap(40), "PRESCALE", 0, "PRESCALE"),
    ):
        await drv.program(plan)
        mark = tb.pins.mark()
        await drv.start()  # a direction change: held for DIR setup
        await ClockCycles(tb.clk, 100)
        await held(tb, drv)
        await tb.bus.write(offset(register), bad)
        await drv.wait_done(idle=lambda: idle(tb))
        assert tb.edges_since(*mark) == model_edges(plan), f"{register} written during the hold changed the move"
        position += -40 if plan.direction else 40
        assert await drv.position() == position
        mark = tb.pins.mark()
        await drv.start()
        with pytest.raises(StepRampError, match=cause):
            await drv.wait_done(idle=lambda: idle(tb))
        await ClockCycles(tb.clk, 3000)
        assert tb.pins.mark()[0] == mark[0], f"a pulse from a START with {register} = {bad:#x}"
        assert await drv.position() == position
    tb.finish()


#: (plan, STEP_WIDTH, STEP_SPACE): 1-, 2- and 3-tick intervals on both sides of STEP_WIDTH + STEP_SPACE.
SPACING_CASES = [
    (exact_plan(2, 1, 1.0), 1, 1),  # the adversarial case: pulses at edges 2 and 3, one 2-clock pulse on the pin
    (exact_plan(2, 1, 2.0), 1, 1),
    (exact_plan(2, 1, 3.0), 2, 2),
    (exact_plan(6, 8, 20, 2.0), 8, 8),
    (exact_plan(6, 8, 20, 2.0), 8, 9),
    (exact_plan(9, 4, 20, 1.5), 3, 2),
    (exact_plan(5, 5, 30, 30, 1.0, direction=1), 2, 3),
    (exact_plan(5, 5, 30, 30, 3.0, direction=1), 10, 6),
]


@cocotb.test(timeout_time=TIMEOUT_MS, timeout_unit="ms")
async def pulses_never_merge(dut) -> None:
    """Every pulse the model keeps reaches the pin as its own STEP pulse, at least STEP_WIDTH + STEP_SPACE after
    the previous one; the first pulse that would come closer ends the move with error STEP_SPACE, POSITION and
    STEP_COUNT exact (it is neither emitted nor counted)."""
    tb = await PeripheralTb.started(dut)
    drv = tb.driver()
    position = 0
    faults = 0
    for plan, width, space in SPACING_CASES:
        await tb.configure(Outputs(mode="half", step_width=width, step_space=space, dir_setup=5), enable=True)
        normal = model_edges(plan)
        k = first_space_fault(normal, min_gap(width, space))
        expected = normal if k is None else normal[:k]
        label = f"P={plan.prescale} W={width} S={space} model {normal}"
        await program(tb, plan)
        mark = tb.pins.mark()
        await drv.start()
        if k is None:
            await drv.wait_done(idle=lambda: idle(tb))
        else:
            faults += 1
            with pytest.raises(StepRampError, match="STEP_SPACE"):
                await drv.wait_done(idle=lambda: idle(tb))
        await ClockCycles(tb.clk, 100)
        pins = tb.edges_since(*mark)
        assert pins == expected, f"{label}: STEP rising edges {pins}"
        position += -len(expected) if plan.direction else len(expected)
        assert await drv.position() == position, label
        assert await tb.bus.read(offset("STEP_COUNT")) == len(expected), label
        gaps = [b - a for a, b in itertools.pairwise(pins)]
        assert all(g >= min_gap(width, space) for g in gaps), f"{label}: STEP rising edges {gaps} clocks apart"
        tb.finish()  # the STEP width monitor: every pulse exactly its width
    assert 0 < faults < len(SPACING_CASES)


@cocotb.test(timeout_time=TIMEOUT_MS, timeout_unit="ms")
async def start_keeps_the_spacing_after_a_move(dut) -> None:
    """A START written right after a move's last pulse is held until the new pulse 0 is STEP_WIDTH + STEP_SPACE
    after it (stepramp.models.stepping.gate_timing: exactly that distance here), so two moves' pulses never merge."""
    tb = await PeripheralTb.started(dut)
    width, space = 200, 100
    await tb.configure(Outputs(mode="half", step_width=width, step_space=space), enable=True)
    drv = tb.driver()
    one = exact_plan(1, 1, 1.0)
    await program(tb, one)
    rises: list[int] = []
    await drv.start()
    await RisingEdge(tb.dut.step)
    rises.append(now_cycles())
    await drv.start()  # the first move is over (its only pulse was its last): accepted, and held
    await held(tb, drv)
    await RisingEdge(tb.dut.step)
    rises.append(now_cycles())
    await ClockCycles(tb.clk, 50)
    await drv.wait_done(idle=lambda: idle(tb))
    assert rises[1] - rises[0] == min_gap(width, space), f"STEP rising edges at {rises}"
    assert await drv.position() == 2
    tb.finish()


@cocotb.test(timeout_time=TIMEOUT_MS, timeout_unit="ms")
async def reset_during_a_move(dut) -> None:
    """Reset while STEP is high, 1, 2 or 13 clocks into a 25-clock pulse: the pulse keeps its 25 clocks. From the
    first reset edge on, ENABLE and the windings are off and DIR is 0 (even inside its hold time); after it no
    pulse comes, every register reads its reset value (POSITION 0: the machine must be homed again), and the core
    runs the next move as the model says."""
    tb = await PeripheralTb.started(dut)
    width = 25
    for cut in (1, 2, 13):
        await tb.configure(Outputs(mode="half", step_width=width, dir_hold=40), enable=True)
        drv = tb.driver()
        await drv.program(trap(-75))
        await drv.start()
        for _ in range(5):
            await RisingEdge(tb.dut.step)
        rise = now_cycles()
        assert int(tb.dut.dir.value) == 1
        tb.finish()  # the DIR hold monitor would see the documented DIR change inside its hold time
        await ClockCycles(tb.clk, cut - 1)
        assert int(tb.dut.step.value) == 1
        reset_task = cocotb.start_soon(tb.reset_pulse())
        await FallingEdge(tb.clk)
        await RisingEdge(tb.clk)  # the first reset edge
        await ReadOnly()
        outputs = {n: int(getattr(tb.dut, n).value) for n in ("step", "dir", "enable", "a1", "a2", "b1", "b2")}
        assert outputs == {"step": 1, "dir": 0, "enable": 0, "a1": 0, "a2": 0, "b1": 0, "b2": 0}, (
            f"cut {cut}: outputs after the first reset edge {outputs}"
        )
        await FallingEdge(tb.dut.step)
        fall = now_cycles()
        assert fall - rise == width, f"reset {cut} clocks into the pulse: STEP high {fall - rise} clocks"
        await reset_task
        mark = tb.pins.mark()
        await ClockCycles(tb.clk, 3000)
        assert tb.pins.mark()[0] == mark[0], "a STEP pulse after the reset"
        for reg in REGISTERS:
            if reg.name in LIVE:
                continue  # the clock count
            got = await tb.bus.read(reg.offset)
            assert got == reg.reset, f"cut {cut}: {reg.name} reads {got:#x} after reset, expected {reg.reset:#x}"
    await tb.configure(Outputs(mode="half", step_width=width), enable=True)
    edges, status = await tb.run_plan(tb.driver(), trap(30))
    assert edges == model_edges(trap(30)) and not status.error
    tb.finish()


@cocotb.test(timeout_time=TIMEOUT_MS, timeout_unit="ms")
async def word_addresses(dut) -> None:
    """The low two address bits are ignored on both buses: an access at offset + 1 .. 3 reaches the register at
    offset (IPIF: the whole word with its byte enables; AXI4-Lite: cocotbext-axi puts the unaligned address on
    AWADDR / ARADDR with the matching WSTRB, so one byte lane changes or is read)."""
    tb = await PeripheralTb.started(dut)
    steps = offset("STEPS")
    await tb.bus.write(steps, 0x1122_3344)
    word = 0x1122_3344
    for b in (1, 2, 3):
        new = word & ~(0xFF << (8 * b)) | (0xA0 + b) << (8 * b)
        if tb.top == "stepramp_axil":
            master = tb.bus.master
            got = int.from_bytes((await master.read(steps + b, 1)).data, "little")
            assert got == word >> (8 * b) & 0xFF, f"byte read at {steps + b:#x}: {got:#x}"
            await master.write(steps + b, bytes([0xA0 + b]))
        else:
            got = await tb.bus.read(steps + b)
            assert got == word, f"read at {steps + b:#x}: {got:#x}"
            assert await tb.bus.read(offset("ID") + b) == REGISTERS[0].reset
            await tb.bus.write(steps + b, new)
        word = new
        assert await tb.bus.read(steps) == word, f"a write at {steps + b:#x} did not reach the register"


@pytest.mark.parametrize("top", TOPS)
def test_faults(top: str) -> None:
    """The issue-11 faults through each top."""
    run_cocotb(top, "test_faults", build_dir(f"{top}_faults"))  # every test of this module
