# SPDX-License-Identifier: MIT
"""The C port of the coordinated stop on the line (stepramp_plan_coordinated_stop, sw/c/src/stepramp_coord.c) against
stepramp.board.coord.plan_coordinated_stop_at: bit for bit.

For random coordinated moves (2 to 8 axes, accel / decel from 1/20 to 20, PRESCALE 1 to 64) and random take-over
pulses (each axis's pulse, anywhere from 0 to past its end, from change_pulse at a random commit edge half of the
time), the C function, given the C plans and info of the same move (stepramp_plan_coordinated_info, itself
bit-identical: test_c_coord.py), must give R_L, every axis's P_i, u_i (to the last bit), N_i, T_i, whether it takes
a CHANGE and every field of that segment, or the same fallback axis and error. Seed printed (STEPRAMP_SEED replays).
"""

from __future__ import annotations

import ctypes
import dataclasses
import math
import os
import random
import re
from typing import Any

from test_c_change import RESULT_NAMES, CChange, _c_fields, change_error_name
from test_c_coord import ARRAY_AXES, CCoordInfo, _c_steps, lib  # noqa: F401 (lib: the fixture)

from c_abi import CPlan
from stepramp.board.change import DOWN, UP
from stepramp.board.coord import coordinated_stop_pulses, plan_coordinated_info, plan_coordinated_stop_at
from stepramp.models.engine import edges

MAX_AXES = 8
NO_AXIS = 0xFFFFFFFF


class CAxisStop(ctypes.Structure):
    _fields_ = [
        ("pulse", ctypes.c_uint32),
        ("has_change", ctypes.c_int),
        ("speed", ctypes.c_double),
        ("natural", ctypes.c_int64),
        ("target", ctypes.c_int64),
        ("change", CChange),
    ]


class CCoordStop(ctypes.Structure):
    _fields_ = [
        ("rest", ctypes.c_int64),
        ("count", ctypes.c_uint32),
        ("fallback_axis", ctypes.c_uint32),
        ("fallback_err", ctypes.c_int),
        ("axis", CAxisStop * MAX_AXES),
    ]


def _py(case: dict[str, Any], pulses: list[int]) -> dict[str, Any]:
    plans, info = plan_coordinated_info(**case)
    args = (case[k] for k in ("accel", "decel", "speed", "spr", "fclk", "prescale"))
    stop = plan_coordinated_stop_at(plans, info, pulses, *args)
    out: dict[str, Any] = {"rest": stop.rest}
    if stop.fallback is not None:
        match = re.match(r"axis (\d+): (.*)$", stop.fallback, re.S)
        assert match
        out["fallback"] = (int(match.group(1)), change_error_name(match.group(2)))
        return out
    axes = []
    for a in stop.axes:
        row: dict[str, Any] = {
            "pulse": a.pulse,
            "speed": float(a.speed).hex(),
            "natural": a.natural,
            "target": a.target,
            "has_change": int(a.change is not None),
        }
        if a.change is not None:
            seg = dataclasses.asdict(a.change.segment)
            seg |= {"length": seg["length"] or 0, "endless": int(seg["length"] is None)}
            seg["head"] = (UP, DOWN).index(seg["head"])
            row["change"] = {**seg, "start_speed": float(a.change.start_speed).hex(), "has_back": 0}
        axes.append(row)
    out["axes"] = axes
    return out


def _c(so: ctypes.CDLL, case: dict[str, Any], pulses: list[int]) -> dict[str, Any]:
    steps = case["steps"]
    plans, info = (CPlan * ARRAY_AXES)(), CCoordInfo()
    physical = [float(case[k]) for k in ("accel", "decel", "speed", "spr", "fclk")]
    assert (
        so.stepramp_plan_coordinated_info(
            plans, ctypes.byref(info), _c_steps(steps), len(steps), *physical, case["prescale"]
        )
        == 0
    )
    out = CCoordStop()
    c_pulses = (ctypes.c_uint32 * ARRAY_AXES)(*pulses)
    rc = so.stepramp_plan_coordinated_stop(
        ctypes.byref(out), plans, ctypes.byref(info), c_pulses, len(steps), *physical, case["prescale"]
    )
    assert rc == 0, RESULT_NAMES.get(rc, rc)
    res: dict[str, Any] = {"rest": out.rest}
    if out.fallback_axis != NO_AXIS:
        res["fallback"] = (out.fallback_axis, RESULT_NAMES.get(out.fallback_err, str(out.fallback_err)))
        return res
    axes = []
    for i in range(len(steps)):
        a = out.axis[i]
        row: dict[str, Any] = {
            "pulse": a.pulse,
            "speed": float(a.speed).hex(),
            "natural": a.natural,
            "target": a.target,
            "has_change": a.has_change,
        }
        if a.has_change:
            fields = _c_fields(a.change)
            row["change"] = {k: v for k, v in fields.items() if k != "back"}
        axes.append(row)
    res["axes"] = axes
    return res


def test_c_coordinated_stop_is_bit_identical(lib: ctypes.CDLL) -> None:  # noqa: F811
    """2,000 random coordinated moves and take-over pulses: stepramp_plan_coordinated_stop gives every value of
    plan_coordinated_stop_at, or the same fallback."""
    so = lib
    so.stepramp_plan_coordinated_stop.argtypes = [
        ctypes.POINTER(CCoordStop),
        ctypes.POINTER(CPlan),
        ctypes.POINTER(CCoordInfo),
        ctypes.POINTER(ctypes.c_uint32),
        ctypes.c_uint32,
        *(ctypes.c_double,) * 5,
        ctypes.c_uint32,
    ]
    so.stepramp_plan_coordinated_stop.restype = ctypes.c_int
    seed = int(os.environ.get("STEPRAMP_SEED", random.randrange(1 << 32)))
    print(f"seed {seed} (STEPRAMP_SEED={seed} replays it)")
    rng = random.Random(seed)
    compared = changes = 0
    for _ in range(2000):
        n = rng.randint(2, MAX_AXES)
        steps = [rng.choice((-1, 1)) * rng.choice((rng.randint(0, 12), rng.randint(2, 20_000))) for _ in range(n)]
        accel = rng.uniform(20, 5_000)
        case = {
            "steps": steps,
            "accel": accel,
            "decel": accel * math.exp(rng.uniform(math.log(0.05), math.log(20))),
            "speed": rng.uniform(5, 300),
            "spr": rng.choice((200.0, 400.0, 3200.0)),
            "fclk": rng.choice((1e6, 50e6)),
            "prescale": rng.randint(1, 64),
        }
        try:
            plans, _ = plan_coordinated_info(**case)
        except ValueError:
            continue
        if rng.random() < 0.5:
            all_edges = [edges(p) if p.steps > 0 else [] for p in plans]
            lead = max(all_edges, key=len)
            pulses = coordinated_stop_pulses(plans, all_edges, rng.randint(0, lead[-1] if lead else 0))
        else:
            pulses = [rng.randint(0, max(p.steps, 1)) for p in plans]
        py, c = _py(case, pulses), _c(so, case, pulses)
        assert py == c, f"{case} pulses {pulses}:\npython {py}\nC      {c}"
        compared += 1
        changes += sum(a["has_change"] for a in py.get("axes", []))
    assert compared > 1000 and changes > 1000, (compared, changes)
    print(f"{compared} stops compared, {changes} take-overs")
