# SPDX-License-Identifier: MIT
"""A command script's schema and loading (docs/algorithm.md, "The take-over, the queue and the script contract"): the
ops and their fields, the clock constants of the contract, the validated Script (load_script), and what the planner
(stepramp.board.script) gives for it: the Actions a testbench plays and the ScriptResult.

A script is a JSON object {"fclk", "spr", "prescale", "commands": [{"at", "op", ...}], "until", "inputs", "ramp"};
load_script checks it and raises ValueError with the reason for a malformed one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, cast

from stepramp.board.change import Change
from stepramp.board.plan import MAX_PRESCALE, RAMP_AVR446, RAMPS, MoveInfo, Plan
from stepramp.board.regmap import ERROR_CODES, REGISTERS_BY_NAME
from stepramp.models.inputs import PINS, filter_length

PREP_CLOCKS = 300
"""The register writes that prepare a command are issued in the PREP_CLOCKS clocks before its commit."""
COMMIT_GAP = 16
"""Least distance in clocks between two committing CTRL writes when the later one needs no other write."""
MARGIN = 2
"""Clocks around an RTL boundary (a START being taken, a soft stop's decision) within which a command is refused."""
EXTRA_CLOCKS = 1000
"""A script without "until" runs to its last edge (or its last command) plus this many clocks."""
CHAIN_MARGIN = 4
"""Clocks between PENDING falling after a queued move's first change (A) and the first write of its second (B)."""


def _ctrl(name: str) -> int:
    return 1 << REGISTERS_BY_NAME["CTRL"].field(name).lsb


START = _ctrl("START")
SOFT_STOP = _ctrl("SOFT_STOP")
HARD_STOP = _ctrl("HARD_STOP")
CHANGE = _ctrl("CHANGE")
QUEUE = _ctrl("QUEUE")

#: Fields of each op: (required, optional). steps and position are integers, the rest numbers (jog: signed speed).
OPS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "move": (("steps", "accel", "decel", "speed"), ()),
    "move_to": (("position",), ("accel", "decel", "speed")),
    "jog": (("speed",), ("accel", "decel")),
    "set": ((), ("speed", "accel", "decel")),
    "queue": (("steps", "accel", "decel", "speed"), ()),
    "soft_stop": ((), ()),
    "hard_stop": ((), ()),
    "input": (("name", "level"), ()),
    "clear_fault": ((), ()),
}
#: Fields any command may carry: the axis of the multi-axis top (0, the only one of a single-axis core).
COMMON_FIELDS = ("axis",)


@dataclass(frozen=True)
class Command:
    """One command of a script: at (the commit edge W), op, and the fields OPS gives it (None: not given)."""

    at: int
    op: str
    steps: int | None = None
    position: int | None = None
    speed: float | None = None
    accel: float | None = None
    decel: float | None = None
    name: str | None = None
    level: int | None = None


@dataclass(frozen=True)
class Script:
    """A validated script (load_script); source is the object it was loaded from."""

    fclk: float
    spr: float
    prescale: int
    commands: tuple[Command, ...]
    until: int | None
    source: dict[str, Any] = field(compare=False, repr=False)
    #: "inputs": INPUT_FILTER in clocks and INPUT_CFG.LIMIT_HARD, written before the first command.
    input_filter: int = 0
    limit_hard: bool = False
    #: "ramp": the core's ramp arithmetic, "avr446" (default) or "exact" (plan.RAMPS).
    ramp: int = RAMP_AVR446


@dataclass(frozen=True)
class Action:
    """What the testbench plays for command `command` (its index in the script; a queued move's second CHANGE, which
    the driver commits itself, has the queue's): the (byte offset, 32-bit value) register writes, in order, in the
    PREP_CLOCKS clocks before `at`, then CTRL byte 0 = ctrl at edge `at`."""

    at: int
    writes: tuple[tuple[int, int], ...]
    ctrl: int
    command: int


@dataclass(frozen=True)
class SuppliedMove:
    """The multi-axis planner's hook for a coordinated move (stepramp.board.multi_script): the axis's `move` takes this
    plan (plan_coordinated's) instead of plan_move's, its writes take the group's `prep` clocks before the commit
    (every axis's writes before one SYNC_START), and its engine starts on the group's common start edge (set by the
    multi-axis planner on the proposal's motion: stepramp.models.stepping.sync_gate_timing)."""

    plan: Plan
    info: MoveInfo
    prep: int = PREP_CLOCKS


@dataclass(frozen=True)
class SuppliedChange:
    """The multi-axis planner's hook for a coordinated stop on the line (stepramp.board.coord.plan_coordinated_stop):
    the axis's `soft_stop` is CTRL.CHANGE committed at `at` (the axis's own write edge W_i), at pulse `pulse` with
    `change`, so that the motion rests on its pulse `rest`; `motion` is the coordinated move's motion, which must
    still run untouched (else the take-over is refused). change None: no action (the axis ends on its target)."""

    at: int
    pulse: int
    change: Change | None
    rest: int
    motion: Any


@dataclass(frozen=True)
class ScriptResult:
    """The planned run: the actions, every STEP rising edge up to `until` (clock edges of the commands' axis), the
    POSITION after each, the refused commands ({"at", "op", "reason"}) and the run's last clock."""

    actions: list[Action]
    edges: list[int]
    positions: list[int]
    rejected: list[dict[str, Any]]
    until: int
    #: (after edge a, pin, level): the input pins to drive (level after polarity, 1: active).
    pins: list[tuple[int, str, int]] = field(default_factory=list)
    #: The core's errors the model predicts, (edge, ERR_CODE), as STATUS shows them: the first, then each change.
    errors: list[tuple[int, int]] = field(default_factory=list)
    #: Input effects the model cannot time exactly (within MARGIN of a START being taken, of a soft stop's decision
    #: or of a take-over): a script with any is not played on the RTL.
    unsure: list[str] = field(default_factory=list)
    #: The script's "inputs": INPUT_FILTER and INPUT_CFG.LIMIT_HARD for the testbench to write before the first
    #: command.
    input_filter: int = 0
    limit_hard: bool = False


# ---------------------------------------------------------------------------------------------------------------
# Loading
# ---------------------------------------------------------------------------------------------------------------


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _positive(where: str, name: str, value: object) -> float:
    if not _is_number(value) or cast(float, value) <= 0:
        raise ValueError(f"{where}: {name} must be a finite number > 0, got {value!r}")
    return float(cast(float, value))


def _load_command(n: int, raw: object, previous_at: int) -> Command:
    where = f"command {n}"
    if not isinstance(raw, dict):
        raise ValueError(f"{where}: must be an object, got {type(raw).__name__}")
    at, op = raw.get("at"), raw.get("op")
    if not _is_int(at):
        raise ValueError(f"{where}: 'at' must be an integer clock edge, got {at!r}")
    at = cast(int, at)
    if at < 0:
        raise ValueError(f"{where}: 'at' must be >= 0, got {at}")
    if at < previous_at:
        raise ValueError(f"{where}: 'at' = {at} is before the previous command's {previous_at} (not in order)")
    if op not in OPS:
        raise ValueError(f"{where}: unknown op {op!r} (one of {', '.join(OPS)})")
    where = f"command {n} ({op} at {at})"
    required, optional = OPS[op]
    unknown = sorted(set(raw) - {"at", "op", *required, *optional, *COMMON_FIELDS})
    if unknown:
        raise ValueError(f"{where}: unknown field(s) {', '.join(unknown)}")
    missing = [name for name in required if name not in raw]
    if missing:
        raise ValueError(f"{where}: missing field(s) {', '.join(missing)}")
    if raw.get("axis", 0) != 0:
        raise ValueError(f"{where}: axis {raw['axis']!r}: a single-axis script has axis 0 only")
    if op == "set" and not any(name in raw for name in optional):
        raise ValueError(f"{where}: set needs at least one of {', '.join(optional)}")
    fields: dict[str, Any] = {}
    for name in (*required, *optional):
        if name not in raw:
            continue
        value = raw[name]
        if name == "name":
            if value not in PINS:
                raise ValueError(f"{where}: name must be one of {', '.join(PINS)}, got {value!r}")
            fields[name] = value
        elif name == "level":
            if value not in (0, 1) or isinstance(value, bool):
                raise ValueError(f"{where}: level must be 0 or 1, got {value!r}")
            fields[name] = value
        elif name in ("steps", "position"):
            if not _is_int(value):
                raise ValueError(f"{where}: {name} must be an integer, got {value!r}")
            fields[name] = value
        elif op == "jog" and name == "speed":
            if not _is_number(value):
                raise ValueError(f"{where}: speed must be a finite number (rad/s, signed), got {value!r}")
            fields[name] = float(value)
        else:
            fields[name] = _positive(where, name, value)
    return Command(at=at, op=cast(str, op), **fields)


def load_script(obj: dict[str, Any]) -> Script:
    """Validate a script object {"fclk", "spr", "prescale" (default 1), "commands": [...], "until" (optional)};
    ValueError with the reason when it is malformed (unknown op or key, missing field, wrong type, `at` out of
    order or after `until`)."""
    if not isinstance(obj, dict):
        raise ValueError(f"a script must be an object, got {type(obj).__name__}")
    unknown = sorted(set(obj) - {"fclk", "spr", "prescale", "commands", "until", "inputs", "ramp"})
    if unknown:
        raise ValueError(f"unknown key(s) {', '.join(unknown)}")
    for name in ("fclk", "spr", "commands"):
        if name not in obj:
            raise ValueError(f"missing key {name!r}")
    fclk = _positive("script", "fclk", obj["fclk"])
    spr = _positive("script", "spr", obj["spr"])
    prescale = obj.get("prescale", 1)
    if not _is_int(prescale) or not 1 <= prescale <= MAX_PRESCALE:
        raise ValueError(f"script: prescale must be an integer in 1 .. {MAX_PRESCALE}, got {prescale!r}")
    until = obj.get("until")
    if until is not None and (not _is_int(until) or until < 0):
        raise ValueError(f"script: until must be an integer clock edge >= 0, got {until!r}")
    raw_commands = obj["commands"]
    if not isinstance(raw_commands, list):
        raise ValueError(f"script: commands must be a list, got {type(raw_commands).__name__}")
    commands: list[Command] = []
    for n, raw in enumerate(raw_commands):
        commands.append(_load_command(n, raw, commands[-1].at if commands else 0))
    if until is not None and commands and commands[-1].at > until:
        raise ValueError(f"script: command {len(commands) - 1} at {commands[-1].at} is after until = {until}")
    inputs = obj.get("inputs", {})
    if not isinstance(inputs, dict) or set(inputs) - {"filter", "limit_hard"}:
        raise ValueError(f"script: inputs must be an object with 'filter' and 'limit_hard', got {inputs!r}")
    input_filter = inputs.get("filter", 0)
    try:
        filter_length(input_filter)
    except ValueError as why:
        raise ValueError(f"script: inputs: {why}") from None
    limit_hard = inputs.get("limit_hard", False)
    if not isinstance(limit_hard, bool):
        raise ValueError(f"script: inputs: limit_hard must be true or false, got {limit_hard!r}")
    ramp = obj.get("ramp", "avr446")
    if ramp not in RAMPS:
        raise ValueError(f"script: ramp must be one of {', '.join(sorted(RAMPS))}, got {ramp!r}")
    return Script(fclk, spr, prescale, tuple(commands), until, obj, input_filter, limit_hard, RAMPS[ramp])


def core_rejections(errors: list[tuple[int, int]] | list[list[int]]) -> list[dict[str, Any]]:
    """The core's errors, (edge, ERR_CODE) as the RTL flagged them or the model predicts them, as "rejected" entries
    ({"at", "op": "core", "reason"})."""
    names = {code: name for name, (code, _) in ERROR_CODES.items()}
    return [{"at": at, "op": "core", "reason": f"the core flagged {names.get(code, str(code))}"} for at, code in errors]
