# SPDX-License-Identifier: MIT
"""The C driver (sw/c/src/stepramp.c): its host unit tests, and its bus writes against the Python driver's.

``make -C sw/c`` builds and runs the host tests (a missing gcc or make is a failure, not a skip). The shared
library holds the driver with its register access routed to the fake register bank of stepramp_fakebus.c, whose
write log ctypes reads: for random plans (stepramp_program) and random valid moves (stepramp_move), each the first
program of a freshly initialised driver, the C driver must write exactly the (offset, value) pairs of
stepramp.board.driver.plan_writes, in the same order, with all byte enables, then the segment registers 0
(segment_writes(NO_SEGMENT): after init the driver does not know what they hold), and START to byte 0 of CTRL; an
invalid move returns the plan's error and writes nothing. A fresh driver's first two moves write what the Python
driver's write (the segment registers 0 with the first only). For random jogs
(stepramp_jog, with random STEP width and space) and the two moves after each, the C driver must write what the
Python driver's jog and move write (plan_jog, plan_writes and segment_writes), or fail with the same error and
write nothing.
"""

from __future__ import annotations

import ctypes
import dataclasses
import math
import random
import re
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from test_c_change import RESULT_NAMES, change_error_name
from test_driver import FakeBank
from test_driver import run as run_async

from c_abi import CPlan, log_uniform, run, struct_fields
from stepramp.board.driver import MODES, NO_SEGMENT, Outputs, StepRamp, plan_writes, segment_writes
from stepramp.board.plan import (
    MAX_PRESCALE,
    MAX_STEPS,
    MIN_INTERVAL_CLKS,
    MIN_INTERVAL_CLKS_EXACT,
    RAMP_AVR446,
    RAMP_EXACT,
    REG_WIDTHS,
    Plan,
    plan_move,
)
from stepramp.board.regmap import ERROR_CODES, ID_RAMP_BIT, ID_VALUE, REGISTERS, RW, offset
from stepramp.sim.profiles import INVALID_INPUTS, PROFILES, design_args
from stepramp.tools import clib

DRIVER_HEADER = clib.SRC_DIR / "stepramp.h"
FAKEBUS_HEADER = clib.HOST_DIR / "stepramp_fakebus.h"


def _define(header: Path, name: str) -> int:
    match = re.search(rf"#define {name} (\d+)u", header.read_text())
    assert match, f"no {name} in {header}"
    return int(match.group(1))


FAKEBUS_WORDS = _define(FAKEBUS_HEADER, "STEPRAMP_FAKEBUS_WORDS")
LOG_MAX = _define(FAKEBUS_HEADER, "STEPRAMP_FAKEBUS_LOG_MAX")
FAKEBUS_BASE = 0x44A0_0000  # STEPRAMP_FAKEBUS_BASE of stepramp_ctypes.h

RANDOM_COUNT = 500


class CWrite(ctypes.Structure):
    """stepramp_fakebus_write_t."""

    _fields_ = [("offset", ctypes.c_uint32), ("value", ctypes.c_uint32), ("be", ctypes.c_uint32)]


class CFakeBus(ctypes.Structure):
    """stepramp_fakebus_t."""

    _fields_ = [
        ("base", ctypes.c_size_t),
        ("regs", ctypes.c_uint32 * FAKEBUS_WORDS),
        ("log", CWrite * LOG_MAX),
        *(
            (name, ctypes.c_uint32)
            for name in (
                "writes",
                "reads",
                "status_reads",
                "bus_errors",
                "idles",
                "starts",
                "soft_stops",
                "hard_stops",
                "finish_after",
                "finish_err_code",
            )
        ),
    ]


class CDev(ctypes.Structure):
    """stepramp_t."""

    _fields_ = struct_fields(DRIVER_HEADER, "stepramp_t")


class COutputs(ctypes.Structure):
    """stepramp_outputs_t."""

    _fields_ = struct_fields(DRIVER_HEADER, "stepramp_outputs_t")


def _driver_result_names() -> dict[int, str]:
    """The driver's own results (stepramp.h), then stepramp_plan.h's, by value."""
    text = re.sub(r"/\*.*?\*/", "", DRIVER_HEADER.read_text(), flags=re.S)
    return RESULT_NAMES | {int(value): name for name, value in re.findall(r"(STEPRAMP_E\w+)\s*=\s*(\d+)", text)}


DRIVER_RESULTS = _driver_result_names()
DRIVER_RESULTS_BY_NAME = {name: value for value, name in DRIVER_RESULTS.items()}

#: The Python driver's own ValueErrors of plan_jog and plan -> the C driver's results.
JOG_ERROR_KEYS = {
    "the jog speed must be a finite non-zero number": "STEPRAMP_EJOG_SPEED",
    "does not fit the jog's shortest interval": "STEPRAMP_EGAP",
    "does not fit the shortest interval of the move": "STEPRAMP_EGAP",
}


@pytest.fixture(scope="module")
def lib(build: Path) -> ctypes.CDLL:
    """libstepramp.so (plan, driver and fake bank) with its argument and result types declared."""
    so = ctypes.CDLL(str(build / "libstepramp.so"))
    so.stepramp_plan_move.argtypes = [ctypes.POINTER(CPlan), ctypes.c_int64, *(ctypes.c_double,) * 5, ctypes.c_uint32]
    so.stepramp_plan_move.restype = ctypes.c_int
    so.stepramp_fakebus_move.argtypes = [ctypes.c_int64, *(ctypes.c_double,) * 5, ctypes.c_uint32]
    so.stepramp_fakebus_move.restype = ctypes.c_int
    so.stepramp_fakebus_program.argtypes = [ctypes.POINTER(CPlan)]
    so.stepramp_fakebus_program.restype = ctypes.c_int
    so.stepramp_fakebus_state.argtypes = []
    so.stepramp_fakebus_state.restype = ctypes.POINTER(CFakeBus)
    for name in ("stepramp_fakebus_sizeof_plan", "stepramp_fakebus_sizeof_state"):
        getattr(so, name).argtypes = []
        getattr(so, name).restype = ctypes.c_size_t
    for name in ("stepramp_strcoreerror", "stepramp_corename"):
        getattr(so, name).argtypes = [ctypes.c_uint32]
        getattr(so, name).restype = ctypes.c_char_p
    so.stepramp_strresult.argtypes = [ctypes.c_int]
    so.stepramp_strresult.restype = ctypes.c_char_p
    dev = ctypes.POINTER(CDev)
    for name, args in {
        "stepramp_init": [dev, ctypes.c_size_t, ctypes.c_double, ctypes.c_double, ctypes.c_uint32],
        "stepramp_init_ramp": [
            dev,
            ctypes.c_size_t,
            ctypes.c_double,
            ctypes.c_double,
            ctypes.c_uint32,
            ctypes.c_uint32,
        ],
        "stepramp_jog": [dev, *(ctypes.c_double,) * 3],
        "stepramp_move": [dev, ctypes.c_int64, *(ctypes.c_double,) * 3],
        "stepramp_configure_outputs": [dev, ctypes.POINTER(COutputs)],
    }.items():
        getattr(so, name).argtypes, getattr(so, name).restype = args, ctypes.c_int
    so.stepramp_fakebus_reset.argtypes = [ctypes.c_size_t, ctypes.c_uint32]
    so.stepramp_fakebus_reset.restype = so.stepramp_fakebus_clear_log.restype = None
    assert so.stepramp_fakebus_sizeof_plan() == ctypes.sizeof(CPlan), "stepramp_plan_t layout"
    assert so.stepramp_fakebus_sizeof_state() == ctypes.sizeof(CFakeBus), "stepramp_fakebus_t layout"
    return so


Write = tuple[int, int, int]
"""(offset, value, byte enables) of one bus write."""


def bus_writes(so: ctypes.CDLL) -> list[Write]:
    """The fake bank's write log since the driver call, after checking that it saw no bus error."""
    state = so.stepramp_fakebus_state().contents
    assert state.bus_errors == 0, f"{state.bus_errors} bus errors"
    assert state.writes <= LOG_MAX
    return [(w.offset, w.value, w.be) for w in state.log[: state.writes]]


def c_plan(plan: Plan) -> CPlan:
    """A Python Plan as stepramp_plan_t (every field the C struct has must be in the Plan)."""
    return CPlan(**{name: getattr(plan, name) for name, _ in CPlan._fields_})


def expected_motion_writes(plan: Plan) -> list[Write]:
    """plan_writes(plan) with full byte enables."""
    return [(addr, value, 0xF) for addr, value in plan_writes(plan)]


ZERO_SEGMENT_WRITES: list[Write] = [(addr, value, 0xF) for addr, value in segment_writes(NO_SEGMENT)]
"""SEGMENT .. HEAD_PROD_HI written 0, which the first program after stepramp_init adds (their contents unknown)."""


def expected_first_program_writes(plan: Plan) -> list[Write]:
    """What the first program of a fresh driver writes: the motion registers, then the segment registers 0."""
    return [*expected_motion_writes(plan), *ZERO_SEGMENT_WRITES]


START_WRITE: Write = (offset("CTRL"), 0x1, 0x1)
"""START: bit 0 in byte 0 of CTRL, the other lanes (the interrupt enables) untouched."""


def _random_field(rng: random.Random, width: int) -> int:
    r = rng.random()
    if r < 0.1:
        return rng.choice((0, 1, (1 << width) - 1, 1 << (width - 1), (1 << min(width, 32)) - 1))
    if r < 0.5:
        return rng.getrandbits(width)
    return rng.getrandbits(rng.randint(1, width))  # small and large magnitudes alike


def random_plans(seed: int, count: int) -> list[Plan]:
    """Plans with random register values over each field's full width (LO/HI splits, sign of STEPS), for either ramp
    (not a register: it changes no write)."""
    rng = random.Random(seed)
    names = [f.name for f in dataclasses.fields(Plan) if f.name in REG_WIDTHS]
    return [
        Plan(
            **{name: _random_field(rng, REG_WIDTHS[name]) for name in names}, ramp=rng.choice((RAMP_AVR446, RAMP_EXACT))
        )
        for _ in range(count)
    ]


def random_valid_moves(seed: int, count: int) -> list[dict[str, Any]]:
    """plan_move keyword arguments that plan without error, designed in the tick domain over wide ranges."""
    rng = random.Random(seed)
    moves: list[dict[str, Any]] = []
    while len(moves) < count:
        prescale = rng.choice((1, 1, 2, 7, 50, 1000, MAX_PRESCALE, rng.randint(1, MAX_PRESCALE)))
        spr = rng.choice((200.0, 400.0, 1600.0, 3200.0, 51200.0)) * rng.choice((1.0, 1.37))
        fclk = log_uniform(rng, 1e5, 2e8)
        period = max(64.0 / prescale, 1.0) * log_uniform(rng, 1.0, 1e4)  # cruise period, ticks
        n_a = log_uniform(rng, 0.1, 1e6)
        n_d = n_a * log_uniform(rng, 1e-2, 1e2)
        steps = rng.choice((0, 1, 2, 3, MAX_STEPS, round(log_uniform(rng, 1.0, MAX_STEPS))))
        move = design_args(steps * rng.choice((1, -1)), period, n_a, n_d, spr, fclk, prescale)
        try:
            plan_move(**move)
        except ValueError:
            continue
        moves.append(move)
    return moves


def _move_args(move: dict[str, Any]) -> tuple[Any, ...]:
    return (move["steps"], *(float(move[k]) for k in ("accel", "decel", "speed", "spr", "fclk")), move["prescale"])


# --------------------------------------------------------------------------------------------------------


def test_host_driver_tests_pass(build: Path) -> None:
    result = run([str(build / "test_stepramp")])
    assert result.returncode == 0, f"C driver host tests failed:\n{result.stdout}\n{result.stderr}"
    match = re.search(r"(\d+) checks, 0 failed", result.stdout)
    assert match, result.stdout
    assert int(match.group(1)) > 1000, result.stdout


def test_plan_struct_matches_python(lib: ctypes.CDLL) -> None:
    python_fields = [f.name for f in dataclasses.fields(Plan)]
    c_fields = [name for name, _ in CPlan._fields_]
    assert c_fields == python_fields


def test_program_random_plans_like_plan_writes(lib: ctypes.CDLL) -> None:
    plans = random_plans(20240613, RANDOM_COUNT)
    mismatches: list[str] = []
    for plan in plans:
        assert lib.stepramp_fakebus_program(ctypes.byref(c_plan(plan))) == 0
        got = bus_writes(lib)
        want = expected_first_program_writes(plan)
        if got != want:
            diff = sorted(set(got) ^ set(want))
            mismatches.append(f"{plan}: differ in {[(hex(a), hex(v), be) for a, v, be in diff]}")
    assert not mismatches, f"{len(mismatches)} of {len(plans)} plans:\n" + "\n".join(mismatches[:5])
    # the random plans reach every corner: both directions, HI words in use, 32-bit cruise integer part
    assert {p.direction for p in plans} == {0, 1}
    assert any(p.c_first >> 32 for p in plans) and any(p.cruise >> 63 for p in plans)


def test_move_random_valid_moves_like_plan_writes(lib: ctypes.CDLL) -> None:
    moves = random_valid_moves(446_2, RANDOM_COUNT) + [p.args() for p in PROFILES]
    mismatches: list[str] = []
    for move in moves:
        rc = lib.stepramp_fakebus_move(*_move_args(move))
        assert rc == 0, f"{move}: C move failed with {lib.stepramp_strresult(rc).decode()}"
        got = bus_writes(lib)
        want = [*expected_first_program_writes(plan_move(**move)), START_WRITE]
        if got != want:
            diff = sorted(set(got) ^ set(want))
            mismatches.append(f"{move}: differ in {[(hex(a), hex(v), be) for a, v, be in diff]}")
        state = lib.stepramp_fakebus_state().contents
        assert (state.starts, state.soft_stops, state.hard_stops) == (1, 0, 0)
    assert not mismatches, f"{len(mismatches)} of {len(moves)} moves:\n" + "\n".join(mismatches[:5])


def test_stop_ratio_written_from_the_plan(lib: ctypes.CDLL) -> None:
    """STOP_RATIO is the plan's accel / decel, like plan_writes."""
    for move in [p.args() for p in PROFILES[:50]]:
        assert lib.stepramp_fakebus_move(*_move_args(move)) == 0
        got = bus_writes(lib)
        assert got == [*expected_first_program_writes(plan_move(**move)), START_WRITE], move


def test_invalid_move_writes_nothing(lib: ctypes.CDLL) -> None:
    checked = 0
    for args, message in INVALID_INPUTS:
        if not (isinstance(args["steps"], int) and isinstance(args["prescale"], int)):
            continue  # a float steps or prescale cannot reach the C API (integer parameters)
        with pytest.raises(ValueError, match=re.escape(message)):
            plan_move(**args)
        out = CPlan()
        plan_rc = lib.stepramp_plan_move(ctypes.byref(out), *_move_args(args))
        assert plan_rc != 0
        assert lib.stepramp_fakebus_move(*_move_args(args)) == plan_rc, f"{args}: not the plan's error"
        assert bus_writes(lib) == [], f"{args}: the driver wrote registers for an invalid move"
        checked += 1
    assert checked >= 15


class Pair:
    """The C driver on the fake bank and the Python driver on test_driver's FakeBank, set up alike (init, stepping
    outputs; with a ramp, stepramp_init_ramp on a core whose ID says that ramp, and StepRamp(..., ramp)), their logs
    cleared before each call; a call gives each side's result and writes."""

    def __init__(
        self, so: ctypes.CDLL, fclk: float, spr: float, prescale: int, outputs: Outputs, ramp: int | None = None
    ) -> None:
        self.so = so
        self.dev = CDev()
        if ramp is None:
            so.stepramp_fakebus_reset(FAKEBUS_BASE, ID_VALUE)
            assert so.stepramp_init(ctypes.byref(self.dev), FAKEBUS_BASE, fclk, spr, prescale) == 0
        else:
            so.stepramp_fakebus_reset(FAKEBUS_BASE, ID_VALUE | ramp << ID_RAMP_BIT)
            assert so.stepramp_init_ramp(ctypes.byref(self.dev), FAKEBUS_BASE, fclk, spr, prescale, ramp) == 0
            assert self.dev.ramp == ramp
        fields = dataclasses.asdict(outputs) | {"mode": MODES[outputs.mode]}
        assert so.stepramp_configure_outputs(ctypes.byref(self.dev), ctypes.byref(COutputs(**fields))) == 0
        self.bank = FakeBank()
        self.drv = StepRamp(self.bank, fclk, spr, prescale, RAMP_AVR446 if ramp is None else ramp)
        run_async(self.drv.configure_outputs(outputs))

    def call(self, name: str, *args: Any) -> tuple[tuple[str, list[Write]], tuple[str, list[Write]]]:
        """(Python's result and writes, C's): the result's C name (STEPRAMP_OK or an error); the writes as (offset,
        value, byte enables: the Python driver's strobe)."""
        self.so.stepramp_fakebus_clear_log()
        self.bank.log.clear()
        try:
            run_async(getattr(self.drv, name)(*args))
            py = "STEPRAMP_OK"
        except ValueError as exc:
            keys = [code for key, code in JOG_ERROR_KEYS.items() if key in str(exc)]
            py = keys[0] if keys else change_error_name(str(exc))
        rc = getattr(self.so, f"stepramp_{name}")(ctypes.byref(self.dev), *args)
        return (py, self.bank.log[:]), (DRIVER_RESULTS.get(rc, f"unknown result {rc}"), bus_writes(self.so))


def test_first_moves_like_the_python_driver(lib: ctypes.CDLL) -> None:
    """A freshly initialised driver's first two moves: the first writes the motion registers, the five segment
    registers 0 and START, the second the motion registers and START only, in C as in Python."""
    assert len(ZERO_SEGMENT_WRITES) == 5 and all(value == 0 for _, value, _ in ZERO_SEGMENT_WRITES)
    mismatches: list[str] = []
    for move in random_valid_moves(2026_0513, 100) + [p.args() for p in PROFILES[:20]]:
        pair = Pair(lib, move["fclk"], move["spr"], move["prescale"], Outputs())
        for i, steps in enumerate((move["steps"], -move["steps"])):
            args = (steps, float(move["accel"]), float(move["decel"]), float(move["speed"]))
            (py, py_writes), (c, c_writes) = pair.call("move", *args)
            plan = plan_move(**(move | {"steps": steps}))
            want = [*(expected_motion_writes(plan) if i else expected_first_program_writes(plan)), START_WRITE]
            if (py, py_writes) != ("STEPRAMP_OK", want) or (c, c_writes) != ("STEPRAMP_OK", want):
                mismatches.append(f"{move} move {i + 1}: python {py} {py_writes}, C {c} {c_writes}")
    assert not mismatches, f"{len(mismatches)} moves differ:\n" + "\n".join(mismatches[:5])


def random_jogs(seed: int, count: int, min_clks: int = 64) -> list[dict[str, Any]]:
    """Jogs designed in the tick domain over wide ranges (some too fast, some with a STEP width + space that does
    not fit, some with no valid speed), each with a STEP width and space, and the accel, decel and speed of a move
    whose shortest interval holds them; min_clks: the speed limit they are designed around (the exact mode's 256)."""
    rng = random.Random(seed)
    jogs = []
    for _ in range(count):
        prescale = rng.choice((1, 1, 2, 7, 50, 1000, MAX_PRESCALE, rng.randint(1, MAX_PRESCALE)))
        spr = rng.choice((200.0, 400.0, 1600.0, 3200.0, 51200.0)) * rng.choice((1.0, 1.37))
        fclk = log_uniform(rng, 1e5, 2e8)
        period = max(min_clks / prescale, 1.0) * log_uniform(rng, 0.5, 1e4)  # the jog's interval, ticks
        n_a, n_d = log_uniform(rng, 0.1, 1e6), log_uniform(rng, 0.1, 1e6)
        gap = min(round(period * prescale * log_uniform(rng, 0.01, 2.0)), 2 * 65535) if rng.random() < 0.3 else 2
        width = rng.randint(max(gap - 65535, 0), min(gap, 65535))
        args = design_args(0, period, n_a, n_d, spr, fclk, prescale)
        speed = args["speed"] * rng.choice((1.0, -1.0))
        if rng.random() < 0.03:
            speed = rng.choice((0.0, -0.0, math.nan, math.inf))
        move = design_args(0, max(period, (gap + min_clks) / prescale + 1.0), n_a, n_d, spr, fclk, prescale)
        jogs.append(
            {
                "init": (fclk, spr, prescale, Outputs(step_width=width, step_space=gap - width, dir_setup=gap % 7)),
                "jog": (speed, args["accel"], args["decel"]),
                "move": (move["accel"], move["decel"], move["speed"]),
            }
        )
    return jogs


def _jogs_like_python(lib: ctypes.CDLL, seed: int, min_clks: int, ramp: int | None) -> Counter[str]:
    """random_jogs(seed, RANDOM_COUNT, min_clks), each on a fresh Pair (with the ramp): the jog, then a move of -1000
    and one of 3 steps at the jog's move accel, decel and speed; every call's result and writes the same in C as in
    Python. Returns the count of each call's result ("jog OK", "move EGAP", ...)."""
    print(f"seed {seed}")
    jogs = random_jogs(seed, RANDOM_COUNT, min_clks)
    mismatches: list[str] = []
    results: Counter[str] = Counter()
    for jog in jogs:
        pair = Pair(lib, *jog["init"], ramp=ramp)
        for name, *args in [("jog", *jog["jog"]), ("move", -1000, *jog["move"]), ("move", 3, *jog["move"])]:
            (py, py_writes), (c, c_writes) = pair.call(name, *args)
            if (py, py_writes) != (c, c_writes):
                mismatches.append(f"{jog} {name}{tuple(args)}: python {py} {py_writes}, C {c} {c_writes}")
            results[f"{name} {py.removeprefix('STEPRAMP_')}"] += 1
    print(sorted(results.items()))
    assert not mismatches, f"{len(mismatches)} calls differ:\n" + "\n".join(mismatches[:5])
    return results


def test_jog_like_the_python_driver(lib: ctypes.CDLL) -> None:
    """stepramp_jog writes what StepRamp.jog writes (the plan's registers, the segment registers, START), and the
    moves after it what StepRamp.move writes (the segment registers cleared once); or both fail alike, writing
    nothing. The moves are slow enough for the STEP width + space (test_a_move_too_fast_for_the_step_gap)."""
    results = _jogs_like_python(lib, 2026_0512, MIN_INTERVAL_CLKS, None)
    assert {"jog OK", "jog EGAP", "jog ETOOFAST", "jog EJOG_SPEED"} <= set(results), results
    assert results["jog OK"] >= RANDOM_COUNT // 2 and results["move OK"] >= RANDOM_COUNT


def test_exact_jog_like_the_python_driver(lib: ctypes.CDLL) -> None:
    """A driver set up for an exact-mode core (stepramp_init_ramp, StepRamp(..., ramp=RAMP_EXACT)): its jogs and the
    moves after them write what the Python driver's write, both planned in exact mode, or both fail alike, writing
    nothing (the jogs designed around the exact mode's 256-clock speed limit)."""
    results = _jogs_like_python(lib, 2026_0514, MIN_INTERVAL_CLKS_EXACT, RAMP_EXACT)
    assert {"jog OK", "jog EGAP", "jog ETOOFAST", "jog EJOG_SPEED", "move OK"} <= set(results), results
    assert results["jog OK"] >= RANDOM_COUNT // 3 and results["move OK"] >= RANDOM_COUNT // 2, results


def test_exact_driver_checks_the_core_ramp(lib: ctypes.CDLL) -> None:
    """stepramp_init_ramp, like StepRamp.check_id, refuses a core whose ID bit 15 (G_RAMP) is not the driver's ramp
    (STEPRAMP_EID), and a ramp that is neither mode (STEPRAMP_ERAMP, as StepRamp's ValueError)."""
    dev = CDev()
    for core in (RAMP_AVR446, RAMP_EXACT):
        lib.stepramp_fakebus_reset(FAKEBUS_BASE, ID_VALUE | core << ID_RAMP_BIT)
        for ramp in (RAMP_AVR446, RAMP_EXACT):
            rc = lib.stepramp_init_ramp(ctypes.byref(dev), FAKEBUS_BASE, 1e6, 200.0, 1, ramp)
            assert DRIVER_RESULTS[rc] == ("STEPRAMP_OK" if ramp == core else "STEPRAMP_EID")
            assert dev.version == ID_VALUE & 0x3FFF
        want = "STEPRAMP_OK" if core == RAMP_AVR446 else "STEPRAMP_EID"
        assert DRIVER_RESULTS[lib.stepramp_init(ctypes.byref(dev), FAKEBUS_BASE, 1e6, 200.0, 1)] == want
    with pytest.raises(ValueError, match="ramp must be"):
        StepRamp(FakeBank(), 1e6, 200.0, 1, 2)
    assert DRIVER_RESULTS[lib.stepramp_init_ramp(ctypes.byref(dev), FAKEBUS_BASE, 1e6, 200.0, 1, 2)] == "STEPRAMP_ERAMP"


def test_a_core_without_windings_like_the_python_driver(lib: ctypes.CDLL) -> None:
    """ID bit 14 (NO_WINDINGS, a core built with G_WINDINGS false): stepramp_init sets dev->windings 0 as
    StepRamp.check_id sets windings False, both take the version from ID bits 13:0, and stepramp_configure_outputs
    refuses every winding mode with STEPRAMP_EWINDINGS (writing nothing) where StepRamp.configure_outputs raises its
    ValueError; the STEP/DIR mode writes the same words in both. With bit 14 clear every mode passes in both."""
    no_windings = 1 << 14
    for core_id in (ID_VALUE, ID_VALUE | no_windings, 0x5352_0000 | no_windings | 0x3F_FF):
        dev = CDev()
        lib.stepramp_fakebus_reset(FAKEBUS_BASE, core_id)
        assert lib.stepramp_init(ctypes.byref(dev), FAKEBUS_BASE, 1e6, 200.0, 1) == 0
        bank = FakeBank()
        bank.regs[offset("ID")] = core_id
        drv = StepRamp(bank, 1e6, 200.0)
        version = run_async(drv.check_id())
        assert version == dev.version == core_id & 0x3FFF, f"{core_id:#x}: version without bit 14"
        assert bool(dev.windings) is drv.windings is not bool(core_id & no_windings)
        for mode, value in MODES.items():
            outputs = Outputs(mode=mode, ustep_log2=1, step_width=3, dir_setup=2, pwm_period=9)
            lib.stepramp_fakebus_clear_log()
            bank.log.clear()
            try:
                run_async(drv.configure_outputs(outputs))
                py, why = "STEPRAMP_OK", ""
            except ValueError as exc:
                py, why = "STEPRAMP_EWINDINGS", str(exc)
            assert py == "STEPRAMP_OK" or ("G_WINDINGS" in why and "ID bit 14" in why), why
            fields = dataclasses.asdict(outputs) | {"mode": value}
            c = DRIVER_RESULTS[lib.stepramp_configure_outputs(ctypes.byref(dev), ctypes.byref(COutputs(**fields)))]
            want = "STEPRAMP_EWINDINGS" if value and core_id & no_windings else "STEPRAMP_OK"
            assert (py, bank.log) == (c, bus_writes(lib)), f"{core_id:#x} {mode}"
            assert c == want and (bank.log == []) == (want != "STEPRAMP_OK"), f"{core_id:#x} {mode}"
    text = lib.stepramp_strresult(DRIVER_RESULTS_BY_NAME["STEPRAMP_EWINDINGS"]).decode()
    assert "G_WINDINGS" in text and "ID bit 14" in text and "STEP/DIR" in text, text


def test_a_move_too_fast_for_the_step_gap(lib: ctypes.CDLL) -> None:
    """StepRamp.plan and stepramp_plan refuse a move whose shortest interval is below the STEP width + space, alike,
    writing nothing; one clock more of interval (a slower cruise) passes in both."""
    # 1 MHz, 400 steps/rev, PRESCALE 4: 20 rad/s cruises at 196 ticks = 784 clocks.
    outputs = Outputs(mode="stepdir", step_width=684, step_space=101)
    for speed, want in ((20.0, "STEPRAMP_EGAP"), (19.9, "STEPRAMP_OK")):
        pair = Pair(lib, 1e6, 400.0, 4, outputs)
        (py, py_writes), (c, c_writes) = pair.call("move", 4000, 40.0, 40.0, speed)
        assert py == c == want and py_writes == c_writes, (speed, py, c)


def test_core_error_texts_match_the_register_map(lib: ctypes.CDLL) -> None:
    for name, (code, cause) in ERROR_CODES.items():
        assert lib.stepramp_corename(code).decode() == name
        assert lib.stepramp_strcoreerror(code).decode() == cause
        assert cause in lib.stepramp_strresult(128 + code).decode()
    for code in range(len(ERROR_CODES), 20):
        assert lib.stepramp_strcoreerror(code).decode() == "unknown error code"
        assert lib.stepramp_corename(code).decode() == "UNKNOWN"


def test_fake_bank_resets_and_write_masks_come_from_the_register_map(lib: ctypes.CDLL) -> None:
    """The fake register bank (sw/c/host/stepramp_fakebus.c) at reset holds every register's reset value, and a
    register written with all ones (while the core is stopped) keeps only its RW bits: both recomputed here from the
    register map's fields, so a reset value or a field added in rdl/stepramp.rdl reaches the bank without a hand
    copy (it uses stepramp_regs.h's STEPRAMP_<REG>_RESET / _RW_MASK)."""
    lib.stepramp_hostbus_write32.argtypes = [ctypes.c_size_t, ctypes.c_uint32]
    lib.stepramp_hostbus_write32.restype = None
    regs = lib.stepramp_fakebus_state().contents.regs
    lib.stepramp_fakebus_reset(FAKEBUS_BASE, ID_VALUE)
    assert {r.name: regs[r.offset // 4] for r in REGISTERS} == {
        r.name: sum(f.reset << f.lsb for f in r.fields) for r in REGISTERS
    }
    kept = {}
    for reg in REGISTERS:
        if reg.name == "STATUS":
            continue  # W1C: test_stepramp.c's STATUS tests
        lib.stepramp_fakebus_reset(FAKEBUS_BASE, ID_VALUE)
        lib.stepramp_hostbus_write32(FAKEBUS_BASE + reg.offset, 0xFFFF_FFFF)
        kept[reg.name] = regs[reg.offset // 4]
    assert kept == {
        r.name: sum(f.mask for f in r.fields if f.access == RW) or sum(f.reset << f.lsb for f in r.fields)
        for r in REGISTERS
        if r.name != "STATUS"
    }
