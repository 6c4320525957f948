# SPDX-License-Identifier: MIT
"""Every readable register read through the bus, during a move and after it, against an independent expectation:
both tops (issue 11, point 4).

Two trapezoid moves (ACCEL, RUN and DECEL all occur; PRESCALE 4 and 1; forwards across the 32-bit POSITION wrap,
then backwards after a DIR change; the second programmed during the first). At a handful of pulses per phase (and
at pulse 0 and every phase change) a burst of reads of STATUS, POSITION, CUR_DELAY and STEP_COUNT is aimed so that
one of them samples at the pulse's own edge (still the old values) or at the edge after it (the new ones); around
the last pulse, reads at its edge and the two after it (END_READS); once per phase, and before, between and after
the moves, a sweep reads every register of stepramp.board.regmap. Each read is compared with:

* the bit-exact model (stepramp.models.engine.edges / phases, the plan's PRESCALE) for STATUS.STATE / BUSY / DIR,
  POSITION, CUR_DELAY and STEP_COUNT, at the exact clock edge at which the register file sampled the read;
* the sticky-flag rules of docs/stepramp_plb.md for DONE, ERROR and ERR_CODE (a POSITION write during the second
  move sets ERROR with POS_BUSY); PENDING 0 (no CHANGE or QUEUE is written);
* the last value written, masked to the register's RW fields (stepramp.board.regmap), for every storage register and
  CTRL (its WS bits read 0); the reset value for constant read-only registers (ID).

The sample edge of a read: the register file samples rd at rising edge S (rd is high in the cycle before S; its
ack rises at S, which is checked) and then returns the engine's registered outputs as set by edges before S. The
engine's edge 0 is the rising edge of its busy (E0; docs/stepramp_engine.md), pulse k is at E0 + e_k with e_k =
stepramp.models.engine.edges(plan)[k], so with s = S - E0:

* STEP_COUNT = #{k : e_k < s}; POSITION = start position +- STEP_COUNT (mod 2^32); BUSY = s <= e_L;
* after pulse k (e_k < s <= e_(k+1), k < L): STATE = phases[k], CUR_DELAY = (e_(k+1) - e_k) / PRESCALE (the ticks
  of interval k + 1), saturated to 32 bits; before pulse 0 and after the last: STOP and 0;
* DONE is set by the register file at E0 + e_L + 1 (it samples the engine's done), visible from s = e_L + 2.

Nothing is sampled clock by clock: the testbench waits on the rd / wr / ack strobes, busy and STEP, and on Timers.
registers_during_and_after_moves runs on an idle-free bus (and checks that the aimed reads did hit both sides of
pulse edges); registers_with_bus_idle repeats it with idle cycles and AXI backpressure, the reads landing wherever
the bus lets them. READBACK_SEED (printed; random unless set) picks the start position, the watched pulses and the
sweep orders.
"""

from __future__ import annotations

import bisect
import os
import random
from collections import defaultdict
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any

import pytest
from cocotb.triggers import Event, RisingEdge, Timer
from cocotb.utils import get_sim_time

from peripheral_tb import TOPS, PeripheralTb
from stepramp.board.driver import Outputs, StepRamp
from stepramp.board.plan import Plan
from stepramp.board.regmap import ERROR_CODES, REGISTERS, REGISTERS_BY_NAME, RO, RW, STAGING, WS, Register, offset
from stepramp.models.engine import ACCEL, DECEL, RUN
from stepramp.models.engine import edges as model_edges
from stepramp.models.engine import phases as model_phases
from stepramp.models.stepping import STEP_LATENCY
from stepramp.sim.clocking import CLK_PERIOD_PS
from stepramp.sim.profiles import PROFILES_BY_NAME
from stepramp.sim.runner import run_cocotb
from tbutil import build_dir, cocotb

#: Registers whose value the engine drives (the rest are storage, CTRL, or constant).
DYNAMIC = ("STATUS", "POSITION", "CUR_DELAY", "STEP_COUNT")
#: STATUS.STATE codes (docs/registers.md).
STATE_CODE = {"STOP": 0, ACCEL: 1, RUN: 2, DECEL: 3}
#: The two moves: forwards with PRESCALE 4, then backwards (a DIR change) with PRESCALE 1.
MOVES = ("trap_prescale_4", "trap_negative")
#: Reads aimed at each watched pulse, and watched pulses per phase.
BURST = len(DYNAMIC)
PER_PHASE = 4
#: Around the last pulse of move 0 and move 1: (register, sample edge - e_L, or None: as soon as possible). Between
#: them: the last interval (e_L), BUSY gone but DONE not yet (e_L + 1), DONE (e_L + 2, and later).
END_READS = (
    (("CUR_DELAY", 0), ("STATUS", 2), ("STEP_COUNT", None), ("POSITION", None)),
    (("STATUS", 1), ("CUR_DELAY", None), ("STEP_COUNT", None), ("POSITION", None), ("STATUS", None)),
)
WORD = 0xFFFF_FFFF


def rw_mask(reg: Register) -> int:
    return sum(f.mask for f in reg.fields if f.access == RW)


def merge(old: int, new: int, strobe: int) -> int:
    """old with the byte lanes selected by strobe taken from new."""
    lanes = sum(0xFF << (8 * b) for b in range(4) if strobe >> b & 1)
    return (old & ~lanes | new & lanes) & WORD


def is_motion(reg: Register) -> bool:
    """The staging registers (STEPS .. STOP_RATIO, SEGMENT .. CHANGE_AT): plain storage that may be written at any
    time while nothing is pending (docs/registers.md; this test never writes CHANGE or QUEUE, so never PENDING)."""
    return reg.name in STAGING


class EdgeClock:
    """Rising edges of the clock numbered from a reference edge; waits with Timers, never clock by clock."""

    def __init__(self, clk: Any) -> None:
        self.clk = clk
        self.origin = 0

    async def sync(self) -> None:
        await RisingEdge(self.clk)
        self.origin = round(get_sim_time("ps"))

    def edge(self) -> int:
        """The most recent rising edge (at an edge's own time step: that edge)."""
        return (round(get_sim_time("ps")) - self.origin) // CLK_PERIOD_PS

    async def until(self, n: int) -> None:
        """Return at rising edge n (at once if it has passed)."""
        if n <= self.edge():
            return
        half_before = self.origin + n * CLK_PERIOD_PS - CLK_PERIOD_PS // 2
        now = round(get_sim_time("ps"))
        if half_before > now:
            await Timer(half_before - now, unit="ps")
        await RisingEdge(self.clk)
        assert self.edge() == n, f"aimed at edge {n}, at {self.edge()}"


class Watch:
    """The rising edges of a signal, as clock-edge numbers. strobe: a one-cycle strobe sampled at the next rising
    edge (it rises after edge n, the logic samples it at n + 1); otherwise a register output (it rises at edge n)."""

    def __init__(self, clock: EdgeClock, signal: Any, strobe: bool) -> None:
        self.clock = clock
        self.edges: list[int] = []
        self.event = Event()
        cocotb.start_soon(self._run(signal, 1 if strobe else 0))

    async def _run(self, signal: Any, delay: int) -> None:
        while True:
            await RisingEdge(signal)
            self.edges.append(self.clock.edge() + delay)
            self.event.set()

    async def wait_count(self, n: int) -> None:
        while len(self.edges) < n:
            self.event.clear()
            await self.event.wait()


@dataclass
class View:
    """The engine outputs the register file sees at a sample edge."""

    busy: bool = False
    state: str = "STOP"
    direction: int = 0
    count: int = 0
    delay: int = 0
    position: int = 0


@dataclass
class Move:
    """One accepted move: its engine edge 0 (absolute) and the model's pulse edges and phases."""

    start: int
    plan: Plan
    edges: list[int] = field(init=False)
    phases: list[str] = field(init=False)

    def __post_init__(self) -> None:
        self.edges = model_edges(self.plan)
        self.phases = model_phases(self.plan)
        assert len(self.edges) >= 2, "the expectation below is for moves of 2 steps or more"
        p = self.plan.prescale
        assert all((b - a) % p == 0 for a, b in zip(self.edges, self.edges[1:], strict=False))

    def view(self, s: int, position: int) -> View:
        """At sample edge s (relative to edge 0, s >= 1): the registered outputs set by edges 0 .. s - 1."""
        n = bisect.bisect_left(self.edges, s)  # pulses emitted: e_k < s
        inside = 0 < n < len(self.edges)  # after pulse n - 1, interval n counting down
        delay = min((self.edges[n] - self.edges[n - 1]) // self.plan.prescale, WORD) if inside else 0
        sign = -1 if self.plan.direction else 1
        return View(
            busy=s <= self.edges[-1],
            state=self.phases[n - 1] if inside else "STOP",
            direction=self.plan.direction,
            count=n,
            delay=delay,
            position=(position + sign * n) & WORD,
        )


@dataclass
class Read:
    name: str
    sample: int
    got: int
    want: int
    move: int | None  # index of the move whose edge 0 precedes the sample
    s: int | None  # sample edge relative to that move's edge 0
    d: int | None  # sample edge relative to the latest pulse edge at or before it
    busy: bool
    state: str


class Expected:
    """What every register reads at a given sample edge, from the writes made (in program order, each with the
    edge at which the register file sampled it) and the moves started (each with its engine edge 0)."""

    def __init__(self) -> None:
        self.by_offset = {r.offset: r for r in REGISTERS}
        # Storage registers and CTRL: the RW bits last written (WS bits read 0).
        self.shadow = {
            r.offset: r.reset & rw_mask(r)
            for r in REGISTERS
            if r.name not in DYNAMIC and rw_mask(r) and all(f.access in (RW, WS) for f in r.fields)
        }
        self.timeline: list[tuple[int, str, Any]] = []  # (edge, "load" | "move", value | Move)
        self.moves: list[Move] = []
        self.flags: list[tuple[int, int, str, int]] = []  # (edge, 0 clear / 1 set, flag, value)
        self.starts: list[int] = []  # sample edges of START writes (one per move)

    # -- engine and flags -------------------------------------------------------------------------------------
    def engine(self, sample: int) -> View:
        view = View()
        for edge, kind, data in self.timeline:
            if edge >= sample:
                break
            if kind == "load":
                view.position = data
            else:
                view = data.view(sample - edge, view.position)
        for i, w in enumerate(self.starts):
            started = self.moves[i].start if i < len(self.moves) else None
            # The stepping logic's gate holds the start from w + 1 to E0: BUSY, engine unchanged; not modelled here.
            assert not (w + 1 < sample and (started is None or sample <= started)), (
                f"a read sampled at {sample}, between START (edge {w}) and the engine's start: not modelled"
            )
        return view

    def sticky(self, sample: int) -> dict[str, int]:
        """DONE, ERROR (set and cleared at sample edges; a set wins over a clear at the same edge) and ERR_CODE."""
        out = {"DONE": 0, "ERROR": 0, "ERR_CODE": 0}
        for edge, is_set, flag, value in sorted(self.flags):
            if edge >= sample:
                break
            if flag == "ERR_CODE" or is_set:
                out[flag] = value
            else:
                out[flag] = 0
        return out

    def add_move(self, start: int, plan: Plan) -> Move:
        assert len(self.starts) == len(self.moves) + 1 and self.starts[-1] < start
        move = Move(start, plan)
        self.moves.append(move)
        self.timeline.append((start, "move", move))
        # The register file samples the engine's done (high after edge E0 + e_L) at the next edge.
        self.flags.append((start + move.edges[-1] + 1, 1, "DONE", 1))
        return move

    # -- bus ----------------------------------------------------------------------------------------------------
    def write(self, addr: int, value: int, strobe: int, sample: int) -> None:
        reg = self.by_offset[addr & ~3]
        view = self.engine(sample)  # what the register file's eng_busy is at that edge
        data = merge(0, value, strobe)
        if reg.name == "POSITION":
            if view.busy:  # ignored, flagged
                code = ERROR_CODES["POS_BUSY"][0]
                self.flags += [(sample, 1, "ERROR", 1), (sample, 1, "ERR_CODE", code)]
            else:  # pos_load after edge w, the engine loads it at w + 1
                self.timeline.append((sample + 1, "load", merge(view.position, value, strobe)))
        elif reg.name == "STATUS":
            for name in ("DONE", "ERROR"):
                if data & reg.field(name).mask:
                    self.flags.append((sample, 0, name, 0))
        elif reg.offset in self.shadow:
            commands = [f.name for f in reg.fields if f.access == WS and data & f.mask]
            assert commands in ([], ["START"]), f"{reg.name} {commands}: not modelled in this test"
            if commands:
                assert not view.busy, "START while busy: not modelled in this test"
                self.starts.append(sample)
            assert not view.busy or is_motion(reg) or reg.name == "CTRL", f"{reg.name} written while busy"
            self.shadow[reg.offset] = merge(self.shadow[reg.offset], value, strobe) & rw_mask(reg)
        else:
            assert all(f.access == RO for f in reg.fields), f"write to {reg.name}: not modelled"

    def value(self, reg: Register, sample: int) -> tuple[int, View]:
        view = self.engine(sample)
        if reg.name == "STATUS":
            want = {
                "STATE": STATE_CODE[view.state],
                "BUSY": int(view.busy),
                "DIR": view.direction,
                "DIR_FAULT": 0,
                "PENDING": 0,  # no CHANGE or QUEUE is ever written here (write() allows START only)
                # the machine inputs are held inactive here (tb/test_inputs_rtl.py drives them)
                **dict.fromkeys(("LIMIT_NEG", "LIMIT_POS", "HOME", "ESTOP", "LIMIT_NEG_EV", "LIMIT_POS_EV"), 0),
                **dict.fromkeys(("HOME_EV", "ESTOP_FAULT", "LATCHED"), 0),
                **self.sticky(sample),
            }
            missing = [f.name for f in reg.fields if f.name not in want]
            assert not missing, f"no expectation for STATUS fields {missing}"
            return sum((want[f.name] << f.lsb) & f.mask for f in reg.fields), view
        mask = sum(f.mask for f in reg.fields)
        if reg.name == "POSITION":
            return view.position & mask, view
        if reg.name == "CUR_DELAY":
            return view.delay & mask, view
        if reg.name == "STEP_COUNT":
            return view.count & mask, view
        if reg.offset in self.shadow:
            return self.shadow[reg.offset], view
        if reg.name == "TIME_LO":
            # TIME after edge k is k - r, r the last edge that saw the reset: edge -3 here (the bench waits two edges
            # after the release, and edge 0 is the next); a read sampled at edge s returns it as after edge s - 1.
            return (sample - 1 + 3) & mask, view
        assert all(f.access == RO for f in reg.fields), f"no expectation for {reg.name}"
        return reg.reset, view  # a constant (ID)

    def classify(self, name: str, sample: int, got: int) -> Read:
        reg = REGISTERS_BY_NAME[name]
        want, view = self.value(reg, sample)
        idx = next((i for i in reversed(range(len(self.moves))) if self.moves[i].start < sample), None)
        s = d = None
        if idx is not None:
            move = self.moves[idx]
            s = sample - move.start
            k = bisect.bisect_right(move.edges, s) - 1
            d = s - move.edges[k] if k >= 0 else None
        return Read(name, sample, got, want, idx, s, d, view.busy, view.state)


class CheckedBus:
    """The driver's register access, recording the sample edge of every access and checking every read."""

    def __init__(self, inner: Any, clock: EdgeClock, dut: Any, expect: Expected) -> None:
        self.inner = inner
        self.expect = expect
        core = dut.core_inst
        self.rd = Watch(clock, core.rd, strobe=True)
        self.wr = Watch(clock, core.wr, strobe=True)
        self.ack = Watch(clock, core.ack, strobe=False)
        self.reads: list[Read] = []

    async def read(self, addr: int) -> int:
        n = len(self.rd.edges)
        got = await self.inner.read(addr)
        assert len(self.rd.edges) == n + 1, f"read {addr:#x}: {len(self.rd.edges) - n} rd strobes"
        sample = self.rd.edges[n]
        assert sample in self.ack.edges[-3:], f"read {addr:#x}: no ack at its sample edge {sample}"
        self.reads.append(self.expect.classify(self.expect.by_offset[addr].name, sample, got))
        return got

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None:
        n = len(self.wr.edges)
        await self.inner.write(addr, value, strobe)
        assert len(self.wr.edges) > n, f"write {addr:#x}: no wr strobe"
        self.expect.write(addr, value, strobe, self.wr.edges[-1])


class Readback:
    """The test's moves and the reads aimed at them."""

    def __init__(self, dut: Any, seed: int, idle: bool) -> None:
        self.dut = dut
        self.rng = random.Random(seed)
        self.tb = PeripheralTb(dut, dut._name, idle=idle, seed=seed)
        self.expect = Expected()
        self.latency = self.gap = 1
        self.bursts = 0
        self.aimed = self.hit = 0

    async def setup(self) -> None:
        await self.tb.reset()
        self.clock = EdgeClock(self.tb.clk)
        await self.clock.sync()
        self.bus = CheckedBus(self.tb.bus, self.clock, self.dut, self.expect)
        self.tb.bus = self.bus
        self.busy = Watch(self.clock, self.dut.core_inst.busy, strobe=False)  # the engine's: its edge 0
        self.step = Watch(self.clock, self.dut.step, strobe=False)
        # Bus timing: clocks from the edge a read is issued at to its sample edge, and between back-to-back reads.
        lat, gaps = [], []
        for _ in range(3):
            await self.clock.until(self.clock.edge() + 1)
            issued = self.clock.edge()
            await self.bus.read(offset("ID"))
            await self.bus.read(offset("ID"))
            first, second = (r.sample for r in self.bus.reads[-2:])
            lat.append(first - issued)
            gaps.append(second - first)
        self.latency, self.gap = min(lat), min(gaps)
        cocotb.log.info(f"read latency {self.latency} clocks, back-to-back reads {self.gap} clocks apart")

    async def read_at(self, name: str, sample: int | None = None) -> None:
        """Read a register so that the register file samples it at edge `sample` (or as soon after as possible)."""
        if sample is not None:
            await self.clock.until(sample - self.latency)
        await self.bus.read(offset(name))
        if sample is not None:
            self.aimed += 1
            self.hit += self.bus.reads[-1].sample == sample

    async def sweep(self) -> None:
        """Every register of the map, in a random order."""
        for reg in self.rng.sample(REGISTERS, len(REGISTERS)):
            await self.bus.read(reg.offset)

    async def burst(self, move: Move, k: int) -> None:
        """The dynamic registers around pulse k: one of them sampled at its edge (offset 0: the values before the
        pulse) or at the next (offset 1: after it), alternating every BURST bursts; the others one bus access
        before it and right after it."""
        i = self.bursts
        self.bursts += 1
        at = move.start + move.edges[k] + (i // BURST) % 2
        for j in range(BURST):
            await self.read_at(DYNAMIC[(i + j) % BURST], max(at + (j - 1) * self.gap, move.start + 1))

    def watched(self, move: Move) -> tuple[list[int], list[int]]:
        """Pulses to aim bursts at (pulse 0, every phase change, PER_PHASE more per phase; not the last, see
        END_READS) and one pulse per phase after which to sweep every register (kept clear of the bursts)."""
        length = len(move.edges) - 1
        sweeps, bursts = [], {0}
        bursts |= {k for k in range(1, length) if move.phases[k] != move.phases[k - 1]}
        for phase in (ACCEL, RUN, DECEL):
            ks = [k for k in range(length) if move.phases[k] == phase]
            assert len(ks) > 2 * PER_PHASE, f"too few pulses in {phase}"
            sweeps.append(ks[len(ks) // 2])
            step = len(ks) // (PER_PHASE + 1)
            bursts |= {ks[step * (j + 1) - self.rng.randrange(step // 2 + 1)] for j in range(PER_PHASE)}
        bursts -= {k + dk for k in sweeps for dk in range(-1, 4)} | {length}  # the last: END_READS
        return sorted(bursts), sweeps

    async def move(
        self, drv: StepRamp, plan: Plan, during: tuple[str, Callable[[], Awaitable[None]]] | None = None
    ) -> Move:
        """Start the programmed move, read through it, and sweep once it is done. `during`: an action taken
        before the sweep in that phase."""
        first_step, first_start = len(self.step.edges), len(self.busy.edges)
        await drv.start()
        await self.busy.wait_count(first_start + 1)
        move = self.expect.add_move(self.busy.edges[first_start], plan)
        bursts, sweeps = self.watched(move)
        actions: list[tuple[int, Callable[[], Awaitable[None]]]] = [
            (move.edges[k] - self.gap, lambda k=k: self.burst(move, k)) for k in bursts
        ]
        for phase, k in zip((ACCEL, RUN, DECEL), sweeps, strict=True):
            actions.append((move.edges[k] + 2, lambda k=k: self.clock.until(move.start + move.edges[k] + 2)))
            if during is not None and during[0] == phase:
                actions.append((move.edges[k] + 2, during[1]))
            actions.append((move.edges[k] + 2, self.sweep))
        for _, action in sorted(actions, key=lambda a: a[0]):
            await action()
        last = move.start + move.edges[-1]
        for name, at in END_READS[(len(self.expect.moves) - 1) % len(END_READS)]:
            await self.read_at(name, None if at is None else last + at)
        await self.clock.until(last + 2 - self.latency)
        await self.sweep()  # after the move: DONE visible
        got = [e - move.start - STEP_LATENCY for e in self.step.edges[first_step:]]
        assert got == move.edges, f"the STEP pin does not follow the model ({len(got)} pulses)"
        return move


async def two_moves(dut, idle: bool) -> Readback:
    """The two moves with reads all along; returns the test's state with every read checked."""
    seed = int(os.environ.get("READBACK_SEED", "1"))
    cocotb.log.info(f"READBACK_SEED={seed}")
    rb = Readback(dut, seed, idle)
    await rb.setup()
    tb, rng = rb.tb, rb.rng
    first_prof, second_prof = (PROFILES_BY_NAME[name] for name in MOVES)
    drv = tb.driver(first_prof.args())
    # Start just below 2^31 - 1: the first move's POSITION wraps to negative numbers. (Before configure: the
    # winding monitors take the position from there.)
    await drv.set_position((1 << 31) - 1 - rng.randrange(first_prof.steps // 2))
    await tb.configure(Outputs(mode="half", step_width=5, dir_setup=20, dir_hold=10), enable=True)
    drv, second = tb.driver(first_prof.args()), tb.driver(second_prof.args())
    await drv.enable_irq(done=True, error=False)
    await rb.sweep()  # idle

    first = drv.plan(first_prof.steps, first_prof.accel, first_prof.decel, first_prof.speed)
    plan2 = second.plan(second_prof.steps, second_prof.accel, second_prof.decel, second_prof.speed)
    assert first.direction == 0 and plan2.direction == 1
    await drv.program(first)
    # The second move is programmed during the first (RUN): the storage registers read the new values at once.
    await rb.move(drv, first, during=(RUN, lambda: second.program(plan2)))
    await drv.clear_flags()
    await rb.sweep()
    # The second: a POSITION write during it is ignored and flagged (ERROR, ERR_CODE POS_BUSY).
    await rb.move(second, plan2, during=(RUN, lambda: drv.set_position(rng.randrange(1 << 31))))
    await drv.clear_flags()
    await rb.sweep()  # ERR_CODE keeps POS_BUSY
    tb.finish()

    reads = rb.bus.reads
    per_reg: dict[str, list[Read]] = defaultdict(list)
    for r in reads:
        per_reg[r.name].append(r)
    for name, rs in per_reg.items():
        wrong = sum(r.got != r.want for r in rs)
        sides = sorted({r.d for r in rs if r.d is not None and r.d < 2})
        cocotb.log.info(
            f"{name:14} {len(rs):4} reads, {sum(r.busy for r in rs):3} during a move, {wrong} wrong"
            + (f"; sampled {sides} edges after a pulse edge" if name in DYNAMIC else "")
        )
    cocotb.log.info(f"{rb.hit} of {rb.aimed} aimed reads sampled at the edge aimed at")
    bad = [r for r in reads if r.got != r.want]
    assert not bad, f"{len(bad)} of {len(reads)} reads differ:\n" + "\n".join(
        f"  {r.name} at edge {r.sample} (s = {r.s}, {r.d} after a pulse edge, {r.state}): "
        f"read {r.got:#010x}, expected {r.want:#010x}"
        for r in bad[:25]
    )
    # Every register during each phase and after a move.
    for reg in REGISTERS:
        rs = per_reg[reg.name]
        seen = {r.state for r in rs if r.busy} | {"after" for r in rs if r.move is not None and not r.busy}
        assert seen >= {ACCEL, RUN, DECEL, "after"}, f"{reg.name}: read only in {sorted(seen)}"
    return rb


@cocotb.test(timeout_time=5, timeout_unit="ms")
async def registers_during_and_after_moves(dut) -> None:
    """Every readable register through the bus at many moments of two moves and after them; the dynamic ones
    sampled exactly at pulse edges (the values before the pulse) and one edge later (after it)."""
    rb = await two_moves(dut, idle=False)
    for name in DYNAMIC:
        sides = {r.d for r in rb.bus.reads if r.name == name and r.busy}
        assert {0, 1} <= sides, f"{name}: never sampled at a pulse edge and at the edge after ({sorted(sides)})"
    # STATUS at the last pulse's edge + 1 (BUSY gone, DONE not yet) and, where the bus is fast enough, + 2 (DONE).
    ends = {r.s - rb.expect.moves[r.move].edges[-1] for r in rb.bus.reads if r.name == "STATUS" and r.move is not None}
    assert 1 in ends and (2 in ends or rb.gap > 2), f"STATUS not sampled just after the last pulse ({sorted(ends)})"


@cocotb.test(timeout_time=5, timeout_unit="ms")
async def registers_with_bus_idle(dut) -> None:
    """The same with idle cycles on the bus (and backpressure on every AXI channel): the reads land wherever the
    bus lets them, each still compared at its own sample edge."""
    await two_moves(dut, idle=True)


#: The cocotb tests, each in a simulation of its own (a test that is not the first in its simulation runs on a clock
#: shifted by one time step, which the STEP width monitor's float arithmetic does not tolerate).
TESTS = ("registers_during_and_after_moves", "registers_with_bus_idle")


@pytest.mark.parametrize("test", TESTS)
@pytest.mark.parametrize("top", TOPS)
def test_readback(top: str, test: str) -> None:
    """Every readable register through each top, during two moves and after them (issue 11, point 4)."""
    seed = int(os.environ.get("READBACK_SEED") or random.randrange(1 << 32))
    print(f"READBACK_SEED={seed}")
    run_cocotb(
        top, "test_readback", build_dir(f"{top}_readback_{test}"), extra_env={"READBACK_SEED": str(seed)}, testcase=test
    )
