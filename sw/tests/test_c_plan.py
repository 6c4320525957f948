# SPDX-License-Identifier: MIT
"""The C driver library (sw/c): its host unit tests, and bit-for-bit parity with stepramp.board.plan.

The library is built with ``make -C sw/c`` (a missing gcc or make is a failure, not a skip), loaded with
ctypes, and compared with the Python driver field by field on many random moves, on every named profile
and on the invalid inputs of stepramp.sim.profiles: the same registers, or the same first error.
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools
import math
import random
import re
from collections import Counter
from pathlib import Path
from typing import Any

import pytest

from c_abi import PLAN_HEADER, CPlan, log_uniform, run
from stepramp.board import plan as pyplan
from stepramp.board.plan import MAX_PRESCALE, MAX_STEPS, MoveInfo, decel_product, plan_move, plan_move_info
from stepramp.sim.profiles import INVALID_INPUTS, PROFILES, design_args

# A substring of each ValueError message of plan.py -> the stepramp_err_t the C library returns for it.
# Exactly one key matches any message; the C message (stepramp_strerror) contains the key as well.
ERROR_KEYS: dict[str, str] = {
    "accel must be finite and > 0": "STEPRAMP_EACCEL",
    "decel must be finite and > 0": "STEPRAMP_EDECEL",
    "speed must be finite and > 0": "STEPRAMP_ESPEED",
    "spr must be finite and > 0": "STEPRAMP_ESPR",
    "fclk must be finite and > 0": "STEPRAMP_EFCLK",
    "prescale must be an integer in 1 .. 65535": "STEPRAMP_EPRESCALE",
    "|steps| must be <= 2^31 - 1": "STEPRAMP_ESTEPS",
    "overflows its register": "STEPRAMP_EOVERFLOW",
    "interval shorter than 1 tick": "STEPRAMP_ETICK",
    "speed too high for the hardware": "STEPRAMP_ETOOFAST",
    "accel in steps units is out of range": "STEPRAMP_EACCEL_UNITS",
    "decel in steps units is out of range": "STEPRAMP_EDECEL_UNITS",
    "speed in steps units is out of range": "STEPRAMP_ESPEED_UNITS",
    "f_tick in steps units is out of range": "STEPRAMP_EFTICK",
    "peak speed underflows": "STEPRAMP_EPEAK",
}

ARG_NAMES = ("steps", "accel", "decel", "speed", "spr", "fclk", "prescale")
Move = dict[str, Any]
Outcome = dict[str, int] | str
"""The registers of a planned move, or the name of the error (a stepramp_err_t enumerator)."""


# stepramp_info_t: plan.MoveInfo field by field, then the unrounded register values (ticks)
MOVE_INFO_FIELDS = [f.name for f in dataclasses.fields(MoveInfo)]
RAW_FIELDS = ["t_first", "t_last", "t_sa", "t_sd", "t_accel_seed", "t_decel_seed", "t_cruise"]
_INFO_INTS = {"length": ctypes.c_int64, "triangle": ctypes.c_int, "m0": ctypes.c_int64}


class CInfo(ctypes.Structure):
    """stepramp_info_t."""

    _fields_ = [(name, _INFO_INTS.get(name, ctypes.c_double)) for name in MOVE_INFO_FIELDS + RAW_FIELDS]


@functools.cache
def _error_names() -> list[str]:
    """The stepramp_err_t enumerators in the header's order (their values: 0, 1, 2, ...)."""
    text = PLAN_HEADER.read_text()
    match = re.search(r"typedef enum \{(.*?)\} stepramp_err_t;", text, re.S)
    assert match, f"no stepramp_err_t enum in {PLAN_HEADER}"
    body = re.sub(r"/\*.*?\*/", "", match.group(1), flags=re.S)
    names = [item.split("=")[0].strip() for item in body.split(",") if item.strip()]
    assert names[0] == "STEPRAMP_OK" and "=" not in body.replace("STEPRAMP_OK = 0", ""), "only OK = 0 is explicit"
    return names


def load_library(build_dir: Path) -> ctypes.CDLL:
    """libstepramp.so with the argument and result types declared."""
    so = ctypes.CDLL(str(build_dir / "libstepramp.so"))
    so.stepramp_plan_move.argtypes = [
        ctypes.POINTER(CPlan),
        ctypes.c_int64,
        *(ctypes.c_double,) * 5,
        ctypes.c_uint32,
    ]
    so.stepramp_plan_move.restype = ctypes.c_int
    so.stepramp_plan_move_info.argtypes = [
        ctypes.POINTER(CPlan),
        ctypes.POINTER(CInfo),
        ctypes.c_int64,
        *(ctypes.c_double,) * 5,
        ctypes.c_uint32,
    ]
    so.stepramp_plan_move_info.restype = ctypes.c_int
    so.stepramp_strerror.argtypes = [ctypes.c_int]
    so.stepramp_strerror.restype = ctypes.c_char_p
    so.stepramp_decel_product.argtypes = [ctypes.c_int64]
    so.stepramp_decel_product.restype = ctypes.c_double
    return so


@pytest.fixture(scope="module")
def lib(build: Path) -> ctypes.CDLL:
    """The C library, built and loaded."""
    return load_library(build)


def _bits(x: float) -> int | str:
    """A value compared bit for bit: an int as is, a double by its exact hex form (NaN, inf, -0.0 too)."""
    return x if isinstance(x, int) else float(x).hex()


def c_outcome_info(so: ctypes.CDLL, move: Move) -> tuple[Outcome, dict[str, int | str]]:
    """The C library's plan (registers) or error name for a move, and its info (empty on error)."""
    out = CPlan()
    info = CInfo()
    err = so.stepramp_plan_move_info(
        ctypes.byref(out),
        ctypes.byref(info),
        move["steps"],
        *(float(move[k]) for k in ("accel", "decel", "speed", "spr", "fclk")),
        move["prescale"],
    )
    if err != 0:
        names = _error_names()
        return (names[err] if err < len(names) else f"unknown error code {err}"), {}
    return {name: getattr(out, name) for name, _ in CPlan._fields_}, {
        name: _bits(getattr(info, name)) for name, _ in CInfo._fields_
    }


def c_outcome(so: ctypes.CDLL, move: Move) -> Outcome:
    """The C library's plan (registers) or error name for a move (through stepramp_plan_move)."""
    out = CPlan()
    err = so.stepramp_plan_move(
        ctypes.byref(out),
        move["steps"],
        *(float(move[k]) for k in ("accel", "decel", "speed", "spr", "fclk")),
        move["prescale"],
    )
    if err != 0:
        names = _error_names()
        return names[err] if err < len(names) else f"unknown error code {err}"
    return {name: getattr(out, name) for name, _ in CPlan._fields_}


def py_error_name(message: str) -> str:
    """The stepramp_err_t enumerator for a ValueError message of plan.py."""
    keys = [key for key in ERROR_KEYS if key in message]
    assert len(keys) == 1, f"message {message!r} matches {keys} of ERROR_KEYS"
    return ERROR_KEYS[keys[0]]


def py_outcome(move: Move) -> Outcome:
    """The Python driver's plan (registers) or error name for a move."""
    try:
        return plan_move(**move).to_dict()
    except ValueError as exc:
        return py_error_name(str(exc))


def py_outcome_info(move: Move) -> tuple[Outcome, dict[str, int | str]]:
    """py_outcome and the MoveInfo, plus the unrounded register values the way plan.py computes them."""
    try:
        plan, info = plan_move_info(**move)
    except ValueError as exc:
        return py_error_name(str(exc)), {}
    values: dict[str, Any] = {name: getattr(info, name) for name in MOVE_INFO_FIELDS}
    values["triangle"] = int(info.triangle)
    raw = dict.fromkeys(RAW_FIELDS, 0.0)
    if info.length >= 1:
        ramp = pyplan._Ramp(info.length, info.a, info.d, info.v, info.f_tick)
        raw |= pyplan.register_doubles(ramp, plan.sa, plan.sd, info.m0)
        raw["t_cruise"] = info.f_tick / info.v
    return plan.to_dict(), {name: _bits(value) for name, value in (values | raw).items()}


# --------------------------------------------------------------------------------------------------------
# random moves
# --------------------------------------------------------------------------------------------------------


def _random_steps(rng: random.Random) -> int:
    r = rng.random()
    if r < 0.12:
        n = rng.choice((0, 1, 2, 3, MAX_STEPS))
    elif r < 0.35:
        n = rng.randint(4, 100)
    else:
        n = round(log_uniform(rng, 1.0, MAX_STEPS))
    return n * rng.choice((1, -1))


def _random_prescale(rng: random.Random) -> int:
    r = rng.random()
    if r < 0.2:
        return 1
    if r < 0.25:
        return MAX_PRESCALE
    if r < 0.6:
        return rng.randint(1, 8)
    return round(log_uniform(rng, 1.0, MAX_PRESCALE))


def _designed_move(rng: random.Random) -> Move:
    """A move designed in the tick domain like test_model's, over wider ranges (valid most of the time)."""
    prescale = _random_prescale(rng)
    spr = rng.choice((24.0, 200.0, 400.0, 1000.0, 1600.0, 3200.0, 25600.0, 51200.0)) * rng.choice((1, 1.37))
    if rng.random() < 0.2:
        spr = log_uniform(rng, 24.0, 51200.0)
    fclk = log_uniform(rng, 1e5, 2e8)
    # cruise period in ticks: mostly above the MIN_INTERVAL_CLKS limit, sometimes at or below it
    period = math.ceil(64 / prescale) * log_uniform(rng, 0.5, 1.0) + log_uniform(rng, 1e-3, 1e6)
    n_a = log_uniform(rng, 1e-3, 1e9)
    n_d = n_a * log_uniform(rng, 1e-4, 1e4)  # accel / decel ratio up to 1e4 both ways
    return design_args(_random_steps(rng), period, n_a, n_d, spr, fclk, prescale)


def _raw_move(rng: random.Random) -> Move:
    """Physical units drawn independently over wide ranges (many too slow or too fast)."""
    accel = log_uniform(rng, 1e-9, 1e9)
    return {
        "steps": _random_steps(rng),
        "accel": accel,
        "decel": accel * log_uniform(rng, 1e-4, 1e4),
        "speed": log_uniform(rng, 1e-7, 1e6),
        "spr": log_uniform(rng, 24.0, 51200.0),
        "fclk": log_uniform(rng, 1e5, 2e8),
        "prescale": _random_prescale(rng),
    }


# Extreme finite values that reach the 'in steps units', 'peak speed underflows' and overflow checks, including
# delays so long (> ~2.7e303 ticks) that their Q32.16 scaling overflows a double.
_EXTREME: dict[str, tuple[float, ...]] = {
    "accel": (5e-324, 1e-300, 1e300, 1.7976931348623157e308),
    "decel": (5e-324, 1e-300, 1e300, 1.7976931348623157e308),
    "speed": (1e-297, 1e-280, 1e300, 1.7976931348623157e308),
    "spr": (5e-324, 1e-300, 0.5, 1e300, 1.7976931348623157e308),
    "fclk": (5e-324, 1e-300, 1e295),
}
_BAD_FLOATS = (0.0, -0.0, -1.0, -1e300, math.nan, math.inf, -math.inf)
_BAD_STEPS = (2**31, -(2**31), 2**40, -(2**62), 2**63 - 1, -(2**63))
_BAD_PRESCALES = (0, MAX_PRESCALE + 1, 100_000, 2**32 - 1)


def _spoil(rng: random.Random, move: Move) -> Move:
    """One or two fields of the move replaced by an invalid or extreme value."""
    move = dict(move)
    for _ in range(rng.choice((1, 1, 2))):
        name = rng.choice(ARG_NAMES)
        if name == "steps":
            move[name] = rng.choice(_BAD_STEPS)
        elif name == "prescale":
            move[name] = rng.choice(_BAD_PRESCALES)
        elif rng.random() < 0.5:
            move[name] = rng.choice(_BAD_FLOATS)
        else:
            move[name] = rng.choice(_EXTREME[name])
    return move


def random_moves(seed: int, count: int) -> list[Move]:
    """count random moves: designed (mostly valid), raw (wide ranges) and spoiled (invalid or extreme)."""
    rng = random.Random(seed)
    moves: list[Move] = []
    while len(moves) < count:
        r = rng.random()
        if r < 0.6:
            move = _designed_move(rng)
        elif r < 0.85:
            move = _raw_move(rng)
        else:
            move = _spoil(rng, _designed_move(rng) if rng.random() < 0.5 else _raw_move(rng))
        moves.append(move)
    return moves


RANDOM_COUNT = 12_000
RANDOM_SEED = 20240612


def _mismatch(move: Move, py: Outcome, c: Outcome) -> str:
    if isinstance(py, dict) and isinstance(c, dict):
        diff = {k: (py[k], c[k]) for k in py if py[k] != c[k]}
        return f"{move}: fields differ (python, C): {diff}"
    return f"{move}: python {py if isinstance(py, str) else 'OK'}, C {c if isinstance(c, str) else 'OK'}"


# --------------------------------------------------------------------------------------------------------
# the tests
# --------------------------------------------------------------------------------------------------------


def test_host_unit_tests_pass(build: Path) -> None:
    result = run([str(build / "test_stepramp_plan")])
    assert result.returncode == 0, f"C host tests failed:\n{result.stdout}\n{result.stderr}"
    assert re.search(r"\d+ checks, 0 failed", result.stdout), result.stdout


def test_error_enum_matches_python(lib: ctypes.CDLL) -> None:
    """stepramp_err_t has a code for each ValueError of plan.py (and NULL), and its text says the same; the plan
    struct is checked against Plan by test_c_driver.py::test_plan_struct_matches_python."""
    names = _error_names()
    assert set(ERROR_KEYS.values()) <= set(names)
    assert set(names) - set(ERROR_KEYS.values()) == {"STEPRAMP_OK", "STEPRAMP_ENULL"}
    for key, name in ERROR_KEYS.items():
        text = lib.stepramp_strerror(names.index(name)).decode()
        assert key in text, f"stepramp_strerror({name}) = {text!r} does not say {key!r}"
    assert lib.stepramp_strerror(len(names)).decode() == "unknown error"


def test_constants_are_the_same_doubles(lib: ctypes.CDLL) -> None:
    # CPython's gamma/lgamma are not libm's: the C library holds Python's values as literals
    assert ctypes.c_double.in_dll(lib, "stepramp_seed_factor").value == pyplan.SEED_FACTOR
    assert ctypes.c_double.in_dll(lib, "stepramp_lgamma_ratio_0").value == pyplan._LGAMMA_RATIO_0


def test_decel_product_bit_for_bit(lib: ctypes.CDLL) -> None:
    rng = random.Random(7)
    ms = [*range(-2, 700), MAX_STEPS - 3, MAX_STEPS, *(round(log_uniform(rng, 257, MAX_STEPS)) for _ in range(5000))]
    bad = [
        (m, decel_product(m), lib.stepramp_decel_product(m))
        for m in ms
        if decel_product(m) != lib.stepramp_decel_product(m)
    ]
    assert not bad, f"{len(bad)} of {len(ms)} differ, e.g. (m, python, C) {bad[:5]}"


def test_random_moves_bit_for_bit(lib: ctypes.CDLL) -> None:
    moves = random_moves(RANDOM_SEED, RANDOM_COUNT)
    outcomes: Counter[str] = Counter()
    shapes: Counter[str] = Counter()
    mismatches: list[str] = []
    for move in moves:
        py, py_info = py_outcome_info(move)
        c, c_info = c_outcome_info(lib, move)
        if py != c:
            mismatches.append(_mismatch(move, py, c))
        elif py_info != c_info:  # every double behind the registers is identical too
            diff = {k: (py_info[k], c_info[k]) for k in py_info if py_info[k] != c_info[k]}
            mismatches.append(f"{move}: info differs (python, C): {diff}")
        elif c_outcome(lib, move) != c:
            mismatches.append(f"{move}: stepramp_plan_move differs from stepramp_plan_move_info")
        outcomes["STEPRAMP_OK" if isinstance(py, dict) else py] += 1
        if isinstance(py, dict):
            n = py["steps"]
            shapes[
                "N<=1" if n <= 1 else "N=2,3" if n <= 3 else "triangle" if py["sa"] == py["sd"] else "trapezoid"
            ] += 1
            shapes["m0>256" if n - 1 - py["sd"] - 1 > 256 else "m0<=256"] += n > 1
            shapes["prescale 65535"] += py["prescale"] == MAX_PRESCALE
            shapes["|steps| 2^31-1"] += n == MAX_STEPS
    assert not mismatches, f"{len(mismatches)} of {len(moves)} moves differ:\n" + "\n".join(mismatches[:20])
    # the random set covers every outcome and shape
    assert set(outcomes) == {"STEPRAMP_OK", *ERROR_KEYS.values()}, outcomes
    assert outcomes["STEPRAMP_OK"] >= len(moves) // 2, outcomes
    assert min(shapes.values()) >= 20, shapes


def test_named_profiles_bit_for_bit(lib: ctypes.CDLL) -> None:
    for profile in PROFILES:
        move = profile.args()
        py, py_info = py_outcome_info(move)
        assert isinstance(py, dict), profile.name
        assert c_outcome_info(lib, move) == (py, py_info), profile.name


def _c_expressible(move: Move) -> bool:
    """steps and prescale are integers, the rest numbers: what the C prototype can take."""
    integers = all(isinstance(move[k], int) and not isinstance(move[k], bool) for k in ("steps", "prescale"))
    numbers = all(isinstance(move[k], (int, float)) and not isinstance(move[k], bool) for k in ARG_NAMES)
    return integers and numbers and 0 <= move["prescale"] < 2**32 and -(2**63) <= move["steps"] < 2**63


def test_invalid_inputs_same_error(lib: ctypes.CDLL) -> None:
    # entries such as steps=1.5 or prescale=2.0 are type errors in Python; a C caller cannot pass them
    cases = [(move, expected) for move, expected in INVALID_INPUTS if _c_expressible(move)]
    assert len(INVALID_INPUTS) - len(cases) == 2, "only steps=1.5 and prescale=2.0 are not expressible in C"
    for move, expected in cases:
        with pytest.raises(ValueError, match=re.escape(expected)) as info:
            plan_move(**move)
        name = py_error_name(str(info.value))
        assert c_outcome(lib, move) == name, (move, expected)
        assert py_outcome(move) == name


def test_huge_delays_overflow_in_both(lib: ctypes.CDLL) -> None:
    # interval 1 is all cruise, f_tick / v ~ 3e303 ticks: a finite double, but not once scaled to Q32.16
    move: Move = {
        "steps": 100,
        "accel": 1000.0,
        "decel": 1000.0,
        "speed": 1e-297,
        "spr": 200.0,
        "fclk": 1e8,
        "prescale": 1,
    }
    assert c_outcome(lib, move) == "STEPRAMP_EOVERFLOW"
    assert py_outcome(move) == "STEPRAMP_EOVERFLOW"
