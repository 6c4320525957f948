# SPDX-License-Identifier: MIT
"""The machine inputs through both single-axis tops (issue 16): LIMIT_NEG, LIMIT_POS, HOME and ESTOP with their
synchroniser, filter and polarity, the limits' stops and refusals, the ESTOP stop and fault, and the position latch
with its timestamp.

Every expectation comes from docs/algorithm.md, "Machine inputs", not from the RTL: a pin changed after clock edge a
reaches the filtered level at edge F = a + N + 2 (N = max(INPUT_FILTER, 1)); a bounce shorter than N samples never
does; a limit is a soft or hard stop committed at F + 1 (the engine samples it at F + 2), ESTOP a hard stop the
engine samples at F + 1; LATCH_TIME = F - r (r: the last edge that saw the reset) and LATCH_POS is POSITION after
edge F. The STEP edges of a stopped move are stepramp.models.engine.edges_with_stop's for that request edge.

Every test that drives ESTOP runs stepramp.sim.monitors's EstopMonitor: no STEP rising edge more than 2 clocks after the
filtered ESTOP edge. The ESTOP latencies it measured are printed (the closing figure of issue 16).
"""

from __future__ import annotations

import math
from typing import Any

import pytest
from cocotb.triggers import ClockCycles, FallingEdge, ReadOnly, RisingEdge, ValueChange

from peripheral_tb import TOPS, PeripheralTb
from stepramp.board.driver import Outputs, StepRamp
from stepramp.board.plan import Plan, plan_move
from stepramp.board.regmap import ERROR_CODES, REGISTERS_BY_NAME, offset
from stepramp.models.engine import edges as model_edges
from stepramp.models.engine import edges_with_stop, segment_edges
from stepramp.sim.clocking import CLK_PERIOD_PS, Cycles, now_periods
from stepramp.sim.coverage import watch_coverage
from stepramp.sim.monitors import EstopMonitor
from stepramp.sim.profiles import PROFILES_BY_NAME
from stepramp.sim.runner import run_cocotb
from tbutil import build_dir, cocotb, edges_differ

PINS = ("limit_neg", "limit_pos", "home", "estop")
STATUS = REGISTERS_BY_NAME["STATUS"]
CTRL = REGISTERS_BY_NAME["CTRL"]
CFG = REGISTERS_BY_NAME["INPUT_CFG"]
LEVEL_FIELDS = ("LIMIT_NEG", "LIMIT_POS", "HOME", "ESTOP")
EVENT_FIELDS = ("LIMIT_NEG_EV", "LIMIT_POS_EV", "HOME_EV", "ESTOP_FAULT")
IRQ_FIELDS = ("IRQ_LIMIT_NEG_EN", "IRQ_LIMIT_POS_EN", "IRQ_HOME_EN", "IRQ_ESTOP_EN", "IRQ_LATCH_EN")
#: The engine samples a limit's stop strobe at F + 2, the ESTOP stop at F + 1 (docs/algorithm.md, "Machine inputs").
LIMIT_SAMPLE = 2
ESTOP_SAMPLE = 1


def field(reg: Any, name: str, value: int = 1) -> int:
    f = reg.field(name)
    return (value << f.lsb) & f.mask


def get(reg: Any, name: str, word: int) -> int:
    f = reg.field(name)
    return (word & f.mask) >> f.lsb


def cfg_word(
    pol: int = 0, limit_en: int = 1, limit_hard: int = 0, latch_src: int = 0, on_active: int = 0, on_release: int = 0
) -> int:
    word = sum(field(CFG, f"POL_{name}", (pol >> i) & 1) for i, name in enumerate(LEVEL_FIELDS))
    word |= field(CFG, "LIMIT_EN", limit_en) | field(CFG, "LIMIT_HARD", limit_hard)
    word |= field(CFG, "LATCH_SRC", latch_src) | field(CFG, "LATCH_ON_ACTIVE", on_active)
    return word | field(CFG, "LATCH_ON_RELEASE", on_release)


class InputsTb:
    """A PeripheralTb with the machine inputs: pins driven between clock edges, the filtered levels and the reset's
    last edge watched, clock edges numbered from time 0 (edge k at k clock periods)."""

    def __init__(self, tb: PeripheralTb, reset_edge: int) -> None:
        self.tb, self.dut, self.clk = tb, tb.dut, tb.clk
        self.reset_edge = reset_edge
        self.core = tb.dut.core_inst
        self.filtered: list[tuple[int, int]] = []  # (edge, level vector) at every change of the filtered levels
        self.pol = 0
        self.filter = 1
        cocotb.start_soon(self._watch_levels())

    @classmethod
    async def started(cls, dut: Any) -> InputsTb:
        tb = PeripheralTb(dut, dut._name)
        rst = dut.core_inst.rst
        seen: list[float] = []

        async def release() -> None:
            await FallingEdge(rst)
            seen.append(now_periods(CLK_PERIOD_PS))

        task = cocotb.start_soon(release())
        await tb.reset()
        tb.bus = watch_coverage(dut.core_inst, tb.bus)
        assert task.done() and seen, "the reset's release was not seen"
        # rst falls between edge r (the last that saw it) and edge r + 1.
        return cls(tb, math.floor(seen[0]))

    async def _watch_levels(self) -> None:
        level = self.core.inputs_inst.level_r
        while True:
            await ValueChange(level)
            self.filtered.append((self.edge(), int(level.value)))

    def edge(self) -> int:
        """The most recent rising edge."""
        return math.floor(now_periods(CLK_PERIOD_PS) + 1e-6)

    async def pin(self, name: str, active: int) -> int:
        """Drive a pin to its active (1) or inactive level, after the next falling edge; returns the edge a before
        the change."""
        await FallingEdge(self.clk)
        level = active ^ ((self.pol >> PINS.index(name)) & 1)
        getattr(self.dut, name).value = level
        return self.edge()

    async def configure(self, filter_clocks: int, **cfg: int) -> None:
        """INPUT_FILTER and INPUT_CFG (while stopped); the pins first go to their inactive level under the new
        polarity, then every level settles and every event and the fault are cleared."""
        self.pol = cfg.get("pol", 0)
        bus = self.tb.bus
        for name in PINS:
            getattr(self.dut, name).value = (self.pol >> PINS.index(name)) & 1
        await bus.write(offset("INPUT_FILTER"), filter_clocks)
        await bus.write(offset("INPUT_CFG"), cfg_word(**cfg))
        self.filter = max(filter_clocks, 1)
        await ClockCycles(self.clk, self.filter + 8)
        await self.clear_events()

    async def clear_events(self) -> None:
        clear = sum(field(STATUS, name) for name in (*EVENT_FIELDS, "LATCHED", "DONE", "ERROR"))
        await self.tb.bus.write(offset("STATUS"), clear)

    async def status(self) -> int:
        return await self.tb.bus.read(offset("STATUS"))

    def filtered_edges(self, bit: int, since: int) -> list[tuple[int, int]]:
        """(edge, level) of every change of one filtered level at or after edge `since`."""
        out, last = [], 0  # (0 after reset)
        for edge, vector in self.filtered:
            level = (vector >> bit) & 1
            if level != last and edge >= since:
                out.append((edge, level))
            last = level
        return out

    def filtered_at(self, bit: int, since: int) -> int:
        """The edge of the first change of one filtered level at or after `since` (AssertionError if none)."""
        changes = self.filtered_edges(bit, since)
        assert changes, f"{PINS[bit]}: the filtered level did not change after edge {since}"
        return changes[0][0]

    async def wait_done(self, cycles: int = 400_000) -> int:
        """STATUS once DONE is set (then DONE and ERROR cleared), without the driver's raise on ERROR."""
        for _ in range(cycles // 200):
            word = await self.status()
            if get(STATUS, "DONE", word):
                await self.tb.bus.write(offset("STATUS"), field(STATUS, "DONE") | field(STATUS, "ERROR"))
                return word
            await Cycles(self.clk, 200)
        raise AssertionError("no DONE")


def trap(steps: int = 200) -> Plan:
    return plan_move(**{**PROFILES_BY_NAME["trap_basic"].args(), "steps": steps})


#: Pulses to wait before the input, and the phase the engine is then in: trap_basic has SA 31 and SD 169.
PHASES = ((10, "ACCEL"), (100, "RUN"), (185, "DECEL"))


async def move_until(ib: InputsTb, drv: StepRamp, plan: Plan, pulses: int) -> tuple[int, int]:
    """Program and start a move, return (first STEP record index, first start record index) once `pulses` pulses are
    out."""
    tb = ib.tb
    await drv.program(plan)
    n0, s0 = len(tb.step_edges), len(tb.start_edges)
    await drv.start()
    while len(tb.step_edges) < n0 + pulses:
        await RisingEdge(ib.dut.step)
    return n0, s0


# ---------------------------------------------------------------------------------------------------------------
# Filter and polarity
# ---------------------------------------------------------------------------------------------------------------


@cocotb.test(timeout_time=2, timeout_unit="ms")
async def filter_and_polarity(dut) -> None:
    """Each input, active high and active low, with FILTER 0 (acts as 1), 5 and 37: a clean change after edge a
    reaches the filtered level at a + N + 2; a bounce of N - 1 samples never does, one of N does; STATUS shows the
    level and the event, the event raises irq when enabled and clears with W1C; ESTOP's fault clears once released."""
    ib = await InputsTb.started(dut)
    bus = ib.tb.bus
    for filter_clocks in (0, 5, 37):
        for pol in (0, 0b1111):
            await ib.configure(filter_clocks, pol=pol)
            n = ib.filter
            for bit, name in enumerate(PINS):
                what = f"{name}, FILTER {filter_clocks}, {'active low' if pol else 'active high'}"
                irq_en = field(CTRL, IRQ_FIELDS[bit])
                await bus.write(offset("CTRL"), irq_en, strobe=0x2)
                # A bounce of N - 1 samples (N >= 2): the filtered level never moves.
                if n >= 2:
                    a = await ib.pin(name, 1)
                    await ClockCycles(ib.clk, n - 1)
                    await ib.pin(name, 0)
                    await ClockCycles(ib.clk, n + 6)
                    assert not ib.filtered_edges(bit, a), f"{what}: a bounce of {n - 1} samples passed the filter"
                # Activation.
                a = await ib.pin(name, 1)
                await ClockCycles(ib.clk, n + 6)
                f = ib.filtered_at(bit, a)
                assert f == a + n + 2, f"{what}: filtered edge {f - a} clocks after the pin's, expected {n + 2}"
                word = await ib.status()
                assert get(STATUS, LEVEL_FIELDS[bit], word) == 1, f"{what}: STATUS level not set"
                assert get(STATUS, EVENT_FIELDS[bit], word) == 1, f"{what}: STATUS event not set"
                await ReadOnly()
                assert int(dut.irq.value) == 1, f"{what}: no irq with its enable set"
                await FallingEdge(ib.clk)
                # W1C clears the event (ESTOP's fault only once the pin is released).
                await bus.write(offset("STATUS"), field(STATUS, EVENT_FIELDS[bit]))
                word = await ib.status()
                assert get(STATUS, EVENT_FIELDS[bit], word) == (1 if name == "estop" else 0), f"{what}: W1C"
                # Release: the same filter.
                a = await ib.pin(name, 0)
                await ClockCycles(ib.clk, n + 6)
                f = ib.filtered_at(bit, a)
                assert f == a + n + 2, f"{what}: released {f - a} clocks after the pin, expected {n + 2}"
                assert get(STATUS, LEVEL_FIELDS[bit], await ib.status()) == 0, f"{what}: STATUS level not cleared"
                await bus.write(offset("STATUS"), field(STATUS, EVENT_FIELDS[bit]))
                word = await ib.status()
                assert get(STATUS, EVENT_FIELDS[bit], word) == 0, f"{what}: the event does not clear"
                await bus.write(offset("CTRL"), 0, strobe=0x2)
                await ReadOnly()
                await ClockCycles(ib.clk, 2)
                assert int(dut.irq.value) == 0, f"{what}: irq stays with the event cleared"
                # A bounce of one sample just after a filtered edge (where the count restarts), swept over the
                # clocks around it, never passes a filter of N >= 2 either (one input: the filter is the same for each).
                if n >= 2 and pol == 0 and bit == 0:
                    for k in range(n - 1, n + 3):
                        a = await ib.pin(name, 1)
                        await ClockCycles(ib.clk, k)
                        await ib.pin(name, 0)
                        await ib.pin(name, 1)
                        await ClockCycles(ib.clk, n + 6)
                        got = ib.filtered_edges(bit, a)
                        assert [lv for _, lv in got] == [1], f"{what}: a 1-sample bounce {k} clocks in passed: {got}"
                        await ib.pin(name, 0)
                        await ClockCycles(ib.clk, n + 6)
                    await ib.clear_events()


# ---------------------------------------------------------------------------------------------------------------
# Limits
# ---------------------------------------------------------------------------------------------------------------


@cocotb.test(timeout_time=30, timeout_unit="ms")
async def limits_in_each_state(dut) -> None:
    """Each limit stops a motion towards it in ACCEL, RUN and DECEL, soft and hard, as a stop committed at F + 1
    (every STEP edge as the model's stop at F + 2), with ERROR LIMIT; the other limit changes nothing; a START
    towards an active limit is refused (no pulse), one away from it runs; a limit during a held start cancels it."""
    ib = await InputsTb.started(dut)
    tb = ib.tb
    await tb.configure(Outputs(step_width=4, dir_setup=12, dir_hold=6), enable=True)
    drv = tb.driver()
    limit_code = ERROR_CODES["LIMIT"][0]
    position = 0
    for hard in (0, 1):
        await ib.configure(3, limit_hard=hard)
        for name, steps in (("limit_pos", 200), ("limit_neg", -200)):
            bit = PINS.index(name)
            plan = trap(steps)
            for pulses, phase in PHASES:
                what = f"{name} {'hard' if hard else 'soft'} in {phase}"
                n0, s0 = await move_until(ib, drv, plan, pulses)
                a = await ib.pin(name, 1)
                word = await ib.wait_done()
                f = ib.filtered_at(bit, a)
                assert f == a + ib.filter + 2
                start = tb.start_edges[s0]
                want = edges_with_stop(plan, "hard" if hard else "soft", f + LIMIT_SAMPLE - start)
                got = tb.edges_since(n0, s0)
                assert got == want, f"{what}: {edges_differ(got, want)}"
                if hard or phase != "DECEL":  # (a soft stop in DECEL changes nothing: the move ends as planned)
                    assert len(got) < plan.steps, f"{what}: the move was not cut short"
                assert get(STATUS, "ERROR", word) and get(STATUS, "ERR_CODE", word) == limit_code, f"{what}: {word:#x}"
                position += -len(got) if plan.direction else len(got)
                assert await drv.position() == position
                # Towards the active limit: refused, nothing moves.
                await drv.program(plan)
                k = len(tb.step_edges)
                await drv.start()
                word = await ib.wait_done()
                await ClockCycles(ib.clk, 3000)
                assert len(tb.step_edges) == k, f"{what}: a START towards the active limit moved"
                assert get(STATUS, "ERR_CODE", word) == limit_code and get(STATUS, "ERROR", word)
                # Away from it: the whole move, as the model says.
                back = trap(-steps // 4)
                edges, status = await tb.run_plan(drv, back)
                assert edges == model_edges(back) and not status.error, f"{what}: the move away"
                position += -len(edges) if back.direction else len(edges)
                await ib.pin(name, 0)
                await ClockCycles(ib.clk, ib.filter + 8)
                await ib.clear_events()
        # The other limit active: a motion away from it is not touched.
        other = trap(60)
        n0, s0 = await move_until(ib, drv, other, 20)
        await ib.pin("limit_neg", 1)
        word = await ib.wait_done()
        assert tb.edges_since(n0, s0) == model_edges(other) and not get(STATUS, "ERROR", word)
        position += 60
        await ib.pin("limit_neg", 0)
        await ClockCycles(ib.clk, ib.filter + 8)
        await ib.clear_events()
    # A limit during a START held for DIR setup (a direction change): the start is cancelled, no pulse.
    await tb.configure(Outputs(step_width=4, dir_setup=3000, dir_hold=6), enable=True)
    await ib.configure(3)
    k = len(tb.step_edges)
    await drv.program(trap(-50))
    await drv.start()
    await ClockCycles(ib.clk, 300)
    assert get(STATUS, "BUSY", await ib.status()), "the held start shows as BUSY"
    await ib.pin("limit_neg", 1)
    word = await ib.wait_done()
    await ClockCycles(ib.clk, 4000)
    assert len(tb.step_edges) == k, "a STEP pulse after a limit cancelled the held start"
    assert get(STATUS, "ERR_CODE", word) == limit_code
    assert await drv.position() == position
    tb.finish()


# ---------------------------------------------------------------------------------------------------------------
# ESTOP
# ---------------------------------------------------------------------------------------------------------------


@cocotb.test(timeout_time=20, timeout_unit="ms")
async def estop_in_every_kind_of_motion(dut) -> None:
    """ESTOP in ACCEL, RUN, DECEL, during a jog and during a held start: every STEP edge as the model's hard stop
    sampled at F + 1, none more than 2 clocks after F (EstopMonitor); the fault latches, ENABLE drops, a START is
    refused, the fault does not clear while ESTOP is active, and after release and clear the next move runs."""
    ib = await InputsTb.started(dut)
    tb = ib.tb
    monitor = EstopMonitor(ib.core.estop_stop, [dut.step]).start()
    drv = tb.driver()
    estop_code = ERROR_CODES["ESTOP"][0]
    plan = trap(200)
    # "aimed": the pin timed so that the filtered edge F is the engine edge of a pulse (its STEP rises at F + 1, the
    # latest a STEP edge can come), "aimed - 1": one clock later (that pulse is the first one suppressed), and
    # "aimed + 1": one clock earlier (F + 1, where the engine samples the stop, is that pulse's own engine edge: a
    # stop one clock late, from the latched fault alone, would let it through).
    aim = {"aimed": 0, "aimed - 1": 1, "aimed + 1": -1}
    cases: list[tuple[str, int]] = [(phase, pulses) for pulses, phase in PHASES] + [
        ("jog", 40),
        ("held", 0),
        ("aimed", 100),
        ("aimed - 1", 100),
        ("aimed + 1", 100),
    ]
    for filter_clocks in (1, 9):
        for case, pulses in cases:
            what = f"ESTOP (FILTER {filter_clocks}) in {case}"
            held = case == "held"
            await tb.configure(Outputs(step_width=4, dir_setup=3000 if held else 12, dir_hold=6), enable=True)
            await ib.configure(filter_clocks)
            n0, s0 = len(tb.step_edges), len(tb.start_edges)
            segment = None
            if case == "jog":
                segment = await drv.jog(100.0 if await drv.position() < 0 else -100.0, 20000.0, 15000.0)
                while len(tb.step_edges) < n0 + pulses:
                    await RisingEdge(dut.step)
            elif held:  # a direction change: the START waits 3000 clocks for DIR setup
                await drv.program(trap(-200 if int(dut.dir.value) == 0 else 200))
                await drv.start()
                await ClockCycles(ib.clk, 300)
            else:
                n0, s0 = await move_until(ib, drv, plan, pulses)
            if case.startswith("aimed"):
                # pulse pulses + 3's engine edge E (the model's edge from the start); F = E (or E + 1 for "- 1")
                e = tb.start_edges[s0] + model_edges(plan)[pulses + 3] + aim[case]
                await ClockCycles(ib.clk, e - max(filter_clocks, 1) - 2 - ib.edge() - 1)
            a = await ib.pin("estop", 1)
            word = await ib.wait_done()
            f = ib.filtered_at(3, a)
            assert f == a + max(filter_clocks, 1) + 2
            got = tb.edges_since(n0, s0)
            if held:
                assert got == [], f"{what}: pulses after the held start was stopped"
            else:
                request = f + ESTOP_SAMPLE - tb.start_edges[s0]
                want = (
                    edges_with_stop(plan, "hard", request)
                    if segment is None
                    else segment_edges(segment, drv.prescale, stop=("hard", request))
                )
                assert got == want, f"{what}: {edges_differ(got, want)}"
            assert get(STATUS, "ERR_CODE", word) == estop_code, f"{what}: ERR_CODE {get(STATUS, 'ERR_CODE', word)}"
            word = await ib.status()
            assert get(STATUS, "ESTOP_FAULT", word) and get(STATUS, "ESTOP", word)
            await ReadOnly()
            assert int(dut.enable.value) == 0, f"{what}: ENABLE still high"
            await FallingEdge(ib.clk)
            assert not get(CTRL, "ENABLE", await tb.bus.read(offset("CTRL"))), f"{what}: CTRL.ENABLE not cleared"
            # A START during the fault: refused, nothing moves; the fault does not clear while ESTOP is active.
            k = len(tb.step_edges)
            await drv.program(plan)
            await drv.start()
            word = await ib.wait_done()
            assert get(STATUS, "ERR_CODE", word) == estop_code
            await tb.bus.write(offset("STATUS"), field(STATUS, "ESTOP_FAULT"))
            assert get(STATUS, "ESTOP_FAULT", await ib.status()), f"{what}: the fault cleared while ESTOP is active"
            await ib.pin("estop", 0)
            await ClockCycles(ib.clk, filter_clocks + 8)
            assert get(STATUS, "ESTOP_FAULT", await ib.status()), "the fault cleared by itself"
            await ClockCycles(ib.clk, 3000)
            assert len(tb.step_edges) == k, f"{what}: a STEP pulse during the fault"
            await ib.clear_events()
            assert not get(STATUS, "ESTOP_FAULT", await ib.status())
            await drv.set_enable(True)
            short = trap(40 if await drv.position() < 0 else -40)
            edges, status = await tb.run_plan(drv, short)
            assert edges == model_edges(short) and not status.error, f"{what}: the move after the fault"
    tb.finish()
    monitor.stop()
    monitor.check()
    after = sorted(set(monitor.latencies))
    print(f"ESTOP: {len(monitor.edges)} filtered edges; STEP rising edges after them at {after} clocks")
    assert after == [1], f"the aimed ESTOP: a STEP edge 1 clock after F was expected, seen {after}"


# ---------------------------------------------------------------------------------------------------------------
# The position latch
# ---------------------------------------------------------------------------------------------------------------


@cocotb.test(timeout_time=10, timeout_unit="ms")
async def position_latch(dut) -> None:
    """LATCH_POS and LATCH_TIME at HOME's activation and release edges during a move, at LIMIT_NEG's activation
    (which also stops the move), and at LIMIT_POS's release (nothing while it is held) and activation at rest:
    LATCH_TIME = F - r, LATCH_POS = POSITION after edge F (the pulses whose engine edge is at or before F, from the
    model); the first edge only until LATCHED is cleared; the irq enable."""
    ib = await InputsTb.started(dut)
    tb = ib.tb
    await tb.configure(Outputs(step_width=4, dir_setup=12, dir_hold=6), enable=True)
    drv = tb.driver()
    bus = tb.bus
    position = 0

    async def latched() -> tuple[int, int, int]:
        word = await ib.status()
        pos = await bus.read(offset("LATCH_POS"))
        t = await bus.read(offset("LATCH_TIME_LO")) | (await bus.read(offset("LATCH_TIME_HI"))) << 32
        return get(STATUS, "LATCHED", word), pos - (1 << 32) * (pos >> 31), t

    def expected(f: int, n0: int, s0: int, start_pos: int, sign: int, plan: Plan) -> tuple[int, int]:
        start = tb.start_edges[s0]
        pulses = sum(1 for e in model_edges(plan) if start + e <= f)
        return start_pos + sign * pulses, f - ib.reset_edge

    # HOME's activation in ACCEL, RUN and DECEL, its release in RUN
    for release, pulses in ((0, 10), (0, 100), (0, 185), (1, 100)):
        await ib.configure(6, latch_src=1, on_active=1 - release, on_release=release)
        await bus.write(offset("CTRL"), field(CTRL, "IRQ_LATCH_EN"), strobe=0x2)
        if release:
            await ib.pin("home", 1)
            await ClockCycles(ib.clk, 20)
        plan = trap(200)
        n0, s0 = await move_until(ib, drv, plan, pulses)
        a = await ib.pin("home", 1 - release)
        await ClockCycles(ib.clk, 20)
        f = ib.filtered_at(2, a)
        assert f == a + 6 + 2
        flag, pos, t = await latched()
        want_pos, want_t = expected(f, n0, s0, position, 1, plan)
        assert flag == 1, "LATCHED not set"
        assert (pos, t) == (want_pos, want_t), f"latched ({pos}, {t}), expected ({want_pos}, {want_t})"
        assert int(dut.irq.value) == 1, "no irq with IRQ_LATCH_EN"
        # A second edge before the clear: not latched.
        await ib.pin("home", release)
        await ClockCycles(ib.clk, 30)
        await ib.pin("home", 1 - release)
        await ClockCycles(ib.clk, 30)
        assert (await latched())[1:] == (pos, t), "a second edge overwrote the latch before the clear"
        await ib.wait_done()
        position += plan.steps
        await ib.pin("home", 0)
        await ClockCycles(ib.clk, 20)
        await ib.clear_events()
        assert (await latched())[0] == 0
    # LIMIT_NEG as the source, with its own stop (homing onto a limit): the latch at F, the soft stop at F + 2.
    await ib.configure(6, latch_src=2, on_active=1)
    plan = trap(-200)
    n0, s0 = await move_until(ib, drv, plan, 100)
    a = await ib.pin("limit_neg", 1)
    await ib.wait_done()
    f = ib.filtered_at(0, a)
    flag, pos, t = await latched()
    assert flag and (pos, t) == expected(f, n0, s0, position, -1, plan), f"limit latch ({pos}, {t})"
    got = tb.edges_since(n0, s0)
    assert got == edges_with_stop(plan, "soft", f + LIMIT_SAMPLE - tb.start_edges[s0])
    # LIMIT_POS as the source (3), at rest: its release latches at F and nothing while it is held; its activation.
    here = await bus.read(offset("POSITION"))
    here -= (1 << 32) * (here >> 31)
    for release in (1, 0):
        await ib.configure(6, latch_src=3, on_active=1 - release, on_release=release)
        if release:
            await ib.pin("limit_pos", 1)
            await ClockCycles(ib.clk, 30)
            await ib.clear_events()
            await ClockCycles(ib.clk, 10)
            assert (await latched())[0] == 0, "LIMIT_POS latched while it is held, before its release"
        a = await ib.pin("limit_pos", 1 - release)
        await ClockCycles(ib.clk, 20)
        f = ib.filtered_at(1, a)
        flag, pos, t = await latched()
        assert flag == 1 and (pos, t) == (here, f - ib.reset_edge), f"LIMIT_POS latch ({flag}, {pos}, {t}) at F = {f}"
        await ib.pin("limit_pos", 0)
        await ClockCycles(ib.clk, 20)
    tb.finish()


TESTS = ["filter_and_polarity", "limits_in_each_state", "estop_in_every_kind_of_motion", "position_latch"]


@pytest.mark.parametrize("test", TESTS)
@pytest.mark.parametrize("top", TOPS)
def test_inputs(top: str, test: str) -> None:
    """The machine inputs through each top (one simulation per test, so that pytest -n spreads them)."""
    run_cocotb(top, "test_inputs_rtl", build_dir(f"{top}_inputs_{test}"), testcase=[test])
