# SPDX-License-Identifier: MIT
"""Test material for the script planner (stepramp.board.script) and the RTL benches: random scripts (the regression)
and named scripts (the issue's cases, with what must happen: sw/tests/test_script.py asserts it from physics)."""

from __future__ import annotations

import math
import random
from typing import Any

from stepramp.board.script_schema import COMMIT_GAP, PREP_CLOCKS

RANDOM_FCLK = 1e6
RANDOM_SPR = 200.0
RANDOM_INTERVALS = (70.0, 400.0)
"""Cruise intervals (clocks) of the random scripts' speeds."""
RANDOM_RAMPS = (8.0, 80.0)
"""Ramp lengths (steps) of the random scripts' accels and decels, at the speed they come with."""
RANDOM_SPACING = (300, 5_000)
"""Clocks between two commands of a random script."""
RANDOM_SPAN = 30_000
"""A random script's until is at most this many clocks."""

_ALPHA = 2.0 * math.pi / RANDOM_SPR


def _random_speed(rng: random.Random) -> float:
    """A speed in rad/s whose cruise interval is log-uniform in RANDOM_INTERVALS."""
    interval = math.exp(rng.uniform(*map(math.log, RANDOM_INTERVALS)))
    return round(RANDOM_FCLK / interval * _ALPHA, 3)


def _random_rate(rng: random.Random, speed: float) -> float:
    """An accel or decel in rad/s^2 whose ramp to `speed` (rad/s) is log-uniform in RANDOM_RAMPS steps."""
    steps = math.exp(rng.uniform(*map(math.log, RANDOM_RAMPS)))
    return round(speed * speed / (2.0 * steps * _ALPHA), 3)


def _move_clocks(cmd: dict[str, Any]) -> float:
    """Clocks a random script's move command takes from rest to rest (its ideal trapezoid at RANDOM_FCLK)."""
    length = max(abs(cmd["steps"]) - 1, 0)
    v, a, d = cmd["speed"] / _ALPHA, cmd["accel"] / _ALPHA, cmd["decel"] / _ALPHA
    n_a, n_d = v * v / (2.0 * a), v * v / (2.0 * d)
    if n_a + n_d > length:
        v = math.sqrt(2.0 * a * d * length / (a + d))
        return RANDOM_FCLK * (v / a + v / d)
    return RANDOM_FCLK * (v / a + v / d + (length - n_a - n_d) / v)


def random_script(rng: random.Random, n_commands: int = 6) -> dict[str, Any]:
    """A random script for the regression: fclk 1 MHz, 200 steps/rev, prescale 1; speeds with cruise intervals of
    RANDOM_INTERVALS clocks, accels and decels with ramps of RANDOM_RAMPS steps at the speed they come with, commands
    RANDOM_SPACING clocks apart, until at most RANDOM_SPAN clocks (short: the bus tops simulate at about 30,000
    clocks/s, and the regression plays 200 scripts through each). Every op appears across scripts; a jog is often
    followed by a jog the other way (through zero), a stop or a speed change; a queue mostly goes the way of the
    move before it, and a first move short enough to end within the span is often followed by a queue written
    while it runs (a queued move without a stop between them, or, written late, from rest)."""
    speed = _random_speed(rng)
    commands: list[dict[str, Any]] = []
    at = 0
    jogging = 0  # the sign of the last jog command (0: none since a stop or a move)
    heading = 0  # the sign of the last move or queue (0: none, or a move_to, jog or stop since)
    first = rng.choice(["move", "move_to", "jog", "jog", "queue"])
    ends = 0.0  # with a queue while the first move runs: that move's last pulse, about
    for n in range(n_commands):
        chain = n == 1 and commands[0]["op"] in ("move", "queue") and rng.random() < 0.6
        if chain:  # a queue while the first move runs (shortened to end within half the span)
            move = commands[0]
            while _move_clocks(move) > RANDOM_SPAN * 0.5 and abs(move["steps"]) > 1:
                move["steps"] = int(math.copysign(max(abs(move["steps"]) * 7 // 10, 1), move["steps"]))
            ends = _move_clocks(move)
            chain = ends > 2.0 * (PREP_CLOCKS + COMMIT_GAP)
            if chain:
                at = max(int(ends * rng.uniform(0.2, 1.0)), PREP_CLOCKS + COMMIT_GAP)
        if n and not chain:
            if n == 2 and ends and rng.random() < 0.6:  # most queued moves run on past their boundary
                at = max(at, int(ends))
            at += int(math.exp(rng.uniform(*map(math.log, RANDOM_SPACING))))
            if at > RANDOM_SPAN * 0.85:
                break
        if n == 0:
            op = first
        elif chain:
            op = "queue"
        elif jogging:
            op = rng.choice(["jog", "jog", "soft_stop", "hard_stop", "set", "move_to", "queue"])
        else:
            op = rng.choice(["move", "move_to", "move_to", "jog", "set", "set", "queue", "soft_stop", "hard_stop"])
        cmd: dict[str, Any] = {"at": at, "op": op}
        full = n == 0 or op in ("move", "queue") or rng.random() < 0.5
        if op in ("move", "queue", "move_to", "jog", "set") and (full or op in ("move", "queue")):
            speed = _random_speed(rng)
            cmd |= {"speed": speed, "accel": _random_rate(rng, speed), "decel": _random_rate(rng, speed)}
        elif op == "set":
            cmd[rng.choice(["speed", "accel", "decel"])] = (
                _random_rate(rng, speed) if rng.random() < 0.6 else _random_speed(rng)
            )
            if "speed" in cmd:
                speed = cmd["speed"]
        if op in ("move", "queue"):
            sign = heading if op == "queue" and heading and rng.random() < 0.7 else rng.choice([-1, 1])
            cmd["steps"] = sign * rng.randint(1, 300)
            jogging, heading = 0, sign
        elif op == "move_to":
            cmd["position"] = rng.randint(-400, 400)
            jogging = heading = 0
        elif op == "jog":
            if rng.random() < 0.12:
                cmd["speed"] = 0.0
            else:
                sign = -jogging if jogging and rng.random() < 0.6 else rng.choice([-1, 1])
                cmd["speed"] = sign * cmd.get("speed", speed)
            jogging = int(math.copysign(1, cmd["speed"])) if cmd["speed"] else 0
        if op in ("jog", "soft_stop", "hard_stop"):
            heading = 0
        if op in ("soft_stop", "hard_stop"):
            jogging = 0
        commands.append(cmd)
    until = min(at + rng.randint(3_000, 12_000), RANDOM_SPAN)
    out: dict[str, Any] = {"fclk": RANDOM_FCLK, "spr": RANDOM_SPR, "prescale": 1, "commands": commands, "until": until}
    if rng.random() < RANDOM_INPUTS:
        _random_inputs(rng, out)
    return out


RANDOM_INPUTS = 0.35
"""The share of random scripts that also drive the machine inputs (_random_inputs)."""


def _random_inputs(rng: random.Random, script: dict[str, Any]) -> None:
    """One or two pins of a random script switched on, sometimes with a bounce shorter than the filter first, and
    off again after a while; after ESTOP, sometimes a clear_fault. The filter is 0 .. 200 clocks, the limits soft or
    hard."""
    filter_clocks = rng.choice([0, 1, 4, 30, 200])
    script["inputs"] = {"filter": filter_clocks, "limit_hard": rng.random() < 0.4}
    until = script["until"]
    added: list[dict[str, Any]] = []
    for _ in range(rng.randint(1, 2)):
        pin = rng.choice(["limit_neg", "limit_pos", "limit_neg", "limit_pos", "estop", "home"])
        t = rng.randrange(300, max(until - 300, 301))
        if filter_clocks >= 4 and rng.random() < 0.3:  # a bounce: shorter than the filter, then the real edge
            for _ in range(rng.randint(1, 3)):
                width = rng.randint(1, filter_clocks - 1)
                added += [
                    {"at": t, "op": "input", "name": pin, "level": 1},
                    {"at": t + width, "op": "input", "name": pin, "level": 0},
                ]
                t += width + rng.randint(1, filter_clocks - 1)
        added.append({"at": t, "op": "input", "name": pin, "level": 1})
        off = t + rng.randint(50, 8_000)
        if off < until:
            added.append({"at": off, "op": "input", "name": pin, "level": 0})
            if pin == "estop" and rng.random() < 0.7 and off + 3 * PREP_CLOCKS < until:
                added.append({"at": off + rng.randint(2 * PREP_CLOCKS, 3 * PREP_CLOCKS), "op": "clear_fault"})
    # a bounce can carry an edge past the end: the script ends there (a command after `until` is not a script)
    added = [cmd for cmd in added if cmd["at"] <= until]
    script["commands"] = sorted([*script["commands"], *added], key=lambda c: c["at"])


_NAMED_BASE: dict[str, Any] = {"fclk": 1e6, "spr": 200.0, "prescale": 1}
_MOVE: dict[str, float] = {"accel": 2000.0, "decel": 2000.0, "speed": 100.0}
"""100 rad/s (3183 steps/s, 314 clocks a step), ramps of 80 steps (50,000 clocks) at 2000 rad/s^2: a 600-step move is
in ACCEL until about edge 50,000 (pulse 80), in RUN until about 188,000 (pulse 520), in DECEL until 238,000."""
_JOG: dict[str, float] = {"accel": 2000.0, "decel": 2000.0}


NAMED_SCALE = 3
"""The named scripts run NAMED_SCALE times faster than their comments say (speeds x3, accels and decels x9, times
/3): the same pulses, a third of the clocks to simulate."""


def _named(*commands: dict[str, Any], until: int | None = None, inputs: dict[str, Any] | None = None) -> dict[str, Any]:
    scaled = []
    for cmd in commands:
        out_cmd = dict(cmd, at=cmd["at"] // NAMED_SCALE)
        if "speed" in cmd:
            out_cmd["speed"] = cmd["speed"] * NAMED_SCALE
        for key in ("accel", "decel"):
            if key in cmd:
                out_cmd[key] = cmd[key] * NAMED_SCALE**2
        scaled.append(out_cmd)
    out: dict[str, Any] = {**_NAMED_BASE, "commands": scaled}
    if inputs is not None:
        out["inputs"] = inputs
    if until is not None:
        out["until"] = until // NAMED_SCALE
    return out


#: The issue's cases as scripts (the RTL tests play them too), each with what must happen (sw/tests/test_script.py
#: asserts it from physics).
NAMED_SCRIPTS: dict[str, dict[str, Any]] = {
    # a 600-step move, faster (150 rad/s) in RUN: the same pulses up to P, 209 clocks a step after, ends sooner at 600
    "speed_up_in_run": _named(
        {"at": 0, "op": "move", "steps": 600, **_MOVE}, {"at": 80_000, "op": "set", "speed": 150.0}
    ),
    # slower (50 rad/s) in RUN: never faster than before, 628 clocks a step, ends later at 600
    "slow_down_in_run": _named(
        {"at": 0, "op": "move", "steps": 600, **_MOVE}, {"at": 80_000, "op": "set", "speed": 50.0}
    ),
    # in ACCEL (pulse 14 of 80): a faster speed at twice the accel, the ramp goes on to 150 rad/s, ends at 600
    "change_in_accel": _named(
        {"at": 0, "op": "move", "steps": 600, **_MOVE},
        {"at": 20_000, "op": "set", "speed": 150.0, "accel": 4000.0},
    ),
    # in DECEL (pulse 554): a decel twice as strong, the last step that of the new decel, ends at 600
    "change_in_decel": _named(
        {"at": 0, "op": "move", "steps": 600, **_MOVE}, {"at": 200_000, "op": "set", "decel": 4000.0}
    ),
    # at 100,000 (position 239) to 270, inside the 80-step stop distance: stop beyond it, reverse, end on 270
    "retarget_inside_stop_distance": _named(
        {"at": 0, "op": "move", "steps": 600, **_MOVE}, {"at": 100_000, "op": "move_to", "position": 270}
    ),
    # to 100, behind the motor: stop, reverse, end exactly on 100
    "retarget_behind": _named(
        {"at": 0, "op": "move", "steps": 600, **_MOVE}, {"at": 100_000, "op": "move_to", "position": 100}
    ),
    # jog up, then down at the same speed: decel to rest, DIR changes once, the count goes down through zero; a
    # soft stop ends it
    "jog_through_zero": _named(
        {"at": 0, "op": "jog", "speed": 100.0, **_JOG},
        {"at": 100_000, "op": "jog", "speed": -100.0},
        {"at": 300_000, "op": "soft_stop"},
    ),
    # a jog faster in its ACCEL, slower (and a weaker decel) in RUN, then to a target ahead: ends on 900
    "jog_changes": _named(
        {"at": 0, "op": "jog", "speed": 100.0, **_JOG},
        {"at": 30_000, "op": "jog", "speed": 150.0},
        {"at": 100_000, "op": "set", "speed": 60.0, "decel": 1000.0},
        {"at": 160_000, "op": "move_to", "position": 900},
    ),
    # 300 steps, then 200 more queued at 60 rad/s: no stop between them, the motor passes 300 at the boundary speed
    # min(100, 60, sqrt(2 d 200)) = 60 rad/s (change A at P towards a virtual rest 28 steps past 300, change B at
    # pulse 299, position 300), ends at 500
    "queue_same_direction": _named(
        {"at": 0, "op": "move", "steps": 300, **_MOVE},
        {"at": 50_000, "op": "queue", "steps": 200, **_MOVE, "speed": 60.0},
    ),
    # 300 steps, then 200 back queued: DIR changes, the second starts 7 clocks after the first's last pulse, ends at 100
    "queue_opposite_direction": _named(
        {"at": 0, "op": "move", "steps": 300, **_MOVE}, {"at": 50_000, "op": "queue", "steps": -200, **_MOVE}
    ),
    # a soft stop in a jog's RUN: ceil(v^2 / (2 d)) = 80 steps after the pulse that decides it
    "soft_stop_in_jog": _named({"at": 0, "op": "jog", "speed": 100.0, **_JOG}, {"at": 120_000, "op": "soft_stop"}),
    # a hard stop in a jog (down): no pulse after the write's next edge
    "hard_stop_in_jog": _named({"at": 0, "op": "jog", "speed": -100.0, **_JOG}, {"at": 120_000, "op": "hard_stop"}),
    # issue 16. LIMIT_POS in RUN (filter 30 clocks): a soft stop committed at F + 1, the decel's 80 steps past it;
    # then a move away (allowed with the limit active), during which the switch releases
    "limit_soft_in_run": _named(
        {"at": 0, "op": "move", "steps": 600, **_MOVE},
        {"at": 100_000, "op": "input", "name": "limit_pos", "level": 1},
        {"at": 200_000, "op": "move", "steps": -200, **_MOVE},
        {"at": 230_000, "op": "input", "name": "limit_pos", "level": 0},
        inputs={"filter": 30},
    ),
    # LIMIT_NEG hard-stops a jog down: no pulse after F + 2; a jog further down is refused while the limit is
    # active, a jog up runs and is soft-stopped
    "limit_hard_in_jog": _named(
        {"at": 0, "op": "jog", "speed": -100.0, **_JOG},
        {"at": 120_000, "op": "input", "name": "limit_neg", "level": 1},
        {"at": 150_000, "op": "jog", "speed": -100.0},
        {"at": 160_000, "op": "jog", "speed": 100.0},
        {"at": 200_000, "op": "input", "name": "limit_neg", "level": 0},
        {"at": 250_000, "op": "soft_stop"},
        until=330_000,
        inputs={"filter": 5, "limit_hard": True},
    ),
    # ESTOP in RUN: no pulse after F + 1; a move is refused during the fault, runs once ESTOP is released and the
    # fault cleared
    "estop_and_recover": _named(
        {"at": 0, "op": "move", "steps": 600, **_MOVE},
        {"at": 100_000, "op": "input", "name": "estop", "level": 1},
        {"at": 120_000, "op": "move", "steps": 100, **_MOVE},
        {"at": 130_000, "op": "input", "name": "estop", "level": 0},
        {"at": 140_000, "op": "clear_fault"},
        {"at": 150_000, "op": "move", "steps": -300, **_MOVE},
        inputs={"filter": 12},
    ),
    # LIMIT_POS bounces (active for 100, 100 and 20 clocks after scaling, filter 300) before it closes for good:
    # only the last edge stops the move
    "limit_bounce": _named(
        {"at": 0, "op": "move", "steps": 600, **_MOVE},
        {"at": 100_000, "op": "input", "name": "limit_pos", "level": 1},
        {"at": 100_300, "op": "input", "name": "limit_pos", "level": 0},
        {"at": 100_600, "op": "input", "name": "limit_pos", "level": 1},
        {"at": 100_900, "op": "input", "name": "limit_pos", "level": 0},
        {"at": 101_200, "op": "input", "name": "limit_pos", "level": 1},
        {"at": 101_260, "op": "input", "name": "limit_pos", "level": 0},
        {"at": 120_000, "op": "input", "name": "limit_pos", "level": 1},
        inputs={"filter": 300},
    ),
}
