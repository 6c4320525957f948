# SPDX-License-Identifier: MIT
"""Shared helpers for the cocotb testbenches: build directories, integers and random seeds from the environment, a
run with the C driver library, and how two lists of step edges differ. The clock, the reset and clock-edge numbers
are stepramp.sim.clocking's (imported here for the benches that take them from here)."""

from __future__ import annotations

import os
import random
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import cocotb

from stepramp.sim.clocking import CLK_PERIOD_NS, now_cycles, start_clock_and_reset
from stepramp.sim.runner import run_cocotb
from stepramp.tools import clib

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


def random_seed(env: str, what: str) -> int:
    """The seed of a random test: $env when set, else a fresh one; printed ("<what>: <env>=<seed>", shown with a
    failure) so that the run can be replayed."""
    seed = env_int(env, random.SystemRandom().randrange(1 << 32))
    print(f"{what}: {env}={seed}")
    return seed


def run_seeded(top: str, module: str, seed_env: str, extra_env: Mapping[str, str] | None = None) -> None:
    """run_cocotb of a unit bench that draws its cases from a seed: a random_seed handed to the simulation in
    $seed_env; built in build_dir of the top's name without "stepramp_"."""
    seed = random_seed(seed_env, top)
    run_cocotb(
        top, module, build_dir(top.removeprefix("stepramp_")), extra_env={seed_env: str(seed), **(extra_env or {})}
    )


#: The C driver library that the benches call through their bus model (stepramp.sim.cdriver; make -C sw/c lib),
#: named to the simulation in $STEPRAMP_C_CB_LIB.
C_CB_LIB = REPO / "sw" / "c" / "build" / "libstepramp_cb.so"


def run_with_c_lib(
    top: str,
    module: str,
    build: Path,
    testcase: str | Sequence[str],
    parameters: Mapping[str, object] | None = None,
) -> None:
    """run_cocotb with C_CB_LIB built first (make -C sw/c lib: a missing toolchain is a failure, not a skip) and
    named in $STEPRAMP_C_CB_LIB."""
    clib.build("lib")
    assert C_CB_LIB.is_file(), f"make -C sw/c lib did not build {C_CB_LIB}"
    run_cocotb(
        top, module, build, parameters=parameters, testcase=testcase, extra_env={"STEPRAMP_C_CB_LIB": str(C_CB_LIB)}
    )


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
    "C_CB_LIB",
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
    "random_seed",
    "run_seeded",
    "run_with_c_lib",
    "start_clock_and_reset",
    "where",
]
