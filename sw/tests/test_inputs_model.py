# SPDX-License-Identifier: MIT
"""stepramp.models.inputs against the rule of docs/algorithm.md ("Machine inputs") played clock by clock: the two
synchroniser flip-flops and a filtered level that takes the second one's value once it has differed for N edges in
a row (a different formulation from the model's runs of samples)."""

from __future__ import annotations

import os
import random

import pytest

from stepramp.models.inputs import MAX_FILTER, filter_length, filtered_edges


def clockwise(changes: list[tuple[int, int]], filter_clocks: int, edges: int) -> list[tuple[int, int]]:
    """The rule, one rising edge at a time: sync1 samples the pin, sync2 follows sync1, and the filtered level
    follows sync2 once sync2 has differed from it at N edges in a row (counting restarts on any agreement)."""
    n = max(filter_clocks, 1)
    pin = sync1 = sync2 = level = count = 0
    out = []
    pending = list(changes)
    for k in range(edges):
        # the edge k: every flip-flop takes its input as it was before the edge
        new_level, new_count = level, 0
        if sync2 != level:
            if count + 1 >= n:
                new_level, new_count = sync2, 0
            else:
                new_count = count + 1
        sync1, sync2 = pin, sync1
        if new_level != level:
            out.append((k, new_level))
        level, count = new_level, new_count
        while pending and pending[0][0] == k:  # a change after edge k
            pin = pending.pop(0)[1]
    return out


def test_clean_change_arrives_n_plus_2_edges_later() -> None:
    for filter_clocks in (0, 1, 2, 7, 100):
        n = max(filter_clocks, 1)
        assert filtered_edges([(10, 1)], filter_clocks) == [(10 + n + 2, 1)]
        assert filtered_edges([(10, 1), (500, 0)], filter_clocks) == [(12 + n, 1), (502 + n, 0)]


def test_bounces_shorter_than_the_filter_vanish() -> None:
    # active for 4 samples, then back: gone with N = 5, through with N = 4
    assert filtered_edges([(10, 1), (14, 0)], 5) == []
    assert filtered_edges([(10, 1), (14, 0)], 4) == [(16, 1), (20, 0)]
    # a bounce on the way: the count restarts after it
    assert filtered_edges([(10, 1), (12, 0), (13, 1)], 5) == [(13 + 5 + 2, 1)]


def test_bad_arguments() -> None:
    with pytest.raises(ValueError, match="filter"):
        filter_length(MAX_FILTER + 1)
    with pytest.raises(ValueError, match="filter"):
        filter_length(-1)
    with pytest.raises(ValueError, match="order"):
        filtered_edges([(10, 1), (5, 0)], 1)
    with pytest.raises(ValueError, match="0 or 1"):
        filtered_edges([(10, 2)], 1)


def test_random_pins_equal_the_clock_by_clock_rule() -> None:
    seed = int(os.environ.get("INPUTS_SEED", random.randrange(1 << 30)))
    print(f"INPUTS_SEED={seed}")
    rng = random.Random(seed)
    for _ in range(400):
        filter_clocks = rng.choice([0, 1, 2, 3, 5, 8, 13])
        changes, a, level = [], 0, 0
        for _ in range(rng.randrange(1, 12)):
            a += rng.randrange(0, 2 * max(filter_clocks, 1) + 3)
            level = rng.choice([level, 1 - level, 1 - level])
            changes.append((a, level))
        want = clockwise(changes, filter_clocks, a + 40)
        assert filtered_edges(changes, filter_clocks) == want, (seed, filter_clocks, changes)
