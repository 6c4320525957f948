# SPDX-License-Identifier: MIT
"""The C port of stepramp.board.change (sw/c/src/stepramp_change.c): bit-for-bit parity with the Python driver.

The library is built with ``make -C sw/c`` (as in test_c_plan.py) and loaded with ctypes. For random changes, extreme
and invalid inputs, stepramp_plan_change must give every field of Python's plan_change (the segment, the move back
field by field, start_speed to the last bit) or the same error, and every register value before its rounding the same
double (recorded on its way into change.py's _to_fixed and _cruise: a register alone would hide a last-bit difference
almost always); stepramp_speed_at_pulse must give speed_at_pulse's double. Random cases print their seed
(STEPRAMP_SEED replays one).

An arithmetic exception of change.py (ZeroDivisionError, OverflowError) instead of a ValueError with its reason fails
the comparison: every input either plans or is refused with the reason.

The exact mode (stepramp_plan_change_ramp against plan_change(..., ramp=RAMP_EXACT)) likewise, on random, extreme and
invalid changes: the ramp constants (recorded on their way into exact.ramp_constant: c0 of the head, cd0 of the decel)
are compared as the doubles they come from.
"""

from __future__ import annotations

import ctypes
import dataclasses
import math
import os
import random
import re
import sys
import traceback
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from test_c_plan import ERROR_KEYS, PLAN_HEADER, CInfo, load_library, py_error_name

from c_abi import CPlan, log_uniform, struct_fields
from stepramp.board import change as pychange
from stepramp.board.change import DOWN, UP, Segment, plan_change, speed_at_pulse
from stepramp.board.plan import MAX_STEPS, RAMP_EXACT, plan_move, plan_move_info
from stepramp.sim.profiles import EXACT_PROFILES, PROFILES
from stepramp.tools import clib

CHANGE_HEADER = clib.SRC_DIR / "stepramp_change.h"
SEED = int(os.environ.get("STEPRAMP_SEED", "20261127"))
RANDOM_COUNT = 3000
ENDLESS = -1  # STEPRAMP_ENDLESS: Python's remaining None

# change.py's own ValueErrors -> the codes stepramp_plan_change adds to stepramp_err_t (stepramp_plan.h); the checks
# of a, d, v and f_tick in steps units are plan.py's messages (ERROR_KEYS: STEPRAMP_EACCEL_UNITS .. STEPRAMP_EFTICK)
CHANGE_ERROR_KEYS: dict[str, str] = {
    "the speed at the change must be finite and >= 0": "STEPRAMP_ECHANGE_SPEED",
    "remaining must be in 0 .. 2^31 - 1 steps": "STEPRAMP_EREMAINING",
    "the stop distance from the speed at the change": "STEPRAMP_ESEGMENT",
    "the stop from the jog speed": "STEPRAMP_ESEGMENT",
    "the accel ramp's index at the speed at the change": "STEPRAMP_ESEGMENT",
    "Segment.": "STEPRAMP_ESEGMENT",
}
# "the target lies N steps behind the stop; the move back: <plan.py's message>": the C port returns the move back's
# own error, the code of plan.py's message
MOVE_BACK = re.compile(r"^the target lies -?\d+ steps behind the stop; the move back: (.*)$", re.S)

PY_CRASH = "python crash: "

Change = dict[str, Any]
Outcome = Change | str
"""Every field of a change (ints, doubles as their hex form), or the name of the error."""


class CSegment(ctypes.Structure):
    """stepramp_segment_t."""

    _fields_ = struct_fields(CHANGE_HEADER, "stepramp_segment_t")


class CChangeInfo(ctypes.Structure):
    """stepramp_change_info_t: the register values before rounding."""

    _fields_ = struct_fields(CHANGE_HEADER, "stepramp_change_info_t")


class CChange(ctypes.Structure):
    """stepramp_change_t."""

    _fields_ = struct_fields(
        CHANGE_HEADER, "stepramp_change_t", {"stepramp_segment_t": CSegment, "stepramp_plan_t": CPlan}
    )


def _result_names() -> dict[int, str]:
    """Every STEPRAMP_E* result of stepramp_plan.h by value: stepramp_err_t's (0, 1, ...) and the change's (= n)."""
    text = re.sub(r"/\*.*?\*/", "", PLAN_HEADER.read_text(), flags=re.S)
    match = re.search(r"typedef enum \{(.*?)\} stepramp_err_t;", text, re.S)
    assert match, f"no stepramp_err_t in {PLAN_HEADER}"
    names = {i: item.split("=")[0].strip() for i, item in enumerate(match.group(1).split(",")) if item.strip()}
    names |= {int(value): name for name, value in re.findall(r"(STEPRAMP_E\w+)\s*=\s*(\d+)", text)}
    return names


RESULT_NAMES = _result_names()


def field_names(struct: type[ctypes.Structure]) -> list[str]:
    return [name for name, _ in struct._fields_]


@pytest.fixture(scope="module")
def lib(build: Path) -> ctypes.CDLL:
    """libstepramp.so with the plan's and the change's functions declared."""
    so = load_library(build)
    args = [ctypes.c_double, ctypes.c_int64, *(ctypes.c_double,) * 5, ctypes.c_uint32]  # u, remaining .. prescale
    so.stepramp_plan_change.argtypes = [ctypes.POINTER(CChange), *args]
    so.stepramp_plan_change_info.argtypes = [ctypes.POINTER(CChange), ctypes.POINTER(CChangeInfo), *args]
    so.stepramp_plan_change.restype = so.stepramp_plan_change_info.restype = ctypes.c_int
    so.stepramp_plan_change_ramp.argtypes = [*so.stepramp_plan_change.argtypes, ctypes.c_uint32]
    so.stepramp_plan_change_info_ramp.argtypes = [*so.stepramp_plan_change_info.argtypes, ctypes.c_uint32]
    so.stepramp_plan_change_ramp.restype = so.stepramp_plan_change_info_ramp.restype = ctypes.c_int
    so.stepramp_segment_of_move.argtypes = [ctypes.POINTER(CSegment), ctypes.POINTER(CPlan)]
    so.stepramp_segment_of_move.restype = ctypes.c_int
    so.stepramp_speed_at_pulse.argtypes = [ctypes.POINTER(CInfo), ctypes.c_int64]
    so.stepramp_speed_at_pulse.restype = ctypes.c_double
    return so


def _hex(x: float) -> str:
    return float(x).hex()


_RAW: dict[str, float] = {}
"""The doubles the running plan_change has rounded into registers so far, by stepramp_change_info_t's names."""


# the callers of exact.ramp_constant in change.py -> the stepramp_change_info_t field of the c0 it is given
_RAMP_CONSTANT_OF = {"plan_change": "t_accel_seed", "_fields": "t_decel_seed"}


@pytest.fixture(autouse=True)
def _record_raw(monkeypatch: pytest.MonkeyPatch) -> None:
    """change.py's _to_fixed, _cruise and ramp_constant, recording their doubles into _RAW (plan.py's own are not
    touched); ramp_constant's c0 under the seed its caller rounds it into (_RAMP_CONSTANT_OF)."""
    to_fixed, cruise, ramp_constant = pychange._to_fixed, pychange._cruise, pychange.ramp_constant

    def recording_to_fixed(name: str, ticks: float, frac: int, width: int) -> int:
        _RAW["t_" + name.removeprefix("c_")] = ticks
        return to_fixed(name, ticks, frac, width)

    def recording_cruise(f_tick: float, v: float) -> int:
        _RAW["t_cruise"] = f_tick / v if v != 0.0 else math.inf  # _cruise itself raises for v == 0
        return cruise(f_tick, v)

    def recording_ramp_constant(c0_ticks: float) -> int:
        _RAW[_RAMP_CONSTANT_OF[sys._getframe(1).f_code.co_name]] = c0_ticks
        return ramp_constant(c0_ticks)

    monkeypatch.setattr(pychange, "_to_fixed", recording_to_fixed)
    monkeypatch.setattr(pychange, "_cruise", recording_cruise)
    monkeypatch.setattr(pychange, "ramp_constant", recording_ramp_constant)


def change_error_name(message: str) -> str:
    """The C result for a ValueError message of plan_change: its own (CHANGE_ERROR_KEYS), the move back's (MOVE_BACK),
    or plan.py's (ERROR_KEYS)."""
    back = MOVE_BACK.match(message)
    if back:
        return py_error_name(back.group(1))
    keys = {name for key, name in CHANGE_ERROR_KEYS.items() if key in message}
    return keys.pop() if len(keys) == 1 else py_error_name(message)


def py_outcome(case: dict[str, Any]) -> Outcome:
    """plan_change's fields (the C struct's names and encodings) and its unrounded register values, or the error's
    name."""
    _RAW.clear()
    try:
        change = plan_change(**case)
    except ValueError as exc:
        return change_error_name(str(exc))
    except (ZeroDivisionError, OverflowError) as exc:
        line = traceback.extract_tb(exc.__traceback__)[-1].line or ""
        return f"{PY_CRASH}{type(exc).__name__} ({exc}) at {line!r}"
    seg = dataclasses.asdict(change.segment)
    seg |= {"length": seg["length"] or 0, "endless": int(seg["length"] is None), "head": (UP, DOWN).index(seg["head"])}
    back = dataclasses.asdict(change.back) if change.back is not None else dict.fromkeys(field_names(CPlan), 0)
    raw = {name: _hex(_RAW.get(name, 0.0)) for name in field_names(CChangeInfo)}
    assert set(_RAW) <= set(raw), f"change.py rounds values stepramp_change_info_t does not hold: {sorted(_RAW)}"
    extra = {"start_speed": _hex(change.start_speed), "has_back": int(change.back is not None), "back": back}
    return {**seg, **extra, "raw": raw}


def _c_fields(out: CChange) -> Change:
    seg = {name: getattr(out.segment, name) for name in field_names(CSegment)}
    back = {name: getattr(out.back, name) for name in field_names(CPlan)}
    return {**seg, "start_speed": _hex(out.start_speed), "has_back": out.has_back, "back": back}


def c_outcome(so: ctypes.CDLL, case: dict[str, Any]) -> Outcome:
    """stepramp_plan_change_info's fields and unrounded register values, or the error's name; stepramp_plan_change
    gives the same. A case with a "ramp" goes to stepramp_plan_change_info_ramp and stepramp_plan_change_ramp."""
    out, plain, info = CChange(), CChange(), CChangeInfo()
    remaining = ENDLESS if case["remaining"] is None else case["remaining"]
    physical = (float(case[k]) for k in ("accel", "decel", "speed", "spr", "fclk"))
    args: tuple[Any, ...] = (case["u"], remaining, *physical, case["prescale"])
    if "ramp" in case:
        args = (*args, case["ramp"])
        err = so.stepramp_plan_change_info_ramp(ctypes.byref(out), ctypes.byref(info), *args)
        assert so.stepramp_plan_change_ramp(ctypes.byref(plain), *args) == err
    else:
        err = so.stepramp_plan_change_info(ctypes.byref(out), ctypes.byref(info), *args)
        assert so.stepramp_plan_change(ctypes.byref(plain), *args) == err
    if err != 0:
        return RESULT_NAMES.get(err, f"unknown result {err}")
    assert _c_fields(plain) == _c_fields(out)
    return {**_c_fields(out), "raw": {name: _hex(getattr(info, name)) for name in field_names(CChangeInfo)}}


def _mismatch(case: dict[str, Any], py: Outcome, c: Outcome) -> str:
    if isinstance(py, dict) and isinstance(c, dict):
        diff = {k: (py[k], c.get(k)) for k in py if py[k] != c.get(k)}
        return f"{case}: fields differ (python, C): {diff}"
    return f"{case}: python {py if isinstance(py, str) else 'OK'}, C {c if isinstance(c, str) else 'OK'}"


def _kind(py: Outcome) -> str:
    if isinstance(py, str):
        return py
    if py["has_back"]:
        return "stop"
    if py["length"] == 0 and not py["endless"]:
        return "at target"
    return ("up", "down")[py["head"]] + ("-jog" if py["endless"] else "")


def _random_change(rng: random.Random) -> dict[str, Any]:
    """test_change.py's _random_case, any speed, with a prescale of 1 .. 8 and targets from 0 to 2^31 - 1."""
    spr = rng.choice([200.0, 400.0, 1600.0, 3200.0])
    fclk = rng.choice([1e6, 2e6, 10e6])
    accel, decel = rng.uniform(5.0, 500.0), rng.uniform(5.0, 500.0)
    speed = rng.uniform(2.0, 60.0)
    v = speed / (2.0 * math.pi / spr)
    u = rng.uniform(0.0, 1.5) * v * rng.choice([0, 1, 1, 1])
    r = rng.random()
    if r < 0.25:
        remaining = None
    elif r < 0.35:
        remaining = 0
    elif r < 0.7:
        remaining = rng.randint(1, 3000)
    else:
        remaining = round(log_uniform(rng, 1.0, MAX_STEPS))
    return {
        "u": u,
        "remaining": remaining,
        "accel": accel,
        "decel": decel,
        "speed": speed,
        "spr": spr,
        "fclk": fclk,
        "prescale": rng.randint(1, 8),
    }


def _compare(lib: ctypes.CDLL, cases: list[dict[str, Any]], what: str | None = None) -> Counter[str]:
    """Every case the same in C as in Python (a crash of change.py is a mismatch); returns the count of each kind of
    outcome (printed as "<count> <what>: ..." when what is given)."""
    kinds: Counter[str] = Counter()
    mismatches: list[str] = []
    for case in cases:
        py, c = py_outcome(case), c_outcome(lib, case)
        if py != c:
            mismatches.append(_mismatch(case, py, c))
        kinds[_kind(py)] += 1
    assert not mismatches, f"{len(mismatches)} of {len(cases)} changes differ:\n" + "\n".join(mismatches[:20])
    if what is not None:
        print(f"{len(cases)} {what}: {sorted(kinds.items())}")
    return kinds


def _seeded(offset: int) -> random.Random:
    """The generator of one random test, seeded SEED + offset (printed: STEPRAMP_SEED=SEED replays it)."""
    print(f"seed {SEED + offset} (STEPRAMP_SEED={SEED} replays it)")
    return random.Random(SEED + offset)


#: The kinds of outcome of the random changes: every one at least 30 times.
RANDOM_KINDS = {"up", "down", "stop", "at target", "up-jog", "down-jog", "STEPRAMP_ETOOFAST"}


def _check_random_changes(lib: ctypes.CDLL, cases: list[dict[str, Any]], what: str) -> None:
    """The random changes the same in C as in Python, every kind of RANDOM_KINDS (and no other) 30 times or more."""
    kinds = _compare(lib, cases, what)
    assert set(kinds) == RANDOM_KINDS, kinds
    assert min(kinds.values()) >= 30, kinds


def test_segment_struct_matches_python() -> None:
    """stepramp_segment_t has every field of change.Segment (and endless for its length None)."""
    python = [f.name for f in dataclasses.fields(Segment)]
    c = field_names(CSegment)
    assert [name for name in c if name != "endless"] == python
    assert field_names(CChange) == ["segment", "start_speed", "has_back", "back"]


def test_random_changes_bit_for_bit(lib: ctypes.CDLL) -> None:
    rng = _seeded(0)
    _check_random_changes(lib, [_random_change(rng) for _ in range(RANDOM_COUNT)], "changes")


def test_a_triangle_whose_boundaries_round_apart(lib: ctypes.CDLL) -> None:
    """A change in the final decel to a farther target (a triangle): x_h rounds past x_c, and both drivers keep
    sa <= sd (sd = sa) the same way."""
    case = {"u": 718.0961047225787, "remaining": 87, "accel": 300.0, "decel": 300.0, "speed": 60.0, "spr": 200.0}
    case |= {"fclk": 1e6, "prescale": 1}
    _compare(lib, [case])
    seg = plan_change(**case).segment
    assert seg.sa == seg.sd == 31, seg


# extreme but finite values: a, d, v in steps units that underflow to 0 or overflow to inf, huge ramp indices
_EXTREME: dict[str, tuple[float | int | None, ...]] = {
    "u": (0.0, 5e-324, 1e-3, 1e6, 1e9, 1e150, 1e200, 1.7976931348623157e308),
    "remaining": (None, 0, 1, 2, 3, 1000, 2**31 - 1),
    "accel": (5e-324, 1e-300, 1e-9, 1e-3, 1e9, 1e300, 1.7976931348623157e308),
    "decel": (5e-324, 1e-300, 1e-9, 1e-3, 1e9, 1e300, 1.7976931348623157e308),
    "speed": (5e-324, 1e-170, 1e-9, 1e-3, 1e3, 1e300),
    "spr": (5e-324, 1e-300, 0.5, 1e10, 1e300),
    "fclk": (5e-324, 1e-300, 1e3, 1e12, 1e300),
    "prescale": (1, 3, 65535),
}


def _extreme(rng: random.Random, case: dict[str, Any]) -> dict[str, Any]:
    """The case with one to three values replaced by extreme ones (_EXTREME)."""
    for _ in range(rng.choice((1, 2, 3))):
        name = rng.choice(list(_EXTREME))
        case[name] = rng.choice(_EXTREME[name])
    return case


def test_extreme_changes_same_outcome(lib: ctypes.CDLL) -> None:
    """Random cases with one to three extreme values: the same fields, or the same error."""
    rng = _seeded(1)
    kinds = _compare(lib, [_extreme(rng, _random_change(rng)) for _ in range(3000)], "extreme changes")
    units = {"STEPRAMP_EACCEL_UNITS", "STEPRAMP_EDECEL_UNITS", "STEPRAMP_ESPEED_UNITS", "STEPRAMP_EFTICK"}
    assert units | {"STEPRAMP_ESEGMENT", "STEPRAMP_EOVERFLOW", "STEPRAMP_ETOOFAST"} <= set(kinds), kinds


_BASE: dict[str, Any] = {
    "u": 400.0,
    "remaining": 100,
    "accel": 50.0,
    "decel": 50.0,
    "speed": 10.0,
    "spr": 400.0,
    "fclk": 1e6,
    "prescale": 1,
}


@pytest.mark.parametrize(
    ("kwargs", "expected"),
    [
        ({"u": -1.0}, "STEPRAMP_ECHANGE_SPEED"),
        ({"u": -0.0}, None),  # -0.0 >= 0: a valid speed
        ({"u": math.nan}, "STEPRAMP_ECHANGE_SPEED"),
        ({"u": math.inf}, "STEPRAMP_ECHANGE_SPEED"),
        ({"u": -math.inf}, "STEPRAMP_ECHANGE_SPEED"),
        ({"remaining": -2}, "STEPRAMP_EREMAINING"),
        ({"remaining": 2**31}, "STEPRAMP_EREMAINING"),
        ({"remaining": 2**62}, "STEPRAMP_EREMAINING"),
        ({"accel": 0.0}, "STEPRAMP_EACCEL"),
        ({"decel": math.nan}, "STEPRAMP_EDECEL"),
        ({"speed": 1e9, "remaining": None}, "STEPRAMP_ETOOFAST"),
        ({"u": 1e6, "remaining": None}, "STEPRAMP_ETOOFAST"),
        ({"prescale": 0}, "STEPRAMP_EPRESCALE"),
        ({"prescale": 65536}, "STEPRAMP_EPRESCALE"),
        # the first bad argument in plan_change's order wins
        ({"u": -1.0, "remaining": -2, "prescale": 0}, "STEPRAMP_EPRESCALE"),
        ({"u": math.nan, "remaining": -2}, "STEPRAMP_ECHANGE_SPEED"),
        # the stop distance u^2 / 2d of 2^31 + 1000 steps (100 steps to the target), 2^31 + 9 (10 steps to it)
        ({"u": math.sqrt(2.0 * 50.0 / (2.0 * math.pi / 400.0) * (2**31 + 1000))}, "STEPRAMP_ESEGMENT"),
        ({"u": math.sqrt(2.0 * 50.0 / (2.0 * math.pi / 400.0) * (2**31 + 9)), "remaining": 10}, "STEPRAMP_ESEGMENT"),
        # ... just below 2^31: to rest 2^31 - 1 steps ahead, then 2^31 - 11 steps back
        ({"u": math.sqrt(2.0 * 50.0 / (2.0 * math.pi / 400.0) * (2**31 - 0.5)), "remaining": 10}, None),
        # the accel ramp's index u^2 / 2a of about 3.1e9 steps (d 1000 times a: the stop distance fits)
        ({"u": 2e4, "accel": 1e-3, "decel": 1.0, "speed": 1000.0, "remaining": None}, "STEPRAMP_ESEGMENT"),
        # a jog's run_stop v^2 / 2d of about 2.5e10 steps
        ({"u": 0.0, "decel": 1e-2, "speed": 1600.0, "fclk": 1e9, "remaining": None}, "STEPRAMP_ESEGMENT"),
        # accel, decel, speed, f_tick in steps units: 0 (2 pi / spr is inf), inf, or finite with an infinite square
        ({"spr": 5e-324}, "STEPRAMP_EACCEL_UNITS"),
        ({"accel": 1e300, "spr": 1e10}, "STEPRAMP_EACCEL_UNITS"),
        ({"accel": 1e160}, "STEPRAMP_EACCEL_UNITS"),
        ({"decel": 1e160}, "STEPRAMP_EDECEL_UNITS"),
        ({"speed": 1e160}, "STEPRAMP_ESPEED_UNITS"),
        ({"fclk": 2e154}, "STEPRAMP_EFTICK"),
        ({"fclk": 2e154, "prescale": 2}, "STEPRAMP_EOVERFLOW"),  # f_tick 1e154 passes; its delays overflow
        # a tiny but positive a in steps units whose square underflows to 0 passes: the stop distance from u does not
        ({"spr": 1e-300}, "STEPRAMP_EACCEL_UNITS"),  # a in steps units squares to 0
        # the target inside the stop distance (k = 2513 steps, 100 to the target): the move back's own error
        ({"u": 4000.0, "fclk": 2e4}, "STEPRAMP_ETOOFAST"),
    ],
)
def test_invalid_changes_same_error(lib: ctypes.CDLL, kwargs: dict[str, Any], expected: str | None) -> None:
    case = _BASE | kwargs
    py = py_outcome(case)
    assert (py if isinstance(py, str) else None) == expected, py
    assert c_outcome(lib, case) == py


def test_errors_leave_the_output_alone(lib: ctypes.CDLL) -> None:
    out = CChange()
    ctypes.memset(ctypes.byref(out), 0x5A, ctypes.sizeof(out))
    before = bytes(out)
    args = (400.0, 100, 0.0, 50.0, 10.0, 400.0, 1e6, 1)
    assert RESULT_NAMES[lib.stepramp_plan_change(ctypes.byref(out), *args)] == "STEPRAMP_EACCEL"
    assert bytes(out) == before
    assert RESULT_NAMES[lib.stepramp_plan_change(None, *args)] == "STEPRAMP_ENULL"


def test_change_results_have_their_texts(lib: ctypes.CDLL) -> None:
    """stepramp_strerror names the change's results with the words of change.py's messages."""
    codes = {name: value for value, name in RESULT_NAMES.items()}
    for key, name in CHANGE_ERROR_KEYS.items():
        text = lib.stepramp_strerror(codes[name]).decode()
        assert key in text, (name, text)
    # 32 .. 63: the change's results, and the coordinated move's (test_c_coord.py)
    change_results = {n for v, n in RESULT_NAMES.items() if v >= 32 and not n.startswith("STEPRAMP_ECOORD_")}
    assert set(CHANGE_ERROR_KEYS.values()) == change_results
    assert not set(CHANGE_ERROR_KEYS) & set(ERROR_KEYS)


def test_segment_of_move(lib: ctypes.CDLL) -> None:
    """Segment.of_move of every profile's plan: the same segment (with its ramp; EXACT_PROFILES in exact mode)."""
    moves = [p.args() for p in PROFILES] + [p.args() | {"ramp": RAMP_EXACT} for p in EXACT_PROFILES]
    for move in moves:
        plan = plan_move(**move)
        seg = CSegment()
        assert lib.stepramp_segment_of_move(ctypes.byref(seg), ctypes.byref(CPlan(**dataclasses.asdict(plan)))) == 0
        py = dataclasses.asdict(Segment.of_move(plan)) | {"endless": 0, "head": 0}
        assert {name: getattr(seg, name) for name in field_names(CSegment)} == py, move
    assert RESULT_NAMES[lib.stepramp_segment_of_move(None, ctypes.byref(CPlan()))] == "STEPRAMP_ENULL"


def test_speed_at_pulse_bit_for_bit(lib: ctypes.CDLL) -> None:
    """On the planned moves of the first 16 profiles, at 20 pulses each from before the first to after the last."""
    checked = 0
    for profile in PROFILES[:16]:
        move = profile.args()
        _, info = plan_move_info(**move)
        c_info = CInfo()
        err = lib.stepramp_plan_move_info(
            ctypes.byref(CPlan()),
            ctypes.byref(c_info),
            move["steps"],
            *(float(move[k]) for k in ("accel", "decel", "speed", "spr", "fclk")),
            move["prescale"],
        )
        assert err == 0, profile.name
        for j in range(20):
            p = round(j * (info.length + 2) / 19) - 1
            py, c = speed_at_pulse(info, p), lib.stepramp_speed_at_pulse(ctypes.byref(c_info), p)
            assert _hex(py) == _hex(c), (profile.name, p, py, c)
            checked += py > 0.0
    assert checked >= 16 * 15
    assert lib.stepramp_speed_at_pulse(None, 5) == 0.0


# --------------------------------------------------------------------------------------------------------------------
# the exact mode (RAMP_EXACT)
# --------------------------------------------------------------------------------------------------------------------

EXACT_COUNT = 3000


def _random_exact_change(rng: random.Random) -> dict[str, Any]:
    """_random_change in exact mode, at 4 times the clock (4, 8 or 40 MHz, as EXACT_PROFILES take the profiles) so that
    its speeds keep the exact mode's 256-clock limit about as often as the AVR446 ones keep 64."""
    case = _random_change(rng) | {"ramp": RAMP_EXACT}
    case["fclk"] *= 4.0
    return case


def test_random_exact_changes_bit_for_bit(lib: ctypes.CDLL) -> None:
    """stepramp_plan_change_info_ramp in exact mode against plan_change(..., ramp=RAMP_EXACT): every field, every double
    behind a register (the c0 of each ramp constant), or the same error."""
    rng = _seeded(2)
    # (no EOVERFLOW: since the scaled ramp constant, c0 of 2^20 ticks or more at the slowest accels and the fastest
    # clock is in range; test_extreme_exact_changes_same_outcome draws constants out of range)
    _check_random_changes(lib, [_random_exact_change(rng) for _ in range(EXACT_COUNT)], "exact-mode changes")


def test_extreme_exact_changes_same_outcome(lib: ctypes.CDLL) -> None:
    """Random exact-mode cases with one to three extreme values (or a ramp that is neither mode): the same fields, or
    the same error, the ramp constants out of range among them."""
    rng = _seeded(3)
    cases = []
    for _ in range(3000):
        case = _extreme(rng, _random_exact_change(rng))
        if rng.random() < 0.02:
            case["ramp"] = rng.choice((2, 7, 2**32 - 1))
        cases.append(case)
    kinds = _compare(lib, cases, "extreme exact-mode changes")
    units = {"STEPRAMP_EACCEL_UNITS", "STEPRAMP_EDECEL_UNITS", "STEPRAMP_ESPEED_UNITS", "STEPRAMP_EFTICK"}
    assert units | {"STEPRAMP_ESEGMENT", "STEPRAMP_EOVERFLOW", "STEPRAMP_ETOOFAST", "STEPRAMP_ERAMP"} <= set(kinds), (
        kinds
    )


@pytest.mark.parametrize(
    ("kwargs", "expected"),
    [
        ({"ramp": 2}, "STEPRAMP_ERAMP"),
        ({"ramp": 2, "u": -1.0, "prescale": 0}, "STEPRAMP_ERAMP"),  # the ramp first
        ({"u": -1.0}, "STEPRAMP_ECHANGE_SPEED"),
        # 10 rad/s at 400 steps/rev is 636.6 steps/s: 300 ticks at 1.91e5 Hz (enough), 250 at 1.59e5 (too few)
        ({"speed": 10.0, "fclk": 1.91e5, "u": 0.0, "remaining": None}, None),
        ({"speed": 10.0, "fclk": 1.59e5, "u": 0.0, "remaining": None}, "STEPRAMP_ETOOFAST"),
        ({"speed": 10.0, "fclk": 1.59e5, "u": 0.0, "remaining": 100000}, "STEPRAMP_ETOOFAST"),
        # the head's constant: c0 = 1e6 sqrt(2 / (0.01 * 400 / 2 pi)) = 1.8e6 ticks > 2^20: in range (a scaled seed
        # word), c0 = 1.1e10 ticks (accel 1e-9) > 2^32 is not
        ({"u": 0.0, "accel": 0.01, "speed": 1.0, "remaining": None}, None),
        ({"u": 0.0, "accel": 1e-9, "speed": 1.0, "remaining": None}, "STEPRAMP_EOVERFLOW"),
        # ... the decel's (cd0), of a jog whose soft stop needs it
        ({"u": 0.0, "decel": 0.01, "speed": 1.0, "remaining": None}, None),
        ({"u": 0.0, "decel": 1e-9, "speed": 0.01, "remaining": None}, "STEPRAMP_EOVERFLOW"),
        # ... c0 of 0.03 ticks: the constant rounds to 0
        ({"u": 0.0, "accel": 1e14, "remaining": None}, "STEPRAMP_EOVERFLOW"),
        # a down head from 3000 steps/s (333 ticks): the decel's constant; from 4000 (250 ticks) too fast
        ({"u": 3000.0, "remaining": 100000}, None),
        ({"u": 4000.0, "remaining": 100000}, "STEPRAMP_ETOOFAST"),
        # the target inside the stop distance: the move back in exact mode, its own error (the exact speed limit)
        ({"u": 4000.0, "fclk": 7e4}, "STEPRAMP_ETOOFAST"),
        ({"u": 4000.0}, None),
        ({"u": 0.0, "remaining": 0}, None),
    ],
)
def test_invalid_exact_changes_same_error(lib: ctypes.CDLL, kwargs: dict[str, Any], expected: str | None) -> None:
    case = _BASE | {"ramp": RAMP_EXACT} | kwargs
    py = py_outcome(case)
    assert (py if isinstance(py, str) else None) == expected, py
    assert c_outcome(lib, case) == py


# c0 = f_tick sqrt(2 / a) of about 1.8e224 ticks: its square is not finite
_INFINITE_SQUARE = {"u": 0.0, "remaining": None, "accel": 1e-150, "decel": 1.0, "speed": 1.0, "spr": 400.0}
_INFINITE_SQUARE |= {"fclk": 1e150, "prescale": 1, "ramp": RAMP_EXACT}


def test_exact_head_constant_of_an_infinite_square_in_c(lib: ctypes.CDLL) -> None:
    """A head constant whose c0 * c0 overflows a double: out of range (STEPRAMP_EOVERFLOW), as a ValueError would be."""
    assert c_outcome(lib, _INFINITE_SQUARE) == "STEPRAMP_EOVERFLOW"


def test_exact_head_constant_of_an_infinite_square_in_python(lib: ctypes.CDLL) -> None:
    """change.py reaches ramp_constant with that c0 before anything refuses it (a move's c_first would)."""
    assert py_outcome(_INFINITE_SQUARE) == c_outcome(lib, _INFINITE_SQUARE)
