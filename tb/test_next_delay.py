# SPDX-License-Identifier: MIT
"""stepramp_next_delay alone: every answer's value, remainder, overflow flag and latency against plain Python
integers (stepramp.models.blocks.next_delay: one step of the recurrence of docs/algorithm.md, or a seed load, with the
latency docs/stepramp_engine.md gives: a seed is registered at the edge that samples req, a step 2 + k edges later,
k = floor(msb(num) / 2) + 1, 0 when num = 0).

* random_requests: 3,000 random requests (seeds, accel and decel steps, indices and values of every bit length,
  remainders below the denominator and arbitrary 33-bit ones), some after a pause, some with req held high across
  the previous answer (and the inputs changed while busy: they must be ignored). The seed is printed and replays the
  run: NEXT_DELAY_SEED=<seed> pytest tb/test_next_delay.py.
* overflow_cases: requests built to land on each side of the Q32.16 range (accel below 0, decel at 2^48), the
  largest numerators (k = 25) and the smallest (num < den, k = 3; num = 0, k = 0).
* flush_drops_the_answer: a flush at the edge that samples req, during the division, at the divider's last edge and
  at the answer's own edge: no answer comes, busy falls, the previous answer stays, and the next request (sampled
  right after the flush) is answered normally. A reset in flight likewise drops the answer.
* busy_until_the_answer: busy, clock by clock, from the sampling edge of a step to the answer's edge (24 requests).
"""

from __future__ import annotations

import os
import random
from dataclasses import dataclass
from typing import Any

from cocotb.triggers import ClockCycles, FallingEdge, First, RisingEdge, Timer

from stepramp.models.blocks import RAMP_VALUE_LIMIT, NextDelayAnswer, next_delay
from tbutil import CLK_PERIOD_NS, cocotb, env_int, now_cycles, run_seeded, start_clock_and_reset

SEED_ENV = "NEXT_DELAY_SEED"
INDEX_BITS = 31
VALUE_BITS = 48
REM_BITS = 33
NUM_BITS = 50  # the numerator 2 * value + remainder (req_num)
#: More than the longest answer (2 + 25 edges).
ANSWER_LIMIT_CYCLES = 64


@dataclass(frozen=True)
class Request:
    seed: bool
    decel: bool
    index: int
    value: int
    rem: int
    gap: int = 1  # idle cycles with req = '0' before it; 0: req stays '1' from the previous request on

    def answer(self) -> NextDelayAnswer:
        return next_delay(self.seed, self.decel, self.index, self.value, self.rem)

    def __str__(self) -> str:
        kind = "seed" if self.seed else "decel" if self.decel else "accel"
        return f"{kind} index={self.index} value={self.value:#x} rem={self.rem:#x}"


def random_request(rng: random.Random) -> Request:
    """Bit lengths drawn first, so that small and large operands (and every alignment distance) occur."""
    decel = rng.random() < 0.5
    index = rng.getrandbits(rng.randint(0, INDEX_BITS))
    den = 4 * index + (3 if decel else 1)
    # mostly a remainder the recurrence can carry (below den), else any 33-bit value
    rem = rng.randrange(den) if rng.random() < 0.75 else rng.getrandbits(rng.randint(0, REM_BITS))
    return Request(
        seed=rng.random() < 0.1,
        decel=decel,
        index=index,
        value=rng.getrandbits(rng.randint(0, VALUE_BITS)),
        rem=rem,
        gap=rng.choice((0, 0, 1, 2, 5)),
    )


def seed_from_env() -> int:
    return int(os.environ[SEED_ENV])


def drive(dut: Any, req: Request) -> None:
    dut.req_seed.value = int(req.seed)
    dut.req_decel.value = int(req.decel)
    dut.req_index.value = req.index
    dut.req_value.value = req.value
    dut.req_num.value = 2 * req.value + req.rem  # the requester forms the numerator


def drive_garbage(dut: Any, rng: random.Random) -> None:
    """Random inputs while the unit is busy: it must ignore them."""
    dut.req_seed.value = rng.getrandbits(1)
    dut.req_decel.value = rng.getrandbits(1)
    dut.req_index.value = rng.getrandbits(INDEX_BITS)
    dut.req_value.value = rng.getrandbits(VALUE_BITS)
    dut.req_num.value = rng.getrandbits(NUM_BITS)


def compare(req: Request, got: tuple[int, int, bool], latency: int) -> str | None:
    """A description of what differs from the expected answer (None: nothing). The value of an overflowing answer
    is not specified (the engine stops on the flag), only its remainder."""
    expect = req.answer()
    value, rem, ovf = got
    wrong = (
        latency != expect.latency
        or ovf != expect.ovf
        or rem != expect.remainder
        or (not expect.ovf and value != expect.value)
    )
    if not wrong:
        return None
    return (
        f"{req}: got value={value:#x} rem={rem:#x} ovf={ovf} latency={latency}; expected value={expect.value:#x} "
        f"rem={expect.remainder:#x} ovf={expect.ovf} latency={expect.latency}"
    )


async def reset_unit(dut: Any) -> None:
    dut.req.value = 0
    dut.flush.value = 0
    drive(dut, Request(False, False, 0, 0, 0))
    await start_clock_and_reset(dut.clk, dut.rst)
    await FallingEdge(dut.clk)


def answer_now(dut: Any) -> tuple[int, int, bool]:
    return int(dut.ans_value.value), int(dut.ans_rem.value), bool(int(dut.ans_ovf.value))


async def run_requests(dut: Any, reqs: list[Request], rng: random.Random) -> tuple[list[str], dict[str, int]]:
    """Play the requests (at a falling edge, the unit idle); returns the differences and a few counts.

    Each request is driven at a falling edge, so the next rising edge samples it (the unit is idle: checked). Its
    answer edge is the edge after which ans_valid is '1' (the sampling edge itself for a seed).
    """
    failures: list[str] = []
    counts = {"answers": 0, "ovf": 0, "held": 0, "max_latency": 0}
    last: NextDelayAnswer | None = None
    for i, req in enumerate(reqs):
        held = req.gap == 0 and i > 0
        if not held:
            dut.req.value = 0
            if req.gap > 1:
                await ClockCycles(dut.clk, req.gap - 1)
            if req.gap > 0:
                await FallingEdge(dut.clk)
            # ans_* hold until the next answer
            if last is not None and not last.ovf and answer_now(dut)[:2] != (last.value, last.remainder):
                failures.append(f"request {i}: the previous answer was not held: {answer_now(dut)[:2]}")
        counts["held"] += held
        if int(dut.busy.value) != 0:
            failures.append(f"request {i} ({req}): busy before the request")
            break
        drive(dut, req)
        dut.req.value = 1
        await RisingEdge(dut.clk)
        sample_edge = now_cycles()
        await FallingEdge(dut.clk)
        next_held = i + 1 < len(reqs) and reqs[i + 1].gap == 0
        if int(dut.ans_valid.value) == 1:
            answer_edge = sample_edge
        else:
            if int(dut.busy.value) != 1:
                failures.append(f"request {i} ({req}): busy is not '1' during the computation")
            drive_garbage(dut, rng)
            dut.req.value = int(next_held)
            timer = Timer(ANSWER_LIMIT_CYCLES * CLK_PERIOD_NS, unit="ns")
            if await First(RisingEdge(dut.ans_valid), timer) is timer:
                failures.append(f"request {i} ({req}): no answer within {ANSWER_LIMIT_CYCLES} cycles")
                break
            answer_edge = now_cycles()
            await FallingEdge(dut.clk)
        latency = answer_edge - sample_edge
        if int(dut.ans_valid.value) != 1 or int(dut.busy.value) != 0:
            failures.append(f"request {i} ({req}): ans_valid {dut.ans_valid.value}, busy {dut.busy.value}")
        problem = compare(req, answer_now(dut), latency)
        if problem is not None:
            failures.append(f"request {i}: {problem}")
        last = req.answer()
        counts["answers"] += 1
        counts["ovf"] += last.ovf
        counts["max_latency"] = max(counts["max_latency"], latency)
        if len(failures) > 20:
            break
    dut.req.value = 0
    return failures, counts


@cocotb.test(timeout_time=10, timeout_unit="ms")
async def random_requests(dut) -> None:
    """Random requests, back to back or after a pause: value, remainder, ovf and latency of every answer."""
    seed = seed_from_env()
    dut._log.info("%s=%d", SEED_ENV, seed)
    rng = random.Random(seed)
    reqs = [random_request(rng) for _ in range(env_int("N_REQUESTS", 3000))]
    await reset_unit(dut)
    failures, counts = await run_requests(dut, reqs, rng)
    dut._log.info("%s", counts)
    assert not failures, f"{SEED_ENV}={seed}:\n" + "\n".join(failures)
    assert counts["answers"] == len(reqs)
    # the draw covers what it should: both sides of the range, held requests, long divisions
    assert 0 < counts["ovf"] < len(reqs) and counts["held"] > 0 and counts["max_latency"] >= 20, counts


def overflow_requests() -> list[Request]:
    """Requests on both sides of the Q32.16 range and at the ends of the latency range, each checked here against
    the side it is meant for (so that the list keeps testing what it says)."""
    top = RAMP_VALUE_LIMIT - 1
    cases: list[tuple[Request, bool]] = [
        # accel index 0 (den 1): A_0 = A - (2A + r) < 0 for any A > 0
        (Request(False, False, 0, 1, 0), True),
        (Request(False, False, 0, 0, 0), False),
        (Request(False, False, 0, top, (1 << REM_BITS) - 1), True),
        # accel index 1 (den 5), A = 1000: r = 3000 gives exactly 0, r = 3005 gives -1
        (Request(False, False, 1, 1000, 3000), False),
        (Request(False, False, 1, 1000, 3005), True),
        # decel index 0 (den 3) from the top of the range, and from 0
        (Request(False, True, 0, top, (1 << REM_BITS) - 1), True),
        (Request(False, True, 0, 0, 0), False),
        # decel, index 2^31 - 1 (den 2^33 - 1): D + q = 2^48 - 1 exactly, and 2^48 from D + 1 (same q)
        (Request(False, True, (1 << 31) - 1, top - 65536, 65538), False),
        (Request(False, True, (1 << 31) - 1, top - 65535, 65538), True),
        # seeds never overflow
        (Request(True, False, 0, top, (1 << REM_BITS) - 1), False),
        (Request(True, True, (1 << 31) - 1, top, 0), False),
        # the longest divisions: num = 2 (2^48 - 1) + 2^33 - 1 (msb 49) and 2^48 + 6 (msb 48): k = 25
        (Request(False, False, 1, top, (1 << REM_BITS) - 1), False),
        (Request(False, True, 1, top >> 1, 6), False),
        # num < den: quotient 0 after k = 3 iterations; num = 0: k = 0
        (Request(False, False, 5, 0, 20), False),
        (Request(False, True, (1 << 31) - 1, 0, 0), False),
    ]
    # decel index 0 (den 3): the largest D that stays in range, and the next one
    lo, hi = 0, top  # invariant: D = lo is in range, D = hi is not
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if next_delay(False, True, 0, mid, 0).ovf:
            hi = mid
        else:
            lo = mid
    cases += [(Request(False, True, 0, lo, 0), False), (Request(False, True, 0, hi, 0), True)]
    for req, ovf in cases:
        assert req.answer().ovf == ovf, f"{req}: the case does not test what it says"
    # k = 25 (a 50-bit numerator, the divider's width: the longest), reached from msb 48 and 49
    assert sum(r.answer().latency == 27 for r, _ in cases) >= 2
    assert max(r.answer().latency for r, _ in cases) == 27
    assert min(r.answer().latency for r, _ in cases if not r.seed) == 2
    # every other one back to back
    return [Request(r.seed, r.decel, r.index, r.value, r.rem, gap=i % 2) for i, (r, _) in enumerate(cases)]


@cocotb.test(timeout_time=1, timeout_unit="ms")
async def overflow_cases(dut) -> None:
    """The overflow flag on each side of the Q32.16 range; the longest and the shortest division."""
    await reset_unit(dut)
    failures, counts = await run_requests(dut, overflow_requests(), random.Random(seed_from_env()))
    assert not failures, "\n".join(failures)
    assert counts["ovf"] == 6, counts


async def pulse(dut: Any, port: str) -> None:
    """port '1' for one clock from this falling edge, sampled by the next rising edge."""
    getattr(dut, port).value = 1
    await RisingEdge(dut.clk)
    await FallingEdge(dut.clk)
    getattr(dut, port).value = 0


@cocotb.test(timeout_time=2, timeout_unit="ms")
async def flush_drops_the_answer(dut) -> None:
    """A flush (or a reset) at the sampling edge or while the answer is being computed: no answer, busy '0' after
    it, and the next request, sampled at the very next edge, is answered as usual."""
    seed = seed_from_env()
    rng = random.Random(seed + 1)
    await reset_unit(dut)
    # a known answer to see held across the flushes
    failures, _ = await run_requests(dut, [Request(False, False, 3, 123456789, 7)], rng)
    held = Request(False, False, 3, 123456789, 7).answer()
    cases = 0
    for trial in range(40):
        port = "rst" if trial % 10 == 9 else "flush"
        req = Request(False, bool(trial % 2), rng.getrandbits(rng.randint(0, 20)), rng.getrandbits(48), 0)
        latency = req.answer().latency  # the answer would be registered at edge e + latency
        # the flush edge, relative to the sampling edge e: e itself, e + 1, inside, the divider's last edge, the answer
        at = (0, 1, rng.randint(1, latency), latency - 1, latency)[trial % 5]
        await FallingEdge(dut.clk)
        drive(dut, req)
        dut.req.value = 1
        if at == 0:
            getattr(dut, port).value = 1
        await RisingEdge(dut.clk)
        sample_edge = now_cycles()
        await FallingEdge(dut.clk)
        dut.req.value = 0
        if at == 0:
            getattr(dut, port).value = 0
        else:
            if at > 1:
                await ClockCycles(dut.clk, at - 1, rising=False)
            await pulse(dut, port)  # sampled by edge e + at
        what = f"{port} at e + {at} of {req} (answer due at e + {latency})"
        if int(dut.ans_valid.value) or int(dut.busy.value):
            failures.append(f"{what}: ans_valid {dut.ans_valid.value}, busy {dut.busy.value} after it")
        # The previous answer stays. Not checked for a flush at the answer's own edge: there the RTL drops
        # ans_valid but still updates ans_value and ans_rem (harmless: nothing reads them without ans_valid).
        if port == "flush" and at < latency and answer_now(dut)[:2] != (held.value, held.remainder):
            failures.append(f"{what}: the previous answer was not held: {answer_now(dut)[:2]}")
        immediate = trial % 4 < 2
        if not immediate:
            # nothing comes out later either
            timer = Timer(ANSWER_LIMIT_CYCLES * CLK_PERIOD_NS, unit="ns")
            if await First(RisingEdge(dut.ans_valid), RisingEdge(dut.busy), timer) is not timer:
                failures.append(f"{what}: an answer or busy at edge e + {now_cycles() - sample_edge}")
            await FallingEdge(dut.clk)
        cases += 1
        # the next request, sampled at the edge right after the flush (or after a pause), is answered normally: a
        # dropped computation that went on would show in its value or its latency
        follow = random_request(rng)
        follow = Request(follow.seed, follow.decel, follow.index, follow.value, follow.rem, gap=0)
        more, _ = await run_requests(dut, [follow], rng)
        failures += [f"after {what}: {m}" for m in more]
        held = follow.answer()
        if held.ovf:  # an overflowing answer's value is not specified: put a known one back
            known = Request(True, False, 0, rng.getrandbits(48), 0, gap=1)
            failures += (await run_requests(dut, [known], rng))[0]
            held = known.answer()
    assert not failures, f"{SEED_ENV}={seed}:\n" + "\n".join(failures)
    assert cases == 40


@cocotb.test(timeout_time=1, timeout_unit="ms")
async def busy_until_the_answer(dut) -> None:
    """busy is '1' in every cycle from the sampling edge of a step request to the edge that registers its answer,
    and '0' from that edge on (with ans_valid): the port's contract, clock by clock, for 24 requests."""
    seed = seed_from_env()
    rng = random.Random(seed + 2)
    await reset_unit(dut)
    failures: list[str] = []
    for i in range(24):
        req = random_request(rng)
        req = Request(False, req.decel, req.index, req.value, req.rem)
        latency = req.answer().latency
        await FallingEdge(dut.clk)
        drive(dut, req)
        dut.req.value = 1
        await RisingEdge(dut.clk)  # the sampling edge e
        await FallingEdge(dut.clk)
        dut.req.value = 0
        for c in range(latency + 1):  # the cycle after edge e + c
            if (int(dut.busy.value), int(dut.ans_valid.value)) != (int(c < latency), int(c == latency)):
                failures.append(
                    f"{SEED_ENV}={seed} request {i} ({req}), answer at e + {latency}: in the cycle after e + {c}, "
                    f"busy {dut.busy.value}, ans_valid {dut.ans_valid.value}"
                )
                break
            await FallingEdge(dut.clk)
    assert not failures, "\n".join(failures)


def test_next_delay() -> None:
    """The three cocotb tests above in one simulation; the seed is random unless NEXT_DELAY_SEED is set."""
    run_seeded("stepramp_next_delay", "test_next_delay", SEED_ENV, {"N_REQUESTS": str(env_int("N_REQUESTS", 3000))})
