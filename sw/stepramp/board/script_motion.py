# SPDX-License-Identifier: MIT
"""The script planner's model of the motion (stepramp.board.script): a motion as the parts (segments) that run one
after the other from its START, with their soft stops and hard stop, the planner's state while it goes through the
commands (RunState: the machine inputs, the state at an edge, what a motion is made of, stops), and the proposal of
an action before it is committed.

Every STEP edge comes from the model (stepramp.models.engine: segment_runs, segment_stop_values) through the one
fractional accumulator of the motion, on the script's clock axis (docs/algorithm.md, "The script contract").
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, cast

from stepramp.board.change import Segment, plan_change, speed_at_pulse, speed_at_segment_pulse
from stepramp.board.driver import NO_SEGMENT, Outputs, RegisterAccess, StepRamp, plan_writes, segment_writes
from stepramp.board.plan import FRAC_CRUISE, MoveInfo, Plan, plan_move_info
from stepramp.board.regmap import ERROR_CODES, REGISTERS_BY_NAME, offset
from stepramp.board.script_schema import MARGIN, PREP_CLOCKS, Action, Command, Script, SuppliedChange, SuppliedMove
from stepramp.models.engine import segment_runs, segment_stop_values, start_acc
from stepramp.models.inputs import PINS, filtered_edges
from stepramp.models.stepping import START_TO_FIRST_STEP, GateTiming, gate_timing

_FRAC_MASK = (1 << FRAC_CRUISE) - 1
PHYSICAL = ("speed", "accel", "decel")


class RejectError(Exception):
    """A command the driver refuses (listed in ScriptResult.rejected; nothing changes)."""


def motion_args(phys: dict[str, float], s: Script) -> tuple[float, float, float, float, float, int, int]:
    """(accel, decel, speed, spr, fclk, prescale, ramp): plan_change's arguments after u and the remaining steps."""
    return phys["accel"], phys["decel"], phys["speed"], s.spr, s.fclk, s.prescale, s.ramp


def driver_call(fn: Callable[..., Any], *args: Any) -> Any:
    """A driver planning call, its ValueError as a rejection with the driver's reason."""
    try:
        return fn(*args)
    except ValueError as err:
        raise RejectError(str(err)) from err


def physical(v: dict[str, float], speed: float | None = None) -> dict[str, float]:
    """The speed (or `speed`), accel and decel of the values in force v."""
    return {"speed": v["speed"] if speed is None else speed, "accel": v["accel"], "decel": v["decel"]}


@dataclass
class Part:
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
class Stop:
    """A soft stop: sampled by the engine at `sample`, decided at the engine edge `decided` (of pulse p = q + 1, q
    the first pulse after the sample; the sample itself when q is the last pulse or there is none), in effect or
    ignored."""

    sample: int
    decided: int
    effective: bool


class Motion:
    """One motion from a START (or a queued START) to its end: parts taken over at pulses, a soft or hard stop. Its
    STEP edges are generated lazily (an endless jog only as far as asked) and cached until it changes."""

    def __init__(self, gate: GateTiming, direction: int, origin: int, prescale: int, part: Part) -> None:
        self.request = gate.request
        self.start_edge = gate.start_edge
        self.direction = direction
        self.sign = -1 if direction else 1
        self.origin = origin
        self.prescale = prescale
        self.parts = [part]
        self.hard: int | None = None
        self.stop: Stop | None = None
        self.queue_pending: list[int] | None = None
        self.limit_hit = False  # a limit stopped it (once per motion)
        self.drops: list[tuple[list[int], int]] = []  # PENDING spans a soft stop on this copy ends: (span, edge)
        self._edges: list[int] = []
        self._gen: Iterator[int] | None = None
        self._done = False

    def clone(self) -> Motion:
        twin = Motion.__new__(Motion)
        twin.__dict__.update(self.__dict__)
        twin.parts = [Part(**p.__dict__) for p in self.parts]
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


@dataclass
class Proposal:
    """An action not yet committed: its writes and CTRL bits, and what it does to the model once accepted."""

    writes: list[tuple[int, int]]
    ctrl: int
    apply: Callable[[], None]
    motion: Motion | None = None  # (a START's motion: the multi-axis planner moves its start to the common edge)


@dataclass
class Chained:
    """Change B of a queued move in the same direction (_Run.chain_proposal): the driver commits it at `at` (CTRL
    write of CHANGE, its writes in the PREP_CLOCKS before) unless a stop is written first. reserved: the span the
    staging is kept for it, from its first write to its own PENDING's end; command: the queue's index."""

    at: int
    writes: tuple[tuple[int, int], ...]
    apply: Callable[[], None]
    reserved: list[int]
    command: int


class RunState:
    """The planner's state while it goes through the commands in order (the commands themselves: script._Run)."""

    def __init__(self, script: Script) -> None:
        self.script = script
        self.outputs = Outputs()
        self.driver = StepRamp(cast(RegisterAccess, None), script.fclk, script.spr, script.prescale, script.ramp)
        self.force: dict[str, float] = {}
        self.motions: list[Motion] = []
        self.actions: list[Action] = []
        self.rejected: list[dict[str, Any]] = []
        self.pending: list[list[int]] = []  # PENDING spans [from, to] of changes and queued moves
        self.chained: Chained | None = None  # a queued move's change B, not committed yet
        self.index = 0  # the command being planned
        #: The multi-axis planner's hooks by command index (coordinated moves and stops; stepramp.board.multi_script).
        self.supplied: dict[int, SuppliedMove | SuppliedChange] = {}
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
            except RejectError as why:
                self.unsure.append(f"{pin} at filtered edge {f}: {why}")

    def clear_fault(self, w: int) -> Proposal | None:
        """STATUS.ESTOP_FAULT written 1 in the PREP_CLOCKS before w: it clears once ESTOP is inactive."""
        if not self.fault:
            return None
        first = w - PREP_CLOCKS - 1
        if self.level_at("estop", first) or any(first <= f <= w for f, _ in self.filtered["estop"]):
            raise RejectError("ESTOP is active: the fault stays")

        def apply() -> None:
            self.fault = False

        return Proposal([(offset("STATUS"), REGISTERS_BY_NAME["STATUS"].field("ESTOP_FAULT").mask)], 0, apply)

    def hard_stop(self, running: Motion, queued: Motion | None, w: int) -> None:
        """HARD_STOP committed at w (the engine samples it at w + 1): no pulse from its edge w + 1 on."""
        self.drop_queue(queued, w)
        for part in running.parts:
            if part.pending is not None:
                part.pending[1] = min(part.pending[1], w + 1)
        running.hard = w
        running.changed()

    # -- the state at an edge -----------------------------------------------------------------------------------

    def situation(self, w: int) -> tuple[Motion | None, Motion | None]:
        """(the motion running at w or None, a queued motion not started yet or None); refuses a command that lands
        while a START is being taken."""
        if not self.motions:
            return None, None
        last = self.motions[-1]
        if last.request - MARGIN <= w + 1 <= last.start_edge + 1 + MARGIN:
            raise RejectError(
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

    def values(self, cmd: Command, names: tuple[str, ...] = PHYSICAL) -> dict[str, float]:
        """The command's speed / accel / decel over those in force; a rejection when one has never been given."""
        given = {name: getattr(cmd, name) for name in PHYSICAL if getattr(cmd, name) is not None}
        if cmd.op == "jog":
            given["speed"] = abs(given["speed"])
        merged = {**self.force, **given}
        missing = [name for name in names if name not in merged]
        if missing:
            raise RejectError(f"no {' or '.join(missing)} given yet")
        return merged

    def accept_values(self, cmd: Command) -> None:
        for name in PHYSICAL:
            value = getattr(cmd, name)
            if value is not None and not (cmd.op == "jog" and name == "speed" and value == 0):
                self.force[name] = abs(value)

    # -- what a motion is made of -------------------------------------------------------------------------------

    def move_part(self, steps: int, v: dict[str, float]) -> tuple[Plan, Part, list[tuple[int, int]]]:
        """A move from rest: its plan, its first part and the staging writes (SEGMENT .. HEAD_PROD cleared)."""
        s = self.script
        sup = self.supplied.get(self.index)
        if isinstance(sup, SuppliedMove):
            plan, info = sup.plan, sup.info
        else:
            plan, info = cast(
                tuple[Plan, MoveInfo],
                driver_call(
                    plan_move_info, steps, v["accel"], v["decel"], v["speed"], s.spr, s.fclk, s.prescale, s.ramp
                ),
            )
        part = Part(0, Segment.of_move(plan), lambda j: speed_at_pulse(info, j), None, phys=physical(v))
        return plan, part, [*plan_writes(plan), *segment_writes(NO_SEGMENT)]

    def jog_part(self, speed: float, v: dict[str, float]) -> tuple[int, Part, list[tuple[int, int]]]:
        """A jog from rest (signed speed): its direction, its first part and the staging writes."""
        s = self.script
        plan, segment, seg = driver_call(self.driver.plan_jog, speed, v["accel"], v["decel"])
        change = plan_change(0.0, None, v["accel"], v["decel"], abs(speed), s.spr, s.fclk, s.prescale, s.ramp)
        assert change.segment == seg
        part = Part(0, seg, lambda j: speed_at_segment_pulse(change, j), None, phys=physical(v, abs(speed)))
        return plan.direction, part, [*plan_writes(plan), *segment_writes(segment)]

    def start(self, w: int, direction: int, origin: int, part: Part, queued_after: Motion | None) -> Motion:
        """The motion of a START committed at w, or queued after a motion (requested one clock after its last STEP
        edge)."""
        if self.fault:
            raise RejectError("an ESTOP fault is latched (clear_fault first)")
        limit = self.limit_towards(direction, w)
        if limit is not None:
            raise RejectError(f"{limit} is active: no motion towards it")
        if queued_after is None:
            request, last_step = w + 1, self.last_step_edge()
        else:
            edges = queued_after.all_edges()
            last_step = edges[-1] if edges else self.last_step_edge()
            request = (edges[-1] if edges else w) + 1
        return Motion(self.gate(request, direction, last_step), direction, origin, self.script.prescale, part)

    # -- stops --------------------------------------------------------------------------------------------------

    def soft(self, m: Motion, sample: int) -> None:
        """A soft stop sampled by the engine at `sample`, on the motion (docs/algorithm.md, "Soft stop" and "Stops
        and a pending change")."""
        if m.stop is not None and (m.stop.effective or sample <= m.stop.decided + MARGIN):
            if not m.stop.effective and sample >= m.stop.decided - MARGIN:
                raise RejectError(f"a soft stop at the edge an earlier one is decided ({m.stop.decided})")
            return  # an earlier request waits for its pulse, or a stop is in effect: nothing changes
        last_pending = m.parts[-1] if m.parts[-1].commit is not None else None
        edges = m.upto(sample + 1)
        while last_pending is not None and len(edges) <= last_pending.pulse and m.more():
            edges = m.upto(-math.inf)
        q = bisect.bisect_right(edges, sample + 1)  # the first pulse whose engine edge is after the sample
        if q >= len(edges) or (m.hard is not None and sample > m.hard):
            m.stop = Stop(sample, sample, False)  # the motion ends first: ignored
            return
        if last_pending is not None:
            took = edges[last_pending.pulse - 1] - 1  # E: pulse P - 1's engine edge
            if took - MARGIN <= sample <= took + 2 + MARGIN:
                raise RejectError(f"a soft stop at the edge the change is taken over ({took + 2})")
            if sample <= took + 1:  # the pending change is dropped, the stop decided by the running segment
                m.parts.pop()
                assert last_pending.pending is not None
                m.drops.append((last_pending.pending, sample))
                m.changed()
        # Decided one pulse after q (docs/algorithm.md, "Soft stop"), by the rules of the part that runs there. A
        # stop sampled after a take-over at P (from E + 2 on; also change A of a queued move when its change B was
        # dropped) has q >= P: it is decided at the segment's pulse 1 at the earliest. One that dropped the pending
        # change has q <= P and is decided by the running segment's rules, at P + 1 at the latest.
        p = q + 1
        assert m.parts[-1].commit is None or p > m.parts[-1].pulse
        edges = m.upto(sample + 1)
        while p >= len(edges) and m.more():
            edges = m.upto(-math.inf)
        if p >= len(edges):
            m.stop = Stop(sample, sample, False)  # q is the motion's last pulse: ignored
            return
        part = m.parts[-1]
        decided = edges[p] - 1
        values = segment_stop_values(part.seg, p - part.pulse)
        if values is None:
            m.stop = Stop(sample, decided, False)
            return
        part.values = values
        m.stop = Stop(sample, decided, True)
        m.changed()

    def adopt(self, m: Motion, twin: Motion) -> None:
        """Replace a motion by its changed copy, ending the PENDING spans the copy's soft stop dropped."""
        self.motions[self.motions.index(m)] = twin
        for span, edge in twin.drops:
            span[1] = min(span[1], edge)
        twin.drops = []

    def drop_queue(self, queued: Motion | None, w: int) -> None:
        if queued is not None:
            self.motions.remove(queued)
            assert queued.queue_pending is not None
            queued.queue_pending[1] = min(queued.queue_pending[1], w)
