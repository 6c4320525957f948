# SPDX-License-Identifier: MIT
"""The C driver library (sw/c): its host unit tests, and bit-for-bit parity with stepramp.board.plan.

The library is built with ``make -C sw/c`` (a missing gcc or make is a failure, not a skip), loaded with
ctypes, and compared with the Python driver field by field on many random moves, on every named profile
and on the invalid inputs of stepramp.sim.profiles: the same registers, or the same first error.

The exact mode (ramp = RAMP_EXACT: stepramp_plan_move_ramp against plan_move(..., ramp=1)) likewise, on random moves
designed around its limits (the ramp constants from 0 to past 2^72, the 256- and 304-clock speed limits) with a spoiled
argument or ramp now and then, on EXACT_PROFILES, and exact.ramp_constant against stepramp_ramp_constant. Its random
draws print their seed; STEPRAMP_SEED=<seed> replays them.
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools
import math
import os
import random
import re
from collections import Counter
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import pytest

from c_abi import PLAN_HEADER, CPlan, log_uniform, run
from stepramp.board import plan as pyplan
from stepramp.board.plan import (
    MAX_PRESCALE,
    MAX_STEPS,
    MIN_INTERVAL_CLKS_EXACT,
    RAMP_AVR446,
    RAMP_EXACT,
    MoveInfo,
    decel_product,
    plan_move,
    plan_move_info,
)
from stepramp.models import exact
from stepramp.sim.profiles import EXACT_PROFILES, INVALID_INPUTS, PROFILES, design_args

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
    # the exact mode's: check_ramp (a code of its own) and exact.ramp_constant (a register overflow, as a delay's)
    "ramp must be 0 (avr446) or 1 (exact)": "STEPRAMP_ERAMP",
    "gives a ramp constant outside": "STEPRAMP_EOVERFLOW",
}
RAMP_ONLY = {"STEPRAMP_ERAMP"}
"""The errors only a ramp argument gives (the AVR446 tests do not draw it)."""

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
    so.stepramp_plan_move_ramp.argtypes = [*so.stepramp_plan_move.argtypes, ctypes.c_uint32]
    so.stepramp_plan_move_info_ramp.argtypes = [*so.stepramp_plan_move_info.argtypes, ctypes.c_uint32]
    so.stepramp_plan_move_ramp.restype = so.stepramp_plan_move_info_ramp.restype = ctypes.c_int
    so.stepramp_ramp_constant.argtypes = [ctypes.c_double, ctypes.POINTER(ctypes.c_uint64)]
    so.stepramp_ramp_constant.restype = ctypes.c_int
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


def _c_args(move: Move) -> tuple[Any, ...]:
    """The arguments after the plan (and info) of stepramp_plan_move(_info), with the ramp of stepramp_plan_move_ramp
    when the move names one."""
    args = (move["steps"], *(float(move[k]) for k in ("accel", "decel", "speed", "spr", "fclk")), move["prescale"])
    return (*args, move["ramp"]) if "ramp" in move else args


def c_outcome_info(so: ctypes.CDLL, move: Move) -> tuple[Outcome, dict[str, int | str]]:
    """The C library's plan (registers and ramp) or error name for a move, and its info (empty on error); a move with
    a "ramp" goes to stepramp_plan_move_info_ramp."""
    out = CPlan()
    info = CInfo()
    function = so.stepramp_plan_move_info_ramp if "ramp" in move else so.stepramp_plan_move_info
    err = function(ctypes.byref(out), ctypes.byref(info), *_c_args(move))
    if err != 0:
        names = _error_names()
        return (names[err] if err < len(names) else f"unknown error code {err}"), {}
    return {name: getattr(out, name) for name, _ in CPlan._fields_}, {
        name: _bits(getattr(info, name)) for name, _ in CInfo._fields_
    }


def c_outcome(so: ctypes.CDLL, move: Move) -> Outcome:
    """The C library's plan (registers and ramp) or error name for a move (through stepramp_plan_move, or
    stepramp_plan_move_ramp for a move with a "ramp")."""
    out = CPlan()
    function = so.stepramp_plan_move_ramp if "ramp" in move else so.stepramp_plan_move
    err = function(ctypes.byref(out), *_c_args(move))
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
    """The Python driver's plan (registers and ramp) or error name for a move."""
    try:
        return dataclasses.asdict(plan_move(**move))
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
        curve = pyplan._Ramp(info.length, info.a, info.d, info.v, info.f_tick)
        if plan.ramp == RAMP_EXACT:  # _exact_plan's doubles: the exact intervals, and c0, cd0 of the ramp constants
            raw |= {
                "t_first": curve.interval(1),
                "t_last": curve.interval(curve.length),
                "t_sa": curve.interval(plan.sa),
                "t_sd": curve.interval(plan.sd),
                "t_accel_seed": curve.k_a,
                "t_decel_seed": curve.k_d,
            }
        else:
            raw |= pyplan.register_doubles(curve, plan.sa, plan.sd, info.m0)
        raw["t_cruise"] = info.f_tick / info.v
    return dataclasses.asdict(plan), {name: _bits(value) for name, value in (values | raw).items()}


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


def _random_spr_fclk(rng: random.Random) -> tuple[float, float]:
    spr = rng.choice((24.0, 200.0, 400.0, 1000.0, 1600.0, 3200.0, 25600.0, 51200.0)) * rng.choice((1, 1.37))
    if rng.random() < 0.2:
        spr = log_uniform(rng, 24.0, 51200.0)
    return spr, log_uniform(rng, 1e5, 2e8)


def _designed_move(rng: random.Random) -> Move:
    """A move designed in the tick domain like test_model's, over wider ranges (valid most of the time)."""
    prescale = _random_prescale(rng)
    spr, fclk = _random_spr_fclk(rng)
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


Draw = Callable[[random.Random], Move]


def _spoiled(draw: Draw) -> Draw:
    """A draw of draw's move or a raw one (half and half), spoiled (_spoil)."""
    return lambda rng: _spoil(rng, draw(rng) if rng.random() < 0.5 else _raw_move(rng))


def _mixed_move(rng: random.Random, kinds: Sequence[tuple[float, Draw]]) -> Move:
    """A move of the first kind whose bound a uniform draw in [0, 1) is below (the bounds ascending, the last 1.0)."""
    r = rng.random()
    return next(draw for bound, draw in kinds if r < bound)(rng)


def random_moves(seed: int, count: int) -> list[Move]:
    """count random moves: designed (mostly valid), raw (wide ranges) and spoiled (invalid or extreme)."""
    rng = random.Random(seed)
    kinds = ((0.6, _designed_move), (0.85, _raw_move), (1.0, _spoiled(_designed_move)))
    return [_mixed_move(rng, kinds) for _ in range(count)]


RANDOM_COUNT = 12_000
RANDOM_SEED = 20240612


def _mismatch(move: Move, py: Outcome, c: Outcome) -> str:
    if isinstance(py, dict) and isinstance(c, dict):
        diff = {k: (py[k], c[k]) for k in py if py[k] != c[k]}
        return f"{move}: fields differ (python, C): {diff}"
    return f"{move}: python {py if isinstance(py, str) else 'OK'}, C {c if isinstance(c, str) else 'OK'}"


def _differs(lib: ctypes.CDLL, move: Move, py: Outcome, py_info: dict[str, int | str]) -> str | None:
    """How the C library's outcome of a move differs from the Python driver's (py, py_info), None when it does not:
    the plan or error, every double of the info, and the plan of the call without the info (stepramp_plan_move, or
    stepramp_plan_move_ramp for a move with a "ramp")."""
    c, c_info = c_outcome_info(lib, move)
    if py != c:
        return _mismatch(move, py, c)
    if py_info != c_info:  # every double behind the registers is identical too
        diff = {k: (py_info[k], c_info[k]) for k in py_info if py_info[k] != c_info[k]}
        return f"{move}: info differs (python, C): {diff}"
    if c_outcome(lib, move) != c:
        ramp = "_ramp" if "ramp" in move else ""
        return f"{move}: stepramp_plan_move{ramp} differs from stepramp_plan_move_info{ramp}"
    return None


def _compare(lib: ctypes.CDLL, moves: list[Move]) -> list[Outcome]:
    """Every move the same in C as in Python (_differs); returns the Python driver's outcomes."""
    outcomes: list[Outcome] = []
    mismatches: list[str] = []
    for move in moves:
        py, py_info = py_outcome_info(move)
        outcomes.append(py)
        if (mismatch := _differs(lib, move, py, py_info)) is not None:
            mismatches.append(mismatch)
    assert not mismatches, f"{len(mismatches)} of {len(moves)} moves differ:\n" + "\n".join(mismatches[:20])
    return outcomes


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
    for py in _compare(lib, moves):
        outcomes["STEPRAMP_OK" if isinstance(py, dict) else py] += 1
        if isinstance(py, dict):
            n = py["steps"]
            shapes[
                "N<=1" if n <= 1 else "N=2,3" if n <= 3 else "triangle" if py["sa"] == py["sd"] else "trapezoid"
            ] += 1
            shapes["m0>256" if n - 1 - py["sd"] - 1 > 256 else "m0<=256"] += n > 1
            shapes["prescale 65535"] += py["prescale"] == MAX_PRESCALE
            shapes["|steps| 2^31-1"] += n == MAX_STEPS
    # the random set covers every outcome and shape (but the ramp's: no ramp argument here)
    assert set(outcomes) == {"STEPRAMP_OK", *ERROR_KEYS.values()} - RAMP_ONLY, outcomes
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


# --------------------------------------------------------------------------------------------------------
# the exact mode (RAMP_EXACT)
# --------------------------------------------------------------------------------------------------------

EXACT_SEED = int(os.environ.get("STEPRAMP_SEED", "20261126"))
EXACT_COUNT = 12_000
_BAD_RAMPS = (2, 3, 255, 2**32 - 1)


def _exact_designed_move(rng: random.Random) -> Move:
    """A move designed for the exact mode: a cruise period from around its 256-clock limit up, and a first interval
    c0 = 2 period sqrt(n_a) from below 0.044 ticks (a ramp constant of 0) past 2^20 ticks (past 2^48: scaled seed
    words and the 304-clock limit) to past 2^32 ticks (past 2^72), the decel up to 1e4 times the accel either way."""
    prescale = _random_prescale(rng)
    spr, fclk = _random_spr_fclk(rng)
    period = math.ceil(MIN_INTERVAL_CLKS_EXACT / prescale) * log_uniform(rng, 0.5, 1.0) + log_uniform(rng, 1e-3, 1e5)
    c0 = log_uniform(rng, 0.02, 2.0**21) if rng.random() < 0.6 else log_uniform(rng, 2.0**19, 2.0**33)
    n_a = (c0 / (2.0 * period)) ** 2
    n_d = n_a * log_uniform(rng, 1e-4, 1e4)
    return design_args(_random_steps(rng), period, n_a, n_d, spr, fclk, prescale)


def random_exact_moves(seed: int, count: int) -> list[Move]:
    """count moves with ramp RAMP_EXACT: designed for the exact mode (most), as random_moves draws them, spoiled, or
    with a ramp that is neither mode."""
    rng = random.Random(seed)
    kinds = (
        (0.55, _exact_designed_move),
        (0.7, _designed_move),
        (0.85, _raw_move),
        (1.0, _spoiled(_exact_designed_move)),
    )
    moves: list[Move] = []
    for _ in range(count):
        move = _mixed_move(rng, kinds)
        move["ramp"] = rng.choice(_BAD_RAMPS) if rng.random() < 0.01 else RAMP_EXACT
        moves.append(move)
    return moves


def _ramp_constant_cause(move: Move) -> bool:
    """Whether plan_move refuses the move for its ramp constant (exact.ramp_constant's message)."""
    try:
        plan_move(**move)
    except ValueError as exc:
        return "gives a ramp constant outside" in str(exc)
    return False


def test_random_exact_moves_bit_for_bit(lib: ctypes.CDLL) -> None:
    """stepramp_plan_move_info_ramp in exact mode against plan_move_info(..., ramp=RAMP_EXACT): every register, the
    ramp, every double of the info, or the same first error; stepramp_plan_move_ramp gives the same."""
    print(f"seed {EXACT_SEED} (STEPRAMP_SEED={EXACT_SEED} replays it)")
    moves = random_exact_moves(EXACT_SEED, EXACT_COUNT)
    outcomes: Counter[str] = Counter()
    for move, py in zip(moves, _compare(lib, moves), strict=True):
        if isinstance(py, dict):
            outcomes["STEPRAMP_OK"] += 1
            outcomes["OK, m0 < 1 (decel_seed still set)"] += py["steps"] >= 2 and py["steps"] - py["sd"] - 2 < 1
            outcomes["OK, N <= 1"] += py["steps"] <= 1
        else:
            outcomes[py] += 1
            outcomes["EOVERFLOW of a ramp constant"] += py == "STEPRAMP_EOVERFLOW" and _ramp_constant_cause(move)
    print(f"{len(moves)} exact-mode moves: {sorted(outcomes.items())}")
    assert set(ERROR_KEYS.values()) | {"STEPRAMP_OK"} <= set(outcomes), outcomes
    assert outcomes["STEPRAMP_OK"] >= 0.4 * len(moves), outcomes
    assert min(outcomes[k] for k in ("EOVERFLOW of a ramp constant", "OK, m0 < 1 (decel_seed still set)")) >= 20


def test_exact_profiles_bit_for_bit(lib: ctypes.CDLL) -> None:
    """EXACT_PROFILES (the 64 profiles at 4 times the clock and PRESCALE) in exact mode: the same plan and info."""
    for profile in EXACT_PROFILES:
        move = profile.args() | {"ramp": RAMP_EXACT}
        py, py_info = py_outcome_info(move)
        assert isinstance(py, dict) and py["ramp"] == RAMP_EXACT, profile.name
        assert c_outcome_info(lib, move) == (py, py_info), profile.name


def test_ramp_constant_bit_for_bit(lib: ctypes.CDLL) -> None:
    """stepramp_ramp_constant against exact.ramp_constant: c0 from 0 to past 2^32 ticks, around both ends of the
    range and every change of scale, and ties (c0 * c0 * 256 ending in .5 after the double rounding: half to even in
    both)."""
    rng = random.Random(EXACT_SEED)
    print(f"seed {EXACT_SEED} (STEPRAMP_SEED={EXACT_SEED} replays it)")
    values = [log_uniform(rng, 1e-3, 2.0**22) for _ in range(20_000)]
    values += [math.sqrt(k / 256.0) * (1.0 + rng.uniform(-1e-15, 1e-15)) for k in (0.5, 1.0, 1.5, 2.0**48 - 1.0)]
    values += [0.0, 0.0625, 2.0**20 - 1.0, 2.0**20, math.nextafter(2.0**20, 0.0)]
    values += [log_uniform(rng, 2.0**20, 2.0**33) for _ in range(20_000)]
    # each change of scale (C = 2^(60 + 2 e)) and the top of the range (C_MAX: c0 = 2^32 - 2^-5 about)
    for c0 in [2.0 ** (26 + e) for e in range(7)] + [2.0**32 - 1.0, 2.0**32, math.sqrt(exact.C_MAX) / 16.0]:
        values += [c0, math.nextafter(c0, 0.0), math.nextafter(c0, math.inf), c0 * (1.0 + 1e-12), c0 * (1.0 - 1e-12)]
    draws = (rng.uniform(2.0**19, 2.0**20 - 1.0) for _ in range(20_000))
    ties = [c0 for c0 in draws if (c0 * c0 * 256.0) % 1.0 == 0.5]
    assert len(ties) >= 100
    mismatches = []
    for c0 in values + ties:
        try:
            py: int | str = exact.ramp_constant(c0)
        except ValueError:
            py = "STEPRAMP_EOVERFLOW"
        out = ctypes.c_uint64(0)
        err = lib.stepramp_ramp_constant(c0, ctypes.byref(out))
        c = out.value if err == 0 else _error_names()[err]
        if py != c:
            mismatches.append((c0.hex(), py, c))
    assert not mismatches, mismatches[:10]
    assert all(exact.ramp_constant(c0) % 2 == 0 for c0 in ties)  # half to even
    scales = {exact.mantissa_scale(exact.ramp_constant(c0))[1] for c0 in values if 0.05 < c0 < 2.0**32 - 1.0}
    assert scales == set(range(exact.SCALE_MAX + 1))


def test_exact_mode_constants_match_python() -> None:
    """STEPRAMP_MIN_INTERVAL_CLKS_EXACT, STEPRAMP_RAMP_AVR446 / _EXACT and STEPRAMP_FRAC_EXACT are plan.py's and
    exact.py's."""
    text = PLAN_HEADER.read_text()

    def define(name: str) -> int:
        match = re.search(rf"#define {name} (\d+)u?\b", text)
        assert match, name
        return int(match.group(1))

    assert define("STEPRAMP_MIN_INTERVAL_CLKS_EXACT") == MIN_INTERVAL_CLKS_EXACT
    assert define("STEPRAMP_MIN_INTERVAL_CLKS_EXACT_WIDE") == pyplan.MIN_INTERVAL_CLKS_EXACT_WIDE
    assert define("STEPRAMP_EXACT_SCALE_MAX") == exact.SCALE_MAX
    assert float(re.findall(r"#define STEPRAMP_EXACT_C_MAX ([0-9.]+)", text)[0]) == exact.C_MAX
    assert define("STEPRAMP_RAMP_AVR446") == RAMP_AVR446
    assert define("STEPRAMP_RAMP_EXACT") == RAMP_EXACT
    assert define("STEPRAMP_FRAC_EXACT") == exact.FRAC_EXACT


def test_exact_mode_checks_the_ramp_first(lib: ctypes.CDLL) -> None:
    """A ramp that is neither mode is refused before any other argument, in both; a plan for the exact mode with no
    interval (N <= 1) still carries its ramp."""
    move: Move = {"steps": 2**40, "accel": -1.0, "decel": 1.0, "speed": 1.0, "spr": 200.0, "fclk": 1e6, "prescale": 0}
    for ramp in _BAD_RAMPS:
        assert py_outcome(move | {"ramp": ramp}) == c_outcome(lib, move | {"ramp": ramp}) == "STEPRAMP_ERAMP"
    assert py_outcome(move | {"ramp": RAMP_EXACT}) == c_outcome(lib, move | {"ramp": RAMP_EXACT}) == "STEPRAMP_EACCEL"
    empty = move | {"steps": -1, "accel": 1.0, "prescale": 3, "ramp": RAMP_EXACT}
    assert (
        c_outcome(lib, empty)
        == py_outcome(empty)
        == {**dict.fromkeys(py_outcome(empty), 0), "steps": 1, "direction": 1, "prescale": 3, "ramp": RAMP_EXACT}
    )
