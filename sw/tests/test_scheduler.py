# SPDX-License-Identifier: MIT
"""The shared ramp computer's scheduler model (stepramp.models.scheduler; docs/ramp_computer.md, "The scheduler")
against the bound it documents: axes whose pulses are at least ``axes * S`` clocks apart, each pulse asking for a
service of at most ``S`` clocks due at the next pulse, are all served in time, at 1, 2, 4 and 8 axes; one clock less
is late in the worst case (every axis asking on the same clock).

* test_worst_case_same_clock: every axis asks on the same clock, every service S: in time at axes * S, late at one
  clock less (the last axis served);
* test_exhaustive_small: every phase and every service length of 2 axes with S = 3 and of 3 axes with S = 2, two
  pulses each, at the shortest interval: none late;
* test_random_arrivals: seeded random phases, intervals from the bound up and service lengths up to S at 1, 2, 4
  and 8 axes: none late (the seed is printed; STEPRAMP_SEED replays it);
* test_serves_one_at_a_time_in_axis_order: services never overlap, an axis's own requests in order, the next
  axis after the last served first;
* test_rejects_bad_requests: an axis out of range, a service of no clock, a bound of no axis.
"""

from __future__ import annotations

import itertools
import os
import random

import pytest

from stepramp.models.scheduler import Request, Served, periodic_requests, round_robin, shortest_interval

S = 64  # the longest service the AVR446 computer is budgeted (docs/ramp_computer.md, "The budget")


def _late(served: list[Served]) -> list[Served]:
    return [s for s in served if s.late]


@pytest.mark.parametrize("axes", [1, 2, 4, 8])
def test_worst_case_same_clock(axes: int) -> None:
    t_min = shortest_interval(axes, S)
    assert t_min == axes * S
    for interval, late in ((t_min, []), (t_min - 1, [axes - 1] * 4)):
        reqs = periodic_requests(axes, [[interval] * 4] * axes, [[S] * 4] * axes, [0] * axes)
        served = round_robin(reqs, axes)
        assert len(served) == 4 * axes
        # at the bound nothing is late; one clock short, the axis served last is late at each of its four pulses
        assert [s.request.axis for s in _late(served)] == late, interval


@pytest.mark.parametrize(("axes", "s"), [(2, 3), (3, 2)])
def test_exhaustive_small(axes: int, s: int) -> None:
    t_min = shortest_interval(axes, s)
    count = 0
    for phases in itertools.product(range(t_min), repeat=axes):
        for lengths in itertools.product(range(1, s + 1), repeat=2 * axes):
            per_axis = [list(lengths[2 * a : 2 * a + 2]) for a in range(axes)]
            served = round_robin(periodic_requests(axes, [[t_min, t_min]] * axes, per_axis, list(phases)), axes)
            assert not _late(served), (phases, per_axis, _late(served))
            count += 1
    assert count == t_min**axes * s ** (2 * axes)


@pytest.mark.parametrize("axes", [1, 2, 4, 8])
def test_random_arrivals(axes: int) -> None:
    seed = int(os.environ.get("STEPRAMP_SEED", random.SystemRandom().randrange(1 << 32)))
    print(f"axes {axes}: STEPRAMP_SEED={seed}")
    rng = random.Random(seed)
    t_min = shortest_interval(axes, S)
    worst_slack = t_min
    for _ in range(200):
        pulses = 12
        intervals = [[t_min + (rng.randrange(3 * S) if rng.random() < 0.5 else 0) for _ in range(pulses)]]
        intervals += [[t_min + rng.choice((0, 0, 1, S, 5 * S)) for _ in range(pulses)] for _ in range(axes - 1)]
        lengths = [[rng.choice((S, S, rng.randint(1, S))) for _ in range(pulses)] for _ in range(axes)]
        phases = [rng.randrange(2 * t_min) for _ in range(axes)]
        served = round_robin(periodic_requests(axes, intervals, lengths, phases), axes)
        assert not _late(served), (seed, _late(served)[:3])
        worst_slack = min(worst_slack, *(s.request.due - s.end for s in served))
    print(f"axes {axes}: shortest interval {t_min} clocks, least slack {worst_slack} clocks")


def test_serves_one_at_a_time_in_axis_order() -> None:
    reqs = [Request(2, 0, 5, 100), Request(0, 0, 5, 100), Request(1, 1, 5, 100), Request(0, 1, 5, 100)]
    served = round_robin(reqs, 3)
    assert [(s.request.axis, s.start, s.end) for s in served] == [(0, 0, 5), (1, 5, 10), (2, 10, 15), (0, 15, 20)]
    # the axis after the last served goes first: after axis 1, axis 2 waits and is served before axis 0
    served = round_robin([Request(1, 0, 2, 50), Request(0, 1, 2, 50), Request(2, 1, 2, 50)], 3)
    assert [s.request.axis for s in served] == [1, 2, 0]
    # an idle computer starts a request at the edge that raises it
    assert round_robin([Request(0, 7, 3, 20)], 1) == [Served(Request(0, 7, 3, 20), 7, 10)]


def test_rejects_bad_requests() -> None:
    with pytest.raises(ValueError, match="axis 3 of 2"):
        round_robin([Request(3, 0, 1, 5)], 2)
    with pytest.raises(ValueError, match="at least one clock"):
        round_robin([Request(0, 0, 0, 5)], 1)
    with pytest.raises(ValueError, match="axes 0"):
        shortest_interval(0, S)
