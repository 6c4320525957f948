# SPDX-License-Identifier: MIT
"""Shared helpers for the cocotb testbenches: build directories, integers from the environment, and how two lists of
step edges differ. The clock, the reset and clock-edge numbers are stepramp.sim.clocking's (imported here for the
benches that take them from here)."""

from __future__ import annotations

import os
import random
import re
from collections.abc import Sequence
from pathlib import Path

import cocotb

from stepramp.sim.clocking import CLK_PERIOD_NS, now_cycles, start_clock_and_reset

REPO = Path(__file__).resolve().parents[1]


def build_dir(name: str) -> Path:
    """A build directory of its own for one test (pytest -n needs one per test), under build/sim or under
    $STEPRAMP_SIM_BUILD (make mutate runs several copies of the suite at once, each in its own)."""
    safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", name)
    path = Path(os.environ.get("STEPRAMP_SIM_BUILD", REPO / "build" / "sim")) / safe
    path.mkdir(parents=True, exist_ok=True)
    return path


def env_int(name: str, default: int) -> int:
    """An integer handed to the simulation through the environment."""
    return int(os.environ.get(name, default))


def first_mismatch(got: Sequence[int], want: Sequence[int]) -> int:
    """Index of the first element where two lists differ (the shorter one's length if it starts the other)."""
    return next((k for k, (a, b) in enumerate(zip(got, want, strict=False)) if a != b), min(len(got), len(want)))


def edges_differ(got: Sequence[int], want: Sequence[int]) -> str:
    """How the step edges seen differ from the model's: both counts and the first difference."""
    k = first_mismatch(got, want)
    return (
        f"{len(got)} edges vs {len(want)} expected; first difference at pulse {k}: "
        f"rtl {list(got[k : k + 3])} model {list(want[k : k + 3])}"
    )


#: The clock period and its half and quarter, in ps (the output-log benches' Timers: tb/test_next_delay_exact.py,
#: tb/test_isqrt.py).
PERIOD = CLK_PERIOD_NS * 1000
HALF, QUARTER = PERIOD // 2, PERIOD // 4


def where(dt: int) -> str:
    """A time after a rising edge, as the edges from it: "at + 3", or between edges."""
    if dt % PERIOD:
        return f"{dt} ps (not at a rising edge)"
    return f"at + {dt // PERIOD}"


def garbage_rng(seed_env: str, seed: int, test: str) -> random.Random:
    """A bench's own generator for the random inputs it drives while a unit is busy: the cases a test draws (from
    the seed in seed_env) do not depend on how much garbage the bench drew."""
    return random.Random(f"{seed_env}={seed} {test} garbage")


__all__ = [
    "CLK_PERIOD_NS",
    "HALF",
    "PERIOD",
    "QUARTER",
    "build_dir",
    "cocotb",
    "edges_differ",
    "env_int",
    "first_mismatch",
    "garbage_rng",
    "now_cycles",
    "start_clock_and_reset",
    "where",
]
