# SPDX-License-Identifier: MIT
"""Golden checksums of the model: what a refactoring of the model or the script planner must not change.

Checksums, in both ramps (AVR446, and the exact ramp: plan ramp=RAMP_EXACT, a script's "ramp": "exact"), of:

* ``profiles``: the edges of every profile of stepramp.sim.profiles (PROFILES, and EXACT_PROFILES in the exact
  ramp): the `stepramp model --summary` checksum (stepramp.tools.summary.summarise_model, bounded memory);
* ``stops``: per profile, soft and hard stops at request edges spread over the move (edge 0, 1, 2 and tenths of the
  last edge), the lazy model's edges (engine.iter_edges with a stop) in one checksum;
* ``moves``: MOVE_COUNT random moves (random_moves, seeded: 1 .. 3,000 steps, a few of 20,000 .. 200,000), each
  valid in both ramps, their summary checksums;
* ``scripts``: SCRIPT_COUNT random scripts (stepramp's random_script, seeded) and the named scripts (single and
  multi-axis), the whole planned result (actions, edges, positions, refusals, errors, pins) in one checksum each; in
  the exact ramp a script runs at EXACT_FACTOR times its clock and PRESCALE (the same ticks, as tb/test_exact_rtl.py
  plays them).

Random inputs are stored with the checksum of the input itself, so a changed generator is told apart from a changed
model. `scripts/golden.py` writes sw/tests/golden/checksums.json; sw/tests/test_golden.py recomputes and compares.
"""

from __future__ import annotations

import hashlib
import json
import random
from collections.abc import Callable, Iterable
from dataclasses import asdict, is_dataclass
from typing import Any

from stepramp.board.plan import RAMP_AVR446, RAMP_EXACT, RAMPS, plan_move
from stepramp.models.engine import HARD, SOFT, iter_edges, last_edge
from stepramp.sim.profiles import SPRS, MoveRanges, random_design_moves
from stepramp.tools.summary import edge_checksum, summarise_model

SEED = 34
"""The seed of the random moves and scripts."""
MOVE_COUNT = 1000
SCRIPT_COUNT = 200
LONG_MOVES = 10
"""The first LONG_MOVES random moves are 20,000 .. 200,000 steps long."""
EXACT_FACTOR = 4
"""A script in the exact ramp runs at this many times its clock and PRESCALE (its shortest intervals then keep the
exact mode's MIN_INTERVAL_CLKS_EXACT)."""
RAMP_NAMES = {value: name for name, value in RAMPS.items()}
SHORT = 16
"""Hex digits kept of a random item's checksums (the groups' full checksums are kept too)."""


def sha(obj: Any) -> str:
    """SHA-256 of an object's canonical JSON (dataclasses as dicts, tuples as lists)."""

    def default(value: Any) -> Any:
        if is_dataclass(value) and not isinstance(value, type):
            return asdict(value)
        if isinstance(value, (set, frozenset)):
            return sorted(value)
        raise TypeError(f"not JSON: {value!r}")

    text = json.dumps(obj, sort_keys=True, separators=(",", ":"), default=default)
    return hashlib.sha256(text.encode()).hexdigest()


# ---------------------------------------------------------------------------------------------------------------
# Inputs
# ---------------------------------------------------------------------------------------------------------------


def random_moves(seed: int = SEED, count: int = MOVE_COUNT, long_moves: int = LONG_MOVES) -> list[dict[str, Any]]:
    """Random plan_move arguments that both ramps plan (random_design_moves, without 51,200 steps per revolution):
    cruise intervals from 256 clocks; the first long_moves 20,000 .. 200,000 steps, the others 1 .. 3,000."""
    ranges = MoveRanges(256, 1e4, (20_000, 200_000), (1, 3000), SPRS[:-1])
    return random_design_moves(seed, count, long_moves, ranges, plan_both)


def plan_both(args: dict[str, Any]) -> None:
    """plan_move of the arguments in both ramps (a ValueError when either refuses them)."""
    for ramp in (RAMP_AVR446, RAMP_EXACT):
        plan_move(**args, ramp=ramp)


def random_scripts(seed: int = SEED, count: int = SCRIPT_COUNT) -> list[dict[str, Any]]:
    """count random single-axis scripts (random_script) from one seeded generator."""
    from stepramp.sim.scripts import random_script

    rng = random.Random(seed)
    return [random_script(rng) for _ in range(count)]


def named_scripts() -> dict[str, dict[str, Any]]:
    """The named single-axis and multi-axis scripts, by name (the multi-axis ones prefixed "multi:")."""
    from stepramp.sim.multi_scripts import NAMED_MULTI_SCRIPTS
    from stepramp.sim.scripts import NAMED_SCRIPTS

    return {**NAMED_SCRIPTS, **{f"multi:{name}": obj for name, obj in NAMED_MULTI_SCRIPTS.items()}}


def exact_script(obj: dict[str, Any], factor: int = EXACT_FACTOR) -> dict[str, Any]:
    """The script in the exact ramp at `factor` times its clock and PRESCALE: every clock count (the commands' edges,
    until, the input filter) `factor` times larger."""
    out = {**obj, "ramp": "exact", "fclk": obj["fclk"] * factor, "prescale": obj.get("prescale", 1) * factor}
    out["commands"] = [dict(cmd, at=cmd["at"] * factor) for cmd in obj["commands"]]
    if obj.get("until") is not None:
        out["until"] = obj["until"] * factor
    if "inputs" in obj:
        out["inputs"] = dict(obj["inputs"], filter=obj["inputs"].get("filter", 0) * factor)
    return out


# ---------------------------------------------------------------------------------------------------------------
# Checksums
# ---------------------------------------------------------------------------------------------------------------


def move_checksum(args: dict[str, Any], ramp: int) -> str:
    """The `stepramp model --summary` checksum of a move (its edges), or "error: ..." when it is not planned."""
    try:
        plan = plan_move(**args, ramp=ramp)
    except ValueError as exc:
        return f"error: {exc}"
    return str(summarise_model(args, plan)["checksum"])


def stop_edges(args: dict[str, Any], ramp: int) -> list[tuple[str, int]]:
    """The stops stops_checksum runs for a move: soft and hard at edges 0, 1, 2 and tenths of its last edge."""
    plan = plan_move(**args, ramp=ramp)
    last = last_edge(plan) or 0
    requests = sorted({0, 1, 2, *(last * k // 10 for k in range(1, 11))})
    return [(kind, e) for e in requests for kind in (SOFT, HARD)]


def stops_checksum(args: dict[str, Any], ramp: int) -> str:
    """One checksum over the edges of every stop of stop_edges (the lazy model: iter_edges with a stop)."""
    try:
        plan = plan_move(**args, ramp=ramp)
    except ValueError as exc:
        return f"error: {exc}"
    parts = [edge_checksum(list(iter_edges(plan, stop=stop))) for stop in stop_edges(args, ramp)]
    return sha(parts)


def script_checksum(obj: dict[str, Any]) -> str:
    """The checksum of a script's planned result (single or multi-axis), or of the error that refuses it."""
    from stepramp.board.multi_script import is_multi, plan_multi_script
    from stepramp.board.script import load_script, plan_script

    try:
        result: Any = plan_multi_script(obj) if is_multi(obj) else plan_script(load_script(obj))
    except ValueError as exc:
        return sha({"error": str(exc)})
    return sha(result)


def in_ramp(obj: dict[str, Any], ramp: int) -> dict[str, Any]:
    return obj if ramp == RAMP_AVR446 else exact_script(obj)


def _short(values: Iterable[str]) -> list[str]:
    return [v if v.startswith("error") else v.removeprefix("sha256:")[:SHORT] for v in values]


def compute(
    moves: Iterable[int] | None = None, scripts: Iterable[int] | None = None, progress: Callable[[str], None] = print
) -> dict[str, Any]:
    """The golden checksums: every group, with the random moves and scripts limited to the given indices (None: all).
    The random groups hold, per ramp, a list of short checksums (None where an index was left out)."""
    from stepramp.sim.profiles import EXACT_PROFILES, PROFILES

    move_args = random_moves()
    script_objs = random_scripts()
    move_idx = range(len(move_args)) if moves is None else sorted(moves)
    script_idx = range(len(script_objs)) if scripts is None else sorted(scripts)
    out: dict[str, Any] = {
        "seed": SEED,
        "inputs": {
            "moves": [sha(a)[:SHORT] for a in move_args],
            "scripts": [sha(s)[:SHORT] for s in script_objs],
            "profiles": sha([[p.name, p.args()] for p in PROFILES]),
            "exact_profiles": sha([[p.name, p.args()] for p in EXACT_PROFILES]),
            "named_scripts": sha(named_scripts()),
        },
    }
    for ramp in (RAMP_AVR446, RAMP_EXACT):
        name = RAMP_NAMES[ramp]
        progress(f"{name}: profiles and stops")
        profiles = PROFILES if ramp == RAMP_AVR446 else EXACT_PROFILES
        group: dict[str, Any] = {
            "profiles": {p.name: move_checksum(p.args(), ramp) for p in profiles},
            "stops": {p.name: stops_checksum(p.args(), ramp) for p in profiles},
        }
        progress(f"{name}: named scripts")
        group["named_scripts"] = {n: script_checksum(in_ramp(obj, ramp)) for n, obj in named_scripts().items()}
        progress(f"{name}: {len(move_idx)} random moves")
        moves_out: list[str | None] = [None] * len(move_args)
        for i in move_idx:
            moves_out[i] = _short([move_checksum(move_args[i], ramp)])[0]
        progress(f"{name}: {len(script_idx)} random scripts")
        scripts_out: list[str | None] = [None] * len(script_objs)
        for i in script_idx:
            scripts_out[i] = script_checksum(in_ramp(script_objs[i], ramp))[:SHORT]
        group["moves"] = moves_out
        group["scripts"] = scripts_out
        out[name] = group
    return out


def differences(want: Any, got: Any, where: str = "") -> list[str]:
    """Where two checksum trees differ (None in `got`: not computed, not compared)."""
    if isinstance(want, dict) and isinstance(got, dict):
        out = [f"{where}/{k}: missing" for k in want.keys() - got.keys()]
        out += [f"{where}/{k}: new" for k in got.keys() - want.keys()]
        for key in want.keys() & got.keys():
            out += differences(want[key], got[key], f"{where}/{key}")
        return sorted(out)
    if isinstance(want, list) and isinstance(got, list) and len(want) == len(got):
        return [d for i, (w, g) in enumerate(zip(want, got, strict=True)) for d in differences(w, g, f"{where}[{i}]")]
    if got is None or want == got:
        return []
    return [f"{where}: {want!r} != {got!r}"]
