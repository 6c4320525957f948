# SPDX-License-Identifier: MIT
"""The driver's planner for a command script, which is also the model's prediction of every STEP edge.

docs/algorithm.md, "The take-over, the queue and the script contract (issue 15)". A script is a list of commands
(move, move_to, jog, set, queue, soft_stop, hard_stop) at clock edges; the driver turns each into register writes
and one committing CTRL write (an Action: START, CHANGE at a pulse P, QUEUE, SOFT_STOP, HARD_STOP, or SOFT_STOP and
QUEUE for a reversal) from its own model of the motion, and the same model gives every STEP rising edge and the
POSITION after it. A move queued in the running motion's direction is two CHANGEs, the second one committed by the
driver itself (an action with the queue's index, unless a stop comes first). The testbench plays the actions on the
RTL and compares.

Clock axis: edge W of a command is the edge at which the register file samples its CTRL write; the strobe acts at
W + 1 (the start gate's request, the engine's CHANGE and stop sampling). A START at W: start_edge s from the start
gate (stepramp.models.stepping.gate_timing, the driver's default outputs), the engine's edge 0 at s + 1, the STEP
pin rising for pulse k at s + 4 + prescale * T_k; pulse k's engine edge is one clock earlier.

Where the RTL's behaviour at a boundary is not pinned down by the contract (a command within a few clocks of a
START being taken, of a soft stop's decision or of pulse P - 1), the planner refuses the command (listed in
`rejected`) rather than guess: the testbench never plays an action whose outcome the model is not sure of.
"""

from __future__ import annotations

import bisect
import math
import random
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any, cast

from stepramp.board.change import Change, Segment, plan_change, speed_at_pulse, speed_at_segment_pulse
from stepramp.board.driver import NO_SEGMENT, Outputs, RegisterAccess, StepRamp, plan_writes, segment_writes
from stepramp.board.plan import (
    FRAC_CRUISE,
    MAX_PRESCALE,
    RAMP_AVR446,
    RAMPS,
    MoveInfo,
    Plan,
    plan_move_info,
    steps_units,
)
from stepramp.board.regmap import ERROR_CODES, REGISTERS_BY_NAME, offset
from stepramp.models.engine import change_pulse, segment_runs, segment_stop_values, start_acc
from stepramp.models.inputs import PINS, filter_length, filtered_edges
from stepramp.models.stepping import START_TO_FIRST_STEP, GateTiming, gate_timing

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

_FRAC_MASK = (1 << FRAC_CRUISE) - 1
_PHYSICAL = ("speed", "accel", "decel")

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


# ---------------------------------------------------------------------------------------------------------------
# The motion model
# ---------------------------------------------------------------------------------------------------------------


class _RejectError(Exception):
    """A command the driver refuses (listed in ScriptResult.rejected; nothing changes)."""


def _motion_args(phys: dict[str, float], s: Script) -> tuple[float, float, float, float, float, int, int]:
    """(accel, decel, speed, spr, fclk, prescale, ramp): plan_change's arguments after u and the remaining steps."""
    return phys["accel"], phys["decel"], phys["speed"], s.spr, s.fclk, s.prescale, s.ramp


def _driver_call(fn: Callable[..., Any], *args: Any) -> Any:
    """A driver planning call, its ValueError as a rejection with the driver's reason."""
    try:
        return fn(*args)
    except ValueError as err:
        raise _RejectError(str(err)) from err


def _phys(v: dict[str, float], speed: float | None = None) -> dict[str, float]:
    """The speed (or `speed`), accel and decel of the values in force v."""
    return {"speed": v["speed"] if speed is None else speed, "accel": v["accel"], "decel": v["decel"]}


@dataclass
class _Part:
    """A piece of a motion: the segment that runs from the motion's pulse `pulse` (its pulse 0) on; values: the
    interval values that replace the segment's own once a soft stop is decided in it. commit / pending: the CHANGE
    that took it over (None for the part a START began) and its PENDING span [commit, E + 2]. phys: the speed,
    accel and decel (rad/s, rad/s^2) the segment was planned with."""

    pulse: int
    seg: Segment
    speed: Callable[[int], float]
    target: int | None
    values: list[int] | None = None
    commit: int | None = None
    pending: list[int] | None = None
    phys: dict[str, float] | None = None

    def value_iter(self) -> Iterator[int]:
        if self.values is not None:
            yield from self.values
            return
        for value, count in segment_runs(self.seg):
            for _ in range(count):
                yield value


@dataclass
class _Stop:
    """A soft stop: sampled by the engine at `sample`, decided at the engine edge `decided` (of pulse p, or the
    sample when there is no pulse left), in effect or ignored."""

    sample: int
    decided: int
    effective: bool


class _Motion:
    """One motion from a START (or a queued START) to its end: parts taken over at pulses, a soft or hard stop. Its
    STEP edges are generated lazily (an endless jog only as far as asked) and cached until it changes."""

    def __init__(self, gate: GateTiming, direction: int, origin: int, prescale: int, part: _Part) -> None:
        self.request = gate.request
        self.start_edge = gate.start_edge
        self.direction = direction
        self.sign = -1 if direction else 1
        self.origin = origin
        self.prescale = prescale
        self.parts = [part]
        self.hard: int | None = None
        self.stop: _Stop | None = None
        self.queue_pending: list[int] | None = None
        self.limit_hit = False  # a limit stopped it (once per motion)
        self.drops: list[tuple[list[int], int]] = []  # PENDING spans a soft stop on this copy ends: (span, edge)
        self._edges: list[int] = []
        self._gen: Iterator[int] | None = None
        self._done = False

    def clone(self) -> _Motion:
        twin = _Motion.__new__(_Motion)
        twin.__dict__.update(self.__dict__)
        twin.parts = [_Part(**p.__dict__) for p in self.parts]
        twin.drops = []
        twin._edges, twin._gen, twin._done = [], None, False
        return twin

    @property
    def target(self) -> int | None:
        return self.parts[-1].target

    @property
    def endless(self) -> bool:
        last = self.parts[-1]
        return self.hard is None and last.values is None and last.seg.length is None

    def changed(self) -> None:
        self._gen = None

    def _values(self) -> Iterator[int]:
        for n, part in enumerate(self.parts):
            values = part.value_iter()
            if n + 1 < len(self.parts):
                count = self.parts[n + 1].pulse - part.pulse
                for _ in range(count):
                    yield next(values)
            else:
                yield from values

    def _generate(self) -> Iterator[int]:
        base = self.start_edge + START_TO_FIRST_STEP
        limit = None if self.hard is None else self.hard + 1  # the pulses whose engine edge is <= the hard stop's W
        t, acc = 0, start_acc(self.parts[0].seg.ramp)
        edge = base
        for value in self._values():
            if limit is not None and edge > limit:
                return
            yield edge
            s = acc + value
            t += s >> FRAC_CRUISE
            acc = s & _FRAC_MASK
            edge = base + self.prescale * t
        if limit is None or edge <= limit:
            yield edge

    def upto(self, clock: float) -> list[int]:
        """The STEP edges, generated past `clock` (one edge beyond it) or to the end."""
        if self._gen is None:
            self._gen, self._edges, self._done = self._generate(), [], False
        while not self._done and (not self._edges or self._edges[-1] <= clock):
            edge = next(self._gen, None)
            if edge is None:
                self._done = True
            else:
                self._edges.append(edge)
        return self._edges

    def more(self) -> bool:
        """One more edge generated (False at the end)."""
        edges = self.upto(-math.inf)
        n = len(edges)
        return len(self.upto(edges[-1] if edges else -math.inf)) > n

    def all_edges(self) -> list[int]:
        if self.endless:
            raise ValueError("an endless jog has no last edge")
        return self.upto(math.inf)

    def moving(self, w: int) -> bool:
        """Whether a command written at edge w finds the motion running (w <= its last STEP edge - 1)."""
        if self.hard is not None and w > self.hard:
            return False
        edges = self.upto(w)
        return bool(edges) and edges[-1] > w

    def stopping(self, w: int) -> bool:
        """A soft stop in effect, or requested and not yet decided (a change would be refused)."""
        return self.stop is not None and (self.stop.effective or w + 1 <= self.stop.decided + MARGIN)

    def end_position(self) -> int:
        return self.origin + self.sign * len(self.all_edges())


# ---------------------------------------------------------------------------------------------------------------
# The planner
# ---------------------------------------------------------------------------------------------------------------


@dataclass
class _Proposal:
    """An action not yet committed: its writes and CTRL bits, and what it does to the model once accepted."""

    writes: list[tuple[int, int]]
    ctrl: int
    apply: Callable[[], None]


@dataclass
class _Chained:
    """Change B of a queued move in the same direction (_Run.chain_proposal): the driver commits it at `at` (CTRL
    write of CHANGE, its writes in the PREP_CLOCKS before) unless a stop is written first. reserved: the span the
    staging is kept for it, from its first write to its own PENDING's end; command: the queue's index."""

    at: int
    writes: tuple[tuple[int, int], ...]
    apply: Callable[[], None]
    reserved: list[int]
    command: int


class _Run:
    """The planner's state while it goes through the commands in order."""

    def __init__(self, script: Script) -> None:
        self.script = script
        self.outputs = Outputs()
        self.driver = StepRamp(cast(RegisterAccess, None), script.fclk, script.spr, script.prescale, script.ramp)
        self.force: dict[str, float] = {}
        self.motions: list[_Motion] = []
        self.actions: list[Action] = []
        self.rejected: list[dict[str, Any]] = []
        self.pending: list[list[int]] = []  # PENDING spans [from, to] of changes and queued moves
        self.chained: _Chained | None = None  # a queued move's change B, not committed yet
        self.index = 0  # the command being planned
        # The machine inputs (docs/algorithm.md, "Machine inputs"): each pin's filtered edges, and their effects in
        # time order, (edge it acts at, pin, level, filtered edge F): a limit's stop is committed at F + 1, ESTOP's
        # hard stop at F.
        self.pins: list[tuple[int, str, int]] = [
            (c.at, cast(str, c.name), cast(int, c.level)) for c in script.commands if c.op == "input"
        ]
        self.filtered: dict[str, list[tuple[int, int]]] = {
            pin: filtered_edges([(a, lv) for a, name, lv in self.pins if name == pin], script.input_filter)
            for pin in PINS
        }
        self.events = sorted(
            (f + (0 if pin == "estop" else 1), pin, level, f) for pin in PINS for f, level in self.filtered[pin]
        )
        self.fault = False
        self.errors: list[tuple[int, int]] = []
        self.unsure: list[str] = []

    # -- the machine inputs -------------------------------------------------------------------------------------

    def level_at(self, pin: str, edge: int) -> int:
        """The pin's filtered level after edge `edge` (what the register file samples at edge + 1)."""
        level = 0
        for f, value in self.filtered[pin]:
            if f > edge:
                break
            level = value
        return level

    def limit_towards(self, direction: int, w: int) -> str | None:
        """The limit that guards `direction` (1: LIMIT_NEG) if it is active for a command committed at w."""
        pin = "limit_neg" if direction else "limit_pos"
        return pin if self.level_at(pin, w - 1) else None

    def input_events(self, upto: float) -> None:
        """Apply the inputs' effects that act before edge `upto`."""
        while self.events and self.events[0][0] < upto:
            w, pin, level, f = self.events.pop(0)
            if pin == "home" or level == 0:
                continue  # (HOME: the latch only; a release stops nothing, and the fault stays)
            if self.chained is not None:  # (the driver would not know of it; the script is not played)
                self.unsure.append(f"{pin} at filtered edge {f} before a queued move's second change")
                self.pending.remove(self.chained.reserved)
                self.chained = None
            try:
                cur, queued = self.situation(w)
                if pin == "estop":
                    self.fault = True
                    self.errors.append((f + 1, ERROR_CODES["ESTOP"][0]))
                    if cur is not None:
                        self.hard_stop(cur, queued, w)
                    else:
                        self.drop_queue(queued, w)
                    continue
                toward = 1 if pin == "limit_neg" else 0
                if queued is not None and queued.direction == toward and (cur is None or cur.direction != toward):
                    self.unsure.append(f"{pin} active at {f} with a queued move towards it")
                if cur is None or cur.direction != toward or cur.limit_hit:
                    continue
                self.errors.append((w, ERROR_CODES["LIMIT"][0]))
                if self.script.limit_hard:
                    self.hard_stop(cur, queued, w)
                else:
                    twin = cur.clone()
                    self.soft(twin, w + 1)
                    self.drop_queue(queued, w)
                    self.adopt(cur, twin)
                    cur = twin
                cur.limit_hit = True
            except _RejectError as why:
                self.unsure.append(f"{pin} at filtered edge {f}: {why}")

    def clear_fault(self, w: int) -> _Proposal | None:
        """STATUS.ESTOP_FAULT written 1 in the PREP_CLOCKS before w: it clears once ESTOP is inactive."""
        if not self.fault:
            return None
        first = w - PREP_CLOCKS - 1
        if self.level_at("estop", first) or any(first <= f <= w for f, _ in self.filtered["estop"]):
            raise _RejectError("ESTOP is active: the fault stays")

        def apply() -> None:
            self.fault = False

        return _Proposal([(offset("STATUS"), REGISTERS_BY_NAME["STATUS"].field("ESTOP_FAULT").mask)], 0, apply)

    def hard_stop(self, running: _Motion, queued: _Motion | None, w: int) -> None:
        """HARD_STOP committed at w (the engine samples it at w + 1): no pulse from its edge w + 1 on."""
        self.drop_queue(queued, w)
        for part in running.parts:
            if part.pending is not None:
                part.pending[1] = min(part.pending[1], w + 1)
        running.hard = w
        running.changed()

    # -- the state at an edge -----------------------------------------------------------------------------------

    def situation(self, w: int) -> tuple[_Motion | None, _Motion | None]:
        """(the motion running at w or None, a queued motion not started yet or None); refuses a command that lands
        while a START is being taken."""
        if not self.motions:
            return None, None
        last = self.motions[-1]
        if last.request - MARGIN <= w + 1 <= last.start_edge + 1 + MARGIN:
            raise _RejectError(
                f"a START is being taken (requested at {last.request}, engine edge 0 at {last.start_edge + 1})"
            )
        if w + 1 < last.request:
            return self.motions[-2], last
        return (last, None) if last.moving(w) else (None, None)

    def position(self) -> int:
        """POSITION once every motion has ended."""
        return self.motions[-1].end_position() if self.motions else 0

    def last_step_edge(self) -> int | None:
        """The last STEP rising edge of the motions that have ended (None: none since reset)."""
        for motion in reversed(self.motions):
            if motion.endless:
                continue
            edges = motion.all_edges()
            if edges:
                return edges[-1]
        return None

    def gate(self, request: int, direction: int, last_step: int | None) -> GateTiming:
        previous = self.motions[-1].direction if self.motions else 0
        out = self.outputs
        return gate_timing(
            request, direction != previous, last_step, out.dir_hold, out.dir_setup, out.step_width, out.step_space
        )

    def values(self, cmd: Command, names: tuple[str, ...] = _PHYSICAL) -> dict[str, float]:
        """The command's speed / accel / decel over those in force; a rejection when one has never been given."""
        given = {name: getattr(cmd, name) for name in _PHYSICAL if getattr(cmd, name) is not None}
        if cmd.op == "jog":
            given["speed"] = abs(given["speed"])
        merged = {**self.force, **given}
        missing = [name for name in names if name not in merged]
        if missing:
            raise _RejectError(f"no {' or '.join(missing)} given yet")
        return merged

    def accept_values(self, cmd: Command) -> None:
        for name in _PHYSICAL:
            value = getattr(cmd, name)
            if value is not None and not (cmd.op == "jog" and name == "speed" and value == 0):
                self.force[name] = abs(value)

    # -- what a motion is made of -------------------------------------------------------------------------------

    def move_part(self, steps: int, v: dict[str, float]) -> tuple[Plan, _Part, list[tuple[int, int]]]:
        """A move from rest: its plan, its first part and the staging writes (SEGMENT .. HEAD_PROD cleared)."""
        s = self.script
        plan, info = cast(
            tuple[Plan, MoveInfo],
            _driver_call(plan_move_info, steps, v["accel"], v["decel"], v["speed"], s.spr, s.fclk, s.prescale, s.ramp),
        )
        part = _Part(0, Segment.of_move(plan), lambda j: speed_at_pulse(info, j), None, phys=_phys(v))
        return plan, part, [*plan_writes(plan), *segment_writes(NO_SEGMENT)]

    def jog_part(self, speed: float, v: dict[str, float]) -> tuple[int, _Part, list[tuple[int, int]]]:
        """A jog from rest (signed speed): its direction, its first part and the staging writes."""
        s = self.script
        plan, segment, seg = _driver_call(self.driver.plan_jog, speed, v["accel"], v["decel"])
        change = plan_change(0.0, None, v["accel"], v["decel"], abs(speed), s.spr, s.fclk, s.prescale, s.ramp)
        assert change.segment == seg
        part = _Part(0, seg, lambda j: speed_at_segment_pulse(change, j), None, phys=_phys(v, abs(speed)))
        return plan.direction, part, [*plan_writes(plan), *segment_writes(segment)]

    def start(self, w: int, direction: int, origin: int, part: _Part, queued_after: _Motion | None) -> _Motion:
        """The motion of a START committed at w, or queued after a motion (requested one clock after its last STEP
        edge)."""
        if self.fault:
            raise _RejectError("an ESTOP fault is latched (clear_fault first)")
        limit = self.limit_towards(direction, w)
        if limit is not None:
            raise _RejectError(f"{limit} is active: no motion towards it")
        if queued_after is None:
            request, last_step = w + 1, self.last_step_edge()
        else:
            edges = queued_after.all_edges()
            last_step = edges[-1] if edges else self.last_step_edge()
            request = (edges[-1] if edges else w) + 1
        return _Motion(self.gate(request, direction, last_step), direction, origin, self.script.prescale, part)

    # -- stops --------------------------------------------------------------------------------------------------

    def soft(self, m: _Motion, sample: int) -> None:
        """A soft stop sampled by the engine at `sample`, on the motion (docs/algorithm.md, "Soft stop" and "Stops
        and a pending change")."""
        if m.stop is not None and (m.stop.effective or sample <= m.stop.decided + MARGIN):
            if not m.stop.effective and sample >= m.stop.decided - MARGIN:
                raise _RejectError(f"a soft stop at the edge an earlier one is decided ({m.stop.decided})")
            return  # an earlier request waits for its pulse, or a stop is in effect: nothing changes
        last_pending = m.parts[-1] if m.parts[-1].commit is not None else None
        edges = m.upto(sample + 1)
        while last_pending is not None and len(edges) <= last_pending.pulse and m.more():
            edges = m.upto(-math.inf)
        p = bisect.bisect_right(edges, sample + 1)  # the first pulse whose engine edge is after the sample
        if p >= len(edges) or (m.hard is not None and sample > m.hard):
            m.stop = _Stop(sample, sample, False)  # the motion ends first: ignored
            return
        if last_pending is not None:
            took = edges[last_pending.pulse - 1] - 1  # E: pulse P - 1's engine edge
            if took - MARGIN <= sample <= took + 2 + MARGIN:
                raise _RejectError(f"a soft stop at the edge the change is taken over ({took + 2})")
            if sample <= took + 1:  # the pending change is dropped, the stop decided by the running segment
                m.parts.pop()
                assert last_pending.pending is not None
                m.drops.append((last_pending.pending, sample))
                m.changed()
            elif p <= last_pending.pulse:  # sampled after the take-over: decided at the segment's pulse 1
                p = last_pending.pulse + 1
        if m.parts[-1].commit is not None and p <= m.parts[-1].pulse:
            # (a queued move's change B dropped before pulse P_A: change A, taken over, decides it at its pulse 1)
            p = m.parts[-1].pulse + 1
        edges = m.upto(sample + 1)
        while p >= len(edges) and m.more():
            edges = m.upto(-math.inf)
        if p >= len(edges):
            m.stop = _Stop(sample, sample, False)
            return
        part = m.parts[-1]
        decided = edges[p] - 1
        values = segment_stop_values(part.seg, p - part.pulse)
        if values is None:
            m.stop = _Stop(sample, decided, False)
            return
        part.values = values
        m.stop = _Stop(sample, decided, True)
        m.changed()

    def adopt(self, m: _Motion, twin: _Motion) -> None:
        """Replace a motion by its changed copy, ending the PENDING spans the copy's soft stop dropped."""
        self.motions[self.motions.index(m)] = twin
        for span, edge in twin.drops:
            span[1] = min(span[1], edge)
        twin.drops = []

    def drop_queue(self, queued: _Motion | None, w: int) -> None:
        if queued is not None:
            self.motions.remove(queued)
            assert queued.queue_pending is not None
            queued.queue_pending[1] = min(queued.queue_pending[1], w)

    # -- commands -----------------------------------------------------------------------------------------------

    def take_over(self, m: _Motion, w: int) -> tuple[int, float]:
        """(P, u): the pulse a change committed at w names and the ideal speed there (steps/s); a rejection when the
        motion ends before or pulse P - 1 comes at the commit itself."""
        edges = m.upto(w + 400)
        while len(edges) < bisect.bisect_right(edges, w) + 2 and m.more():
            edges = m.upto(-math.inf)
        p = _driver_call(change_pulse, edges, w)
        if edges[p - 1] <= w + MARGIN:
            raise _RejectError(f"pulse P - 1 = {p - 1} is emitted at the commit (STEP edge {edges[p - 1]})")
        part = m.parts[-1]
        return p, part.speed(p - part.pulse)

    def change_proposal(
        self, m: _Motion, w: int, p: int, change: Change, target: int | None, phys: dict[str, float]
    ) -> _Proposal:
        seg = change.segment
        plan, segment = seg.registers(m.direction)
        writes = [*plan_writes(plan), *segment_writes(segment), (offset("CHANGE_AT"), p)]

        def apply() -> None:
            edges = m.upto(-math.inf)
            while len(edges) < p and m.more():
                edges = m.upto(-math.inf)
            pending = [w, edges[p - 1] - 1 + 2]
            self.pending.append(pending)
            speed = (lambda j: speed_at_segment_pulse(change, j)) if change.pieces else (lambda j: 0.0)
            m.parts.append(_Part(p, seg, speed, target, commit=w, pending=pending, phys=phys))
            m.changed()

        return _Proposal(writes, CHANGE, apply)

    def queue_proposal(
        self, m: _Motion, w: int, part: _Part, direction: int, writes: list[tuple[int, int]], stop: bool
    ) -> _Proposal:
        """QUEUE (with SOFT_STOP: a reversal) of a motion from rest after m; m with the stop applied when stop."""
        twin = m.clone()
        if stop:
            self.soft(twin, w + 1)
        if twin.endless:
            raise _RejectError("the running motion does not end (a jog): nothing to queue behind")
        queued = self.start(w, direction, twin.end_position(), part, queued_after=twin)

        def apply() -> None:
            self.adopt(m, twin)
            pending = [w, queued.request]
            self.pending.append(pending)
            queued.queue_pending = pending
            self.motions.append(queued)

        return _Proposal(writes, (SOFT_STOP if stop else 0) | QUEUE, apply)

    def stop_proposal(self, m: _Motion, w: int, queued: _Motion | None) -> _Proposal:
        twin = m.clone()
        self.soft(twin, w + 1)

        def apply() -> None:
            self.drop_queue(queued, w)
            self.adopt(m, twin)

        return _Proposal([], SOFT_STOP, apply)

    def move_back(self, m: _Motion, w: int, target: int, v: dict[str, float], stop: bool) -> _Proposal | None:
        """To `target` after m ends (stopped at w when stop): QUEUE (SOFT_STOP and QUEUE) of the move from where the
        model says m ends; only the stop (or nothing) when it ends on the target."""
        twin = m.clone()
        if stop:
            self.soft(twin, w + 1)
        if twin.endless:
            raise _RejectError("the running motion does not end (a jog): nothing to queue behind")
        steps = target - twin.end_position()
        if steps == 0:
            return self.stop_proposal(m, w, None) if stop else None
        plan, part, writes = self.move_part(steps, v)
        part.target = target
        return self.queue_proposal(m, w, part, plan.direction, writes, stop)

    def to_target(self, m: _Motion, w: int, target: int, v: dict[str, float], reject_late: bool) -> _Proposal | None:
        """A running motion to an absolute target: CHANGE at P, or a stop and a move back (target behind or inside
        the stop distance). When the motion ends before P: a queued move (or a rejection with reject_late)."""
        s = self.script
        try:
            p, u = self.take_over(m, w)
        except _RejectError:
            if reject_late:
                raise
            return self.move_back(m, w, target, v, stop=False)
        remaining = m.sign * (target - (m.origin + m.sign * (p + 1)))
        if remaining >= 0:
            change = cast(
                Change,
                _driver_call(
                    plan_change, u, remaining, v["accel"], v["decel"], v["speed"], s.spr, s.fclk, s.prescale, s.ramp
                ),
            )
            if change.back is None:
                return self.change_proposal(m, w, p, change, target, _phys(v))
        return self.move_back(m, w, target, v, stop=True)

    def to_jog(self, m: _Motion, w: int, speed: float, v: dict[str, float], reject_late: bool) -> _Proposal | None:
        """A running motion to a jog at the signed speed: CHANGE at P (same direction), SOFT_STOP and QUEUE of the
        jog (the other direction), SOFT_STOP (0)."""
        s = self.script
        if speed == 0:
            return self.stop_proposal(m, w, None)
        direction = int(speed < 0)
        if direction == m.direction:
            try:
                p, u = self.take_over(m, w)
            except _RejectError:
                if reject_late:
                    raise
            else:
                change = cast(
                    Change,
                    _driver_call(
                        plan_change, u, None, v["accel"], v["decel"], abs(speed), s.spr, s.fclk, s.prescale, s.ramp
                    ),
                )
                return self.change_proposal(m, w, p, change, None, _phys(v, abs(speed)))
            _, part, writes = self.jog_part(speed, v)
            return self.queue_proposal(m, w, part, direction, writes, stop=False)
        _, part, writes = self.jog_part(speed, v)
        return self.queue_proposal(m, w, part, direction, writes, stop=True)

    def chain_proposal(self, m: _Motion, w: int, steps: int, v: dict[str, float]) -> _Proposal | None:
        """A queued move in the running positioning motion's direction, without a stop between them
        (docs/algorithm.md, "QUEUE"): two take-overs. Change A at P_A (the usual pulse), with the running values:
        towards a virtual rest mb = floor(vb^2 / (2 d1)) steps past the target, so that the motion passes the target
        at about vb = min(v1, v2, sqrt(2 d2 N2)); change B at the target's pulse P_B, to the queued move's end at its
        values from the speed of A's ideal profile there, committed by the driver itself once PENDING of A fell (at
        W_B). None when a condition fails (the caller queues the move from rest): nothing pending, no stop, P_B
        reachable from W_B by the usual rule (P_B >= change_pulse), both plans without a reversal."""
        part = m.parts[-1]
        length = part.seg.length
        if (
            m.target is None
            or length is None
            or part.values is not None
            or part.phys is None
            or m.hard is not None
            or m.stopping(w)
            or (part.pending is not None and part.pending[1] >= w - PREP_CLOCKS)
        ):
            return None
        s = self.script
        try:
            p_a, u_a = self.take_over(m, w)
        except _RejectError:
            return None
        last = part.pulse + length  # L1: the motion's pulse at its target
        if p_a > last:
            return None
        ph1, ph2 = part.phys, _phys(v)
        _, _, d1, v1 = steps_units(ph1["accel"], ph1["decel"], ph1["speed"], s.spr, s.fclk, s.prescale)
        _, _, d2, v2 = steps_units(ph2["accel"], ph2["decel"], ph2["speed"], s.spr, s.fclk, s.prescale)
        n2 = abs(steps)
        vb = min(v1, v2, math.sqrt(2.0 * d2 * n2))
        mb = math.floor(vb * vb / (2.0 * d1) * (1.0 + 1e-9))  # (v^2 / (2 d) of equal values is not floored short)
        try:
            change_a = plan_change(u_a, last - p_a + mb, *_motion_args(ph1, s))
            change_b = plan_change(speed_at_segment_pulse(change_a, last - p_a), n2, *_motion_args(ph2, s))
        except ValueError:
            return None
        if change_a.back is not None or change_b.back is not None:
            return None
        target_a = cast(int, m.target) + m.sign * mb
        prop_a = self.change_proposal(m, w, p_a, change_a, target_a, ph1)
        # B's commit: its writes after PENDING of A fell (two clocks after pulse P_A - 1's engine edge)
        edges = m.upto(-math.inf)
        w_b = edges[p_a - 1] + 1 + PREP_CLOCKS + CHAIN_MARGIN
        twin = m.clone()
        twin.parts.append(_Part(p_a, change_a.segment, lambda j: speed_at_segment_pulse(change_a, j), target_a))
        try:
            p_min, _ = self.take_over(twin, w_b)
        except _RejectError:
            return None
        if last < p_min:
            return None
        twin_edges = twin.upto(-math.inf)
        while len(twin_edges) < last and twin.more():
            twin_edges = twin.upto(-math.inf)
        reserved = [w_b - PREP_CLOCKS, twin_edges[last - 1] + 1]
        prop_b = self.change_proposal(m, w_b, last, change_b, cast(int, m.target) + m.sign * n2, ph2)
        index = self.index

        def apply() -> None:
            prop_a.apply()
            self.pending.append(reserved)
            self.chained = _Chained(w_b, tuple(prop_b.writes), prop_b.apply, reserved, index)

        return _Proposal(prop_a.writes, CHANGE, apply)

    def flush(self, upto: float) -> None:
        """Commit change B of a queued move (an internal action) once the script reaches its edge."""
        chained = self.chained
        if chained is None or chained.at > upto:
            return
        self.chained = None
        self.pending.remove(chained.reserved)
        chained.apply()
        self.actions.append(Action(chained.at, chained.writes, CHANGE, chained.command))

    def proposal(self, cmd: Command) -> _Proposal | None:
        """The action a command makes (None: none), or a rejection."""
        w, op = cmd.at, cmd.op
        cur, queued = self.situation(w)
        if op == "clear_fault":
            return self.clear_fault(w)
        if op in ("soft_stop", "hard_stop"):
            if cur is None:
                return None
            if op == "soft_stop":
                return self.stop_proposal(cur, w, queued)
            running = cur
            return _Proposal([], HARD_STOP, lambda: self.hard_stop(running, queued, w))
        if op == "jog" and cmd.speed == 0 and (cur is None or cur.stopping(w)):
            return None  # nothing to stop
        if op == "move_to" and cur is None and cmd.position == self.position():
            return None  # already there
        needs = {"set": (), "jog": ("accel", "decel")}.get(op, _PHYSICAL)
        v = self.values(cmd, needs)
        if op == "set":
            if cur is None or cur.stopping(w):
                return None
            if queued is not None:
                raise _RejectError("a queued move is pending")
            v = self.values(cmd)
            if cur.target is None:
                speed = v["speed"] * cur.sign
                return self.to_jog(cur, w, speed, v, reject_late=True)
            return self.to_target(cur, w, cur.target, v, reject_late=True)
        if op in ("move", "queue"):
            steps = cast(int, cmd.steps)
            if cur is not None and op == "move":
                raise _RejectError("moving: a move is refused (use move_to, set or queue)")
            if steps == 0:
                return None
            if cur is not None:
                if queued is not None:
                    raise _RejectError("a queued move is pending")
                if cur.endless:
                    raise _RejectError("a queue behind a jog (it does not end)")
                plan, part, writes = self.move_part(steps, v)
                if plan.direction == cur.direction:
                    chained = self.chain_proposal(cur, w, steps, v)
                    if chained is not None:
                        return chained
                part.target = cur.end_position() + steps
                return self.queue_proposal(cur, w, part, plan.direction, writes, stop=False)
            return self.idle_move(w, steps, v)
        if op == "move_to":
            target = cast(int, cmd.position)
            if cur is None:
                steps = target - self.position()
                return None if steps == 0 else self.idle_move(w, steps, v)
            if queued is not None:
                raise _RejectError("a queued move is pending")
            if cur.stopping(w):
                return self.move_back(cur, w, target, v, stop=False)
            return self.to_target(cur, w, target, v, reject_late=False)
        # jog
        speed = cast(float, cmd.speed)
        if cur is None:
            if speed == 0:
                return None
            direction, part, writes = self.jog_part(speed, v)
            return self.idle_start(w, direction, part, writes)
        if cur.stopping(w):
            if speed == 0:
                return None
            if queued is not None:
                raise _RejectError("a queued move is pending")
            _, part, writes = self.jog_part(speed, v)
            return self.queue_proposal(cur, w, part, int(speed < 0), writes, stop=False)
        if queued is not None and speed != 0:
            raise _RejectError("a queued move is pending")
        if speed == 0:
            return self.stop_proposal(cur, w, queued)
        return self.to_jog(cur, w, speed, v, reject_late=False)

    def idle_move(self, w: int, steps: int, v: dict[str, float]) -> _Proposal:
        plan, part, writes = self.move_part(steps, v)
        part.target = self.position() + steps
        return self.idle_start(w, plan.direction, part, writes)

    def idle_start(self, w: int, direction: int, part: _Part, writes: list[tuple[int, int]]) -> _Proposal:
        motion = self.start(w, direction, self.position(), part, queued_after=None)
        return _Proposal(writes, START, lambda: self.motions.append(motion))

    def command(self, n: int, cmd: Command) -> None:
        """Command n: its action (and the model's change), or its refusal. A queued move's change B not committed
        yet is committed first when the command comes at or after its edge; a stop written before cancels it."""
        if cmd.op == "input":
            return  # (the pin: self.pins; its effects: input_events)
        self.input_events(cmd.at - MARGIN)
        self.flush(cmd.at)
        self.index = n
        stop = cmd.op in ("soft_stop", "hard_stop") or (cmd.op == "jog" and cmd.speed == 0)
        try:
            near = [e for e in self.events if e[0] <= cmd.at + MARGIN and e[2] == 1 and e[1] != "home"]
            if near:
                raise _RejectError(f"{near[0][1]} acts at {near[0][0]}, within {MARGIN} clocks of it")
            prop = self.proposal(cmd)
            if prop is not None:
                self.check_window(cmd.at, bool(prop.writes))
                if self.chained is not None and not stop:  # (a set may need no writes: a stop at A's target)
                    raise _RejectError(
                        f"a queued move's second change is to be committed at {self.chained.at}: only a stop can come "
                        "before it"
                    )
        except _RejectError as why:
            self.rejected.append({"at": cmd.at, "op": cmd.op, "reason": str(why)})
            return
        self.accept_values(cmd)
        if prop is not None:
            if self.chained is not None:  # a stop before change B is committed: the driver does not commit it
                self.pending.remove(self.chained.reserved)
                self.chained = None
            prop.apply()
            self.actions.append(Action(cmd.at, tuple(prop.writes), prop.ctrl, n))

    def check_window(self, w: int, writes: bool) -> None:
        """The action's writes (or its commit alone) must not overlap the previous action, nor a PENDING span."""
        if self.actions:
            previous = self.actions[-1].at
            if writes and w - PREP_CLOCKS <= previous:
                raise _RejectError(f"its writes ({PREP_CLOCKS} clocks) would overlap the action at {previous}")
            if w - previous < COMMIT_GAP:
                raise _RejectError(f"less than {COMMIT_GAP} clocks after the action at {previous}")
        if writes:
            for first, last in self.pending:
                if first <= w and last >= w - PREP_CLOCKS:
                    raise _RejectError(f"a change or queued move is pending ({first} .. {last}): the staging is locked")

    def finish(self) -> ScriptResult:
        until = self.script.until
        self.input_events(math.inf if until is None else until + 1)
        self.flush(math.inf if until is None else until)  # (one after until changes nothing up to it)
        if until is None:
            for motion in self.motions:
                if motion.endless:
                    raise ValueError("the script leaves an endless jog running: give it an 'until'")
            last = max((m.all_edges()[-1] for m in self.motions if m.all_edges()), default=0)
            last_at = self.script.commands[-1].at if self.script.commands else 0
            until = max(last, last_at) + EXTRA_CLOCKS
        edges: list[int] = []
        positions: list[int] = []
        for motion in self.motions:
            got = motion.upto(until)
            for k, edge in enumerate(got):
                if edge > until:
                    break
                edges.append(edge)
                positions.append(motion.origin + motion.sign * (k + 1))
        errors: list[tuple[int, int]] = []
        for edge, code in sorted(self.errors):
            if edge <= until and (not errors or errors[-1][1] != code):
                errors.append((edge, code))
        s = self.script
        return ScriptResult(
            self.actions,
            edges,
            positions,
            self.rejected,
            until,
            self.pins,
            errors,
            self.unsure,
            s.input_filter,
            s.limit_hard,
        )


def core_rejections(errors: list[tuple[int, int]] | list[list[int]]) -> list[dict[str, Any]]:
    """The core's errors, (edge, ERR_CODE) as the RTL flagged them or the model predicts them, as "rejected" entries
    ({"at", "op": "core", "reason"})."""
    names = {code: name for name, (code, _) in ERROR_CODES.items()}
    return [{"at": at, "op": "core", "reason": f"the core flagged {names.get(code, str(code))}"} for at, code in errors]


def plan_script(script: Script) -> ScriptResult:
    """The actions that carry out the script, every STEP rising edge up to `until` and the POSITION after each, and
    the commands refused with the reason (docs/algorithm.md, "The script contract"). ValueError when the script
    leaves an endless jog running and gives no `until`."""
    run = _Run(script)
    for n, cmd in enumerate(script.commands):
        run.command(n, cmd)
    return run.finish()


# ---------------------------------------------------------------------------------------------------------------
# Random scripts (the regression) and named scripts (the cases)
# ---------------------------------------------------------------------------------------------------------------

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
