# SPDX-License-Identifier: MIT
"""stepramp_sched (issue 35): the shared ramp computer's round-robin scheduler against
stepramp.models.scheduler.round_robin, at 1, 2, 4 and 8 axes.

The bench plays the axes and the computer: a request of the model raised at edge t holds its axis's `req` from the
falling edge before t until the edge that grants it; the computer is `free` at an edge when no service runs or the
one running ends there (a service granted at edge s of length L ends at s + L). Every service's axis, start and end
edge must equal the model's, in the model's order:

* worst case: every axis asks on the same clock and then at every pulse of intervals of N * S clocks (S the
  longest service), and again at N * S - 1, where the model has late services: the RTL serves exactly as the model
  (its lateness is the model's, checked in sw/tests/test_scheduler.py);
* random: seeded random phases, intervals of at least N * S and service lengths 1 .. S, where the model is never
  late, plus a burst of several requests of one axis (served in the order raised).

The seed is printed and replays with SCHED_SEED=<seed> pytest tb/test_sched.py.
"""

from __future__ import annotations

import os
import random

import pytest
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge

from stepramp.models.scheduler import Request, Served, periodic_requests, round_robin
from stepramp.sim.runner import run_cocotb
from tbutil import build_dir, cocotb, random_seed, start_clock_and_reset

SEED_ENV = "SCHED_SEED"
#: The longest service in these runs (clocks).
S = 5


async def play(dut, requests: list[Request], axes: int) -> list[Served]:
    """Run the requests through the RTL; returns the services in the order they started."""
    queues = [sorted((r for r in requests if r.axis == a), key=lambda r: r.at) for a in range(axes)]
    served: list[Served] = []
    busy_until = 0
    t = 0
    last_at = max((r.at for r in requests), default=0)
    while any(queues) or t <= last_at:
        # inputs for edge t, set between the edges
        waiting = [1 if q and q[0].at <= t else 0 for q in queues]
        dut.req.value = sum(bit << a for a, bit in enumerate(waiting))
        dut.free.value = int(busy_until <= t)
        await ReadOnly()
        grant = int(dut.grant.value)
        await RisingEdge(dut.clk)  # edge t
        if grant:
            assert grant & (grant - 1) == 0, f"edge {t}: grant {grant:b} is not one-hot"
            axis = grant.bit_length() - 1
            assert waiting[axis] and busy_until <= t, f"edge {t}: grant {grant:b} without a request or while busy"
            req = queues[axis].pop(0)
            served.append(Served(req, t, t + req.length))
            busy_until = t + req.length
        await FallingEdge(dut.clk)
        t += 1
    return served


async def start(dut) -> int:
    axes = len(dut.grant.value)
    dut.req.value = 0
    dut.free.value = 0
    await start_clock_and_reset(dut.clk, dut.rst)
    await FallingEdge(dut.clk)
    return axes


async def reset(dut) -> None:
    """One clock of rst (between runs: the model starts each run with axis 0 first)."""
    dut.req.value = 0
    dut.rst.value = 1
    await FallingEdge(dut.clk)
    dut.rst.value = 0


def check(label: str, got: list[Served], want: list[Served]) -> None:
    for k, (g, w) in enumerate(zip(got, want, strict=False)):
        assert (g.request, g.start, g.end) == (w.request, w.start, w.end), f"{label}: service {k}: RTL {g}, model {w}"
    assert len(got) == len(want), f"{label}: {len(got)} services, the model {len(want)}"


@cocotb.test(timeout_time=2, timeout_unit="ms")
async def worst_case(dut) -> None:
    """Every axis asks at edge 0, then at intervals of N * S (in time) and N * S - 1 (late in the model)."""
    axes = await start(dut)
    for interval, in_time in ((axes * S, True), (axes * S - 1, False)):
        reqs = periodic_requests(axes, [[interval] * 6] * axes, [[S] * 6] * axes, [0] * axes)
        want = round_robin(reqs, axes)
        got = await play(dut, reqs, axes)
        check(f"{axes} axes, intervals {interval}", got, want)
        late = any(s.late for s in want)
        assert late != in_time, f"{axes} axes, intervals {interval}: the model's lateness {late}"
        dut._log.info("%d axes, intervals %d: %d services, late %s", axes, interval, len(got), late)
        await reset(dut)


@cocotb.test(timeout_time=4, timeout_unit="ms")
async def random_arrivals(dut) -> None:
    """Random phases, intervals >= N * S and lengths 1 .. S (never late), and a burst of one axis."""
    axes = await start(dut)
    rng = random.Random(int(os.environ[SEED_ENV]))
    reqs = periodic_requests(
        axes,
        [[rng.randint(axes * S, axes * S + 7) for _ in range(12)] for _ in range(axes)],
        [[rng.randint(1, S) for _ in range(12)] for _ in range(axes)],
        [rng.randint(0, axes * S) for _ in range(axes)],
    )
    want = round_robin(reqs, axes)
    assert not any(s.late for s in want)
    check(f"{axes} axes, random", await play(dut, reqs, axes), want)
    await reset(dut)
    t0 = 3
    burst = [Request(axes - 1, t0 + k, rng.randint(1, S), t0 + 1000) for k in range(3)]
    burst += [Request(a, t0 + 1, S, t0 + 1000) for a in range(axes - 1)]
    check(f"{axes} axes, burst", await play(dut, burst, axes), round_robin(burst, axes))


@pytest.mark.parametrize("axes", [1, 2, 4, 8])
def test_sched(axes: int) -> None:
    seed = random_seed(SEED_ENV, f"stepramp_sched, {axes} axes")
    run_cocotb(
        "stepramp_sched",
        "test_sched",
        build_dir(f"sched_{axes}"),
        parameters={"G_AXES": axes},
        extra_env={SEED_ENV: str(seed)},
    )
