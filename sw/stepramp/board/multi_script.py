# SPDX-License-Identifier: MIT
"""Command scripts for the multi-axis top (issue 16; docs/algorithm.md, "Machine inputs", "In scripts").

A multi-axis script is a single-axis script (stepramp.board.script) with `"axes": N` (1 .. 8) and an `"axis"` on
any command (0 when left out). Each axis is planned on its own by the single-axis planner, from its own commands;
an `"input"` of `"estop"` is the top's one ESTOP pin and goes to every axis (its `"axis"`, if any, is ignored), the
other inputs are the axis's own pins. `{"op": "soft_stop", "axes": [...]}` soft-stops the listed axes on one clock:
each axis plans it as its own soft_stop at `at`, and the testbench writes one SYNC_SOFT_STOP of the axes that are
moving then (an idle axis has nothing to stop) instead of their CTRL writes. The actions of all axes share one
bus: two of them must leave each other the PREP_CLOCKS that prepare a command (COMMIT_GAP when the later one writes
nothing but its commit), else the script is listed as `conflicts` and not played. The testbench plays every action
in axis i's register window (byte offset 0x100 * (i + 1)) on stepramp_multi_plb or stepramp_multi_axil, whose axes
each take a CTRL write (or a SYNC_SOFT_STOP) at the edge the top samples it, as the single-axis core does.
"""

from __future__ import annotations

import itertools
import random
from dataclasses import dataclass, field
from typing import Any

from stepramp.board.multi import MAX_AXES, REG_SYNC_SOFT_STOP, axis_base
from stepramp.board.regmap import REGISTERS_BY_NAME, offset
from stepramp.board.script import (
    COMMIT_GAP,
    PREP_CLOCKS,
    ScriptResult,
    load_script,
    plan_script,
    random_script,
)

#: CTRL's offset in an axis window, and its SOFT_STOP bit (what an axis's soft_stop action writes).
CTRL_OFFSET = offset("CTRL")
SOFT_STOP_BIT = 1 << REGISTERS_BY_NAME["CTRL"].field("SOFT_STOP").lsb


@dataclass(frozen=True)
class MultiResult:
    """The planned run of each axis (its actions' writes at the axis's own offsets), the common last clock, the
    ESTOP pin's changes (after edge a, level), and the bus conflicts between axes (a script with any is not
    played)."""

    axes: int
    results: list[ScriptResult]
    until: int
    estop: list[tuple[int, int]] = field(default_factory=list)
    conflicts: list[str] = field(default_factory=list)
    #: The SYNC_SOFT_STOP writes, (at, axis mask), of the script's `soft_stop` commands with `axes`; the axes'
    #: own actions for them (`synced`: (axis, command index)) are not played.
    sync_stops: list[tuple[int, int]] = field(default_factory=list)
    synced: frozenset[tuple[int, int]] = frozenset()

    @property
    def unsure(self) -> list[str]:
        return [f"axis {i}: {u}" for i, r in enumerate(self.results) for u in r.unsure]


def is_multi(obj: object) -> bool:
    """A script for the multi-axis top (it gives "axes")."""
    return isinstance(obj, dict) and "axes" in obj


def _axis_scripts(obj: dict[str, Any]) -> tuple[list[dict[str, Any]], list[tuple[int, list[tuple[int, int]]]]]:
    """Each axis's single-axis script, and the coordinated soft stops: (at, [(axis, its command index)])."""
    axes = obj.get("axes")
    if isinstance(axes, bool) or not isinstance(axes, int) or not 1 <= axes <= MAX_AXES:
        raise ValueError(f"script: axes must be an integer in 1 .. {MAX_AXES}, got {axes!r}")
    commands = obj.get("commands")
    if not isinstance(commands, list):
        raise ValueError("script: commands must be a list")
    per_axis: list[list[dict[str, Any]]] = [[] for _ in range(axes)]
    syncs: list[tuple[int, list[tuple[int, int]]]] = []
    for n, cmd in enumerate(commands):
        if not isinstance(cmd, dict):
            raise ValueError(f"command {n}: must be an object")
        if "axes" in cmd:
            chosen = cmd["axes"]
            if cmd.get("op") != "soft_stop" or "axis" in cmd:
                raise ValueError(f'command {n}: only a soft_stop takes "axes" (and no "axis" with it)')
            if (
                not isinstance(chosen, list)
                or not chosen
                or any(isinstance(a, bool) or not isinstance(a, int) or not 0 <= a < axes for a in chosen)
                or len(set(chosen)) != len(chosen)
            ):
                raise ValueError(
                    f"command {n}: axes must be a list of distinct axes in 0 .. {axes - 1}, got {chosen!r}"
                )
            members = []
            for axis in sorted(chosen):
                members.append((axis, len(per_axis[axis])))
                per_axis[axis].append({k: v for k, v in cmd.items() if k != "axes"})
            syncs.append((cmd.get("at"), members))
            continue
        if cmd.get("op") == "input" and cmd.get("name") == "estop":
            for axis_cmds in per_axis:
                axis_cmds.append({k: v for k, v in cmd.items() if k != "axis"})
            continue
        axis = cmd.get("axis", 0)
        if isinstance(axis, bool) or not isinstance(axis, int) or not 0 <= axis < axes:
            raise ValueError(f"command {n}: axis must be an integer in 0 .. {axes - 1}, got {axis!r}")
        per_axis[axis].append({k: v for k, v in cmd.items() if k != "axis"})
    base = {k: v for k, v in obj.items() if k not in ("axes", "commands")}
    return [{**base, "commands": c} for c in per_axis], syncs


def plan_multi_script(obj: dict[str, Any]) -> MultiResult:
    """Each axis's plan (stepramp.board.script.plan_script), all up to one `until` (the script's, else the latest
    axis's), and the bus conflicts between the axes' actions. ValueError with the reason for a malformed script."""
    subs, syncs = _axis_scripts(obj)
    results = [plan_script(load_script(s)) for s in subs]
    until = max(r.until for r in results)
    if any(r.until != until for r in results):
        results = [plan_script(load_script({**s, "until": until})) for s in subs]
    estop = [(c["at"], c["level"]) for c in subs[0]["commands"] if c.get("op") == "input" and c["name"] == "estop"]
    # A coordinated soft stop: the axes whose planner commits a SOFT_STOP then (the moving ones) in one write.
    soft = SOFT_STOP_BIT
    sync_stops: list[tuple[int, int]] = []
    synced: set[tuple[int, int]] = set()
    for at, members in syncs:
        mask = 0
        for axis, index in members:
            mine = [a for a in results[axis].actions if a.command == index]
            if any(a.writes or a.ctrl != soft or a.at != at for a in mine):
                raise ValueError(f"axis {axis}: its soft_stop at {at} is not a plain SOFT_STOP: {mine}")
            if mine:
                mask |= 1 << axis
                synced.add((axis, index))
        if mask:
            sync_stops.append((at, mask))
    actions = sorted(
        [(a.at, i, bool(a.writes)) for i, r in enumerate(results) for a in r.actions if (i, a.command) not in synced]
        + [(at, -1, False) for at, _ in sync_stops]
    )
    conflicts = []
    for (at_a, axis_a, _), (at_b, axis_b, writes_b) in itertools.pairwise(actions):
        gap = PREP_CLOCKS if writes_b else COMMIT_GAP
        if axis_a != axis_b and at_b - at_a < gap:
            conflicts.append(f"axis {axis_b}'s action at {at_b} is {at_b - at_a} clocks after axis {axis_a}'s")
    return MultiResult(len(subs), results, until, estop, conflicts, sync_stops, frozenset(synced))


def played_actions(planned: MultiResult) -> list[dict[str, Any]]:
    """What the testbench plays, in time order: each axis's actions ({"at", "axis", "writes" at the top's byte
    offsets, "commit": the CTRL address in its window, "ctrl": the byte written there}), with a coordinated soft
    stop as one write of its mask to SYNC_SOFT_STOP ("axis" -1) instead of its axes' CTRL writes."""
    out: list[dict[str, Any]] = [
        {
            "at": a.at,
            "axis": axis,
            "writes": [list(w) for w in action_writes(axis, a.writes)],
            "commit": axis_base(axis) + CTRL_OFFSET,
            "ctrl": a.ctrl,
        }
        for axis, r in enumerate(planned.results)
        for a in r.actions
        if (axis, a.command) not in planned.synced
    ]
    out += [
        {"at": at, "axis": -1, "writes": [], "commit": REG_SYNC_SOFT_STOP, "ctrl": mask}
        for at, mask in planned.sync_stops
    ]
    return sorted(out, key=lambda a: a["at"])


def action_writes(axis: int, writes: tuple[tuple[int, int], ...]) -> list[tuple[int, int]]:
    """An action's register writes at their byte offsets in the multi-axis top."""
    return [(axis_base(axis) + addr, value) for addr, value in writes]


def random_multi_script(rng: random.Random, axes: int = 3, tries: int = 20) -> dict[str, Any]:
    """A random multi-axis script: a short random single-axis script per axis (stepramp.board.script.random_script,
    three commands each), the axes' commands staggered by up to 6,000 clocks, and ESTOP moved to the top's one pin;
    the machine inputs' settings are the first axis's. Drawn again (at most `tries` times) while the axes' actions
    conflict on the bus."""
    for _ in range(tries - 1):
        out = _random_multi(rng, axes)
        if not plan_multi_script(out).conflicts:
            return out
    return _random_multi(rng, axes)


def _random_multi(rng: random.Random, axes: int) -> dict[str, Any]:
    commands: list[dict[str, Any]] = []
    inputs: dict[str, Any] | None = None
    until = 0
    for axis in range(axes):
        one = random_script(rng, n_commands=3)
        shift = rng.randrange(0, 6_000)
        for cmd in one["commands"]:
            if cmd.get("op") == "input" and cmd["name"] == "estop" and axis:
                continue  # (one ESTOP pin: the first axis's script drives it)
            commands.append({**cmd, "at": cmd["at"] + shift, "axis": axis})
        until = max(until, one["until"] + shift)
        if inputs is None and "inputs" in one:
            inputs = one["inputs"]
    out: dict[str, Any] = {
        "fclk": 1e6,
        "spr": 200.0,
        "prescale": 1,
        "axes": axes,
        "commands": sorted(commands, key=lambda c: c["at"]),
        "until": until,
    }
    if inputs is not None:
        out["inputs"] = inputs
    return out


_FAST: dict[str, float] = {"accel": 18_000.0, "decel": 18_000.0}
"""300 rad/s (105 clocks a step at 1 MHz and 200 steps/rev), ramps of 80 steps: the named scripts' pace."""

#: The issues' multi-axis cases as scripts (tb/test_script_rtl.py plays them on both multi-axis tops).
NAMED_MULTI_SCRIPTS: dict[str, dict[str, Any]] = {
    # three axes: a move, a jog down that LIMIT_NEG of axis 1 stops (soft), a move back; ESTOP stops all three
    # (no STEP edge of any axis after F + 2); each axis clears its own fault; axis 1 jogs away from its active
    # limit, axis 0 moves back
    "three_axes_limit_and_estop": {
        "fclk": 1e6,
        "spr": 200.0,
        "prescale": 1,
        "axes": 3,
        "inputs": {"filter": 20},
        "until": 60_000,
        "commands": [
            {"at": 0, "op": "move", "axis": 0, "steps": 400, "speed": 300.0, **_FAST},
            {"at": 400, "op": "jog", "axis": 1, "speed": -300.0, **_FAST},
            {"at": 800, "op": "move", "axis": 2, "steps": -300, "speed": 300.0, **_FAST},
            {"at": 20_000, "op": "input", "axis": 1, "name": "limit_neg", "level": 1},
            {"at": 30_000, "op": "input", "name": "estop", "level": 1},
            {"at": 32_000, "op": "input", "name": "estop", "level": 0},
            {"at": 33_000, "op": "clear_fault", "axis": 0},
            {"at": 33_400, "op": "clear_fault", "axis": 1},
            {"at": 33_800, "op": "clear_fault", "axis": 2},
            {"at": 34_200, "op": "jog", "axis": 1, "speed": 300.0},
            {"at": 34_600, "op": "move", "axis": 0, "steps": -100, "speed": 300.0, **_FAST},
            {"at": 36_000, "op": "input", "axis": 1, "name": "limit_neg", "level": 0},
            {"at": 45_000, "op": "soft_stop", "axis": 1},
        ],
    },
    # three axes moving, two started together and one later; one SYNC_SOFT_STOP of all three while axis 0 is in
    # RUN, axis 1 in ACCEL and axis 2 idle (left out of the mask: nothing to stop), then a move of axis 2 alone
    "coordinated_soft_stop": {
        "fclk": 1e6,
        "spr": 200.0,
        "prescale": 1,
        "axes": 3,
        "until": 50_000,
        "commands": [
            {"at": 0, "op": "move", "axis": 0, "steps": 400, "speed": 300.0, **_FAST},
            {"at": 400, "op": "move", "axis": 1, "steps": -300, "speed": 300.0, "accel": 3_000.0, "decel": 9_000.0},
            {"at": 22_000, "op": "soft_stop", "axes": [0, 1, 2]},
            {"at": 24_000, "op": "move", "axis": 2, "steps": 60, "speed": 300.0, **_FAST},
        ],
    },
}


__all__ = [
    "NAMED_MULTI_SCRIPTS",
    "MultiResult",
    "action_writes",
    "is_multi",
    "plan_multi_script",
    "played_actions",
    "random_multi_script",
]
