# SPDX-License-Identifier: MIT
"""stepramp_isqrt: the rounded root and the latency of every run against the model (stepramp.models.exact_unit.isqrt:
exact.root of R 4^e, and L = floor(msb(R) / 2) + e + 5, 1 for R = 0, e = min(extra, G_EXTRA)), with busy, done and
the held root checked in every clock.

How the bench checks every clock without waking at every clock (Bench, the technique of tb/test_next_delay_exact.py):
a monitor on each output logs its changes with the simulated time, and the bench, which wakes only where it drives
the inputs or reads the outputs (Timers to falling edges), fails on any logged change where none may come; an output
that does not change holds. A run is driven at a falling edge, sampled by the next rising edge e, and read at the
falling edge after e: busy '1', done '0', the previous root held. From there busy and done may not change before edge
e + L (the model's latency), and then only at that edge; the root only at the edges e + 1 .. e + L (it shows the
iteration while busy). The done cycle is read at its falling edge: done '1', busy '0', the model's root; the next read
(after the next run's sampling edge, or at the end of an idle gap) sees done '0' again and the root held. An idle gap
is read at its last falling edge (busy '0', done '0', the root held), and no output may change in it but done at its
first edge: so the outputs held these values all through it. A run with a wrong latency is stepped on, a clock at a
time, until its done (or the limit), to report the latency seen.

The root's monitor would wake at every clock of a run; it watches where the root must hold over more than one edge:
from the start of an idle gap to the read after the next sampling edge (then it logs the run's first change, which
must be at e + 1 .. e + L, and sleeps until the next gap). Between a done cycle and the next run started in it there
is one edge (e), with the root read on both sides: a change there shows in the second read. The monitors of busy and
done watch all the time.

What is driven when: a run's radicand, extra and start '1' at the falling edge before its sampling edge e; random
radicand, extra and start at the falling edge after e and again at one random falling edge between it and the done's
edge (the model's latency): start is '1' at the done's edge in about half of the runs, and the inputs change once
more mid-run (a unit that reads one while busy, in whichever cycle, computes with garbage); a random radicand and
extra with start '0' at the start of an idle gap. The garbage has a random generator of its own (garbage_rng, from
the seed): the runs a test draws (radicands, extras, pauses) do not depend on it.

* isqrt_against_model: width 4 and 12, every radicand (0 .. 4095 at 12, all ones included: the rounding carries into
  the root's extra bit); width 80 (the next-delay unit's) and 128 (the largest): the corners (0, 1, 2^k, 2^k - 1,
  2^k + 1, s^2 - 1, s^2, s^2 + s, s^2 + s + 1, all ones) and random radicands of every bit length. Runs back to back
  (start held into the done cycle) or after a pause; while busy, start and the radicand are random and must be
  ignored. Every run has a random `extra` of 0 .. 15 (taken as at most G_EXTRA: 0 at widths 4, 12, 80 and 128; 3 at
  width 12 and 6 at width 92, the next-delay unit's). The seed is printed and replays the run:
  ISQRT_SEED=<seed> pytest tb/test_isqrt.py.
* reset_drops_the_run: a reset at the sampling edge or during a run: no done, busy '0' and root 0 after it (and no
  output change for L + 1 more clocks), and the next run is answered as usual.
"""

from __future__ import annotations

import os
import random
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import pytest
from cocotb.triggers import Event, FallingEdge, Timer
from cocotb.utils import get_sim_steps, get_sim_time

from stepramp.models.exact_unit import isqrt
from stepramp.sim.runner import run_cocotb
from tbutil import (
    HALF,
    PERIOD,
    QUARTER,
    build_dir,
    cocotb,
    env_int,
    garbage_rng,
    random_seed,
    start_clock_and_reset,
    where,
)

SEED_ENV = "ISQRT_SEED"
#: Random radicands per bit length at the wide widths.
PER_LENGTH = env_int("ISQRT_PER_LENGTH", 24)
#: The simulated-time limit of a run of isqrt_against_model (the pytest wrapper sizes it to the width and the count).
LIMIT_US = env_int("ISQRT_LIMIT_US", 5000)


def radicands(width: int, rng: random.Random) -> list[int]:
    """Every radicand up to width 12; corners and random ones of every bit length above."""
    top = (1 << width) - 1
    if width <= 12:
        values = list(range(top + 1))
        rng.shuffle(values)
        return values
    specials = {0, 1, 2, 3, top, top - 1}
    for k in range(width):
        specials |= {1 << k, (1 << k) - 1, (1 << k) + 1}
    roots = [(1 << j) + d for j in range(width // 2 + 1) for d in (-1, 0, 1)]
    roots += [rng.getrandbits(rng.randint(1, width // 2)) for _ in range(4 * width)]
    for s in roots:
        specials |= {s * s - 1, s * s, s * s + s, s * s + s + 1, s * s + 2 * s}
    values = sorted(v for v in specials if 0 <= v <= top)
    for length in range(1, width + 1):
        values += [rng.getrandbits(length) | 1 << (length - 1) for _ in range(PER_LENGTH)]
    rng.shuffle(values)
    return values


@dataclass(frozen=True)
class Run:
    """A radicand, its extra, and the idle cycles before it (0: start stays '1' from the previous done cycle on)."""

    radicand: int
    extra: int
    gap: int = 1


def draw_runs(values: list[int], width: int, top_extra: int, rng: random.Random) -> list[Run]:
    """Each radicand with a random extra (half of them G_EXTRA) and pause (none in 3 of 5: back to back)."""
    runs = []
    for i, r in enumerate(values):
        gap = rng.choice((0, 0, 0, 1, 3)) if i else 1
        # (the largest radicand always at the largest extra: the one run whose rounding surely carries out of the top
        # bit, so that every seed covers the carry; a random extra alone missed it with ISQRT_SEED=1465634534)
        if r == (1 << width) - 1:
            extra = min(top_extra, 15)
        else:
            extra = rng.randrange(16) if rng.random() < 0.5 else min(top_extra, 15)
        runs.append(Run(r, extra, gap))
    return runs


def max_extra(dut: Any) -> int:
    """G_EXTRA, from the root port's width (G_WIDTH / 2 + G_EXTRA + 1)."""
    return len(dut.root) - 1 - len(dut.radicand) // 2


def edges(first: int, last: int) -> Callable[[int], bool]:
    """The rising edges from time first to time last (ps), both included."""
    return lambda t: first <= t <= last and (t - first) % PERIOD == 0


def times(*ts: int) -> Callable[[int], bool]:
    """These times (ps) only."""
    return lambda t: t in ts


class Bench:
    """The unit, the root it holds, and its outputs' change log. rng draws the garbage and the cycles it is driven in.

    Every change of busy and done is logged by a monitor of its own, with its simulated time; the root's monitor logs
    the root's changes while root_watch is set (from the start of an idle gap; cleared at the read after the next
    sampling edge, it logs one more change, the run's first, and sleeps). The bench reads the outputs at a falling
    edge, and between two reads it takes the log since the first one (check) and fails on any change there that is
    not allowed."""

    def __init__(self, dut: Any, rng: random.Random) -> None:
        self.dut = dut
        self.rng = rng
        # the handles, looked up once (a lookup by name costs as much as a read)
        self.busy, self.done, self.root = dut.busy, dut.done, dut.root
        self.start, self.radicand, self.extra = dut.start, dut.radicand, dut.extra
        self.steps_per_ps = get_sim_steps(1, "ps")
        self.timers: dict[int, Timer] = {}  # Timer(cycles * PERIOD) by cycles: built once, awaited again and again
        self.width = len(dut.radicand)
        self.top_extra = max_extra(dut)
        self.held = 0  # the root after reset
        self.start_now = 0  # the value last written to start
        self.failures: list[str] = []
        self.counts = {"runs": 0, "held": 0, "max_latency": 0, "carry": 0}
        self.changes: list[tuple[int, str]] = []
        self.root_watch = Event()
        self.root_watch.set()

    def now(self) -> int:
        """Simulated time in ps (from the simulator's steps: cheaper than get_sim_time("ps"), at every change)."""
        return get_sim_time("step") // self.steps_per_ps

    def fail(self, text: str) -> None:
        self.failures.append(text)

    async def reset(self) -> None:
        """Clock and reset, ending at a falling edge; then the monitors start."""
        dut = self.dut
        dut.start.value = 0
        dut.radicand.value = 0
        dut.extra.value = 0
        await start_clock_and_reset(dut.clk, dut.rst)
        await FallingEdge(dut.clk)
        cocotb.start_soon(self._monitor("busy", self.busy))
        cocotb.start_soon(self._monitor("done", self.done))
        cocotb.start_soon(self._root_monitor())

    async def _monitor(self, name: str, signal: Any) -> None:
        while True:
            await signal.value_change
            self.changes.append((self.now(), name))

    async def _root_monitor(self) -> None:
        while True:
            await self.root_watch.wait()
            await self.root.value_change
            self.changes.append((self.now(), "root"))

    def check(self, what: str, t_ref: int, allowed: dict[str, Callable[[int], bool]] | None = None) -> None:
        """The outputs' changes since the last check (time in ps, name), oldest first: each one must be allowed (by
        the output's entry in allowed: its time)."""
        if not self.changes:
            return
        new, self.changes = self.changes, []
        for t, name in new:
            if allowed is None or name not in allowed or not allowed[name](t):
                self.fail(f"{what}: {name} changed {where(t - t_ref)}")

    def after(self, cycles: int) -> Timer:
        """A Timer of so many clock periods."""
        timer = self.timers.get(cycles)
        if timer is None:
            timer = self.timers[cycles] = Timer(cycles * PERIOD, unit="ps")
        return timer

    def garbage(self, start: int) -> None:
        """Random radicand and extra (and start, if start < 0): the unit must ignore them."""
        bits = self.rng.getrandbits(self.width + 5)
        self.radicand.value = bits >> 5
        self.extra.value = bits >> 1 & 15
        self.drive_start(bits & 1 if start < 0 else start)

    def drive_start(self, value: int) -> None:
        """start, written only when it changes (half the writes of start are the value it has)."""
        if value != self.start_now:
            self.start.value = self.start_now = value

    def flags(self) -> tuple[int, int]:
        return int(self.busy.value), int(self.done.value)

    def holding(self) -> bool:
        """The outputs of an idle unit: busy '0', done '0', the root held."""
        return self.flags() == (0, 0) and int(self.root.value) == self.held

    async def idle(self, cycles: int, last: bool = False) -> None:
        """start '0' (and a random radicand and extra, driven once) for this many cycles, from a falling edge to a
        falling edge: nothing moves. The outputs are read at the gap's last falling edge: busy '0', done '0', the root
        held; and no output may change in the gap but done at its first edge (falling after a done cycle). So they
        held these values from the first edge on: the same as a read at the first falling edge and no change after
        it, with one wake instead of two. Waits with a Timer to the falling edge's time (the outputs read the same
        whether the simulator runs it before or after the clock's fall there: they change only at rising edges);
        last: a single cycle that ends on the FallingEdge trigger itself, so that a caller's next `await FallingEdge`
        is the one after it, whatever order the simulator runs a Timer and the clock in."""
        self.garbage(0)
        self.root_watch.set()
        t_edge = self.now() + HALF
        if last:
            await Timer(PERIOD - QUARTER, unit="ps")
            await FallingEdge(self.dut.clk)
        else:
            await self.after(cycles)
        if not self.holding():
            self.fail(f"idle: busy, done {self.flags()}, root {int(self.root.value):#x} (held {self.held:#x})")
        self.check(f"idle ({cycles} cycles)", t_edge, {"done": edges(t_edge, t_edge)})

    async def play(self, runs: list[Run]) -> None:
        """Play the runs from a falling edge with the unit idle.

        Run i is driven at a falling edge and sampled by the next rising edge e. In the cycle after edge e + k, busy
        must be '1', done '0' for k < L (read at k = 0, then neither may change before edge e + L); at k = L done is
        '1' (one cycle), busy '0', and the root the model's. The root holds until edge e + 1 and may change at the
        edges e + 1 .. e + L only. A run with gap 0 is driven in the done cycle (start held high), so that the next
        edge samples it. Random inputs while busy: at k = 0 and at one random k before the model's latency.
        """
        width, top_extra = self.width, self.top_extra
        limit = width // 2 + top_extra + 7  # edges a run may take before the bench gives up on it
        for run in runs:
            r = run.radicand
            if run.gap:
                await self.idle(run.gap)
            else:
                self.counts["held"] += 1  # (the done cycle: read by the previous run)
            self.radicand.value = r
            self.extra.value = run.extra
            self.drive_start(1)
            expect = isqrt(r, width, run.extra, top_extra)
            latency = expect.latency
            stops = sorted({self.rng.randint(1, latency - 1), latency} if latency > 1 else {1})
            t_e = self.now() + HALF  # the sampling edge e
            await self.after(1)  # the falling edge after e
            flags, root = self.flags(), int(self.root.value)
            if flags != (1, 0) or root != self.held:
                self.fail(f"R={r:#x}, cycle after e: busy, done {flags}, root {root:#x} (held {self.held:#x})")
            # edge e: busy rises, done falls after a done cycle
            at_e = edges(t_e, t_e)
            self.check(f"R={r:#x}, to the cycle after e", t_e, {"busy": at_e, "done": at_e})
            self.root_watch.clear()  # the root may change at every edge from e + 1 on: its monitor sleeps after one
            t_done = t_e + latency * PERIOD
            k = 0  # the falling edge after e + k
            for stop in stops:
                self.garbage(-1)
                await self.after(stop - k)
                k = stop
            # busy and done change at edge e + L only; the root at the edges e + 1 .. e + L
            at_done = edges(t_done, t_done)
            self.check(
                f"R={r:#x} (done due at + {latency})",
                t_e,
                {"busy": at_done, "done": at_done, "root": edges(t_e + PERIOD, t_done)},
            )
            flags = self.flags()
            while not flags[1]:  # no done: where is it (a failure already)
                if k >= limit:
                    self.fail(f"R={r:#x}: no done within {limit} edges (expected {latency})")
                    return
                await self.after(1)
                k += 1
                flags = self.flags()
            seen = k
            if seen != latency:
                self.changes = []  # the late run's changes: the latency says it
            root = int(self.root.value)
            if flags != (0, 1) or (root, seen) != (expect.root, latency):
                self.fail(
                    f"R={r:#x}: busy {flags[0]}, root {root:#x} latency {seen}, expected {expect.root:#x} / {latency}"
                )
            self.held = expect.root
            self.counts["runs"] += 1
            self.counts["max_latency"] = max(self.counts["max_latency"], seen)
            self.counts["carry"] += expect.root >> (width // 2 + top_extra)
            if len(self.failures) > 20:
                break
        await self.idle(1, last=True)


@cocotb.test(timeout_time=LIMIT_US, timeout_unit="us")
async def isqrt_against_model(dut) -> None:
    """Every run's root and latency, busy, done and the held root in every clock."""
    seed = int(os.environ[SEED_ENV])
    dut._log.info("%s=%d", SEED_ENV, seed)
    width = len(dut.radicand)
    rng = random.Random(seed)
    values = radicands(width, rng)
    bench = Bench(dut, garbage_rng(SEED_ENV, seed, "isqrt_against_model"))
    await bench.reset()
    await bench.play(draw_runs(values, width, bench.top_extra, rng))
    counts = bench.counts
    dut._log.info("width %d: %s", width, counts)
    assert not bench.failures, f"{SEED_ENV}={seed} width {width}:\n" + "\n".join(bench.failures)
    assert counts["runs"] == len(values)
    # the set covers what it claims: the longest run, the rounding's carry out of the top bit, runs back to back
    assert counts["max_latency"] == width // 2 + max_extra(dut) + 4, counts
    assert counts["carry"] >= 1 and counts["held"] > 0, counts


@cocotb.test(timeout_time=200, timeout_unit="us")
async def reset_drops_the_run(dut) -> None:
    """A reset at the sampling edge or at any edge of a run: no done after it, busy '0', root 0, and the next run
    (started right after the reset) gives the model's root and latency."""
    seed = int(os.environ[SEED_ENV])
    width = len(dut.radicand)
    rng = random.Random(seed + 1)
    bench = Bench(dut, garbage_rng(SEED_ENV, seed, "reset_drops_the_run"))
    await bench.reset()
    for trial in range(15):
        r = rng.getrandbits(width) | 1 << (width - 1)
        latency = isqrt(r, width).latency
        # the reset edge, counted from the sampling edge: itself, the align edge, the last two edges, any
        at = (0, 1, latency - 1, latency, rng.randint(1, latency))[trial % 5]
        what = f"reset at e + {at} of R={r:#x}"
        dut.radicand.value = r
        dut.extra.value = 0
        bench.drive_start(1)
        if at == 0:
            dut.rst.value = 1
        t_e = bench.now() + HALF  # the sampling edge e
        t_rst = t_e + at * PERIOD
        bench.root_watch.clear()  # the root may change at every edge up to the reset's
        await bench.after(1)  # the falling edge after e
        bench.drive_start(0)
        if at:
            if at > 1:
                await bench.after(at - 1)
            dut.rst.value = 1
            await bench.after(1)
        dut.rst.value = 0
        flags, root = bench.flags(), int(dut.root.value)
        if flags != (0, 0) or root != 0:
            bench.fail(f"{what}: busy, done {flags}, root {root:#x} after it, not 0, 0, 0")
        # busy rises at e and falls at the reset's edge; no done; the root changes at e + 1 .. the reset's edge (at e
        # itself with a reset there)
        allowed = {"root": edges(t_e + min(at, 1) * PERIOD, t_rst)}
        if at:
            allowed["busy"] = times(t_e, t_rst)  # rises at e, falls at the reset's edge
        bench.check(what, t_e, allowed)
        bench.held = 0
        bench.root_watch.set()
        # nothing for L + 1 more clocks
        await bench.after(latency + 1)
        bench.check(f"{what}, after it", t_rst)
        before = len(bench.failures)
        await bench.play(draw_runs([rng.getrandbits(rng.randint(1, width))], width, bench.top_extra, rng))
        bench.failures[before:] = [f"after a reset at e + {at}: {m}" for m in bench.failures[before:]]
    assert not bench.failures, f"{SEED_ENV}={seed}:\n" + "\n".join(bench.failures)


@pytest.mark.parametrize(("width", "extra"), [(4, 0), (12, 0), (12, 3), (80, 0), (92, 6), (128, 0)])
def test_isqrt(width: int, extra: int) -> None:
    """Both cocotb tests at one width and G_EXTRA; the seed is random unless ISQRT_SEED is set."""
    seed = random_seed(SEED_ENV, f"stepramp_isqrt width {width}, G_EXTRA {extra}")
    # every run at the worst latency with the longest pause, and margin (10 ns clock)
    limit_us = len(radicands(width, random.Random(seed))) * (width // 2 + extra + 5 + 4) * 10 // 1000 + 100
    run_cocotb(
        "stepramp_isqrt",
        "test_isqrt",
        build_dir(f"isqrt_w{width}_e{extra}"),
        parameters={"G_WIDTH": width, "G_EXTRA": extra},
        extra_env={SEED_ENV: str(seed), "ISQRT_LIMIT_US": str(limit_us)},
    )
