# SPDX-License-Identifier: MIT
"""The machine inputs' synchroniser and filter (docs/algorithm.md, "Machine inputs"): when a pin's changes reach the
filtered level that the core acts on.

A pin change "after edge a" is sampled new from edge a + 1 on; the filtered level takes a new value at the edge where
the last N = max(FILTER, 1) samples, two edges old, all held it: a clean change after edge a arrives at
F = a + N + 2, and a level held for fewer than N samples (a bounce) never arrives.
"""

from __future__ import annotations

from collections.abc import Sequence

#: The inputs of one axis, in the order of their bits in STATUS and INPUT_CFG (ESTOP: one per core).
PINS: tuple[str, ...] = ("limit_neg", "limit_pos", "home", "estop")
#: Edges from a pin's first sample (edge a + 1) to the filtered level with N = 1: the synchroniser's two flip-flops.
SYNC_EDGES = 2
#: Widest INPUT_FILTER value (20 bits).
MAX_FILTER = (1 << 20) - 1


def filter_length(filter_clocks: int) -> int:
    """N: the samples a new level must hold (INPUT_FILTER, with 0 acting as 1); ValueError outside 0 .. MAX_FILTER."""
    if not isinstance(filter_clocks, int) or isinstance(filter_clocks, bool) or not 0 <= filter_clocks <= MAX_FILTER:
        raise ValueError(f"filter must be an integer number of clocks in 0 .. {MAX_FILTER}, got {filter_clocks!r}")
    return max(filter_clocks, 1)


def filtered_edges(changes: Sequence[tuple[int, int]], filter_clocks: int) -> list[tuple[int, int]]:
    """The filtered level's changes (edge F, new level) for a pin whose active level (after its polarity) becomes
    `level` after edge `a`, for each (a, level) of `changes` in time order; the level is 0 before the first change
    (as after reset). A run of samples of one value that lasts N samples or more moves the filtered level at its
    N-th sample, two edges later."""
    n = filter_length(filter_clocks)
    last: dict[int, int] = {}  # per edge, the level the pin ends with after it (the one sampled)
    previous = None
    for a, level in changes:
        if level not in (0, 1):
            raise ValueError(f"a pin level is 0 or 1, got {level!r}")
        if previous is not None and a < previous:
            raise ValueError(f"pin changes out of order: {a} after {previous}")
        last[a] = level
        previous = a
    runs: list[tuple[int, int]] = []  # (first edge, level) of each run of samples of one level
    for a, level in last.items():
        if level != (runs[-1][1] if runs else 0):
            runs.append((a, level))
    out: list[tuple[int, int]] = []
    filtered = 0
    for i, (a, level) in enumerate(runs):
        # Samples a + 1 .. the next change's edge (inclusive) hold this level.
        samples = None if i + 1 == len(runs) else runs[i + 1][0] - a
        if level != filtered and (samples is None or samples >= n):
            filtered = level
            out.append((a + n + SYNC_EDGES, level))
    return out


__all__ = ["MAX_FILTER", "PINS", "SYNC_EDGES", "filter_length", "filtered_edges"]
