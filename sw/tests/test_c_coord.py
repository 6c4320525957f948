# SPDX-License-Identifier: MIT
"""The C port of stepramp.board.coord (sw/c/src/stepramp_coord.c): bit-for-bit parity with the Python driver.

The library is built with ``make -C sw/c`` (as in test_c_plan.py) and loaded with ctypes. For random coordinated
moves (valid ones, wide physical ranges, invalid and extreme values, 0 to 9 axes), stepramp_plan_coordinated_info
must give every register of plan_coordinated_info's plans and every value of its CoordInfo (the doubles to the last
bit), or the same error for the same axis; stepramp_time_before_last and stepramp_ideal_end the same doubles as
time_before_last and ideal_end. Random cases print their seed (STEPRAMP_SEED replays one).
"""

from __future__ import annotations

import ctypes
import dataclasses
import math
import os
import random
import re
import traceback
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from test_c_change import RESULT_NAMES
from test_c_plan import MOVE_INFO_FIELDS, CInfo, load_library, py_error_name
from test_coord import NAMED

from c_abi import CPlan, log_uniform
from stepramp.board.coord import MAX_AXES, ideal_end, plan_coordinated_info, time_before_last
from stepramp.board.plan import MAX_PRESCALE, MAX_STEPS, Plan, plan_move, plan_move_info
from stepramp.sim.profiles import PROFILES, design_args
from stepramp.tools import clib

COORD_HEADER = clib.SRC_DIR / "stepramp_coord.h"
SEED = int(os.environ.get("STEPRAMP_SEED", "20261203"))
RANDOM_COUNT = 6000
ARRAY_AXES = MAX_AXES + 1  # the steps array passed to C: room for the 9-axis refusal

# coord.py's own ValueErrors -> the codes stepramp_plan_coordinated adds (stepramp_plan.h); an axis's plan_move error
# is plan.py's message after "axis i (...): " (test_c_plan.ERROR_KEYS)
COORD_ERROR_KEYS: dict[str, str] = {
    "no axes": "STEPRAMP_ECOORD_AXES",
    "axes: at most 8 axes are coordinated": "STEPRAMP_ECOORD_AXES",
    "every axis has 0 steps": "STEPRAMP_ECOORD_ZERO",
    "shorter than the move's shortest interval": "STEPRAMP_ECOORD_END",
    "the path lasts": "STEPRAMP_ECOORD_LONG",
}
NO_AXIS = 0xFFFFFFFF
PY_CRASH = "python crash: "

Case = dict[str, Any]
Outcome = dict[str, Any] | tuple[str, int | None]
"""Every register and info value of a coordinated move, or (the error's name, the failed axis or None)."""


def _coord_info_struct() -> type[ctypes.Structure]:
    """stepramp_coord_info_t as stepramp_coord.h declares it (arrays of STEPRAMP_COORD_MAX_AXES)."""
    text = re.sub(r"/\*.*?\*/", "", COORD_HEADER.read_text(), flags=re.S)
    size = re.search(r"#define STEPRAMP_COORD_MAX_AXES (\d+)u", text)
    body = re.search(r"typedef struct \{([^{}]*)\} stepramp_coord_info_t;", text)
    assert size and body, f"no STEPRAMP_COORD_MAX_AXES or stepramp_coord_info_t in {COORD_HEADER}"
    assert int(size.group(1)) == MAX_AXES
    types = {"uint32_t": ctypes.c_uint32, "double": ctypes.c_double, "stepramp_info_t": CInfo}
    fields: list[tuple[str, Any]] = []
    for ctype, name, length in re.findall(r"(\w+)\s+(\w+)\s*(?:\[(\w+)\])?\s*;", body.group(1)):
        assert length in ("", "STEPRAMP_COORD_MAX_AXES"), (name, length)
        fields.append((name, types[ctype] * MAX_AXES if length else types[ctype]))
    return type("CCoordInfo", (ctypes.Structure,), {"_fields_": fields})


CCoordInfo = _coord_info_struct()


@pytest.fixture(scope="module")
def lib(build: Path) -> ctypes.CDLL:
    """libstepramp.so with the coordinated move's functions declared."""
    so = load_library(build)
    args = [ctypes.POINTER(ctypes.c_int64), ctypes.c_uint32, *(ctypes.c_double,) * 5, ctypes.c_uint32]
    so.stepramp_plan_coordinated.argtypes = [ctypes.POINTER(CPlan), *args]
    so.stepramp_plan_coordinated_info.argtypes = [ctypes.POINTER(CPlan), ctypes.POINTER(CCoordInfo), *args]
    so.stepramp_plan_coordinated.restype = so.stepramp_plan_coordinated_info.restype = ctypes.c_int
    so.stepramp_time_before_last.argtypes = [ctypes.POINTER(CPlan)]
    so.stepramp_time_before_last.restype = ctypes.c_double
    so.stepramp_ideal_end.argtypes = [ctypes.POINTER(CInfo)]
    so.stepramp_ideal_end.restype = ctypes.c_double
    return so


def _hex(x: float) -> str:
    return float(x).hex()


def _info_values(values: dict[str, Any]) -> dict[str, Any]:
    """A MoveInfo's fields (stepramp_info_t's first ones): ints as they are, doubles as their hex form."""
    return {k: (int(values[k]) if k in ("length", "triangle", "m0") else _hex(values[k])) for k in MOVE_INFO_FIELDS}


def coord_error(message: str) -> tuple[str, int | None]:
    """The C result and failed axis for a ValueError message of plan_coordinated_info."""
    axis = re.match(r"axis (\d+)", message)
    keys = {name for key, name in COORD_ERROR_KEYS.items() if key in message}
    name = keys.pop() if len(keys) == 1 else py_error_name(message)
    return name, int(axis.group(1)) if axis else None


def py_outcome(case: Case) -> Outcome:
    """plan_coordinated_info's plans and info (the C struct's names and encodings), or its error and axis."""
    try:
        plans, info = plan_coordinated_info(**case)
    except ValueError as exc:
        return coord_error(str(exc))
    except (ZeroDivisionError, OverflowError) as exc:
        line = traceback.extract_tb(exc.__traceback__)[-1].line or ""
        return f"{PY_CRASH}{type(exc).__name__} ({exc}) at {line!r}", None
    return {
        "plans": [dataclasses.asdict(plan) for plan in plans],  # Plan.ramp too (0: AVR446), as stepramp_plan_t
        "lead": info.lead,
        "t_end": _hex(info.t_end),
        "end_tick": _hex(float(info.end_tick)),
        "ratio": [_hex(r) for r in info.ratios],
        "last_interval": [_hex(t) for t in info.last_intervals],
        "axis": [_info_values({k: getattr(i, k) for k in MOVE_INFO_FIELDS}) for i in info.infos],
    }


def _c_steps(steps: list[int]) -> ctypes.Array[ctypes.c_int64]:
    return (ctypes.c_int64 * ARRAY_AXES)(*steps)


def c_outcome(so: ctypes.CDLL, case: Case) -> Outcome:
    """stepramp_plan_coordinated_info's plans and info, or its error and failed axis; stepramp_plan_coordinated gives
    the same plans and result, and neither writes the plans on error."""
    steps = case["steps"]
    plans, plain = (CPlan * ARRAY_AXES)(), (CPlan * ARRAY_AXES)()
    info = CCoordInfo()
    physical = (float(case[k]) for k in ("accel", "decel", "speed", "spr", "fclk"))
    args = (_c_steps(steps), len(steps), *physical, case["prescale"])
    err = so.stepramp_plan_coordinated_info(plans, ctypes.byref(info), *args)
    assert so.stepramp_plan_coordinated(plain, *args) == err
    assert bytes(plain) == bytes(plans)
    if err != 0:
        assert bytes(plans) == bytes((CPlan * ARRAY_AXES)()), "plans written on error"
        return RESULT_NAMES.get(err, f"unknown result {err}"), None if info.failed_axis == NO_AXIS else info.failed_axis
    assert info.failed_axis == NO_AXIS and info.count == len(steps)
    count = len(steps)
    return {
        "plans": [{name: getattr(plans[i], name) for name, _ in CPlan._fields_} for i in range(count)],
        "lead": info.lead,
        "t_end": _hex(info.t_end),
        "end_tick": _hex(info.end_tick),
        "ratio": [_hex(info.ratio[i]) for i in range(count)],
        "last_interval": [_hex(info.last_interval[i]) for i in range(count)],
        "axis": [_info_values({k: getattr(info.axis[i], k) for k in MOVE_INFO_FIELDS}) for i in range(count)],
    }


# --------------------------------------------------------------------------------------------------------------------
# random coordinated moves
# --------------------------------------------------------------------------------------------------------------------


def _random_steps(rng: random.Random, count: int) -> list[int]:
    lead = rng.choice((1, 2, 3, 4, MAX_STEPS)) if rng.random() < 0.1 else round(log_uniform(rng, 2.0, MAX_STEPS))
    steps = [lead]
    for _ in range(count - 1):
        r = rng.random()
        n = rng.randint(0, 4) if r < 0.25 else lead if r < 0.3 else round(log_uniform(rng, 1.0, lead))
        steps.append(min(n, lead) * rng.choice((1, -1)))
    rng.shuffle(steps)
    return steps


def _designed(rng: random.Random, count: int) -> Case:
    """A path designed in the tick domain (mostly valid), as test_c_plan's designed moves."""
    prescale = rng.choice((1, 1, 2, 7, 64, 1000, MAX_PRESCALE))
    spr = rng.choice((24.0, 200.0, 400.0, 1600.0, 51200.0)) * rng.choice((1, 1.37))
    fclk = log_uniform(rng, 1e5, 2e8)
    period = math.ceil(64 / prescale) * log_uniform(rng, 0.9, 1.2) + log_uniform(rng, 1e-3, 1e6)
    n_a = log_uniform(rng, 1e-3, 1e9)
    n_d = n_a * log_uniform(rng, 1e-4, 1e4)
    steps = _random_steps(rng, count)
    path = design_args(max(abs(n) for n in steps), period, n_a, n_d, spr, fclk, prescale)
    return {**path, "steps": steps}


def _raw(rng: random.Random, count: int) -> Case:
    """Physical values drawn independently over wide ranges (many refused)."""
    accel = log_uniform(rng, 1e-9, 1e9)
    return {
        "steps": _random_steps(rng, count),
        "accel": accel,
        "decel": accel * log_uniform(rng, 1e-4, 1e4),
        "speed": log_uniform(rng, 1e-7, 1e6),
        "spr": log_uniform(rng, 24.0, 51200.0),
        "fclk": log_uniform(rng, 1e5, 2e8),
        "prescale": rng.choice((1, 3, 64, MAX_PRESCALE)),
    }


_BAD: dict[str, tuple[float | int, ...]] = {
    "accel": (0.0, -1.0, math.nan, math.inf, 5e-324, 1e300),
    "decel": (0.0, math.nan, -math.inf, 5e-324, 1.7976931348623157e308),
    "speed": (0.0, math.nan, 1e-297, 1e300),
    "spr": (-0.0, math.inf, 5e-324, 1e300),
    "fclk": (0.0, math.nan, 5e-324, 1e295),
    "prescale": (0, MAX_PRESCALE + 1, 2**32 - 1),
}


def _spoil(rng: random.Random, case: Case) -> Case:
    """One value made invalid or extreme: an argument, a step count out of range, all steps 0, 0 or 9 axes."""
    case = dict(case)
    r = rng.random()
    if r < 0.5:
        name = rng.choice(list(_BAD))
        case[name] = rng.choice(_BAD[name])
    elif r < 0.7:
        steps = list(case["steps"])
        steps[rng.randrange(len(steps))] = rng.choice((2**31, -(2**31), 2**40, -(2**63)))
        case["steps"] = steps
    elif r < 0.8:
        case["steps"] = [0] * len(case["steps"])
    elif r < 0.9:
        case["steps"] = []
    else:
        case["steps"] = [*case["steps"], *([7] * (ARRAY_AXES - len(case["steps"])))]
    return case


def random_cases(seed: int, count: int) -> list[Case]:
    rng = random.Random(seed)
    cases = []
    for _ in range(count):
        axes = rng.randint(1, MAX_AXES)
        r = rng.random()
        case = _designed(rng, axes) if r < 0.6 else _raw(rng, axes)
        if rng.random() < 0.15:
            case = _spoil(rng, case)
        cases.append(case)
    return cases


def _kind(py: Outcome) -> str:
    return py[0] if isinstance(py, tuple) else "STEPRAMP_OK"


def _compare(lib: ctypes.CDLL, cases: list[Case]) -> Counter[str]:
    kinds: Counter[str] = Counter()
    mismatches: list[str] = []
    for case in cases:
        py, c = py_outcome(case), c_outcome(lib, case)
        if py != c:
            if isinstance(py, dict) and isinstance(c, dict):
                diff = {k: (py[k], c[k]) for k in py if py[k] != c[k]}
                mismatches.append(f"{case}: differ (python, C): {diff}")
            else:
                mismatches.append(f"{case}: python {py if isinstance(py, tuple) else 'OK'}, C {c}")
        kinds[_kind(py)] += 1
    assert not mismatches, f"{len(mismatches)} of {len(cases)} moves differ:\n" + "\n".join(mismatches[:20])
    return kinds


def test_random_coordinated_moves_bit_for_bit(lib: ctypes.CDLL) -> None:
    print(f"seed {SEED} (STEPRAMP_SEED={SEED} replays it)")
    kinds = _compare(lib, random_cases(SEED, RANDOM_COUNT))
    print(f"{RANDOM_COUNT} coordinated moves: {sorted(kinds.items())}")
    assert kinds["STEPRAMP_OK"] >= RANDOM_COUNT // 3, kinds
    for name in ("STEPRAMP_ECOORD_AXES", "STEPRAMP_ECOORD_ZERO", "STEPRAMP_ESTEPS", "STEPRAMP_EOVERFLOW"):
        assert kinds[name] >= 20, kinds
    assert kinds["STEPRAMP_ECOORD_LONG"] >= 10, kinds


def test_named_coordinated_moves_bit_for_bit(lib: ctypes.CDLL) -> None:
    cases = [{**path, "steps": steps} for steps, path in NAMED.values()]
    kinds = _compare(lib, cases)
    assert kinds == {"STEPRAMP_OK": len(cases)}


def test_a_failing_axis_is_named_in_both(lib: ctypes.CDLL) -> None:
    # axis 2 (2 steps beside a long, slow lead) lasts the whole move in one interval: more than 2^32 ticks
    path = design_args(100_000, 60_000.0, 10.0, 10.0)
    case = {**path, "steps": [100_000, 50_000, -2]}
    assert py_outcome(case) == c_outcome(lib, case) == ("STEPRAMP_EOVERFLOW", 2)
    case = {**path, "steps": [3, 2**31, 2]}
    assert py_outcome(case) == c_outcome(lib, case) == ("STEPRAMP_ESTEPS", 1)


def test_coordinated_results_have_their_texts(lib: ctypes.CDLL) -> None:
    codes = {name: value for value, name in RESULT_NAMES.items()}
    for key, name in COORD_ERROR_KEYS.items():
        if key != "no axes":
            text = lib.stepramp_strerror(codes[name]).decode()
            assert key in text, (name, text)
    assert {n for n in RESULT_NAMES.values() if n.startswith("STEPRAMP_ECOORD_")} == set(COORD_ERROR_KEYS.values())


def test_null_pointers(lib: ctypes.CDLL) -> None:
    steps = _c_steps([10, 5])
    args = (*(ctypes.c_double(x) for x in (40.0, 40.0, 20.0, 400.0, 1e6)), 1)
    plans = (CPlan * ARRAY_AXES)()
    assert RESULT_NAMES[lib.stepramp_plan_coordinated(None, steps, 2, *args)] == "STEPRAMP_ENULL"
    assert RESULT_NAMES[lib.stepramp_plan_coordinated(plans, None, 2, *args)] == "STEPRAMP_ENULL"
    assert RESULT_NAMES[lib.stepramp_plan_coordinated(plans, None, 0, *args)] == "STEPRAMP_ECOORD_AXES"
    assert lib.stepramp_time_before_last(None) == 0.0
    assert lib.stepramp_ideal_end(None) == 0.0


# --------------------------------------------------------------------------------------------------------------------
# the helpers on their own
# --------------------------------------------------------------------------------------------------------------------


def _c_plan(plan: Plan) -> CPlan:
    return CPlan(**dataclasses.asdict(plan))


def _hand_made_plans(rng: random.Random, count: int) -> list[Plan]:
    """Plans with any boundary layout (sa, sd anywhere in 1 .. L, coinciding or not) and any register values."""
    plans = []
    for _ in range(count):
        steps = rng.choice((0, 1, 2, 3, 4, rng.randint(5, 100), rng.randint(2, MAX_STEPS)))
        length = max(steps - 1, 1)
        sa = rng.randint(1, length)
        sd = rng.choice((sa, rng.randint(sa, length), length))
        regs = [rng.randrange(1 << 48) for _ in range(6)]
        plans.append(Plan(steps, 0, 1, *regs[:2], sa, regs[2], sd, *regs[3:], rng.randrange(1 << 64), 1 << 16))
    return plans


def test_time_before_last_bit_for_bit(lib: ctypes.CDLL) -> None:
    rng = random.Random(SEED + 1)
    print(f"seed {SEED + 1} (STEPRAMP_SEED={SEED} replays it)")
    plans = [plan_move(**profile.args()) for profile in PROFILES] + _hand_made_plans(rng, 3000)
    bad = [p for p in plans if _hex(time_before_last(p)) != _hex(lib.stepramp_time_before_last(_c_plan(p)))]
    assert not bad, f"{len(bad)} of {len(plans)} differ, e.g. {bad[:3]}"


def test_ideal_end_bit_for_bit(lib: ctypes.CDLL) -> None:
    for profile in PROFILES:
        info = CInfo()
        args = profile.args()
        values = [
            args["steps"],
            *(float(args[k]) for k in ("accel", "decel", "speed", "spr", "fclk")),
            args["prescale"],
        ]
        assert lib.stepramp_plan_move_info(ctypes.byref(CPlan()), ctypes.byref(info), *values) == 0
        assert _hex(lib.stepramp_ideal_end(ctypes.byref(info))) == _hex(ideal_end(plan_move_info(**args)[1]))
