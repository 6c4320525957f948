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

The script's schema and loading are in stepramp.board.script_schema (imported here too), the planner's model of the
motion in stepramp.board.script_motion; the random and named scripts (test material) in stepramp.sim.scripts.
"""

from __future__ import annotations

import bisect
import math
from typing import cast

from stepramp.board.change import Change, change_pulse, plan_change, speed_at_segment_pulse
from stepramp.board.driver import plan_writes, segment_writes
from stepramp.board.plan import steps_units
from stepramp.board.regmap import offset
from stepramp.board.script_motion import (
    PHYSICAL,
    Chained,
    Motion,
    Part,
    Proposal,
    RejectError,
    RunState,
    driver_call,
    motion_args,
    physical,
)
from stepramp.board.script_schema import (
    CHAIN_MARGIN,
    CHANGE,
    COMMIT_GAP,
    EXTRA_CLOCKS,
    HARD_STOP,
    MARGIN,
    PREP_CLOCKS,
    QUEUE,
    SOFT_STOP,
    START,
    Action,
    Command,
    Script,
    ScriptResult,
    SuppliedChange,
    SuppliedMove,
)
from stepramp.board.script_schema import OPS as OPS
from stepramp.board.script_schema import core_rejections as core_rejections
from stepramp.board.script_schema import load_script as load_script


class _Run(RunState):
    """The planner: each command in order, as a proposal (writes and CTRL bits) committed or refused."""

    # -- commands -----------------------------------------------------------------------------------------------

    def take_over(self, m: Motion, w: int) -> tuple[int, float]:
        """(P, u): the pulse a change committed at w names and the ideal speed there (steps/s); a rejection when the
        motion ends before or pulse P - 1 comes at the commit itself."""
        edges = m.upto(w + 400)
        while len(edges) < bisect.bisect_right(edges, w) + 2 and m.more():
            edges = m.upto(-math.inf)
        p = driver_call(change_pulse, edges, w)
        if edges[p - 1] <= w + MARGIN:
            raise RejectError(f"pulse P - 1 = {p - 1} is emitted at the commit (STEP edge {edges[p - 1]})")
        part = m.parts[-1]
        return p, part.speed(p - part.pulse)

    def change_proposal(
        self, m: Motion, w: int, p: int, change: Change, target: int | None, phys: dict[str, float]
    ) -> Proposal:
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
            m.parts.append(Part(p, seg, speed, target, commit=w, pending=pending, phys=phys))
            m.changed()

        return Proposal(writes, CHANGE, apply)

    def queue_proposal(
        self, m: Motion, w: int, part: Part, direction: int, writes: list[tuple[int, int]], stop: bool
    ) -> Proposal:
        """QUEUE (with SOFT_STOP: a reversal) of a motion from rest after m; m with the stop applied when stop."""
        twin = m.clone()
        if stop:
            self.soft(twin, w + 1)
        if twin.endless:
            raise RejectError("the running motion does not end (a jog): nothing to queue behind")
        queued = self.start(w, direction, twin.end_position(), part, queued_after=twin)

        def apply() -> None:
            self.adopt(m, twin)
            pending = [w, queued.request]
            self.pending.append(pending)
            queued.queue_pending = pending
            self.motions.append(queued)

        return Proposal(writes, (SOFT_STOP if stop else 0) | QUEUE, apply)

    def stop_proposal(self, m: Motion, w: int, queued: Motion | None) -> Proposal:
        twin = m.clone()
        self.soft(twin, w + 1)

        def apply() -> None:
            self.drop_queue(queued, w)
            self.adopt(m, twin)

        return Proposal([], SOFT_STOP, apply)

    def move_back(self, m: Motion, w: int, target: int, v: dict[str, float], stop: bool) -> Proposal | None:
        """To `target` after m ends (stopped at w when stop): QUEUE (SOFT_STOP and QUEUE) of the move from where the
        model says m ends; only the stop (or nothing) when it ends on the target."""
        twin = m.clone()
        if stop:
            self.soft(twin, w + 1)
        if twin.endless:
            raise RejectError("the running motion does not end (a jog): nothing to queue behind")
        steps = target - twin.end_position()
        if steps == 0:
            return self.stop_proposal(m, w, None) if stop else None
        plan, part, writes = self.move_part(steps, v)
        part.target = target
        return self.queue_proposal(m, w, part, plan.direction, writes, stop)

    def to_target(self, m: Motion, w: int, target: int, v: dict[str, float], reject_late: bool) -> Proposal | None:
        """A running motion to an absolute target: CHANGE at P, or a stop and a move back (target behind or inside
        the stop distance). When the motion ends before P: a queued move (or a rejection with reject_late)."""
        s = self.script
        try:
            p, u = self.take_over(m, w)
        except RejectError:
            if reject_late:
                raise
            return self.move_back(m, w, target, v, stop=False)
        remaining = m.sign * (target - (m.origin + m.sign * (p + 1)))
        if remaining >= 0:
            change = cast(
                Change,
                driver_call(
                    plan_change, u, remaining, v["accel"], v["decel"], v["speed"], s.spr, s.fclk, s.prescale, s.ramp
                ),
            )
            if change.back is None:
                return self.change_proposal(m, w, p, change, target, physical(v))
        return self.move_back(m, w, target, v, stop=True)

    def to_jog(self, m: Motion, w: int, speed: float, v: dict[str, float], reject_late: bool) -> Proposal | None:
        """A running motion to a jog at the signed speed: CHANGE at P (same direction), SOFT_STOP and QUEUE of the
        jog (the other direction), SOFT_STOP (0)."""
        s = self.script
        if speed == 0:
            return self.stop_proposal(m, w, None)
        direction = int(speed < 0)
        if direction == m.direction:
            try:
                p, u = self.take_over(m, w)
            except RejectError:
                if reject_late:
                    raise
            else:
                change = cast(
                    Change,
                    driver_call(
                        plan_change, u, None, v["accel"], v["decel"], abs(speed), s.spr, s.fclk, s.prescale, s.ramp
                    ),
                )
                return self.change_proposal(m, w, p, change, None, physical(v, abs(speed)))
            _, part, writes = self.jog_part(speed, v)
            return self.queue_proposal(m, w, part, direction, writes, stop=False)
        _, part, writes = self.jog_part(speed, v)
        return self.queue_proposal(m, w, part, direction, writes, stop=True)

    def chain_proposal(self, m: Motion, w: int, steps: int, v: dict[str, float]) -> Proposal | None:
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
        except RejectError:
            return None
        last = part.pulse + length  # L1: the motion's pulse at its target
        if p_a > last:
            return None
        ph1, ph2 = part.phys, physical(v)
        _, _, d1, v1 = steps_units(ph1["accel"], ph1["decel"], ph1["speed"], s.spr, s.fclk, s.prescale)
        _, _, d2, v2 = steps_units(ph2["accel"], ph2["decel"], ph2["speed"], s.spr, s.fclk, s.prescale)
        n2 = abs(steps)
        vb = min(v1, v2, math.sqrt(2.0 * d2 * n2))
        mb = math.floor(vb * vb / (2.0 * d1) * (1.0 + 1e-9))  # (v^2 / (2 d) of equal values is not floored short)
        try:
            change_a = plan_change(u_a, last - p_a + mb, *motion_args(ph1, s))
            change_b = plan_change(speed_at_segment_pulse(change_a, last - p_a), n2, *motion_args(ph2, s))
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
        twin.parts.append(Part(p_a, change_a.segment, lambda j: speed_at_segment_pulse(change_a, j), target_a))
        try:
            p_min, _ = self.take_over(twin, w_b)
        except RejectError:
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
            self.chained = Chained(w_b, tuple(prop_b.writes), prop_b.apply, reserved, index)

        return Proposal(prop_a.writes, CHANGE, apply)

    def flush(self, upto: float) -> None:
        """Commit change B of a queued move (an internal action) once the script reaches its edge."""
        chained = self.chained
        if chained is None or chained.at > upto:
            return
        self.chained = None
        self.pending.remove(chained.reserved)
        chained.apply()
        self.actions.append(Action(chained.at, chained.writes, CHANGE, chained.command))

    def proposal(self, cmd: Command) -> Proposal | None:
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
            return Proposal([], HARD_STOP, lambda: self.hard_stop(running, queued, w))
        if op == "jog" and cmd.speed == 0 and (cur is None or cur.stopping(w)):
            return None  # nothing to stop
        if op == "move_to" and cur is None and cmd.position == self.position():
            return None  # already there
        needs = {"set": (), "jog": ("accel", "decel")}.get(op, PHYSICAL)
        v = self.values(cmd, needs)
        if op == "set":
            if cur is None or cur.stopping(w):
                return None
            if queued is not None:
                raise RejectError("a queued move is pending")
            v = self.values(cmd)
            if cur.target is None:
                speed = v["speed"] * cur.sign
                return self.to_jog(cur, w, speed, v, reject_late=True)
            return self.to_target(cur, w, cur.target, v, reject_late=True)
        if op in ("move", "queue"):
            steps = cast(int, cmd.steps)
            if cur is not None and op == "move":
                raise RejectError("moving: a move is refused (use move_to, set or queue)")
            if steps == 0:
                return None
            if cur is not None:
                if queued is not None:
                    raise RejectError("a queued move is pending")
                if cur.endless:
                    raise RejectError("a queue behind a jog (it does not end)")
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
                raise RejectError("a queued move is pending")
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
                raise RejectError("a queued move is pending")
            _, part, writes = self.jog_part(speed, v)
            return self.queue_proposal(cur, w, part, int(speed < 0), writes, stop=False)
        if queued is not None and speed != 0:
            raise RejectError("a queued move is pending")
        if speed == 0:
            return self.stop_proposal(cur, w, queued)
        return self.to_jog(cur, w, speed, v, reject_late=False)

    def idle_move(self, w: int, steps: int, v: dict[str, float]) -> Proposal:
        plan, part, writes = self.move_part(steps, v)
        part.target = self.position() + steps
        return self.idle_start(w, plan.direction, part, writes)

    def idle_start(self, w: int, direction: int, part: Part, writes: list[tuple[int, int]]) -> Proposal:
        motion = self.start(w, direction, self.position(), part, queued_after=None)
        return Proposal(writes, START, lambda: self.motions.append(motion), motion)

    def command(self, n: int, cmd: Command) -> None:
        """Command n: its action (and the model's change), or its refusal. A queued move's change B not committed
        yet is committed first when the command comes at or after its edge; a stop written before cancels it."""
        if cmd.op == "input":
            return  # (the pin: self.pins; its effects: input_events)
        try:
            prop = self.prepare(n, cmd)
        except RejectError as why:
            self.reject(cmd, str(why))
            return
        self.commit(n, cmd, prop)

    def commit_edge(self, n: int, cmd: Command) -> int:
        """The edge W of command n's commit: its `at`, or a coordinated stop's take-over edge (SuppliedChange)."""
        sup = self.supplied.get(n)
        return sup.at if isinstance(sup, SuppliedChange) else cmd.at

    def prepare(self, n: int, cmd: Command) -> Proposal | None:
        """Command n's action (None: none) once the inputs and a queued move's change B before it are applied; a
        rejection when the driver refuses it. Changes nothing of the model until commit()."""
        w = self.commit_edge(n, cmd)
        self.input_events(w - MARGIN)
        self.flush(w)
        self.index = n
        stop = cmd.op in ("soft_stop", "hard_stop") or (cmd.op == "jog" and cmd.speed == 0)
        near = [e for e in self.events if e[0] <= w + MARGIN and e[2] == 1 and e[1] != "home"]
        if near:
            raise RejectError(f"{near[0][1]} acts at {near[0][0]}, within {MARGIN} clocks of it")
        sup = self.supplied.get(n)
        prop = self.supplied_change(sup) if isinstance(sup, SuppliedChange) else self.proposal(cmd)
        if prop is not None:
            self.check_window(w, bool(prop.writes), sup.prep if isinstance(sup, SuppliedMove) else PREP_CLOCKS)
            if self.chained is not None and not stop:  # (a set may need no writes: a stop at A's target)
                raise RejectError(
                    f"a queued move's second change is to be committed at {self.chained.at}: only a stop can come "
                    "before it"
                )
        return prop

    def commit(self, n: int, cmd: Command, prop: Proposal | None) -> None:
        """Accept command n with its action from prepare()."""
        self.accept_values(cmd)
        if prop is not None:
            if self.chained is not None:  # a stop before change B is committed: the driver does not commit it
                self.pending.remove(self.chained.reserved)
                self.chained = None
            prop.apply()
            self.actions.append(Action(self.commit_edge(n, cmd), tuple(prop.writes), prop.ctrl, n))

    def reject(self, cmd: Command, reason: str) -> None:
        self.rejected.append({"at": cmd.at, "op": cmd.op, "reason": reason})

    def supplied_change(self, sup: SuppliedChange) -> Proposal | None:
        """A coordinated stop's take-over (SuppliedChange) at its edge: the coordinated move must still run untouched
        (nothing pending, no stop) and its pulse be one change_pulse allows there; None when it takes none."""
        if sup.change is None:
            return None
        w = sup.at
        cur, queued = self.situation(w)
        m = cast(Motion, sup.motion)
        if cur is not m or queued is not None or len(m.parts) != 1 or m.stop is not None or m.hard is not None:
            raise RejectError("the coordinated move does not run as it was started: no take-over")
        edges = m.upto(w + 400)
        while len(edges) <= max(bisect.bisect_right(edges, w) + 1, sup.pulse) and m.more():
            edges = m.upto(-math.inf)
        least = driver_call(change_pulse, edges, w)
        if not least <= sup.pulse < len(edges) or edges[sup.pulse - 1] <= w + MARGIN:
            raise RejectError(f"its take-over pulse {sup.pulse} cannot be named at {w} (change_pulse {least})")
        target = m.origin + m.sign * (sup.rest + 1)
        return self.change_proposal(m, w, sup.pulse, sup.change, target, cast(dict[str, float], m.parts[0].phys))

    def check_window(self, w: int, writes: bool, prep: int = PREP_CLOCKS) -> None:
        """The action's writes (in the `prep` clocks before w) or its commit alone must not overlap the previous
        action, nor a PENDING span."""
        if self.actions:
            previous = self.actions[-1].at
            if writes and w - prep <= previous:
                raise RejectError(f"its writes ({prep} clocks) would overlap the action at {previous}")
            if w - previous < COMMIT_GAP:
                raise RejectError(f"less than {COMMIT_GAP} clocks after the action at {previous}")
        if writes:
            for first, last in self.pending:
                if first <= w and last >= w - prep:
                    raise RejectError(f"a change or queued move is pending ({first} .. {last}): the staging is locked")

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


def plan_script(script: Script) -> ScriptResult:
    """The actions that carry out the script, every STEP rising edge up to `until` and the POSITION after each, and
    the commands refused with the reason (docs/algorithm.md, "The script contract"). ValueError when the script
    leaves an endless jog running and gives no `until`."""
    run = _Run(script)
    for n, cmd in enumerate(script.commands):
        run.command(n, cmd)
    return run.finish()


class AxisPlanner:
    """plan_script one command at a time, with the multi-axis planner's hooks (stepramp.board.multi_script runs one
    per axis, side by side in the script's time order): a coordinated move's axis takes a supplied plan and starts on
    the group's common start edge (SuppliedMove, propose then start), a coordinated stop's axis a supplied take-over
    (SuppliedChange). plan_script(s) is AxisPlanner(s) advanced to the end, then finish()."""

    def __init__(self, script: Script) -> None:
        self._run = _Run(script)
        self.script = script
        self.next = 0
        """The first command not planned yet."""

    def advance(self, upto: int) -> None:
        """Plan the commands before index `upto` not planned yet."""
        while self.next < upto:
            self._run.command(self.next, self.script.commands[self.next])
            self.next += 1

    def propose(self, n: int, sup: SuppliedMove) -> Proposal:
        """Command n (a move) with the supplied plan, not committed: its proposal (proposal.motion.start_edge is its
        own start gate's edge); ValueError with the driver's reason when the axis refuses it."""
        self.advance(n)
        self._run.supplied[n] = sup
        try:
            prop = self._run.prepare(n, self.script.commands[n])
        except RejectError as why:
            raise ValueError(str(why)) from None
        if prop is None or prop.motion is None:
            raise ValueError("the move starts nothing")
        return prop

    def start(self, n: int, prop: Proposal, start_edge: int) -> None:
        """Commit command n's proposal with its engine started after `start_edge` (the group's common start edge, at
        or after its own: stepramp.models.stepping.sync_gate_timing)."""
        motion = cast(Motion, prop.motion)
        assert start_edge >= motion.start_edge, (start_edge, motion.start_edge)
        motion.start_edge = start_edge
        motion.changed()
        self._run.commit(n, self.script.commands[n], prop)
        self.next = n + 1

    def reject(self, n: int, reason: str) -> None:
        """Refuse command n with the reason (nothing changes)."""
        self.advance(n)
        self._run.reject(self.script.commands[n], reason)
        self.next = n + 1

    def supply(self, n: int, sup: SuppliedMove | SuppliedChange) -> None:
        """Plan command n with the hook."""
        self.advance(n)
        self._run.supplied[n] = sup
        self.advance(n + 1)

    def settle(self, w: int) -> None:
        """Apply the inputs' effects and a queued move's change B due before a command at w."""
        self._run.input_events(w - MARGIN)
        self._run.flush(w)

    def untouched_edges(self, motion: object) -> list[int] | None:
        """The STEP edges of `motion` (a START's proposal.motion) when it is still the axis's last motion and runs as
        it was started (no change, stop, hard stop or queued move after it); None otherwise."""
        run = self._run
        m = cast(Motion, motion)
        if not run.motions or run.motions[-1] is not m or run.chained is not None:
            return None
        if len(m.parts) != 1 or m.stop is not None or m.hard is not None or m.endless:
            return None
        return m.all_edges()

    def window_refusal(self, w: int, writes: bool) -> str | None:
        """Why an action committed at w (with writes in the PREP_CLOCKS before) would be refused by the bus window or a
        PENDING span (None: it would not)."""
        try:
            self._run.check_window(w, writes)
        except RejectError as why:
            return str(why)
        return None

    def finish(self) -> ScriptResult:
        self.advance(len(self.script.commands))
        return self._run.finish()
