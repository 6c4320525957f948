# SPDX-License-Identifier: MIT
"""stepramp_next_delay_exact alone: every answer's value and latency against the model
(stepramp.models.exact_unit.NextDelayExact: values from stepramp.models.exact, latencies from the documented
formulas, fresh msb(x) + L(C x) + L(C (x + 1)) + 3 or continued L(radicand) + 2, and the continuation rule), with
busy, ans_valid and the held answer checked in every clock of every request.

How the bench checks every clock without waking at every clock (Bench): a monitor on each output (busy, ans_valid,
ans_value, ans_rem, ans_ovf) logs its every change with the simulated time, and the bench, which wakes only where it
reads the outputs or drives the inputs (Timers), fails on any logged change where none may come; an output that does
not change holds. A request is driven at a falling edge, sampled by the next rising edge e, and read at the falling
edge after e: busy '1', ans_valid '0', the previous answer held. From there any change of an output before edge
e + latency (the model's) fails, and so does a change away from a rising edge; the answer's cycle is read at its falling
edge: ans_valid '1', busy '0', the model's value, rem and ovf. The cycle after it (the next request's first, or an
idle one) is read too: ans_valid '0' again. An idle gap is read at its first falling edge (busy '0', ans_valid '0',
the answer held), and no output may change from there to its end.

What is driven when: a request at the falling edge before its sampling edge e; random values on all six request inputs
and on req at the falling edge after e, and again at one random falling edge between it and the answer's edge (the
model's latency); random request inputs with req '0' at the start of an idle gap. So from edge e + 1 to the answer the
inputs differ from the request's (a unit that reads one while busy, in whichever cycle, computes with garbage), req is
'1' at the answer's edge in about half of the requests, and the inputs change once more mid-computation. The garbage
has a random generator of its own (garbage_rng, from the test's seed): the requests a test draws do not depend on it.

* random_requests: random requests (accel and decel, plain, seed and alternative; x of every bit length with 0 and
  2^31 - 1; C = m 4^e as seed words, of every bit length up to 2^72 with 0, 2^48 - 1, the driver's largest
  2^72 - 2^36 and the unit's (2^60 - 1) 4^6, whose value at x = 0 overflows, and now and then a scale of 7 .. 15,
  taken as 6; about half of them the next index of the kept run, so that runs continue and break), back to back
  (req held high into the answer cycle) or after a pause, the inputs random while busy (ignored). The seed is
  printed and replays the run: NEXT_DELAY_EXACT_SEED=<seed> pytest tb/test_next_delay_exact.py.
* long_runs: runs of 200 consecutive indices up (accel) and down (decel), with alternatives interleaved that must
  not break them (each run's answers after the first are all continued: one square root each, seen in the
  latency); up to 2^31 - 1 and down to 0, then the index on the other side of the range, which must be fresh.
* flush_drops_the_request: a flush (or a reset) at the sampling edge, during the multiply or a root, at the edge
  before the answer and at the answer's own edge: no answer, busy '0' after it, the previous answer held, and the
  next request, the next index of the run the flush forgot, is fresh (its latency) and right.
"""

from __future__ import annotations

import os
import random
from dataclasses import dataclass, replace
from typing import Any

from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge, Timer
from cocotb.utils import get_sim_time

from stepramp.models import exact
from stepramp.models.exact_unit import FRESH_WORST, ExactRequest, NextDelayExact, fresh_latency
from tbutil import HALF, PERIOD, QUARTER, cocotb, env_int, garbage_rng, run_seeded, start_clock_and_reset, where

SEED_ENV = "NEXT_DELAY_EXACT_SEED"
X_BITS = 31
SEED_BITS = 64
X_MAX = (1 << X_BITS) - 1
C_NARROW = exact.seed_word((1 << 48) - 1, 0)
"""The largest constant below 2^48 (scale 0)."""
C_DRIVER_MAX = exact.seed_word(exact.C_MAX >> 12, 6)
"""C = 2^72 - 2^36, the driver's largest (c0 below 2^32 ticks)."""
C_MAX = exact.seed_word((1 << exact.MANT_WIDTH) - 1, exact.SCALE_MAX)
"""The unit's largest constant, (2^60 - 1) 4^6: its value at x = 0 is 2^36 Q.4 ticks, ans_ovf."""
#: Random requests of random_requests.
N_REQUESTS = env_int("N_REQUESTS", 1500)
#: Edges an answer may take before the bench gives up on it: more than the longest (FRESH_WORST).
ANSWER_LIMIT = FRESH_WORST + 8
#: Simulated time of a request at the longest latency with the longest pause (10 ns clock), in us.
US_PER_REQUEST = (ANSWER_LIMIT + 6) * 10 / 1000


@dataclass(frozen=True)
class Step:
    """A request and the idle cycles before it (0: req stays '1' from the previous answer's cycle on)."""

    req: ExactRequest
    gap: int = 1


def seed_of(c: int) -> int:
    """The seed word of a constant below 2^72, with the smallest scale (as the driver encodes it)."""
    e = 0
    while c >> (2 * e) >= 1 << exact.MANT_WIDTH:
        e += 1
    return exact.seed_word(c >> (2 * e), e)


def random_c(rng: random.Random) -> int:
    """A seed word: 0, the corners, a constant of any bit length, or a scale of 7 .. 15 (the unit takes 6)."""
    r = rng.random()
    if r < 0.05:
        return exact.seed_word(rng.getrandbits(60), rng.randint(7, 15))
    if r < 0.45:
        return rng.choice((0, C_MAX, C_NARROW, C_DRIVER_MAX))
    return seed_of(rng.getrandbits(rng.randint(0, 72)))


def random_x(rng: random.Random) -> int:
    return rng.choice((0, X_MAX, rng.getrandbits(rng.randint(0, X_BITS)), rng.getrandbits(rng.randint(0, X_BITS))))


def drive(dut: Any, req: ExactRequest) -> None:
    dut.req_seed.value = int(req.seed)
    dut.req_decel.value = int(req.decel)
    dut.req_alt.value = int(req.alt)
    dut.req_index.value = req.x
    dut.c_head.value = req.c_head
    dut.c_dec.value = req.c_dec


def drive_garbage(dut: Any, rng: random.Random) -> None:
    """Random inputs while the unit is busy: it must ignore them."""
    bits = rng.getrandbits(3)
    garbage = ExactRequest(
        bool(bits & 1),
        rng.getrandbits(X_BITS),
        rng.getrandbits(SEED_BITS),
        rng.getrandbits(SEED_BITS),
        bool(bits & 2),
        bool(bits & 4),
    )
    drive(dut, garbage)


def answer_now(dut: Any) -> tuple[int, int, int]:
    return int(dut.ans_value.value), int(dut.ans_rem.value), int(dut.ans_ovf.value)


def flags(dut: Any) -> tuple[int, int]:
    return int(dut.busy.value), int(dut.ans_valid.value)


def now_ps() -> int:
    """Simulated time in ps."""
    return round(get_sim_time("ps"))


class Bench:
    """The unit, its model, and the answer it holds. rng draws the garbage and the cycles it is driven in.

    Every change of an output (busy, ans_valid, ans_value, ans_rem, ans_ovf) is logged by a monitor of its own, with
    its simulated time; the bench reads the outputs at a falling edge, and between two reads it takes the log since
    the first one (new_changes) and fails on any change there that is not allowed."""

    def __init__(self, dut: Any, rng: random.Random) -> None:
        self.dut = dut
        self.rng = rng
        self.model = NextDelayExact()
        self.held = (0, 0)  # ans_value and ans_ovf after reset: 0
        self.failures: list[str] = []
        self.counts = {"answers": 0, "continued": 0, "held_req": 0, "max_latency": 0, "ovf": 0}
        self.changes: list[tuple[int, str]] = []

    def fail(self, text: str) -> None:
        self.failures.append(text)

    async def reset(self) -> None:
        """Clock and reset, ending at a falling edge; then the monitors start."""
        self.dut.req.value = 0
        self.dut.flush.value = 0
        drive(self.dut, ExactRequest(False, 0, 0, 0))
        await start_clock_and_reset(self.dut.clk, self.dut.rst)
        await FallingEdge(self.dut.clk)
        for name in ("busy", "ans_valid", "ans_value", "ans_rem", "ans_ovf"):
            cocotb.start_soon(self._monitor(name, getattr(self.dut, name)))

    async def _monitor(self, name: str, signal: Any) -> None:
        while True:
            await signal.value_change
            self.changes.append((now_ps(), name))

    def new_changes(self) -> list[tuple[int, str]]:
        """The outputs' changes (time in ps, name) since the last call, oldest first."""
        new, self.changes = self.changes, []
        return new

    def holding(self) -> bool:
        """The outputs of an idle unit: busy '0', ans_valid '0', the answer held."""
        return flags(self.dut) == (0, 0) and answer_now(self.dut) == (self.held[0], 0, self.held[1])

    async def idle(self, cycles: int, last: bool = False) -> None:
        """req '0' (and random request inputs, driven once) for this many cycles, from a falling edge to a falling
        edge: nothing moves. The outputs are read at the first falling edge (ans_valid '0' again after an answer);
        after it no output may change. Waits with a Timer to the falling edge's time (the outputs read the same
        whether the simulator runs it before or after the clock's fall there: they change only at rising edges);
        last: a single cycle that ends on the FallingEdge trigger itself (play's last), so that a caller's next
        `await FallingEdge` is the one after it, whatever order the simulator runs a Timer and the clock in."""
        self.dut.req.value = 0
        drive_garbage(self.dut, self.rng)
        self.new_changes()  # (read before: the caller's)
        if last:
            await Timer(PERIOD - QUARTER, unit="ps")
            await FallingEdge(self.dut.clk)
        else:
            await Timer(PERIOD, unit="ps")
        if not self.holding():
            self.fail(f"idle: busy, ans_valid {flags(self.dut)}, answer {answer_now(self.dut)} (held {self.held})")
        self.new_changes()  # the edge before the read: covered by the read
        if cycles > 1 and not last:
            t_first = now_ps() - HALF  # the gap's first edge
            await Timer((cycles - 1) * PERIOD, unit="ps")
            for t, name in self.new_changes():
                self.fail(f"idle: {name} changed {where(t - t_first)} from the gap's first edge (of {cycles})")

    async def play(self, steps: list[Step]) -> list[bool]:
        """Play the requests from a falling edge with the unit idle; returns the model's verdict on each (continued
        or fresh: what the request tests; the RTL's path shows in its latency, which must be the model's).

        Request i is driven at a falling edge and sampled by the next rising edge e. In the cycle after edge e + k,
        busy must be '1', ans_valid '0' and the previous answer held for k < latency (read at k = 0, then no output
        may change before edge e + latency); at k = latency ans_valid is '1' (one cycle), busy '0', and the answer
        the model's. A request with gap 0 is driven in that cycle (req held high), so the next edge samples it.
        Random inputs while busy: at k = 0 and at one random k before the model's latency.
        """
        dut = self.dut
        continued: list[bool] = []
        for i, step in enumerate(steps):
            if step.gap:
                await self.idle(step.gap)
            else:
                self.counts["held_req"] += 1
            if flags(dut) != (0, int(step.gap == 0 and i > 0)):  # gap 0: the previous answer's cycle
                self.fail(f"before {step.req}: busy, ans_valid {flags(dut)}")
            drive(dut, step.req)
            dut.req.value = 1
            expect = self.model.request(step.req)
            stops = sorted({self.rng.randint(1, expect.latency - 1), expect.latency} if expect.latency > 1 else {1})
            self.new_changes()  # (read before)
            await Timer(PERIOD, unit="ps")  # the falling edge after the sampling edge e
            t_e = now_ps() - HALF
            if flags(dut) != (1, 0) or answer_now(dut) != (self.held[0], 0, self.held[1]):
                self.fail(f"{step.req}, cycle after e: busy, ans_valid {flags(dut)}, answer {answer_now(dut)} not held")
            self.new_changes()  # edge e (busy rises, ans_valid falls after an answer): covered by the read
            k = 0  # the falling edge after e + k
            for stop in stops:
                drive_garbage(dut, self.rng)
                dut.req.value = self.rng.getrandbits(1)
                await Timer((stop - k) * PERIOD, unit="ps")
                k = stop
                for t, name in self.new_changes():  # none before the answer's edge
                    if t != t_e + expect.latency * PERIOD:
                        self.fail(
                            f"{step.req}: {name} changed {where(t - t_e)} from e (answer due at + {expect.latency})"
                        )
            latency: int | None = k
            while not flags(dut)[1]:  # no answer: where is it (a failure already)
                if k >= ANSWER_LIMIT - 1:
                    latency = None
                    break
                await Timer(PERIOD, unit="ps")
                k += 1
                latency = k
            if latency is None:
                self.fail(f"{step.req}: no answer within {ANSWER_LIMIT} edges (model: {expect})")
                break
            got = answer_now(dut)
            if flags(dut) != (0, 1) or got != (expect.value, 0, int(expect.ovf)) or latency != expect.latency:
                self.fail(
                    f"{step.req}: busy {flags(dut)[0]}, value {got[0]:#x} rem {got[1]} ovf {got[2]}, latency "
                    f"{latency}; model: value {expect.value:#x} ovf {int(expect.ovf)}, latency {expect.latency} "
                    f"({'continued' if expect.continued else 'fresh'})"
                )
            self.held = (expect.value, int(expect.ovf))
            self.counts["ovf"] += expect.ovf
            continued.append(expect.continued)
            self.counts["answers"] += 1
            self.counts["continued"] += expect.continued
            self.counts["max_latency"] = max(self.counts["max_latency"], latency)
            dut.req.value = 0
            if len(self.failures) > 20:
                break
        await self.idle(1, last=True)
        return continued


def random_step(model: NextDelayExact, rng: random.Random) -> Step:
    """A random request; about half of them the next index of the kept run (with the run's constant)."""
    decel = rng.random() < 0.5
    req = ExactRequest(decel, random_x(rng), random_c(rng), random_c(rng), rng.random() < 0.1, rng.random() < 0.15)
    if model.valid and rng.random() < 0.5:
        x = model.x_lo + (-1 if model.decel else 1)
        if 0 <= x <= X_MAX:
            req = replace(req, decel=model.decel, x=x, seed=rng.random() < 0.05, alt=rng.random() < 0.1)
    if model.continues(req):  # the run's constant goes on (the contract: it changes only with a flush)
        req = replace(req, c_dec=model.word) if req.decel else replace(req, c_head=model.word)
    return Step(req, rng.choice((0, 0, 1, 2, 5)))


@cocotb.test(timeout_time=round(N_REQUESTS * US_PER_REQUEST) + 50, timeout_unit="us")
async def random_requests(dut) -> None:
    """Random requests, back to back or after a pause: value, rem, ovf, latency and the port timing of each."""
    seed = int(os.environ[SEED_ENV])
    dut._log.info("%s=%d", SEED_ENV, seed)
    rng = random.Random(seed)
    bench = Bench(dut, garbage_rng(SEED_ENV, seed, "random_requests"))
    await bench.reset()
    planner = NextDelayExact()  # the model ahead of the bench's, to draw requests that continue
    steps = []
    for _ in range(N_REQUESTS):
        steps.append(random_step(planner, rng))
        planner.request(steps[-1].req)
    cont = await bench.play(steps)
    dut._log.info("%s", bench.counts)
    assert not bench.failures, f"{SEED_ENV}={seed}:\n" + "\n".join(bench.failures)
    assert bench.counts["answers"] == len(steps)
    assert bench.counts["max_latency"] == FRESH_WORST, bench.counts  # x = 2^31 - 1 and C = (2^60 - 1) 4^6, fresh
    # the draw covers what it claims: fresh and continued of both kinds, seeds and alternatives, the range ends
    reqs = [s.req for s in steps]
    for what, n in {
        "accel continued": sum(c and not r.decel for c, r in zip(cont, reqs, strict=True)),
        "decel continued": sum(c and r.decel for c, r in zip(cont, reqs, strict=True)),
        "fresh": cont.count(False),
        "seed": sum(r.seed for r in reqs),
        "alt": sum(r.alt for r in reqs),
        "x = 0": sum(r.x == 0 for r in reqs),
        "x = 2^31 - 1": sum(r.x == X_MAX for r in reqs),
        "C = 0": sum(r.constant == 0 for r in reqs),
        "C = 2^48 - 1": sum(r.constant == exact.constant_of(C_NARROW) for r in reqs),
        "C = 2^72 - 2^36": sum(r.constant == exact.C_MAX for r in reqs),
        "C = (2^60 - 1) 4^6": sum(r.constant == exact.constant_of(C_MAX) for r in reqs),
        "scale above 6": sum(((r.c_dec if r.decel else r.c_head) >> 60) > 6 for r in reqs),
        "ovf": bench.counts["ovf"],
        "held": bench.counts["held_req"],
    }.items():
        assert n > 0, f"no request of the kind '{what}'"


def run(c_head: int, c_dec: int, decel: bool, xs: list[int], rng: random.Random, alt_every: int) -> list[Step]:
    """Requests for the indices xs of one kind, an alternative (random kind, index and constants) after every
    alt_every-th of them, back to back or after a short pause; the first one a seed."""
    steps: list[Step] = []
    for i, x in enumerate(xs):
        steps.append(Step(ExactRequest(decel, x, c_head, c_dec, seed=i == 0), rng.choice((0, 1, 2))))
        if i % alt_every == alt_every - 1:
            alt = ExactRequest(rng.random() < 0.5, random_x(rng), random_c(rng), random_c(rng), alt=True)
            steps.append(Step(alt, rng.choice((0, 1))))
    return steps


@cocotb.test(timeout_time=3000, timeout_unit="us")
async def long_runs(dut) -> None:
    """Runs of 200 indices up and down, alternatives interleaved: every answer after a run's first is continued."""
    seed = int(os.environ[SEED_ENV])
    rng = random.Random(seed + 1)
    bench = Bench(dut, garbage_rng(SEED_ENV, seed, "long_runs"))
    await bench.reset()
    # (C of the run, the first index, kind): a ramp from rest, a run up to the top of the index range, a run down to
    # 0, one down from the top, one up from a random index; C small, random and the largest
    plans = [
        (rng.getrandbits(20) | 1, 0, False),
        (C_MAX, X_MAX - 199, False),
        (seed_of(rng.getrandbits(48)), 199, True),
        (C_MAX, X_MAX, True),
        (seed_of(rng.getrandbits(70)), rng.getrandbits(24) + 200, False),
    ]
    for c, first, decel in plans:
        xs = [first - i for i in range(200)] if decel else [first + i for i in range(200)]
        steps = run(c, c ^ 0x5A5A, decel, xs, rng, rng.choice((3, 5, 7)))
        cont = await bench.play(steps)
        # play() holds each answer to the model's latency; the model's verdicts say what the run tests: the run's
        # own requests (not the alternatives) the seed fresh, every later one continued
        own = [k for k, s in zip(cont, steps, strict=True) if not s.req.alt]
        assert own == [False] + [True] * 199, f"the run from {first} does not continue as it should in the model"
        # past the end of the index range (no wrap), or a gap of one index: fresh
        beyond = {(False, X_MAX): 0, (True, 0): X_MAX}.get((decel, xs[-1]), xs[-1] + (-2 if decel else 2))
        assert await bench.play([Step(ExactRequest(decel, beyond, c, c ^ 0x5A5A), 1)]) == [False]
        dut.flush.value = 1  # the segment ends: the engine flushes
        await FallingEdge(dut.clk)
        dut.flush.value = 0
        bench.model.flush()
    assert not bench.failures, f"{SEED_ENV}={seed}:\n" + "\n".join(bench.failures)
    assert bench.counts["continued"] == 5 * 199, bench.counts


@cocotb.test(timeout_time=2000, timeout_unit="us")
async def flush_drops_the_request(dut) -> None:
    """A flush (or a reset) at the sampling edge or while the answer is being computed: no answer, busy '0' after it,
    the previous answer held, and the run forgotten: the next index of the run, asked right after the flush or after
    a pause, is answered fresh."""
    seed = int(os.environ[SEED_ENV])
    rng = random.Random(seed + 2)
    bench = Bench(dut, garbage_rng(SEED_ENV, seed, "flush_drops_the_request"))
    await bench.reset()
    cases = 0
    for trial in range(40):
        port = "rst" if trial % 8 == 7 else "flush"
        decel = bool(trial % 2)
        c = seed_of(rng.getrandbits(rng.randint(1, 72))) | 1
        x0 = rng.getrandbits(rng.randint(2, X_BITS - 1)) + 3  # x0 +/- 3 is an index
        step = -1 if decel else 1
        # a run of two sets the kept state up; the request to drop continues it or is fresh
        await bench.play([Step(ExactRequest(decel, x0, c, c, seed=True)), Step(ExactRequest(decel, x0 + step, c, c))])
        if trial % 3:
            req = ExactRequest(decel, x0 + 2 * step, c, c)
            nxt = ExactRequest(decel, x0 + 3 * step, c, c)
        else:
            req = ExactRequest(bool(rng.getrandbits(1)), random_x(rng), random_c(rng), random_c(rng))
            nxt = ExactRequest(decel, x0 + 2 * step, c, c)
        latency = _latency(bench.model, req)
        # the flush edge, counted from the sampling edge e: e itself, e + 1, inside, the edge before the answer, the
        # answer's own edge
        at = (0, 1, rng.randint(1, latency - 1), latency - 1, latency)[trial % 5]
        drive(dut, req)
        dut.req.value = 1
        if at == 0:
            getattr(dut, port).value = 1
        await RisingEdge(dut.clk)
        await FallingEdge(dut.clk)
        dut.req.value = 0
        if at:
            await ClockCycles(dut.clk, at - 1, rising=False)
            getattr(dut, port).value = 1
            await FallingEdge(dut.clk)
        getattr(dut, port).value = 0
        bench.model.flush()
        if port == "rst":
            bench.held = (0, 0)  # a reset clears the answer
        what = f"{port} at e + {at} of {req} (answer due at e + {latency})"
        if flags(dut) != (0, 0) or answer_now(dut) != (bench.held[0], 0, bench.held[1]):
            bench.fail(f"{what}: busy, ans_valid {flags(dut)}, answer {answer_now(dut)} after it")
        # nothing comes later either (idle checks every cycle), then the next index of the forgotten run: fresh
        pause = rng.choice((0, latency + 2))
        if pause:
            await bench.idle(pause)
        # play() holds the answer to the model's latency, fresh here (a continued answer would come earlier)
        assert _latency(bench.model, nxt) == fresh_latency(nxt.constant, nxt.x)
        await bench.play([Step(nxt, 1 if pause else 0)])
        cases += 1
    assert not bench.failures, f"{SEED_ENV}={seed}:\n" + "\n".join(bench.failures)
    assert cases == 40


def _latency(model: NextDelayExact, req: ExactRequest) -> int:
    """The latency the request would have, without changing the model."""
    return replace(model).request(req).latency


def test_next_delay_exact() -> None:
    """The three cocotb tests above in one simulation; the seed is random unless NEXT_DELAY_EXACT_SEED is set."""
    run_seeded("stepramp_next_delay_exact", "test_next_delay_exact", SEED_ENV, {"N_REQUESTS": str(N_REQUESTS)})
