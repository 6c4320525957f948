# SPDX-License-Identifier: MIT
"""Command scripts for the multi-axis top (issue 16; docs/algorithm.md, "Machine inputs", "In scripts").

A multi-axis script is a single-axis script (stepramp.board.script) with `"axes": N` (1 .. 8) and an `"axis"` on
any command (0 when left out). Each axis is planned on its own by the single-axis planner, from its own commands;
an `"input"` of `"estop"` is the top's one ESTOP pin and goes to every axis (its `"axis"`, if any, is ignored), the
other inputs are the axis's own pins. Three ops take a group `"axes": [...]` instead (docs/algorithm.md, "The
script contract", multi-axis scripts; the axes' planners, AxisPlanner, run side by side for them):

* `{"op": "move", "axes", "steps": [...], "accel", "decel", "speed"}`: a coordinated move (plan_coordinated), every
  axis's writes, then one SYNC_START; the axes' engines start on the latest of their start gates; refused on every
  axis when one refuses;
* `{"op": "soft_stop", "axes"}`: the coordinated stop on the line of the last coordinated move
  (plan_coordinated_stop), one CHANGE per moving axis at its own edge (`at`, then PREP_CLOCKS apart), or, where it
  falls back (LineStop.fallback), the SYNC_SOFT_STOP below;
* `{"op": "sync_soft_stop", "axes"}`: each axis plans its own soft_stop at `at`, and the testbench writes one
  SYNC_SOFT_STOP of the axes that are moving then (an idle axis has nothing to stop) instead of their CTRL writes.

The actions of all axes share one bus: two of them must leave each other the PREP_CLOCKS that prepare a command
(COMMIT_GAP when the later one writes nothing but its commit; a SYNC_START's writes take PREP_CLOCKS per axis), else
the script is listed as `conflicts` and not played. The testbench plays every action in axis i's register window
(byte offset 0x100 * (i + 1)) on stepramp_multi_plb or stepramp_multi_axil, whose axes each take a CTRL write (or a
SYNC_START, SYNC_SOFT_STOP) at the edge the top samples it, as the single-axis core does.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace
from typing import Any, cast

from stepramp.board.coord import CoordInfo, CoordStop, plan_coordinated_info, plan_coordinated_stop
from stepramp.board.multi import MAX_AXES, REG_SYNC_SOFT_STOP, REG_SYNC_START, axis_base, mask_of
from stepramp.board.plan import RAMP_AVR446, Plan
from stepramp.board.regmap import REGISTERS_BY_NAME, offset
from stepramp.board.script import (
    COMMIT_GAP,
    PREP_CLOCKS,
    AxisPlanner,
    Script,
    ScriptResult,
    SuppliedChange,
    SuppliedMove,
    load_script,
)

#: CTRL's offset in an axis window, and its SOFT_STOP bit (what an axis's soft_stop action writes).
CTRL_OFFSET = offset("CTRL")
SOFT_STOP_BIT = 1 << REGISTERS_BY_NAME["CTRL"].field("SOFT_STOP").lsb


@dataclass(frozen=True)
class LineStop:
    """What a script's coordinated soft stop (`soft_stop` with `axes`) did: at its edge `at`, on the line (`stop`:
    plan_coordinated_stop's CoordStop, `commits`: each axis's CHANGE edge W_i, by axis) or, with `fallback` (the
    reason), one SYNC_SOFT_STOP of the listed moving axes."""

    at: int
    axes: tuple[int, ...]
    stop: CoordStop | None = None
    commits: dict[int, int] = field(default_factory=dict)
    fallback: str | None = None


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
    #: The SYNC_SOFT_STOP writes, (at, axis mask), of the script's `sync_soft_stop` commands (and of the `soft_stop`
    #: commands with `axes` that fall back); the axes' own actions for them (`synced`: (axis, command index)) are
    #: not played.
    sync_stops: list[tuple[int, int]] = field(default_factory=list)
    synced: frozenset[tuple[int, int]] = frozenset()
    #: The SYNC_START writes, (at, axis mask, prep clocks), of the coordinated moves (`move` with `axes`); the axes'
    #: own START actions for them (`started`) are played as that one write, after all their writes.
    sync_starts: list[tuple[int, int, int]] = field(default_factory=list)
    started: frozenset[tuple[int, int]] = frozenset()
    #: The coordinated soft stops (`soft_stop` with `axes`), in script order.
    line_stops: list[LineStop] = field(default_factory=list)

    @property
    def unsure(self) -> list[str]:
        return [f"axis {i}: {u}" for i, r in enumerate(self.results) for u in r.unsure]


def is_multi(obj: object) -> bool:
    """A script for the multi-axis top (it gives "axes")."""
    return isinstance(obj, dict) and "axes" in obj


#: The ops that take "axes" (a group of axes, no "axis"): a coordinated move, the coordinated stop on the line, the
#: one-clock SYNC_SOFT_STOP.
GROUP_OPS = ("move", "soft_stop", "sync_soft_stop")
_MOVE_FIELDS = ("steps", "accel", "decel", "speed")


@dataclass(frozen=True)
class _Group:
    """A command with "axes": its index n, at, op, the axes (in the command's order), each one's command index in its
    own script, the coordinated move's step counts and path values, and each axis's command index at the group's
    edge (how far to plan each axis before it)."""

    n: int
    at: int
    op: str
    axes: tuple[int, ...]
    index: dict[int, int]
    steps: tuple[int, ...] = ()
    values: tuple[float, float, float] = (0.0, 0.0, 0.0)
    before: tuple[int, ...] = ()


def _group_axes(n: int, cmd: dict[str, Any], axes: int) -> list[int]:
    chosen = cmd["axes"]
    if cmd.get("op") not in GROUP_OPS or "axis" in cmd:
        raise ValueError(f'command {n}: only {", ".join(GROUP_OPS)} take "axes" (and no "axis" with it)')
    if (
        not isinstance(chosen, list)
        or not chosen
        or any(isinstance(a, bool) or not isinstance(a, int) or not 0 <= a < axes for a in chosen)
        or len(set(chosen)) != len(chosen)
    ):
        raise ValueError(f"command {n}: axes must be a list of distinct axes in 0 .. {axes - 1}, got {chosen!r}")
    allowed = {"at", "op", "axes", *(_MOVE_FIELDS if cmd["op"] == "move" else ())}
    unknown = sorted(set(cmd) - allowed)
    if unknown:
        raise ValueError(f"command {n} ({cmd['op']} with axes): unknown field(s) {', '.join(unknown)}")
    return list(chosen)


def _axis_scripts(obj: dict[str, Any]) -> tuple[list[dict[str, Any]], list[_Group]]:
    """Each axis's single-axis script, and the commands with "axes" (_Group). A coordinated move's axis gets a move
    of its own step count with the path's values times its ratio L_i / L_lead (the values then in force on it: its
    plan is supplied, plan_coordinated's); a coordinated or SYNC soft stop's axis a soft_stop at `at`."""
    axes = obj.get("axes")
    if isinstance(axes, bool) or not isinstance(axes, int) or not 1 <= axes <= MAX_AXES:
        raise ValueError(f"script: axes must be an integer in 1 .. {MAX_AXES}, got {axes!r}")
    commands = obj.get("commands")
    if not isinstance(commands, list):
        raise ValueError("script: commands must be a list")
    per_axis: list[list[dict[str, Any]]] = [[] for _ in range(axes)]
    groups: list[_Group] = []
    for n, cmd in enumerate(commands):
        if not isinstance(cmd, dict):
            raise ValueError(f"command {n}: must be an object")
        if "axes" in cmd:
            chosen = _group_axes(n, cmd, axes)
            before = tuple(len(c) for c in per_axis)
            if cmd["op"] != "move":
                index = {}
                for axis in chosen:
                    index[axis] = len(per_axis[axis])
                    per_axis[axis].append({"at": cmd.get("at"), "op": "soft_stop"})
                groups.append(_Group(n, cast(int, cmd.get("at")), cmd["op"], tuple(chosen), index, before=before))
                continue
            missing = [k for k in _MOVE_FIELDS if k not in cmd]
            if missing:
                raise ValueError(f"command {n} (move with axes): missing field(s) {', '.join(missing)}")
            steps = cmd["steps"]
            if (
                not isinstance(steps, list)
                or len(steps) != len(chosen)
                or any(isinstance(k, bool) or not isinstance(k, int) for k in steps)
            ):
                raise ValueError(f"command {n}: steps must be a list of integers, one per axis of axes, got {steps!r}")
            values = []
            for name in ("accel", "decel", "speed"):
                value = cmd[name]
                if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value < math.inf:
                    raise ValueError(f"command {n}: {name} must be a finite number > 0, got {value!r}")
                values.append(float(value))
            lengths = [abs(k) - 1 for k in steps]
            lead = max(lengths)
            index = {}
            for axis, k, length in zip(chosen, steps, lengths, strict=True):
                ratio = length / lead if length >= 1 and lead >= 1 else 1.0
                index[axis] = len(per_axis[axis])
                per_axis[axis].append(
                    {"at": cmd.get("at"), "op": "move", "steps": k}
                    | {name: v * ratio for name, v in zip(("accel", "decel", "speed"), values, strict=True)}
                )
            groups.append(
                _Group(n, cast(int, cmd.get("at")), "move", tuple(chosen), index, tuple(steps), tuple(values), before)
            )
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
    return [{**base, "commands": c} for c in per_axis], groups


@dataclass
class _Started:
    """A coordinated move that started: its group, plans and CoordInfo, and each started axis's motion."""

    group: _Group
    plans: list[Plan]
    info: CoordInfo
    motions: dict[int, object]


class _Lockstep:
    """The axes' planners (AxisPlanner) side by side: each group of axes is planned when the script reaches it, every
    axis planned up to it first."""

    def __init__(self, scripts: list[Script], groups: list[_Group]) -> None:
        self.scripts = scripts
        self.runs = [AxisPlanner(s) for s in scripts]
        self.syncs: list[tuple[int, list[tuple[int, int]]]] = []
        self.sync_starts: list[tuple[int, int, int]] = []
        self.started: set[tuple[int, int]] = set()
        self.line_stops: list[LineStop] = []
        self.moves: list[_Started] = []
        for g in groups:
            for axis, run in enumerate(self.runs):
                run.advance(g.before[axis])
            if g.op == "move":
                self.move(g)
            elif g.op == "soft_stop":
                self.line_stop(g)
            else:
                self.sync(g)

    def results(self) -> list[ScriptResult]:
        return [run.finish() for run in self.runs]

    def sync(self, g: _Group) -> None:
        """Each axis's own soft_stop at `at`; played as one SYNC_SOFT_STOP of the moving ones."""
        for axis in g.axes:
            self.runs[axis].advance(g.index[axis] + 1)
        self.syncs.append((g.at, [(axis, g.index[axis]) for axis in g.axes]))

    def move(self, g: _Group) -> None:
        """A coordinated move: plan_coordinated's plans; every axis with steps proposes its START, and when all take
        it they start on the latest of their start edges (one SYNC_START); else every axis refuses it."""
        s = self.scripts[0]
        reasons: list[str] = []
        plans: list[Plan] = []
        try:
            if s.ramp != RAMP_AVR446:
                raise ValueError("coordinated moves are planned for the AVR446 ramp")
            plans, info = plan_coordinated_info(list(g.steps), *g.values, s.spr, s.fclk, s.prescale)
        except ValueError as why:
            reasons.append(str(why))
        moving = [(k, axis) for k, axis in enumerate(g.axes) if g.steps[k] != 0]
        props = {}
        prep = PREP_CLOCKS * len(moving)
        if not reasons and g.at < prep - PREP_CLOCKS:
            reasons.append(f"its writes take {prep} clocks before it: at must be at least {prep - PREP_CLOCKS}")
        if not reasons:
            for k, axis in moving:
                try:
                    props[axis] = self.runs[axis].propose(g.index[axis], SuppliedMove(plans[k], info.infos[k], prep))
                except ValueError as why:
                    reasons.append(f"axis {axis}: {why}")
        if reasons:
            for axis in g.axes:
                self.runs[axis].reject(g.index[axis], "coordinated move: " + "; ".join(reasons))
            return
        edge = max(cast(Any, p.motion).start_edge for p in props.values())
        for axis, prop in props.items():
            self.runs[axis].start(g.index[axis], prop, edge)
            self.started.add((axis, g.index[axis]))
        for axis in g.axes:  # (the axes of 0 steps: nothing)
            self.runs[axis].advance(g.index[axis] + 1)
        self.sync_starts.append((g.at, mask_of(a for _, a in moving), PREP_CLOCKS * len(moving)))
        self.moves.append(_Started(g, plans, info, {axis: p.motion for axis, p in props.items()}))

    def line_stop(self, g: _Group) -> None:
        """The coordinated stop on the line (docs/algorithm.md, "Multi-axis scripts"): each moving axis of the running
        coordinated move takes its CHANGE from plan_coordinated_stop, committed at its own edge W_i (at, then
        PREP_CLOCKS apart in axis order); or, with the reason, the SYNC_SOFT_STOP of the listed axes."""
        at = g.at
        for run in self.runs:
            run.settle(at)
        why, stop, commits = self.on_the_line(g)
        if why is not None:
            self.line_stops.append(LineStop(at, g.axes, fallback=why))
            self.sync(g)
            return
        assert stop is not None
        move = self.moves[-1]
        changes = {}
        for k, axis in enumerate(move.group.axes):
            a = stop.axes[k]
            if a.change is not None:
                changes[axis] = SuppliedChange(commits[axis], a.pulse, a.change, a.target, move.motions[axis])
        for axis in g.axes:
            self.runs[axis].supply(g.index[axis], changes.get(axis, SuppliedChange(at, 0, None, 0, None)))
        self.line_stops.append(LineStop(at, g.axes, stop, {a: c.at for a, c in changes.items()}))

    def on_the_line(self, g: _Group) -> tuple[str | None, CoordStop | None, dict[int, int]]:
        """(the reason to fall back or None, the CoordStop, each axis's commit edge)."""
        at = g.at
        if not self.moves:
            return "no coordinated move was started", None, {}
        move = self.moves[-1]
        edges: list[list[int]] = []
        moving: list[int] = []
        for k, axis in enumerate(move.group.axes):
            if axis not in move.motions:
                edges.append([])
                continue
            got = self.runs[axis].untouched_edges(move.motions[axis])
            if got is None:
                if move.plans[k].steps < 2:
                    edges.append([])
                    continue
                return f"axis {axis} does not run the coordinated move at {move.group.at} as started", None, {}
            edges.append(got)
            if move.plans[k].steps >= 2 and got[-1] > at:
                moving.append(axis)
        missing = sorted(set(moving) - set(g.axes))
        if missing:
            return f"axes {missing} of the coordinated move at {move.group.at} move and are not listed", None, {}
        commits = {axis: at + PREP_CLOCKS * rank for rank, axis in enumerate(sorted(moving))}
        s = self.scripts[0]
        stop = plan_coordinated_stop(
            move.plans,
            move.info,
            edges,
            [commits.get(axis, at) for axis in move.group.axes],
            *move.group.values,
            s.spr,
            s.fclk,
            s.prescale,
        )
        if stop.fallback is not None:
            return stop.fallback, None, {}
        for k, axis in enumerate(move.group.axes):
            if stop.axes[k].change is not None:
                refusal = self.runs[axis].window_refusal(commits[axis], True)
                if refusal is not None:
                    return f"axis {axis}'s take-over at {commits[axis]}: {refusal}", None, {}
        return None, stop, commits


def _plan(subs: list[dict[str, Any]], groups: list[_Group]) -> _Lockstep:
    return _Lockstep([load_script(sub) for sub in subs], groups)


def plan_multi_script(obj: dict[str, Any]) -> MultiResult:
    """Each axis's plan (stepramp.script.AxisPlanner, side by side with the others for the commands with "axes"), all
    up to one `until` (the script's, else the latest axis's), and the bus conflicts between the axes' actions.
    ValueError with the reason for a malformed script."""
    subs, groups = _axis_scripts(obj)
    run = _plan(subs, groups)
    results = run.results()
    until = max(r.until for r in results)
    if any(r.until != until for r in results):
        subs = [{**sub, "until": until} for sub in subs]
        run = _plan(subs, groups)
        results = run.results()
    estop = [(c["at"], c["level"]) for c in subs[0]["commands"] if c.get("op") == "input" and c["name"] == "estop"]
    # A SYNC_SOFT_STOP: the axes whose planner commits a SOFT_STOP then (the moving ones) in one write.
    soft = SOFT_STOP_BIT
    sync_stops: list[tuple[int, int]] = []
    synced: set[tuple[int, int]] = set()
    for at, members in run.syncs:
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
    planned = MultiResult(
        len(subs),
        results,
        until,
        estop,
        [],
        sync_stops,
        frozenset(synced),
        run.sync_starts,
        frozenset(run.started),
        run.line_stops,
    )
    played = sorted(played_actions(planned), key=lambda a: a["at"])
    conflicts = []
    for a, b in itertools.pairwise(played):
        gap = b.get("prep", PREP_CLOCKS) if b["writes"] else COMMIT_GAP
        if _owner(a) != _owner(b) and b["at"] - a["at"] < gap:
            conflicts.append(f"{_name(b)}'s action at {b['at']} is {b['at'] - a['at']} clocks after {_name(a)}'s")
    return replace(planned, conflicts=conflicts)


def _owner(action: dict[str, Any]) -> tuple[int, int]:
    """Whose action (an axis's, or a group write's: SYNC_START, SYNC_SOFT_STOP at its edge)."""
    return (action["axis"], -1) if action["axis"] >= 0 else (-1, action["at"])


def _name(action: dict[str, Any]) -> str:
    return f"axis {action['axis']}" if action["axis"] >= 0 else f"the group write at {action['at']}"


def played_actions(planned: MultiResult) -> list[dict[str, Any]]:
    """What the testbench plays, in time order: each axis's actions ({"at", "axis", "writes" at the top's byte
    offsets, "commit": the CTRL address in its window, "ctrl": the byte written there}), with a SYNC soft stop as one
    write of its mask to SYNC_SOFT_STOP ("axis" -1) instead of its axes' CTRL writes, and a coordinated move as
    one write of its mask to SYNC_START ("axis" -1, "prep": the clocks before it that its axes' writes take, in axis
    order) instead of their STARTs."""
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
        if (axis, a.command) not in planned.synced and (axis, a.command) not in planned.started
    ]
    out += [
        {"at": at, "axis": -1, "writes": [], "commit": REG_SYNC_SOFT_STOP, "ctrl": mask}
        for at, mask in planned.sync_stops
    ]
    for at, mask, prep in planned.sync_starts:
        writes = [
            list(w)
            for axis, r in enumerate(planned.results)
            for a in r.actions
            if (axis, a.command) in planned.started and a.at == at and mask >> axis & 1
            for w in action_writes(axis, a.writes)
        ]
        out.append({"at": at, "axis": -1, "writes": writes, "commit": REG_SYNC_START, "ctrl": mask, "prep": prep})
    return sorted(out, key=lambda a: a["at"])


def action_writes(axis: int, writes: tuple[tuple[int, int], ...]) -> list[tuple[int, int]]:
    """An action's register writes at their byte offsets in the multi-axis top."""
    return [(axis_base(axis) + addr, value) for addr, value in writes]


__all__ = [
    "GROUP_OPS",
    "LineStop",
    "MultiResult",
    "action_writes",
    "is_multi",
    "plan_multi_script",
    "played_actions",
]
