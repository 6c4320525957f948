# SPDX-License-Identifier: MIT
"""The script planner (stepramp.board.script; docs/algorithm.md, "The take-over, the queue and the script contract"):
load errors, a single move and a single change against the engine model's own functions shifted by the START timing,
random scripts judged by physics (the ideal trapezoid and IdealSegment, the speed limit, the lead of a take-over, the
target reached, the pins' spacing and direction), the named scripts of the issue, and `stepramp model --script`.

The judge does not use the planner's model: it splits the edges into motions by itself (a START's first edge, or a
queued START a few clocks after the last pulse), describes each motion from the actions' registers and the commands'
values (the ideal trajectory from rest, then an IdealSegment from each CHANGE_AT pulse, with the speed there from the
previous ideal), and holds every pulse it can attribute to one ideal within the bound of a move. A move queued in the
running motion's direction is two CHANGEs with the queue's index: the judge holds the first to the running values and
a virtual rest floor(vb^2 / (2 d1)) steps past the running target, the second to that target's pulse, the queued
steps and the first's ideal speed there (what it can reach, at most vb). Random scripts print their seed
(STEPRAMP_SEED replays one); the queued moves without a stop have tests of their own (the named one, a short one,
one too late, stops before and after the second change).
"""

from __future__ import annotations

import bisect
import itertools
import json
import math
import os
import random
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import pytest

from stepramp.board.change import (
    Change,
    Segment,
    change_pulse,
    plan_change,
    speed_at_pulse,
    speed_at_segment_pulse,
)
from stepramp.board.driver import plan_writes, segment_writes
from stepramp.board.plan import plan_move, plan_move_info
from stepramp.board.regmap import ERROR_CODES, offset
from stepramp.board.script import (
    CHANGE,
    HARD_STOP,
    PREP_CLOCKS,
    QUEUE,
    SOFT_STOP,
    START,
    Action,
    ScriptResult,
    load_script,
    plan_script,
)
from stepramp.models import ideal
from stepramp.models.engine import (
    accumulate,
    change_edges,
    edges_with_stop,
    segment_edges,
    segment_stop_values,
    segment_values,
    soft_stop_pulse,
)
from stepramp.models.engine import edges as model_edges
from stepramp.sim.scripts import NAMED_SCALE, NAMED_SCRIPTS, random_script
from stepramp.tools.cli import main

SEED = int(os.environ.get("STEPRAMP_SEED", "20261201"))
BOUND_C0 = 0.008  # the bound of a move (sw/tests/test_model.py), in c0 of the slower ramp
BOUND_TICKS = 2.0
# A down head that ends within a step or two of its virtual rest (v^2 / (2 d) < 2 steps) is up to 0.013 c0 off its
# IdealSegment in plan_change itself (the decel recurrence's deficit near rest, only half put back): held to the bound
# sw/tests/test_change.py holds a soft stop in a down head to.
NEAR_REST_STEPS = 2.0
NEAR_REST_BOUND_C0 = 0.016
CARRY_TICKS = 1.0  # a segment starts with the accumulator's fraction left at pulse P (sw/tests/test_change.py)
QUEUED_GAP = 64  # clocks: no interval within a motion is shorter (MIN_INTERVAL_CLKS); a queued START is 5 or 7
BASE = {"fclk": 1e6, "spr": 200.0, "prescale": 1}
ALPHA = 2.0 * math.pi / BASE["spr"]
MOVE = {"accel": 2000.0, "decel": 2000.0, "speed": 100.0}


def script(*commands: dict[str, Any], until: int | None = None) -> dict[str, Any]:
    obj: dict[str, Any] = {**BASE, "commands": list(commands)}
    if until is not None:
        obj["until"] = until
    return obj


def run(obj: dict[str, Any]) -> ScriptResult:
    return plan_script(load_script(obj))


# ---------------------------------------------------------------------------------------------------------------
# (a) load errors
# ---------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("obj", "reason"),
    [
        ([], "must be an object"),
        ({"spr": 200, "commands": []}, "missing key 'fclk'"),
        ({**BASE, "commands": [], "speed": 3}, "unknown key"),
        ({**BASE, "commands": {}}, "commands must be a list"),
        ({**BASE, "prescale": 0, "commands": []}, "prescale"),
        ({**BASE, "prescale": 1.5, "commands": []}, "prescale"),
        ({**BASE, "fclk": -1, "commands": []}, "fclk"),
        ({**BASE, "commands": [{"at": 0, "op": "spin"}]}, "unknown op 'spin'"),
        ({**BASE, "commands": [{"op": "soft_stop"}]}, "'at' must be an integer"),
        ({**BASE, "commands": [{"at": 1.0, "op": "soft_stop"}]}, "'at' must be an integer"),
        ({**BASE, "commands": [{"at": True, "op": "soft_stop"}]}, "'at' must be an integer"),
        ({**BASE, "commands": [{"at": -3, "op": "soft_stop"}]}, "'at' must be >= 0"),
        ({**BASE, "commands": [{"at": 9, "op": "soft_stop"}, {"at": 8, "op": "hard_stop"}]}, "not in order"),
        ({**BASE, "commands": [{"at": 0, "op": "move", "steps": 10, "accel": 1, "decel": 1}]}, "missing field.*speed"),
        ({**BASE, "commands": [{"at": 0, "op": "move_to"}]}, "missing field.*position"),
        ({**BASE, "commands": [{"at": 0, "op": "move_to", "position": 1.5}]}, "position must be an integer"),
        ({**BASE, "commands": [{"at": 0, "op": "move", "steps": "9", **MOVE}]}, "steps must be an integer"),
        ({**BASE, "commands": [{"at": 0, "op": "jog", "speed": "fast"}]}, "speed must be a finite number"),
        ({**BASE, "commands": [{"at": 0, "op": "jog", "speed": math.inf}]}, "speed must be a finite number"),
        ({**BASE, "commands": [{"at": 0, "op": "set", "accel": -5}]}, "accel must be a finite number > 0"),
        ({**BASE, "commands": [{"at": 0, "op": "set", "speed": 0}]}, "speed must be a finite number > 0"),
        ({**BASE, "commands": [{"at": 0, "op": "set"}]}, "at least one of"),
        ({**BASE, "commands": [{"at": 0, "op": "soft_stop", "speed": 3}]}, "unknown field"),
        ({**BASE, "commands": [{"at": 0, "op": "jog", "speed": 3, "position": 1}]}, "unknown field"),
        ({**BASE, "commands": ["move"]}, "must be an object"),
        ({**BASE, "commands": [{"at": 10, "op": "soft_stop"}], "until": 5}, "after until"),
        ({**BASE, "commands": [], "until": -1}, "until"),
    ],
)
def test_malformed_scripts_raise_with_the_reason(obj: Any, reason: str) -> None:
    with pytest.raises(ValueError, match=reason):
        load_script(obj)


def test_a_valid_script_loads_with_defaults() -> None:
    got = load_script({"fclk": 1e6, "spr": 200, "commands": [{"at": 0, "op": "jog", "speed": -3}]})
    assert got.prescale == 1 and got.until is None
    assert got.commands[0].speed == -3.0 and got.commands[0].accel is None


def test_an_endless_jog_needs_until() -> None:
    jog = {"at": 0, "op": "jog", "speed": 50.0, "accel": 2000.0, "decel": 2000.0}
    with pytest.raises(ValueError, match="endless jog"):
        run(script(jog))
    got = run(script(jog, until=100_000))
    assert got.until == 100_000 and got.edges[-1] <= 100_000 and len(got.edges) > 50


# ---------------------------------------------------------------------------------------------------------------
# (b), (c): one move, one change, against the engine model's functions
# ---------------------------------------------------------------------------------------------------------------


def test_a_single_move_is_the_plan_after_the_start_timing() -> None:
    """START written at W: the start gate samples the request at W + 1 and, with no DIR change and no pulse before,
    lets it through at once (start_edge s = W + 1); the engine's edge 0 is s + 1, pulse 0 is high after its edge 2
    and STEP rises one clock later: pulse k at W + 5 + T_k (prescale 1), the plan's edges (2 + T_k) plus W + 3."""
    for at, steps in ((0, 300), (1234, 57)):
        got = run(script({"at": at, "op": "move", "steps": steps, **MOVE}))
        plan = plan_move(steps, **MOVE, spr=200.0, fclk=1e6)
        assert got.edges == [e + at + 3 for e in model_edges(plan)]
        assert got.positions == list(range(1, steps + 1))
        assert got.until == got.edges[-1] + 1000
        assert [(a.at, a.ctrl) for a in got.actions] == [(at, START)]
    # a move down: DIR changes first (request at W + 1, DIR at W + 2, the engine's start one clock later)
    got = run(script({"at": 0, "op": "move", "steps": -40, **MOVE}))
    plan = plan_move(-40, **MOVE, spr=200.0, fclk=1e6)
    assert got.edges == [e + 5 for e in model_edges(plan)]
    assert got.positions == list(range(-1, -41, -1))


def test_one_change_is_change_edges_after_the_start_timing() -> None:
    """A set committed at W: P is change_pulse of the move's STEP edges, the segment plan_change's from the move's
    trapezoid speed at P to the same target; every edge is change_edges (one accumulator), shifted as the move."""
    plan, info = plan_move_info(300, **MOVE, spr=200.0, fclk=1e6)
    before = [e + 3 for e in model_edges(plan)]
    for at, speed in ((20_000, 150.0), (70_000, 150.0), (70_000, 50.0), (120_000, 150.0), (125_000, 30.0)):
        got = run(script({"at": 0, "op": "move", "steps": 300, **MOVE}, {"at": at, "op": "set", "speed": speed}))
        p = change_pulse(before, at)
        change = plan_change(speed_at_pulse(info, p), info.length - p, 2000.0, 2000.0, speed, 200.0, 1e6)
        assert change.back is None
        assert got.edges == [e + 3 for e in change_edges(Segment.of_move(plan), p, change.segment, 1)], (at, speed)
        assert got.positions == list(range(1, 301))
        action = got.actions[1]
        assert action.ctrl == CHANGE and action.at == at
        assert (offset("CHANGE_AT"), p) == action.writes[-1]
        assert got.edges != before  # the change does change the motion


def test_a_change_at_the_last_pulse_is_a_segment_of_length_0() -> None:
    """A set whose P is the move's last pulse (L): the speed there is 0, the target is P's own position, so the
    segment has length 0 (STEPS = 1) and the motion ends with pulse P, exactly as the move would have."""
    plain = _plain(300)
    at = next(w for w in range(plain[-3] - 600, plain[-1]) if _pulse_or_none(plain, w) == 299)
    got = run(script({"at": 0, "op": "move", "steps": 300, **MOVE}, {"at": at, "op": "set", "speed": 150.0}))
    assert got.rejected == [] and got.edges == plain
    regs = dict(got.actions[1].writes)
    assert got.actions[1].ctrl == CHANGE and regs[offset("STEPS")] == 1 and regs[offset("CHANGE_AT")] == 299


def _pulse_or_none(edges: list[int], at: int) -> int | None:
    try:
        return change_pulse(edges, at)
    except ValueError:
        return None


def test_a_soft_stop_and_a_pending_change() -> None:
    """A soft stop sampled up to E + 1 (E: pulse P - 1's engine edge) drops the pending change and is decided as in
    the move (one pulse after the first pulse after it, P + 1 at the latest); one sampled after the take-over (E + 2
    on) is decided by the segment's rules, at its pulse 1 (P + 1) at the earliest; one within a few clocks of the
    take-over is refused (the boundary is the RTL's)."""
    plan, info = plan_move_info(300, **MOVE, spr=200.0, fclk=1e6)
    plain = _plain(300)
    at = 80_000
    p = change_pulse(plain, at)
    took = plain[p - 1] - 1  # E
    change = plan_change(speed_at_pulse(info, p), info.length - p, 2000.0, 2000.0, 150.0, 200.0, 1e6)
    move = {"at": 0, "op": "move", "steps": 300, **MOVE}
    commit = {"at": at, "op": "set", "speed": 150.0}
    # dropped: sampled at E - 3 (the move's edge E - 5), after pulse P - 2's engine edge: the first pulse after it is
    # P - 1, so it is decided at pulse P by the move's own rules
    assert plain[p - 2] - 1 < took - 3
    assert soft_stop_pulse(plan, took - 3 - 2) == p
    got = run(script(move, commit, {"at": took - 4, "op": "soft_stop"}))
    assert got.rejected == [] and got.edges == [e + 3 for e in edges_with_stop(plan, "soft", took - 3 - 2)]
    # after the take-over: sampled at E + 5, before pulse P's engine edge (the first pulse after it is P): decided at
    # P + 1, the segment's pulse 1, by the segment's rules
    assert plain[p] - 1 > took + 5
    got = run(script(move, commit, {"at": took + 4, "op": "soft_stop"}))
    values = segment_stop_values(change.segment, 1)
    assert got.rejected == [] and values is not None
    want = accumulate(segment_values(Segment.of_move(plan), p) + values)
    assert got.edges == [t + 5 for t in want]
    # at the take-over itself: refused, nothing changes
    for sample in (took - 2, took + 1, took + 2, took + 4):
        got = run(script(move, commit, {"at": sample - 1, "op": "soft_stop"}))
        assert [r["op"] for r in got.rejected] == ["soft_stop"] and "taken over" in got.rejected[0]["reason"]
        assert got.edges == run(script(move, commit)).edges


def test_refusals_and_commands_without_an_action() -> None:
    move = {"at": 0, "op": "move", "steps": 300, **MOVE}
    jog = {"at": 0, "op": "jog", "speed": 100.0, "accel": 2000.0, "decel": 2000.0}
    cases: list[tuple[list[dict[str, Any]], str]] = [
        ([move, {"at": 20_000, "op": "move", "steps": 5, **MOVE}], "moving"),
        ([move, {"at": 299, "op": "set", "speed": 50.0}], "overlap the action at 0"),
        ([move, {"at": 15, "op": "soft_stop"}], "less than 16 clocks"),
        ([move, {"at": 20_000, "op": "set", "speed": 50.0}, {"at": 20_400, "op": "set", "speed": 40.0}], "pending"),
        (
            [move, {"at": 20_000, "op": "queue", "steps": -5, **MOVE}, {"at": 40_000, "op": "set", "speed": 9.0}],
            "queue",
        ),
        ([jog, {"at": 20_000, "op": "queue", "steps": 5, **MOVE}], "behind a jog"),
        ([move, {"at": 143_000, "op": "set", "speed": 50.0}], "ends before the change"),
        ([jog, {"at": 20_000, "op": "jog", "speed": 5000.0}], "speed too high"),
        ([{"at": 0, "op": "move_to", "position": 10}], "no speed or accel or decel given yet"),
        ([{"at": 0, "op": "move", "steps": 10_000, **MOVE, "speed": 1e4}], "speed too high"),
    ]
    for commands, reason in cases:
        got = run(script(*commands, until=400_000))
        assert len(got.rejected) == 1 and reason in got.rejected[0]["reason"], (commands[-1], got.rejected)
        assert got.rejected[0]["at"] == commands[-1]["at"] and got.rejected[0]["op"] == commands[-1]["op"]
        assert [a.command for a in got.actions] == list(range(len(commands) - 1)), "a refused command acted"
    # nothing to do: stops when idle, a jog at 0 when idle, a move_to where the motor is, a move of 0, a set
    idle = [
        {"at": 0, "op": "soft_stop"}, {"at": 10, "op": "hard_stop"}, {"at": 20, "op": "jog", "speed": 0.0},
        {"at": 30, "op": "move_to", "position": 0}, {"at": 40, "op": "move", "steps": 0, **MOVE},
        {"at": 50, "op": "set", "speed": 30.0},
    ]  # fmt: skip
    got = run(script(*idle))
    assert got.actions == [] and got.rejected == [] and got.edges == []
    # the set is in force for what follows: a move_to with no values of its own runs at 30 rad/s
    got = run(script(*idle, {"at": 400, "op": "move_to", "position": 300}))
    assert abs(min(_intervals(got.edges)) - _period(30.0)) <= 1.0 and got.positions[-1] == 300


def test_stops_are_the_engine_models_stops() -> None:
    """A soft stop written at W is sampled at the move's edge W + 1 - (s + 1) and a hard stop at W: exactly
    edges_with_stop in the move's numbering (tb/peripheral_tb.py's stop_after), also for a jog (segment_edges)."""
    plan = plan_move(300, **MOVE, spr=200.0, fclk=1e6)
    plain = _plain(300)
    start_edge = 1  # a START at 0: the gate passes the request of edge 1 at once
    # around pulses' edges (STEP edge - 1 is the engine's): a soft stop sampled at pulse k's engine edge is decided at
    # pulse k + 2, one sampled a clock earlier at pulse k + 1; a hard stop at W keeps a pulse whose engine edge is W
    around = [plain[k] + dw for k in (10, 150) for dw in (-3, -2, -1, 0)]
    for at in (3_000, 30_000, 80_000, 125_000, 140_000, *around):
        for kind, op in (("soft", "soft_stop"), ("hard", "hard_stop")):
            got = run(script({"at": 0, "op": "move", "steps": 300, **MOVE}, {"at": at, "op": op}))
            request = at + 1 - (start_edge + 1) if kind == "soft" else at - start_edge
            assert got.edges == [e + 3 for e in edges_with_stop(plan, kind, request)], (kind, at)
    jog = {"at": 0, "op": "jog", "speed": 100.0, "accel": 2000.0, "decel": 2000.0}
    seg = plan_change(0.0, None, 2000.0, 2000.0, 100.0, 200.0, 1e6).segment
    for at in (20_000, 90_000):
        got = run(script(jog, {"at": at, "op": "soft_stop"}))
        assert got.edges == [e + 3 for e in segment_edges(seg, 1, stop=("soft", at + 1 - 2))]
        got = run(script(jog, {"at": at, "op": "hard_stop"}))
        assert got.edges == [e + 3 for e in segment_edges(seg, 1, stop=("hard", at - 1))]


# ---------------------------------------------------------------------------------------------------------------
# (d) physics on random scripts
# ---------------------------------------------------------------------------------------------------------------


def _steps_register(action: Action) -> tuple[int, bool]:
    """(signed STEPS, endless) of an action's staging writes."""
    regs = dict(action.writes)
    raw = regs[offset("STEPS")]
    return (raw - (1 << 32) if raw >> 31 else raw), bool(regs[offset("SEGMENT")] & 2)


def _segment_speed(seg: ideal.IdealSegment, x: float) -> float:
    """The IdealSegment's speed (steps/s) at position x: its first ramp from u, the cruise at the peak, the decel."""
    u, w = seg.u, seg.peak
    rate = seg.a if w >= u else seg.d
    x1 = abs(w * w - u * u) / (2.0 * rate)
    if x <= x1:
        return math.sqrt(max(u * u + (2.0 if w >= u else -2.0) * rate * x, 0.0))
    x2 = seg.length - w * w / (2.0 * seg.d) if seg.length is not None else math.inf
    if x <= x2:
        return w
    return math.sqrt(max(w * w - 2.0 * seg.d * (x - x2), 0.0))


@dataclass
class Judge:
    """One ideal for the pulses from edge index `origin` on (its pulse 0 there), in steps units; values: the speed,
    accel and decel (rad/s, rad/s^2) it runs with; end: the edge index of its last pulse (None: endless)."""

    origin: int
    move: ideal.IdealMove | None
    seg: ideal.IdealSegment | None
    c0_slow: float
    slack: float  # extra ticks (the carried fraction of a take-over)
    bound_c0: float = BOUND_C0
    values: dict[str, float] | None = None
    end: int | None = None

    def time(self, k: int) -> float:
        return self.move.time_at(float(k)) if self.move is not None else self.seg.time_at(float(k))  # type: ignore[union-attr]

    def speed(self, k: int) -> float:
        return self.move.speed_at(float(k)) if self.move is not None else _segment_speed(self.seg, float(k))  # type: ignore[arg-type]


def _values(obj: dict[str, Any], got: ScriptResult) -> list[dict[str, float] | None]:
    """The speed / accel / decel in force at each command (None: rejected), by the contract's rule (the last given by
    an accepted command; a jog's speed as its magnitude)."""
    rejected = [(r["at"], r["op"]) for r in got.rejected]
    force: dict[str, float] = {}
    out: list[dict[str, float] | None] = []
    for cmd in obj["commands"]:
        if (cmd["at"], cmd["op"]) in rejected:
            rejected.remove((cmd["at"], cmd["op"]))
            out.append(None)
            continue
        for name in ("speed", "accel", "decel"):
            if name in cmd and cmd[name] != 0:
                force[name] = abs(cmd[name])
        out.append(dict(force))
    return out


def _motion_starts(got: ScriptResult) -> list[int]:
    """Edge indices at which a motion begins: the first edge after a START, and a queued START a few clocks after a
    motion's last pulse (closer than any interval within a motion)."""
    starts = {0} if got.edges else set()
    for i in range(1, len(got.edges)):
        if got.edges[i] - got.edges[i - 1] < QUEUED_GAP:
            starts.add(i)
    for action in got.actions:
        if action.ctrl & START:
            first = next((i for i, e in enumerate(got.edges) if e > action.at), None)
            if first is not None:
                starts.add(first)
    return sorted(starts)


def check_physics(obj: dict[str, Any], got: ScriptResult) -> dict[str, int]:
    """Every check of the random regression on one script; returns counts of what was judged."""
    f_tick = obj["fclk"] / obj["prescale"]
    edges, positions = got.edges, got.positions
    counts = {"pulses": 0, "changes": 0, "queued": 0, "chained": 0, "starts": 0}
    assert all(e <= got.until for e in edges)
    # the pins: rising edges at least STEP width + space (2 clocks) apart, POSITION +-1 per edge
    assert all(b - a >= 2 for a, b in itertools.pairwise(edges)), "two STEP edges closer than 2 clocks"
    steps = [b - a for a, b in zip([0, *positions], positions, strict=False)]
    assert all(s in (1, -1) for s in steps), "POSITION moves by other than one step per edge"
    values = _values(obj, got)
    speeds = [abs(c["speed"]) / ALPHA for c in obj["commands"] if c.get("speed")]
    rates = [c[k] / ALPHA for c in obj["commands"] for k in ("accel", "decel") if k in c]
    starts = _motion_starts(got)
    bounds = [*starts, len(edges)]
    for b, e in itertools.pairwise(bounds):
        # one direction per motion, and a queued START 5 clocks after the last pulse (7 with a DIR change)
        assert len(set(steps[b:e])) == 1, f"the direction changes within the motion from edge {edges[b]}"
        started = any(a.ctrl & START and edges[b] - a.at in (5, 7) for a in got.actions)
        if b and edges[b] - edges[b - 1] < QUEUED_GAP and not started:
            assert edges[b] - edges[b - 1] == (5 if steps[b] == steps[b - 1] else 7), edges[b]
            counts["queued"] += 1
    # never faster than the fastest commanded speed (beyond the bound)
    if speeds:
        c0_max = f_tick * math.sqrt(2.0 / min(rates))
        shortest = f_tick / max(speeds) - 2.0 * (BOUND_C0 * c0_max + BOUND_TICKS)
        starts_set = set(starts)
        for i in range(1, len(edges)):
            if i not in starts_set:
                assert (edges[i] - edges[i - 1]) / obj["prescale"] >= shortest, f"too fast at edge {edges[i]}"
    # the ideals, motion by motion
    for n, b in enumerate(starts):
        e = bounds[n + 1]
        counts["pulses"] += _judge_motion(obj, got, values, b, e, counts)
    return counts


def _start_action(got: ScriptResult, edges: list[int], b: int) -> Action:
    """The action that began the motion whose first edge is edges[b]: a START just before it, else the last QUEUE."""
    starts = [a for a in got.actions if a.ctrl & START and 0 < edges[b] - a.at <= 7]
    if starts:
        return starts[-1]
    return [a for a in got.actions if a.ctrl & QUEUE and a.at < edges[b]][-1]


def _judge_motion(
    obj: dict[str, Any],
    got: ScriptResult,
    values: list[dict[str, float] | None],
    b: int,
    e: int,
    counts: dict[str, int],
) -> int:
    """Hold the pulses of the motion edges[b:e] to the ideal of whatever the actions made of it; returns the number
    of pulses judged."""
    edges = got.edges
    prescale, f_tick, spr, fclk = obj["prescale"], obj["fclk"] / obj["prescale"], obj["spr"], obj["fclk"]
    first = _start_action(got, edges, b)
    if first.ctrl & START:
        assert edges[b] - first.at in (5, 7), f"START at {first.at}: first STEP edge {edges[b]}"
        counts["starts"] += 1
    v = values[first.command]
    assert v is not None
    steps, endless = _steps_register(first)
    a, d, speed = v["accel"] / ALPHA, v["decel"] / ALPHA, v["speed"] / ALPHA
    assert (steps < 0) == (got.positions[b] < (got.positions[b - 1] if b else 0))
    c0_slow = f_tick * math.sqrt(2.0 / min(a, d))
    if endless:
        judge = Judge(b, None, ideal.IdealSegment(0.0, a, d, speed, None, f_tick), c0_slow, 0.0, values=v)
    else:
        move = ideal.ideal_move(steps, v["accel"], v["decel"], v["speed"], spr, fclk, prescale)
        judge = Judge(b, move, None, c0_slow, 0.0, values=v, end=b + abs(steps) - 1)
    later = [x for x in got.actions if x.at > first.at and x.at < edges[e - 1]]
    timeline = [judge]  # each judge holds from its origin on, up to the next one's
    judged = 0
    done = b  # edges[b:done] judged
    for action in later:
        upto = done  # no action changes a pulse whose STEP edge is at or before its W + 1
        while upto < e and edges[upto] <= action.at + 1:
            upto += 1
        judged += _judge_span(timeline, edges, done, upto, prescale)
        done = upto
        if action.ctrl & (SOFT_STOP | HARD_STOP):
            if action.ctrl & HARD_STOP:
                assert all(x <= action.at + 1 for x in edges[b:e]), f"a pulse after the hard stop at {action.at}"
            return judged
        if not action.ctrl & CHANGE:
            continue
        p = dict(action.writes)[offset("CHANGE_AT")]
        emitted = sum(1 for x in edges[b:e] if x <= action.at)
        # the lead of a take-over: at least 2 pulses and 400 clocks after the commit
        assert p >= emitted + 1, (action.at, p, emitted)
        if b + p >= e:
            return judged  # the motion ended before P (cut by until)
        assert edges[b + p] >= action.at + 400, (action.at, p)
        w = values[action.command]
        assert w is not None
        seg_steps, seg_endless = _steps_register(action)
        length = None if seg_endless else abs(seg_steps) - 1
        running = timeline[-1]
        u = running.speed(b + p - running.origin)  # the running ideal's speed at pulse P
        queued = obj["commands"][action.command]
        if queued["op"] == "queue":  # a queued move in the same direction, without a stop: two changes
            chain = [x for x in got.actions if x.command == action.command]
            if action is chain[0]:  # A: the running values, to a virtual rest beyond the target (_check_chain_a)
                w = running.values
                assert w is not None and length is not None
                _check_chain_a(running, w, values[action.command], queued["steps"], b + p, length)
            else:  # B: at the old target, from the speed there, to the queued move's end
                old = timeline[-2]
                assert action is chain[1] and b + p == old.end, f"change B at {b + p}, not at the target {old.end}"
                assert length == abs(queued["steps"]), "change B does not end the queued move's steps further"
                _check_boundary_speed(old, running, u)
                counts["chained"] += 1
        a2, d2, v2 = w["accel"] / ALPHA, w["decel"] / ALPHA, w["speed"] / ALPHA
        args = (w["accel"], w["decel"], w["speed"], spr, fclk, prescale)
        start = _matching_change(u, length, args, int(seg_steps < 0), action).start_speed
        segment = ideal.IdealSegment(start, a2, d2, v2, length, f_tick)
        near_rest = start > v2 and v2 * v2 / (2.0 * d2) < NEAR_REST_STEPS
        c0_slow = f_tick * math.sqrt(2.0 / min(a2, d2))
        bound = NEAR_REST_BOUND_C0 if near_rest else BOUND_C0
        end = None if length is None else b + p + length
        timeline.append(Judge(b + p, None, segment, c0_slow, CARRY_TICKS, bound, values=w, end=end))
        counts["changes"] += 1
    judged += _judge_span(timeline, edges, done, e, prescale)
    return judged


def _boundary(v1: dict[str, float], v2: dict[str, float], n2: int) -> float:
    """vb (steps/s) of a queued move of n2 steps at v2 behind a motion at v1: the speed from which the queued move
    can still stop in its steps, at most either speed."""
    return min(v1["speed"] / ALPHA, v2["speed"] / ALPHA, math.sqrt(2.0 * v2["decel"] / ALPHA * n2))


def _check_chain_a(
    running: Judge, v1: dict[str, float], v2: dict[str, float] | None, steps: int, p: int, length: int
) -> None:
    """Change A of a queued move: from pulse p to a virtual rest mb = floor(vb^2 / (2 d1)) steps past the running
    motion's target (its end), the decel from which passes the target at vb."""
    assert v2 is not None and running.end is not None
    mb = length - (running.end - p)
    x = _boundary(v1, v2, abs(steps)) ** 2 / (2.0 * v1["decel"] / ALPHA)
    assert x - 1.0 < mb <= x + 1e-6, f"change A ends {mb} steps past the target, not floor({x:.3f})"


def _check_boundary_speed(old: Judge, a: Judge, u: float) -> None:
    """The speed at the old target (u, from A's ideal) is what A can reach there: at most the speed from which it
    stops at its virtual rest (about vb), the speed it accelerates to from its start, and its commanded speed."""
    assert a.seg is not None and a.values is not None and old.end is not None
    seg, r = a.seg, old.end - a.origin
    v1 = a.values["speed"] / ALPHA
    assert seg.length is not None
    if seg.u <= v1:
        reach = math.sqrt(seg.u**2 + 2.0 * seg.a * r)
    else:  # a down head: decel to v1
        reach = max(v1, math.sqrt(max(seg.u**2 - 2.0 * seg.d * r, 0.0)))
    want = min(reach, v1, math.sqrt(2.0 * seg.d * (seg.length - r)))
    scale = v1 * v1 + seg.u * seg.u  # (squared speeds: sqrt near 0 magnifies rounding)
    assert abs(u * u - want * want) <= 1e-9 * scale, f"speed at the old target {u!r} steps/s, not {want!r}"


def _matching_change(u: float, length: int | None, args: tuple[float, ...], direction: int, action: Action) -> Change:
    """plan_change from the ideal speed u at P, as the action's registers hold it: u or one of its nearest doubles
    (the snap floor(u^2 / (2 d)) is not continuous where P lies in a cruise at a snapped speed, and the ideal speed
    is computed in another order of operations than the driver's)."""
    want = list(action.writes[:-1])
    for ulps in (0, 1, -1, 2, -2, 3, -3, 4, -4):
        x = u
        for _ in range(abs(ulps)):
            x = math.nextafter(x, math.inf if ulps > 0 else 0.0)
        change = plan_change(x, length, *args)
        plan, segment = change.segment.registers(direction)
        if [*plan_writes(plan), *segment_writes(segment)] == want:
            return change
    raise AssertionError(f"CHANGE at {action.at}: its segment is not plan_change's from the ideal speed {u} at P")


#: The largest |error| - 2 ticks (- the carried tick after a take-over) seen by _judge_span, in c0 of the slower ramp,
#: for the judges held to 0.008 c0 ("bound") and to 0.016 c0 ("near rest"): printed by the random test.
WORST: dict[str, float] = {}


def _judge_span(timeline: list[Judge], edges: list[int], lo: int, hi: int, prescale: int) -> int:
    """Hold edges[lo:hi] to the judges of the timeline (each from its origin on)."""
    for i in range(lo, hi):
        judge = [j for j in timeline if j.origin <= i][-1]
        bound = judge.bound_c0 * judge.c0_slow + BOUND_TICKS + judge.slack
        t0 = edges[judge.origin]
        err = (edges[i] - t0) / prescale - judge.time(i - judge.origin)
        kind = "near rest" if judge.bound_c0 == NEAR_REST_BOUND_C0 else "bound"
        WORST[kind] = max(WORST.get(kind, 0.0), (abs(err) - BOUND_TICKS - judge.slack) / judge.c0_slow)
        assert abs(err) <= bound, (
            f"pulse at edge {edges[i]} ({i - judge.origin} after {t0}) is {err:.2f} ticks off the ideal "
            f"({err / judge.c0_slow:.5f} c0)"
        )
    return max(hi - lo, 0)


def _goal(obj: dict[str, Any], got: ScriptResult) -> int | None:
    """Where the motor must end when the run goes on to the end: the target of the last accepted positioning command
    (move_to; a move from where it stood; a queue adds its steps; a set keeps it), None after a jog or a stop."""
    values = _values(obj, got)
    acting = {a.command: a.ctrl for a in got.actions}
    goal: int | None = 0
    for n, cmd in enumerate(obj["commands"]):
        if values[n] is None:
            continue
        op, ctrl = cmd["op"], acting.get(n)
        if op == "move_to":
            goal = cmd["position"]
        elif op in ("move", "queue") and ctrl == START:  # from where the motor stood
            stood = [p for e, p in zip(got.edges, got.positions, strict=True) if e <= cmd["at"]]
            goal = (stood[-1] if stood else 0) + cmd["steps"]
        elif op == "queue" and ctrl is not None:  # after the running motion
            goal = None if goal is None else goal + cmd["steps"]
        elif (op == "jog" and cmd["speed"] != 0) or (op in ("soft_stop", "hard_stop", "jog") and ctrl is not None):
            goal = None
    return goal


def test_random_scripts_against_physics() -> None:
    rng = random.Random(SEED)
    print(f"seed {SEED} (STEPRAMP_SEED={SEED} replays it)")
    totals = {"pulses": 0, "changes": 0, "queued": 0, "chained": 0, "starts": 0, "goals": 0}
    ctrls: set[int] = set()
    ops: set[str] = set()
    jog_cases = {"reversals": 0, "soft": 0, "hard": 0}
    for n in range(200):
        # (the machine inputs' effects are judged by the named input scripts below; here, the motion commands)
        obj = random_script(rng)
        obj = {k: v for k, v in obj.items() if k != "inputs"}
        obj["commands"] = [c for c in obj["commands"] if c["op"] not in ("input", "clear_fault")]
        got = run(obj)
        try:
            for key, value in check_physics(obj, got).items():
                totals[key] += value
            goal = _goal(obj, got)
            if goal is not None:
                ended = run({k: value for k, value in obj.items() if k != "until"})
                final = ended.positions[-1] if ended.positions else 0
                assert final == goal, f"ends at {final}, not at the target {goal}"
                totals["goals"] += 1
        except AssertionError as err:
            raise AssertionError(f"script {n} of seed {SEED}: {err}\n{json.dumps(obj)}") from err
        ctrls |= {a.ctrl for a in got.actions}
        for before, action in itertools.pairwise(got.actions):
            jogging = bool(before.writes) and _steps_register(before)[1]
            if jogging and action.ctrl == SOFT_STOP | QUEUE and _steps_register(action)[1]:
                jog_cases["reversals"] += 1  # a jog through zero: stop, then the jog the other way
            elif jogging and action.ctrl in (SOFT_STOP, HARD_STOP):
                jog_cases["soft" if action.ctrl == SOFT_STOP else "hard"] += 1
        ops |= {c["op"] for c in obj["commands"]}
    print(f"200 scripts: {totals}, in jogs: {jog_cases}")
    print("worst error beyond the ticks, in c0: " + ", ".join(f"{k} {v:.5f}" for k, v in sorted(WORST.items())))
    assert min(jog_cases.values()) >= 5, jog_cases
    assert ops == {"move", "move_to", "jog", "set", "queue", "soft_stop", "hard_stop"}
    assert ctrls == {START, CHANGE, QUEUE, SOFT_STOP, HARD_STOP, SOFT_STOP | QUEUE}
    assert totals["changes"] >= 100 and totals["queued"] >= 50 and totals["goals"] >= 40, totals
    assert totals["chained"] >= 10, "too few queued moves without a stop (change B judged) in random scripts"


# ---------------------------------------------------------------------------------------------------------------
# (e) the named scripts
# ---------------------------------------------------------------------------------------------------------------

F_TICK = BASE["fclk"]


def _period(speed: float) -> float:
    """Clocks a step at `speed` rad/s (prescale 1)."""
    return F_TICK / (speed / ALPHA)


def _cd0(decel: float) -> float:
    """The last step of a decel at `decel` rad/s^2 to rest, clocks: f sqrt(2 / d)."""
    return F_TICK * math.sqrt(2.0 / (decel / ALPHA))


def _intervals(edges: list[int]) -> list[int]:
    return [b - a for a, b in itertools.pairwise(edges)]


K = NAMED_SCALE  # the named scripts run K times faster than their comments say (stepramp.board.script)
NAMED_MOVE = {"accel": 2000.0 * K**2, "decel": 2000.0 * K**2, "speed": 100.0 * K}


def _reversals(positions: list[int]) -> list[int]:
    """Indices of the edges at which the direction of the count changes."""
    steps = [b - a for a, b in itertools.pairwise([0, *positions])]
    return [i for i in range(1, len(steps)) if steps[i] != steps[i - 1]]


def _plain(steps: int, move: dict[str, float] = MOVE) -> list[int]:
    """The STEP edges of a move from rest STARTed at 0 (no DIR change: the request of edge 1 passes at once, STEP
    rises 4 clocks after the engine's start)."""
    plan = plan_move(steps, **move, spr=200.0, fclk=1e6)
    return [e + 3 for e in model_edges(plan)]


def _named(name: str) -> ScriptResult:
    got = run(NAMED_SCRIPTS[name])
    assert got.rejected == [], (name, got.rejected)
    check_physics(NAMED_SCRIPTS[name], got)
    return got


def _change_at(got: ScriptResult) -> int:
    (action,) = [a for a in got.actions if a.ctrl == CHANGE]
    return dict(action.writes)[offset("CHANGE_AT")]


def test_named_speed_up_and_slow_down_in_run() -> None:
    plain = _plain(600, NAMED_MOVE)
    for name, speed in (("speed_up_in_run", 150.0), ("slow_down_in_run", 50.0)):
        got = _named(name)
        p = _change_at(got)
        assert 80 < p < 520, "the change lands in RUN (ramps of 80 steps)"
        assert got.edges[: p + 1] == plain[: p + 1], "the pulses up to P are the move's"
        assert got.positions[-1] == 600
        after = _intervals(got.edges[p:])
        cruise = [i for i in after if abs(i - _period(speed * K)) <= 1.0]
        assert len(cruise) >= 100, f"{name}: no cruise at {speed} rad/s ({_period(speed * K):.1f} clocks)"
        assert min(after) >= math.floor(_period(max(speed, 100.0) * K)) - 1, f"{name}: faster than commanded"
        assert (got.edges[-1] < plain[-1]) == (speed > 100.0), "a faster motion ends sooner, a slower one later"


def test_named_changes_in_accel_and_in_decel() -> None:
    plain = _plain(600, NAMED_MOVE)
    got = _named("change_in_accel")
    p = _change_at(got)
    assert 2 <= p < 80 and got.edges[: p + 1] == plain[: p + 1]
    ramp = _intervals(got.edges[p:])
    top = ramp.index(min(ramp))
    assert all(b <= a + 1 for a, b in itertools.pairwise(ramp[:top])), "the accel does not go on up to the speed"
    assert abs(min(ramp) - _period(150.0 * K)) <= 1.0 and got.positions[-1] == 600
    # the new ramp: twice the accel, so the speed grows faster than in the plain move after P
    assert got.edges[p + 20] - got.edges[p] < plain[p + 20] - plain[p]
    got = _named("change_in_decel")
    p = _change_at(got)
    assert 520 < p < 599 and got.edges[: p + 1] == plain[: p + 1] and got.positions[-1] == 600
    last = _intervals(got.edges)[-1]
    assert abs(last - _cd0(4000.0 * K**2)) <= 0.01 * _cd0(4000.0 * K**2), f"last step {last}, not that of the new decel"
    assert abs(_intervals(plain)[-1] - _cd0(2000.0 * K**2)) <= 0.01 * _cd0(2000.0 * K**2)
    assert min(_intervals(got.edges[p:])) >= math.floor(_period(100.0 * K)) - 1


@pytest.mark.parametrize(("name", "target"), [("retarget_inside_stop_distance", 270), ("retarget_behind", 100)])
def test_named_retargets_reverse_and_end_on_the_target(name: str, target: int) -> None:
    """The motor cannot stop at (or go back to) the target from its speed: a soft stop at the decel, DIR changes,
    and a move back ends exactly on the target."""
    got = _named(name)
    assert [a.ctrl for a in got.actions] == [START, SOFT_STOP | QUEUE]
    (turn,) = _reversals(got.positions)
    stop_at = got.positions[turn - 1]
    stood = [p for e, p in zip(got.edges, got.positions, strict=True) if e <= 100_000 // K][-1]
    # it stops the stop distance v^2 / (2 d) (80 steps at 100 rad/s and 2000 rad/s^2) beyond where it was
    assert abs(stop_at - stood - 80) <= 3 and stop_at > target
    assert got.edges[turn] - got.edges[turn - 1] == 7, "the move back starts after DIR setup (7 clocks)"
    before = _intervals(got.edges[:turn])
    rest = _cd0(2000.0 * K**2)
    assert abs(before[-1] - rest) <= 0.01 * rest, "the motor is not at rest before reversing"
    assert got.positions[turn:] == list(range(stop_at - 1, target - 1, -1)), "not counting down to the target"


def test_named_jog_through_zero() -> None:
    got = _named("jog_through_zero")
    (turn,) = _reversals(got.positions)
    up, down = got.positions[:turn], got.positions[turn:]
    assert up == list(range(1, turn + 1)) and all(b == a - 1 for a, b in itertools.pairwise([up[-1], *down]))
    assert got.edges[turn] - got.edges[turn - 1] == 7, "DIR changes between the two jogs"
    before, after = _intervals(got.edges[:turn]), _intervals(got.edges[turn:])
    assert abs(before[-1] - _cd0(2000.0 * K**2)) <= 0.01 * _cd0(2000.0 * K**2), "not at rest before reversing"
    assert abs(min(before) - _period(100.0 * K)) <= 1.0 and abs(min(after) - _period(100.0 * K)) <= 1.0
    assert abs(after[-1] - _cd0(2000.0 * K**2)) <= 0.01 * _cd0(2000.0 * K**2), "the soft stop does not end at rest"
    assert down[-1] < 0, "the way down goes through zero"


def test_named_jog_changes_end_on_the_target() -> None:
    got = _named("jog_changes")
    assert [a.ctrl for a in got.actions] == [START, CHANGE, CHANGE, CHANGE]
    steps = _intervals(got.edges)
    assert abs(min(steps) - _period(150.0 * K)) <= 1.0
    assert sum(1 for i in steps if abs(i - _period(60.0 * K)) <= 1.0) >= 50
    assert got.positions == list(range(1, 901))


def _from_rest(got: ScriptResult, first: int, steps: int, gap: int, move: dict[str, float]) -> None:
    """A move of `first` steps, then `steps` queued from rest: the queued move starts exactly as a START written at
    the running move's last STEP edge: its request one clock later, STEP 4 clocks after the gate lets it through (same
    direction: at once, `gap` 5; DIR change: DIR at the next edge, the start one clock after, `gap` 7)."""
    assert [a.ctrl for a in got.actions] == [START, QUEUE]
    assert got.edges[:first] == _plain(first, move)
    last = got.edges[first - 1]
    second = plan_move(steps, **move, spr=200.0, fclk=1e6)
    assert got.edges[first:] == [last + gap - 2 + e for e in model_edges(second)]
    assert got.positions[-1] == first + steps and len(_reversals(got.positions)) == (steps < 0)


def test_named_queued_moves() -> None:
    """The other way: the queued move starts from rest after the DIR change (QUEUE)."""
    _from_rest(_named("queue_opposite_direction"), 300, -200, 7, NAMED_MOVE)


def _ramp_step(vb: float, rate: float) -> tuple[float, float]:
    """The speeds one step of a ramp at `rate` (steps/s^2) below and above vb (steps/s)."""
    return math.sqrt(max(vb * vb - 2.0 * rate, 0.0)), math.sqrt(vb * vb + 2.0 * rate)


def _passes_at(got: ScriptResult, k: int, vb: float, rate: float, span: int = 5) -> None:
    """No stop at pulse k: every interval within `span` pulses of it at most that of one ramp step below vb (a clock
    of quantization), far below the rest interval; the time of the two intervals around it within a ramp step of
    vb."""
    slow, fast = _ramp_step(vb, rate)
    near = _intervals(got.edges[k - span : k + span + 1])
    assert max(near) <= F_TICK / slow + 1.0, f"intervals {near} around pulse {k}: slower than {vb:.1f} steps/s"
    assert max(near) < F_TICK * math.sqrt(2.0 / rate) / 5.0, "a stop at the boundary"
    t = got.edges[k + 1] - got.edges[k - 1]
    assert 2.0 * F_TICK / fast - 2.0 <= t <= 2.0 * F_TICK / slow + 2.0, f"{2.0 * F_TICK / t:.1f} steps/s, not {vb:.1f}"


def _chain(got: ScriptResult) -> tuple[int, int]:
    """(P_A, P_B) of a queued move without a stop: START, then its two CHANGEs, both with the queue's index 1."""
    assert [(a.ctrl, a.command) for a in got.actions[:3]] == [(START, 0), (CHANGE, 1), (CHANGE, 1)], got.actions
    p_a, p_b = (dict(a.writes)[offset("CHANGE_AT")] for a in got.actions[1:3])
    return p_a, p_b


def test_named_queue_in_the_same_direction_does_not_stop() -> None:
    """A move queued in the running move's direction follows it without a stop: change A at the usual P with the
    running values, towards a virtual rest mb = floor(vb^2 / (2 d1)) steps past the target, and change B (the
    driver's own commit, the queue's index) at the target's pulse, so that the motor passes the old target at the
    boundary speed vb = min(v1, v2, sqrt(2 d2 N2)): 60 rad/s here (100 rad/s and sqrt(2 d 200) are faster)."""
    got = _named("queue_same_direction")
    plain = _plain(300, NAMED_MOVE)
    p_a, p_b = _chain(got)
    assert p_a == change_pulse(plain, 50_000 // K) and got.edges[: p_a + 1] == plain[: p_a + 1]
    assert p_b == 299, "change B does not take over at the old target (position 300)"
    d1 = 2000.0 * K**2 / ALPHA
    vb = 60.0 * K / ALPHA
    mb = math.floor(vb * vb / (2.0 * d1))
    assert mb == 28 and _steps_register(got.actions[1])[0] == 299 - p_a + mb + 1, "change A's virtual rest"
    assert _steps_register(got.actions[2])[0] == 201, "change B does not run the queued move's 200 steps"
    # change B's writes come after PENDING of A fell (two clocks after pulse P_A - 1's engine edge, its STEP edge + 1)
    assert got.actions[2].at - PREP_CLOCKS > plain[p_a - 1] + 1
    assert got.positions == list(range(1, 501))
    _passes_at(got, 299, vb, d1)
    # before: the move at 100 rad/s slows down to vb; after: the queued move cruises at 60 rad/s and ends at rest
    assert abs(min(_intervals(got.edges[:p_b])) - _period(100.0 * K)) <= 1.0
    assert sum(1 for i in _intervals(got.edges[p_b:]) if abs(i - _period(60.0 * K)) <= 1.0) >= 50
    assert abs(_intervals(got.edges)[-1] - _cd0(2000.0 * K**2)) <= 0.01 * _cd0(2000.0 * K**2)


def test_a_short_queued_move_passes_the_target_at_its_stopping_speed() -> None:
    """20 steps queued behind a 300-step move at 100 rad/s (ramps of 79.6 steps): vb = sqrt(2 d2 N2), the speed from
    which the queued move can just stop in its 20 steps; the motor passes 300 at it in one deceleration to rest at
    320 (the intervals only grow from the decel's start on)."""
    move = {"at": 0, "op": "move", "steps": 300, **MOVE}
    obj = script(move, {"at": 80_000, "op": "queue", "steps": 20, **MOVE})
    got = run(obj)
    check_physics(obj, got)
    _, p_b = _chain(got)
    assert p_b == 299 and got.positions == list(range(1, 321))
    d = 2000.0 / ALPHA
    _passes_at(got, 299, math.sqrt(2.0 * d * 20), d, span=1)  # (the decel goes on after it)
    ramp = (100.0 / ALPHA) ** 2 / (2.0 * d)
    tail = _intervals(got.edges[math.ceil(320 - ramp) :])
    assert all(b >= a - 1 for a, b in itertools.pairwise(tail)), "the speed rises in the decel through 300"
    assert abs(tail[-1] - _cd0(2000.0)) <= 0.01 * _cd0(2000.0)


def test_a_queue_too_late_for_the_take_overs_starts_from_rest() -> None:
    """The queue's commit moved over the move's decel: early, the two changes (the lead of change B from its commit
    after A, 2 pulses and 400 clocks, is met: check_physics holds it); late, QUEUE from rest 5 clocks after the last
    pulse; once it falls back, every later commit does."""
    plain = _plain(300)
    move = {"at": 0, "op": "move", "steps": 300, **MOVE}
    chained = []
    for k in range(250, 299, 3):
        obj = script(move, {"at": plain[k] + 10, "op": "queue", "steps": 200, **MOVE})
        got = run(obj)
        check_physics(obj, got)
        chained.append(got.actions[-1].ctrl == CHANGE)
        if chained[-1]:
            assert _chain(got)[1] == 299 and got.positions == list(range(1, 501))
        else:
            _from_rest(got, 300, 200, 5, MOVE)
    assert chained[0] and not chained[-1] and chained == sorted(chained, reverse=True), chained


def _queue_at_60(move: dict[str, Any]) -> dict[str, Any]:
    return {"at": 80_000, "op": "queue", "steps": 200, **MOVE, "speed": 60.0}


def test_a_stop_before_change_b_cancels_it() -> None:
    """A soft or hard stop written before W_B (change B's commit): the driver does not commit B. A soft stop sampled
    after A took over, before pulse P_A's engine edge, is decided at A's pulse 1 (P_A + 1) by A's rules (here its
    cruise: the stop distance from 100 rad/s); one sampled while A is pending drops A and is decided by the move's; a
    hard stop ends the motion. Change A is plan_change's from the move's speed at P_A, towards a virtual rest
    floor(vb^2 / (2 d1)) steps past 300."""
    plan, info = plan_move_info(300, **MOVE, spr=200.0, fclk=1e6)
    plain = _plain(300)
    move = {"at": 0, "op": "move", "steps": 300, **MOVE}
    queue = _queue_at_60(move)
    chained = run(script(move, queue))
    p_a, _ = _chain(chained)
    w_b = chained.actions[2].at
    d1 = 2000.0 / ALPHA
    mb = math.floor((60.0 / ALPHA) ** 2 / (2.0 * d1))
    change_a = plan_change(speed_at_pulse(info, p_a), 299 - p_a + mb, 2000.0, 2000.0, 100.0, 200.0, 1e6)
    regs, seg = change_a.segment.registers(0)
    assert list(chained.actions[1].writes) == [*plan_writes(regs), *segment_writes(seg), (offset("CHANGE_AT"), p_a)]
    took = plain[p_a - 1] + 1  # PENDING of A falls (E_A + 2)
    at = took + 20
    assert at < w_b and at + 1 < plain[p_a] - 1  # (the first pulse after the sample is P_A)
    got = run(script(move, queue, {"at": at, "op": "soft_stop"}))
    assert [(a.ctrl, a.command) for a in got.actions] == [(START, 0), (CHANGE, 1), (SOFT_STOP, 2)]
    values = segment_stop_values(change_a.segment, 1)
    assert values is not None
    assert got.edges == [t + 5 for t in accumulate(segment_values(Segment.of_move(plan), p_a) + values)]
    stop = (100.0 / ALPHA) ** 2 / (2.0 * d1)
    assert abs(len(got.edges) - 1 - (p_a + 1) - stop) <= 1.0, "not the stop distance from 100 rad/s"
    assert abs(_intervals(got.edges)[-1] - _cd0(2000.0)) <= 0.01 * _cd0(2000.0)
    # while A is pending: both dropped, decided by the move's rules (the sample at + 1, the move's edge at - 1)
    at = queue["at"] + 50
    got = run(script(move, queue, {"at": at, "op": "soft_stop"}))
    assert [a.ctrl for a in got.actions] == [START, CHANGE, SOFT_STOP]
    assert got.edges == [e + 3 for e in edges_with_stop(plan, "soft", at - 1)]
    # a hard stop
    got = run(script(move, queue, {"at": took + 20, "op": "hard_stop"}))
    assert [a.ctrl for a in got.actions] == [START, CHANGE, HARD_STOP]
    assert got.edges == [e for e in plain if e <= took + 21]
    # the run ends before W_B: B is not committed, the edges up to the end are the same
    got = run(script(move, queue, until=w_b - 1))
    assert [a.ctrl for a in got.actions] == [START, CHANGE]
    assert got.edges == [e for e in chained.edges if e <= w_b - 1]
    # the staging is reserved for B from A's commit to B's take-over: a set between them is refused
    for at in (took + 100, w_b + 1000):
        got = run(script(move, queue, {"at": at, "op": "set", "speed": 50.0}))
        assert [r["op"] for r in got.rejected] == ["set"] and "staging is locked" in got.rejected[0]["reason"]
        assert got.edges == chained.edges


def test_a_soft_stop_after_change_b_is_committed() -> None:
    """Sampled up to E_B + 1 (pulse P_B - 1's engine edge + 1) it drops B and is decided by A's rules: in A's final
    decel it is ignored, and A runs on to its virtual rest, mb steps past the old target (the core's rule). Sampled
    later, it is decided at pulse P_B + 1 by B's rules."""
    plan, info = plan_move_info(300, **MOVE, spr=200.0, fclk=1e6)
    move = {"at": 0, "op": "move", "steps": 300, **MOVE}
    queue = _queue_at_60(move)
    chained = run(script(move, queue))
    p_a, p_b = _chain(chained)
    d1 = 2000.0 / ALPHA
    mb = math.floor((60.0 / ALPHA) ** 2 / (2.0 * d1))
    change_a = plan_change(speed_at_pulse(info, p_a), 299 - p_a + mb, 2000.0, 2000.0, 100.0, 200.0, 1e6)
    before = segment_values(Segment.of_move(plan), p_a)
    # A's final decel from 100 rad/s begins 79.6 steps before its virtual rest at 300 + mb
    at = chained.edges[290]
    assert chained.actions[2].at < at and 299 + mb - (100.0 / ALPHA) ** 2 / (2.0 * d1) < 291
    got = run(script(move, queue, {"at": at, "op": "soft_stop"}))
    assert [a.ctrl for a in got.actions] == [START, CHANGE, CHANGE, SOFT_STOP]
    assert got.positions == list(range(1, 300 + mb + 1)), "not on to A's virtual rest"
    want = accumulate(before + segment_values(change_a.segment, cast(int, change_a.segment.length)))
    assert got.edges == [t + 5 for t in want]
    assert abs(_intervals(got.edges)[-1] - _cd0(2000.0)) <= 0.01 * _cd0(2000.0)
    # after the take-over of B: decided at its pulse 1
    at = chained.edges[p_b - 1] + 5
    got = run(script(move, queue, {"at": at, "op": "soft_stop"}))
    u_b = speed_at_segment_pulse(change_a, 299 - p_a)
    change_b = plan_change(u_b, 200, 2000.0, 2000.0, 60.0, 200.0, 1e6)
    values = segment_stop_values(change_b.segment, 1)
    assert values is not None
    want = accumulate(before + segment_values(change_a.segment, 299 - p_a) + values)
    assert got.edges == [t + 5 for t in want]
    assert abs(len(got.edges) - 301 - (60.0 / ALPHA) ** 2 / (2.0 * d1)) <= 2.0, "not the stop distance from vb"
    # queued in the first steps (intervals of thousands of clocks): B is committed before pulse P_A; a stop between
    # them drops B, and A, taken over, decides it at its pulse 1 (P_A + 1)
    queue = dict(queue, at=3_000)
    early = run(script(move, queue))
    p_a, _ = _chain(early)
    assert early.actions[2].at + 500 < early.edges[p_a] - 1, "B is not committed before pulse P_A"
    got = run(script(move, queue, {"at": early.actions[2].at + 500, "op": "soft_stop"}))
    assert [a.ctrl for a in got.actions] == [START, CHANGE, CHANGE, SOFT_STOP]
    change_a = plan_change(speed_at_pulse(info, p_a), 299 - p_a + mb, 2000.0, 2000.0, 100.0, 200.0, 1e6)
    values = segment_stop_values(change_a.segment, 1)
    assert values is not None
    assert got.edges == [t + 5 for t in accumulate(segment_values(Segment.of_move(plan), p_a) + values)]


def test_named_stops_in_a_jog() -> None:
    got = _named("soft_stop_in_jog")
    # decided one pulse after the first engine edge after the sample (docs/algorithm.md, "Soft stop"), and the stop
    # distance from 100 rad/s (80 steps, whatever K)
    decided = next(i for i, e in enumerate(got.edges) if e - 1 > (120_000 // K + 1)) + 1
    stop = math.ceil((100.0 * K / ALPHA) ** 2 / (2.0 * 2000.0 * K**2 / ALPHA))
    assert len(got.edges) == decided + 1 + stop
    tail = _intervals(got.edges[decided:])
    assert all(b >= a - 1 for a, b in itertools.pairwise(tail)), "the speed rises in the stop"
    assert abs(tail[-1] - _cd0(2000.0 * K**2)) <= 0.01 * _cd0(2000.0 * K**2)
    got = _named("hard_stop_in_jog")
    assert got.edges[-1] <= (120_000 // K + 1) < got.edges[-1] + math.ceil(_period(100.0 * K)) + 1
    assert got.positions == list(range(-1, -len(got.edges) - 1, -1))


def test_named_scripts_are_all_tested() -> None:
    tested = {
        "speed_up_in_run", "slow_down_in_run", "change_in_accel", "change_in_decel", "retarget_inside_stop_distance",
        "retarget_behind", "jog_through_zero", "jog_changes", "queue_same_direction", "queue_opposite_direction",
        "soft_stop_in_jog", "hard_stop_in_jog", "limit_soft_in_run", "limit_hard_in_jog", "estop_and_recover",
        "limit_bounce",
    }  # fmt: skip
    assert set(NAMED_SCRIPTS) == tested


# ---------------------------------------------------------------------------------------------------------------
# the command line
# ---------------------------------------------------------------------------------------------------------------


def test_model_script_on_the_command_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "script.json"
    path.write_text(json.dumps(NAMED_SCRIPTS["retarget_behind"]))
    out = tmp_path / "out.json"
    assert main(["model", "--script", str(path), "--json", str(out)]) == 0
    got = json.loads(out.read_text())
    assert list(got) == ["tool", "script", "edges", "positions", "rejected", "error"]
    planned = run(NAMED_SCRIPTS["retarget_behind"])
    assert got["tool"] == "model" and got["script"] == NAMED_SCRIPTS["retarget_behind"] and got["error"] is None
    assert got["edges"] == planned.edges and got["positions"] == planned.positions and got["rejected"] == []
    assert got["positions"][-1] == 100
    # invalid scripts: exit 2 with the reason, nothing planned
    path.write_text(json.dumps({**BASE, "commands": [{"at": 0, "op": "spin"}]}))
    assert main(["model", "--script", str(path)]) == 2
    got = json.loads(capsys.readouterr().out)
    assert "unknown op 'spin'" in got["error"] and got["edges"] == []
    path.write_text("{not json")
    assert main(["model", "--script", str(path)]) == 2
    assert "cannot read the script" in json.loads(capsys.readouterr().out)["error"]
    # the move options: required without --script, refused with it
    assert main(["model", "--steps", "10"]) == 2
    assert "required (without --script): --accel" in capsys.readouterr().err
    assert main(["model", "--script", str(path), "--steps", "10"]) == 2
    assert "--script takes no move options (--steps)" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------------------------
# Machine inputs in scripts (issue 16; docs/algorithm.md, "Machine inputs")
# ---------------------------------------------------------------------------------------------------------------


def _filtered(obj: dict[str, Any], pin: str) -> list[int]:
    """Where a clean pin change arrives, from the documented rule alone: F = a + max(FILTER, 1) + 2 for each change
    of `pin` that holds at least N samples (the named scripts' bounces are shorter than N)."""
    n = max(obj.get("inputs", {}).get("filter", 0), 1)
    changes = [c for c in obj["commands"] if c["op"] == "input" and c["name"] == pin]
    out = []
    for c, nxt in zip(changes, [*changes[1:], None], strict=True):
        if nxt is None or nxt["at"] - c["at"] >= n:
            out.append(c["at"] + n + 2)
    return out


def _inputs_named(name: str) -> tuple[dict[str, Any], ScriptResult]:
    obj = NAMED_SCRIPTS[name]
    got = run(obj)
    assert not got.unsure, got.unsure
    return obj, got


def test_named_limit_soft_stop_and_move_away() -> None:
    """LIMIT_POS in RUN: the move's own edges up to the stop's sample at F + 2, then a decel at d to rest: the stop
    distance v^2 / (2 d) from the pulse that decides it, the last interval that of the decel to rest (within 1 %);
    ERROR LIMIT at F + 1; the move away from the active limit runs whole (200 steps back)."""
    obj, got = _inputs_named("limit_soft_in_run")
    (f,) = _filtered(obj, "limit_pos")[:1]
    plain = _plain(600, NAMED_MOVE)
    k = bisect.bisect_right(plain, f + 2)  # the pulses due up to the sample are the move's
    assert got.edges[:k] == plain[:k]
    first_back = _reversals(got.positions)[0]
    v = NAMED_MOVE["speed"] / ALPHA
    stop = v * v / (2.0 * NAMED_MOVE["decel"] / ALPHA)
    assert abs(first_back - (k + 1) - stop) <= 1.5, (first_back, k, stop)
    assert abs(_intervals(got.edges[:first_back])[-1] - _cd0(NAMED_MOVE["decel"])) <= 0.01 * _cd0(NAMED_MOVE["decel"])
    assert got.positions[-1] == got.positions[first_back - 1] - 200
    assert got.errors == [(f + 1, ERROR_CODES["LIMIT"][0])]


def test_named_limit_hard_stop_in_a_jog() -> None:
    """LIMIT_NEG hard-stops a jog down (LIMIT_HARD): no STEP edge after F + 2 (the engine's sample, plus the STEP
    register); a jog further down is refused, one up runs."""
    obj, got = _inputs_named("limit_hard_in_jog")
    f = _filtered(obj, "limit_neg")[0]
    before = [e for e in got.edges if e <= f + 2]
    assert before and not [e for e in got.edges if f + 2 < e < obj["commands"][3]["at"]]
    assert [r["op"] for r in got.rejected] == ["jog"] and "limit_neg is active" in got.rejected[0]["reason"]
    assert got.positions[len(before) - 1] == -len(before)
    assert got.positions[-1] > got.positions[len(before) - 1], "the jog up did not run"


def test_named_estop_and_recover() -> None:
    """ESTOP in RUN: the move's edges up to F + 1 and none after it (the engine samples the stop at F + 1); a move
    during the fault is refused; after the release and clear_fault the next move runs whole (300 steps back)."""
    obj, got = _inputs_named("estop_and_recover")
    f = _filtered(obj, "estop")[0]
    plain = _plain(600, NAMED_MOVE)
    k = bisect.bisect_right(plain, f + 1)
    assert got.edges[:k] == plain[:k] and got.positions[k - 1] == k
    assert all(e > obj["commands"][5]["at"] for e in got.edges[k:]), "a pulse during the fault"
    assert len(got.edges) == k + 300 and got.positions[-1] == k - 300
    assert [r["op"] for r in got.rejected] == ["move"] and "ESTOP" in got.rejected[0]["reason"]
    assert got.errors == [(f + 1, ERROR_CODES["ESTOP"][0])]


def test_named_limit_bounce_is_filtered() -> None:
    """Bounces of 100, 100 and 20 clocks on LIMIT_POS with FILTER 300 reach nothing: the move is stopped by the last,
    clean edge only (its soft stop sampled at F + 2)."""
    obj, got = _inputs_named("limit_bounce")
    f = _filtered(obj, "limit_pos")[-1]
    plain = _plain(600, NAMED_MOVE)
    k = bisect.bisect_right(plain, f + 2)
    assert got.edges[:k] == plain[:k] and len(got.edges) < 600
    assert got.errors == [(f + 1, ERROR_CODES["LIMIT"][0])]


def test_inputs_in_scripts_are_checked() -> None:
    base = {"fclk": 1e6, "spr": 200.0, "commands": []}
    with pytest.raises(ValueError, match="name must be one of"):
        load_script({**base, "commands": [{"at": 0, "op": "input", "name": "probe", "level": 1}]})
    with pytest.raises(ValueError, match="level must be 0 or 1"):
        load_script({**base, "commands": [{"at": 0, "op": "input", "name": "home", "level": 2}]})
    with pytest.raises(ValueError, match="axis 1"):
        load_script({**base, "commands": [{"at": 0, "op": "soft_stop", "axis": 1}]})
    with pytest.raises(ValueError, match="filter"):
        load_script({**base, "inputs": {"filter": 1 << 20}})
