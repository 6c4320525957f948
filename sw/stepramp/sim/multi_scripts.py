# SPDX-License-Identifier: MIT
"""Test material for the multi-axis script planner (stepramp.board.multi_script) and the multi-axis RTL benches:
random multi-axis scripts and the named ones (the issues' cases)."""

from __future__ import annotations

import random
from typing import Any

from stepramp.board.multi_script import plan_multi_script
from stepramp.sim.scripts import random_script


def random_multi_script(rng: random.Random, axes: int = 3, tries: int = 20) -> dict[str, Any]:
    """A random multi-axis script: a short random single-axis script per axis (stepramp.sim.scripts.random_script,
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

_QUICK: dict[str, float] = {"accel": 36_000.0, "decel": 36_000.0}
_PATH: dict[str, float] = {"speed": 300.0, "accel": 12_000.0, "decel": 2_000.0}
"""The coordinated stop's path: accel = 6 decel, so that a SYNC_SOFT_STOP in ACCEL leaves the line by steps."""

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
    "sync_soft_stop": {
        "fclk": 1e6,
        "spr": 200.0,
        "prescale": 1,
        "axes": 3,
        "until": 50_000,
        "commands": [
            {"at": 0, "op": "move", "axis": 0, "steps": 400, "speed": 300.0, **_FAST},
            {"at": 400, "op": "move", "axis": 1, "steps": -300, "speed": 300.0, "accel": 3_000.0, "decel": 9_000.0},
            {"at": 22_000, "op": "sync_soft_stop", "axes": [0, 1, 2]},
            {"at": 24_000, "op": "move", "axis": 2, "steps": 60, "speed": 300.0, **_FAST},
        ],
    },
    # a coordinated move that changes DIR on two axes (one SYNC_START, every axis's last pulse on one edge), then one
    # back that changes DIR on all three, stopped on the line in its ACCEL (accel = 6 decel): each axis's CHANGE from
    # plan_coordinated_stop, 300 clocks apart (one SYNC_SOFT_STOP there leaves axis 1 5.6 steps off the line)
    "coordinated_stop_on_the_line": {
        "fclk": 1e6,
        "spr": 200.0,
        "prescale": 1,
        "axes": 3,
        "commands": [
            {"at": 600, "op": "move", "axes": [0, 1, 2], "steps": [60, -38, -20], "speed": 300.0, **_QUICK},
            {"at": 20_000, "op": "move", "axes": [0, 1, 2], "steps": [-300, 180, 61], **_PATH},
            {"at": 23_000, "op": "soft_stop", "axes": [0, 1, 2]},
        ],
    },
}
