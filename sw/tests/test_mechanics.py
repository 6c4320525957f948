# SPDX-License-Identifier: MIT
"""The mechanical model's pure parts (stepramp.sim.mechanics): switches and the bounce pattern generator. Each
pattern, sampled by a clock at a random phase and passed through the input filter as docs/algorithm.md specifies it
("Filter"), must change the filtered level once, N + 2 edges after the edge that first samples the pin's last
change: the filter removes every bounce, however close to N its intervals come."""

from __future__ import annotations

import itertools
import math
import random

import pytest

from stepramp.sim.mechanics import Bounce, Switch, bounce_intervals


def test_switch_sides_and_first_position_off() -> None:
    home = Switch("home", at=-40, side=-1)
    assert [home.active(p) for p in (-41, -40, -39)] == [True, True, False]
    assert home.first_off == -39
    top = Switch("limit_pos", at=500, side=1, active_low=True)
    assert [top.active(p) for p in (499, 500)] == [False, True]
    assert top.first_off == 499
    assert (top.level(True), top.level(False), home.level(True)) == (0, 1, 1)


def filtered_changes(samples: list[int], n: int) -> list[int]:
    """The clock edges k at which the filtered level changes, for the synchroniser's first flip-flop holding
    samples[k] after edge k (docs/algorithm.md, "Filter": f changes at k when p(k-1-N) .. p(k-2) all differ from f and
    all come after f's previous change)."""
    f, last, out = 0, -(10**9), []
    for k in range(len(samples)):
        window = range(k - 1 - n, k - 1)
        if window.start >= 0 and k - n - 1 >= last - 1 and all(samples[i] != f for i in window):
            f, last = 1 - f, k
            out.append(k)
    return out


def sample(changes: list[float], edges: int) -> list[int]:
    """A pin that starts at 0 and toggles at each time of `changes` (clocks, not on an edge), sampled at edges
    0 .. edges-1 (a change between edges a and a + 1 is seen from edge a + 1 on)."""
    out, level, i = [], 0, 0
    for k in range(edges):
        while i < len(changes) and changes[i] < k:
            level ^= 1
            i += 1
        out.append(level)
    return out


@pytest.mark.parametrize("n", [4, 5, 17, 60, 200])
def test_bounce_patterns_pass_the_filter_once(n: int) -> None:
    bounce = Bounce(filter_clocks=n, max_bounces=5, near=0.4, clean=0.1)
    rng = random.Random(n)
    counts, near = set(), 0
    for _ in range(400):
        intervals = bounce_intervals(rng, bounce)
        assert len(intervals) % 2 == 0, "the pin must end at its new level"
        assert all(bounce.min_clocks <= d <= bounce.max_interval < n - 1 for d in intervals), intervals
        counts.add(len(intervals) // 2)
        near += bool(intervals) and max(intervals[0::2]) > bounce.max_interval - 3
        start = 10 + rng.random()  # the crossing, at a random phase of the clock
        times = [start, *(start + t for t in itertools.accumulate(intervals))]
        if any(abs(t - round(t)) < 1e-9 for t in times):
            continue  # a change on an edge: the sampling is ambiguous (measure zero)
        edges = math.ceil(times[-1]) + 3 * n + 10
        changes = filtered_changes(sample(times, edges), n)
        assert changes == [math.floor(times[-1]) + n + 2], (intervals, changes)
    assert counts == set(range(6)), counts  # clean patterns and 1 .. max_bounces bounces
    assert near > 40, "too few patterns near the filter length"
    assert bounce.settle_clocks >= bounce.lag_clocks + 2 * bounce.max_bounces * bounce.max_interval


def test_a_run_as_long_as_the_filter_would_pass() -> None:
    """The reference filter itself: a level held N samples passes, N - 1 does not (so the test above can fail)."""
    n = 10
    assert filtered_changes(sample([5.5, 5.5 + n - 1], 60), n) == []
    assert filtered_changes(sample([5.5, 5.5 + n], 60), n) == [6 + n + 1, 16 + n + 1]  # up, then down again


def test_bounce_is_seeded_and_checked() -> None:
    bounce = Bounce(filter_clocks=60)
    assert bounce_intervals(random.Random(3), bounce) == bounce_intervals(random.Random(3), bounce)
    with pytest.raises(ValueError, match="at least 4 clocks"):
        bounce_intervals(random.Random(1), Bounce(filter_clocks=3))
    with pytest.raises(ValueError, match="min_clocks"):
        bounce_intervals(random.Random(1), Bounce(filter_clocks=10, min_clocks=0.5))
    assert bounce_intervals(random.Random(1), Bounce(filter_clocks=10, max_bounces=0)) == []
