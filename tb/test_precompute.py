# SPDX-License-Identifier: MIT
"""stepramp_precompute alone (issue 12): the bench plays the sequencer (stepramp_engine) in Python and checks, at
every pulse edge, the next interval and the soft-stop alternative the precompute offers against stepramp.models.engine.

The sequencer's side, with the timing of docs/stepramp_engine.md ("Timing", "Theory of operation"): the move inputs
(l = N - 1, sa, ... stop_ratio from a Plan) are held from before edge 0; begin_move and latch at edge 0, setup at
edge 1, pulse 0 at edge 2 and pulse k at every following pulse edge E: advance at E + 1 (the sequencer registers
it; take_alt when a soft stop is taken there; finish at E itself at the last pulse, or at a pulse whose soft stop
ends the move). Pulse edges are min(max(P * ticks, 64), 80) clocks apart: the engine's own distance P * ticks (a
plan's interval lasts at least MIN_INTERVAL_CLKS = 64 clocks), capped at 80 clocks, more than any budget of "Latency
budget" needs for the plans used here (a recurrence step 8 + k <= 56, the alternative at most 45 + 2 log2(ticks) <
80 below 2^17 ticks), so that a move of a few hundred intervals simulates in a few tens of thousands of clocks.

Checked just before each pulse edge p (the interval now counting is p; pulse 0 ends none), from the model only:

* nxt_ok = '1', nxt_d = the ticks of interval p + 1 (the fractional-carry accumulator over
  stepramp.models.engine.interval_values, equal to the differences of tick_times), nxt_state = its phase
  (stepramp.models.engine.phases), nxt_last = '1' exactly for interval L, nxt_code = 0 (ZERO_TICKS for an interval of 0
  ticks, from a hand-made plan);
* the soft-stop alternative "decided at pulse p" for p >= 1 (stepramp.models.engine.soft_stop_length): None -> alt_kind
  "00"; 0 -> "01"; m >= 1 -> "10" with alt_ok = '1', alt_d = the ticks of the stop's first interval (accumulator
  over stepramp.models.engine.soft_stop_values), alt_one = (m = 1), alt_code = 0. At pulse 0 (no interval counts: the
  sequencer itself ends a move whose stop came before pulse 0), at the last pulse and once a stop is in effect:
  "00";
* stop_mode = '1' exactly after a take_alt of the current move;
* white box: the accumulator fraction after the interval, the internal registers nxt_acc and alt_acc (named in
  "Theory of operation"), equal to the model's. A value one Q32.16 LSB off changes the ticks only when the sum
  crosses a tick (about once in 2^16), the fraction at once.

A soft stop taken at pulse p switches the expected intervals to the stop's (soft_stop_values: DECEL, nxt_last at
the new last interval p + m); with alt_one the stop's only interval is c_last and the move finishes at pulse p + 1.
After begin_move: nxt_ok, alt_ok, stop_mode '0' and alt_kind "00"; after a reset likewise.

Moves marked early (the cocotb test early_pulses) pulse as soon as the precompute allows instead: one clock after
nxt_ok rises (after alt_ok too where the soft stop is taken). There nxt_ok and alt_ok must rise exactly at the edge
"Latency budget" gives (a register ready for a pulse at E + 4, the decel seed E + 6, a recurrence step E + 8 + k,
the alternative 3 + 2 + k after the normal value, c_last as the alternative 1 after it; k from
stepramp.models.blocks.next_delay on the model's values), and an alternative still in the making at a pulse edge is
dropped without delaying or disturbing the next interval.

The cocotb tests: plan_intervals (trapezoids with m0 = 0 and 1, a cruise of one and two intervals, sd = L,
triangles; a trapezoid and a triangle again with stop_armed '0', where no alternative may be prepared), short_moves
(sa = 1, sa = 2 and 3, sa = sd = L, sa = sd = 1, N = 0 .. 3, a first interval above 2^16 ticks, intervals of 1 .. 8
ticks), rule_order (hand-made registers that make each rule of the spec's order visible: c_sa /= c_sd with sa = sd,
c_sa / c_sd /= c_last with sa = sd = L, c_sa /= c_first with sa = 1, and an interval of 0 ticks; a plan from
plan_move holds equal values wherever two rules match), soft_stops (taken in ACCEL with m >= 2, m = 1, m = 0, at p =
1 and p = sa - 1, in RUN with m >= 2 and m = 1, in a triangle, plus a random one), long_accel_ramp (a 300-interval
accel ramp to the speed limit, stopped near its end), aborts_and_restarts (finish, as a hard stop does, or a reset
at random clocks of the precompute, also during a stop, then the next move exact from its edge 0) and early_pulses.
Moves follow each other back to back (begin_move at the edge after finish) or after a few idle clocks. The random
draws print their seed and replay with PRECOMPUTE_SEED=<seed> pytest tb/test_precompute.py.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import os
import random
from collections import Counter
from dataclasses import dataclass
from typing import Any

from cocotb.triggers import ClockCycles, FallingEdge, First, RisingEdge
from cocotb.utils import get_sim_time

from stepramp.board.plan import FRAC_CRUISE, FRAC_RAMP, MIN_INTERVAL_CLKS, Plan, plan_move
from stepramp.board.regmap import ERROR_CODES
from stepramp.models.blocks import next_delay
from stepramp.models.engine import (
    ACCEL,
    DECEL,
    RUN,
    interval_values,
    phase_of,
    soft_stop_length,
    soft_stop_values,
    tick_times,
)
from stepramp.models.engine import phases as model_phases
from stepramp.sim.engine_bench import SEGMENT_INPUTS
from stepramp.sim.profiles import PROFILES_BY_NAME, Profile
from tbutil import CLK_PERIOD_NS, cocotb, run_seeded, start_clock_and_reset

SEED_ENV = "PRECOMPUTE_SEED"
#: Longest distance between two pulse edges in the bench (clocks); see the module docstring.
GAP_MAX = 80
#: A move's failures reported before the bench gives up on it (one wrong tick count shifts the rest).
MAX_FAILURES_PER_MOVE = 6

STATE = {ACCEL: 0b01, RUN: 0b10, DECEL: 0b11}
ALT_IGNORE, ALT_END, ALT_LOAD = 0b00, 0b01, 0b10
ERR_NONE = ERROR_CODES["NONE"][0]
ERR_ZERO_TICKS = ERROR_CODES["ZERO_TICKS"][0]
FRAC_MASK = (1 << FRAC_CRUISE) - 1
SHIFT = FRAC_CRUISE - FRAC_RAMP  # Q32.16 -> Q32.32
ONE_TICK = 1 << FRAC_RAMP  # one tick in Q32.16
#: "Latency budget": a register value is ready for a pulse at E + 4, one from the next-delay unit at E + 6 + the
#: unit's latency (a seed: 0, E + 6; a recurrence step: 2 + k, E + 8 + k).
REGISTER_READY = 4
UNIT_READY = 6


# ---------------------------------------------------------------------------------------------------------------
# Expected values (stepramp.models.engine only)
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Interval:
    """One interval as the precompute must offer it in nxt_* (frac: the accumulator fraction after it, the internal
    nxt_acc; ready: the X of "ready for a pulse at E + X" in "Latency budget", E the edge that starts the interval
    before it; None for interval 1, prepared at setup, and for a soft stop's first interval, the alternative)."""

    ticks: int
    state: int
    last: bool
    code: int
    frac: int
    ready: int | None


@dataclass(frozen=True)
class Alternative:
    """The soft-stop alternative "decided at pulse p" as alt_* must show it (the rest only for LOAD)."""

    kind: int
    m: int | None = None
    ticks: int = 0
    one: bool = False
    code: int = ERR_NONE
    frac: int = 0  # the internal alt_acc
    ready: int = 0  # X: ready for a pulse at E + X, E the edge of pulse p - 1


def accumulate(values: list[int]) -> tuple[list[int], list[int]]:
    """Ticks of each interval and the accumulator fraction after it (docs/algorithm.md, "Emission")."""
    ticks, fracs = [], []
    acc = 0
    for value in values:
        s = acc + value
        ticks.append(s >> FRAC_CRUISE)
        acc = s & FRAC_MASK
        fracs.append(acc)
    return ticks, fracs


def intervals_of(values: list[int], states: list[str], ready: list[int | None]) -> list[Interval]:
    ticks, fracs = accumulate(values)
    last = len(values)
    return [
        Interval(t, STATE[s], i == last, ERR_ZERO_TICKS if t == 0 else ERR_NONE, f, x)
        for i, (t, s, f, x) in enumerate(zip(ticks, states, fracs, ready, strict=True), start=1)
    ]


class Expect:
    """What a plan makes the precompute offer: the intervals 1 .. L, and per pulse the alternative.

    The values and ticks come from stepramp.models.engine. The latencies are the formulas of "Latency budget": a
    register is ready for a pulse at E + 4, a value from the next-delay unit at E + 6 + its latency (a seed: 0, a step:
    2 + k, stepramp.models.blocks.next_delay), the alternative 3 + its latency after the normal value of the same
    interval (m = 1, c_last: 1 after). The recurrence requests are run here on stepramp.models.blocks.next_delay and
    each answer is held equal to the model's value, so the latencies belong to the model's values."""

    def __init__(self, plan: Plan) -> None:
        self.plan = plan
        self.values = list(interval_values(plan))
        times = tick_times(plan)
        # the accumulator here is the spec's: the same as the model's tick times
        self.ticks, self.fracs = accumulate(self.values)
        assert self.ticks == [b - a for a, b in itertools.pairwise(times)], "accumulator != tick_times"
        self.intervals = intervals_of(self.values, model_phases(plan), self._ready())

    def _ready(self) -> list[int | None]:
        plan, length = self.plan, self.plan.steps - 1
        ready: list[int | None] = [None][:length]  # interval 1: c_first, at setup
        acc = (plan.accel_seed, 0)  # A_(n-1) and its remainder
        dec: tuple[int, int] | None = None  # D_(m+1) and its remainder, once the decel seed is loaded
        for j in range(2, length + 1):  # the rule order of DECIDE (j >= 2)
            if j == length or j in (plan.sa, plan.sd) or plan.sa < j < plan.sd:
                ready.append(REGISTER_READY)
                continue
            if j < plan.sa:
                ans = next_delay(False, False, j - 1, *acc)
                acc = (ans.value, ans.remainder)
            else:
                ans = next_delay(dec is None, True, length - j, *(dec or (plan.decel_seed, 0)))
                dec = (ans.value, ans.remainder)
            assert ans.value << SHIFT == self.values[j - 1], f"interval {j}: the unit's answer is not the model's"
            ready.append(UNIT_READY + ans.latency)
        return ready

    def alternative(self, p: int) -> Alternative:
        """Soft stop decided at pulse p >= 1 (the end of interval p)."""
        m = soft_stop_length(self.plan, p)
        if m is None:
            return Alternative(ALT_IGNORE)
        if m == 0:
            return Alternative(ALT_END, 0)
        values = soft_stop_values(self.plan, p)
        assert values is not None and values[:p] == self.values[:p] and len(values) == p + m
        s = self.fracs[p - 1] + values[p]  # the accumulator just continues after interval p
        ticks = s >> FRAC_CRUISE
        normal = self.intervals[p].ready  # interval p + 1 of the plan: D
        assert normal is not None
        if m == 1:
            ready = normal + 1  # c_last: ALT_ADD right after ADD
        else:
            ans = next_delay(False, True, m - 1, self.values[p] >> SHIFT, 0)  # D_(m-1) from D_m := D, r = 0
            assert ans.value << SHIFT == values[p]
            ready = normal + 3 + ans.latency
        code = ERR_ZERO_TICKS if ticks == 0 else ERR_NONE
        return Alternative(ALT_LOAD, m, ticks, m == 1, code, s & FRAC_MASK, ready)

    def stop_intervals(self, p: int) -> list[Interval]:
        """Intervals 1 .. p + m of the move after a soft stop (m >= 1) taken at pulse p."""
        m = soft_stop_length(self.plan, p)
        values = soft_stop_values(self.plan, p)
        assert m is not None and values is not None and len(values) == p + m
        ready: list[int | None] = [iv.ready for iv in self.intervals[:p]] + [None]  # p + 1: the alternative
        if m >= 2:
            dec = (self.values[p] >> SHIFT, 0)
            for j in range(p + 1, p + m):  # interval j gets D_(p+m-j); its request comes during interval j - 1
                ans = next_delay(False, True, p + m - j, *dec)
                dec = (ans.value, ans.remainder)
                assert ans.value << SHIFT == values[j - 1]
                if j > p + 1:
                    ready.append(UNIT_READY + ans.latency)
            ready.append(REGISTER_READY)  # c_last
        return intervals_of(values, model_phases(self.plan)[:p] + [DECEL] * m, ready)


# ---------------------------------------------------------------------------------------------------------------
# Moves
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Move:
    """One move as the sequencer plays it.

    soft_at: a soft stop decided at this pulse is taken (take_alt for m >= 1, finish for m = 0).
    abort: ("finish" | "rst", k, offset): the sequencer's finish (a hard stop) or a one-clock reset at the edge
    `offset` clocks after pulse k's edge (offset 0: at that edge, instead of the pulse's advance).
    idle: clocks with no strobe between the previous move's last edge and this move's edge 0.
    early: each pulse edge comes one clock after nxt_ok rises (the earliest the sequencer can copy it), so that an
    alternative still in the making is dropped; not before the last pulse and the soft stop's pulse.
    armed: stop_armed is '1' through the move, as if a soft stop request were armed at every pulse, so every pulse's
    alternative is prepared; False: '0' through the move, and no alternative may be prepared (alt_ok stays '0',
    alt_kind still as the model says).
    arm_late: as the engine arms a request (armed False until then): stop_armed rises with the strobe of pulse
    soft_at - 1 (the pulse after the request) and falls with the strobe of pulse soft_at, which decides it.
    """

    name: str
    plan: Plan
    soft_at: int | None = None
    abort: tuple[str, int, int] | None = None
    idle: int = 0
    early: bool = False
    armed: bool = True
    arm_late: bool = False


def designed(name: str, steps: int, period: float, n_a: float, n_d: float, prescale: int = 1) -> Profile:
    """A profile from tick-domain values (as stepramp.sim.profiles designs its named ones): cruise period in ticks and
    the steps needed to reach and to leave the cruise speed."""
    spr, fclk = 200.0, 1e6
    alpha = 2.0 * math.pi / spr
    v = fclk / prescale / period
    accel, decel = alpha * v * v / (2.0 * n_a), alpha * v * v / (2.0 * n_d)
    return Profile(name, steps, accel, decel, alpha * v, spr, fclk, prescale)


def named(name: str, **kw: Any) -> Move:
    return Move(name, plan_move(**PROFILES_BY_NAME[name].args()), **kw)


def soft(name: str, plan: Plan, p: int, kind: int, phase: str, m_range: tuple[int, int]) -> Move:
    """A soft stop taken at pulse p, checked to be the case it is meant for (so that the list keeps testing it)."""
    m = soft_stop_length(plan, p)
    assert m is not None and m_range[0] <= m <= m_range[1], f"{name}: m = {m} at p = {p}"
    assert (ALT_END if m == 0 else ALT_LOAD) == kind and phase_of(plan, p) == phase, f"{name} at p = {p}"
    return Move(f"{name} soft@{p} m={m}", plan, soft_at=p)


def rule_order_plans() -> list[Move]:
    """Hand-made register contents in which each rule of the spec's order gives another value than the rules after
    it (a plan from plan_move holds the same value in every register that matches: there the order cannot show)."""
    tri = plan_move(**PROFILES_BY_NAME["triangle_asym"].args())  # sa = sd = 28
    peak = plan_move(**PROFILES_BY_NAME["triangle_peak_last_interval"].args())  # sa = sd = L = 9
    run = plan_move(**PROFILES_BY_NAME["run_start_short_ramps"].args())  # sa = 1, sd = L = 79
    assert tri.sa == tri.sd < tri.steps - 1 and peak.sa == peak.sd == peak.steps - 1
    assert run.sa == 1 and run.sd == run.steps - 1
    moves = [
        # rule 3 before rule 4: interval sa = sd is c_sa (and a soft stop at sa - 1 starts from c_sa)
        Move("rule_order c_sa before c_sd", dataclasses.replace(tri, c_sd=tri.c_sa + 37 * ONE_TICK + 1234)),
        # rule 2 before 3 and 4: interval L = sa = sd is c_last
        Move(
            "rule_order c_last before c_sa, c_sd",
            dataclasses.replace(peak, c_sa=peak.c_last + 51 * ONE_TICK, c_sd=peak.c_last + 77 * ONE_TICK),
        ),
        # rule 1 before 3, rule 2 before 4: sa = 1 is c_first, sd = L is c_last
        Move(
            "rule_order c_first before c_sa, c_last before c_sd",
            dataclasses.replace(run, c_sa=run.c_first + 40 * ONE_TICK, c_sd=run.c_last + 90 * ONE_TICK + 5),
        ),
    ]
    # an accel value below one tick after an interval without fraction: ZERO_TICKS with interval 2
    base = plan_move(**PROFILES_BY_NAME["trap_sa_three"].args())  # sa = 3: interval 2 is A_1
    zero = dataclasses.replace(base, c_first=300 * ONE_TICK, accel_seed=ONE_TICK + ONE_TICK // 2)
    assert accumulate(list(interval_values(zero)))[0][1] == 0
    moves.append(Move("zero_ticks at interval 2", zero))
    # each case tests what it says: the first matching register wins, and the next one would differ
    for move, (index, win, lose) in zip(
        moves[:3],
        [(tri.sa, "c_sa", ("c_sd",)), (9, "c_last", ("c_sa", "c_sd")), (1, "c_first", ("c_sa",))],
        strict=True,
    ):
        value = list(interval_values(move.plan))[index - 1]
        assert value == getattr(move.plan, win) << SHIFT, move.name
        assert all(value != getattr(move.plan, r) << SHIFT for r in lose), move.name
    assert list(interval_values(moves[2].plan))[-1] != moves[2].plan.c_sd << SHIFT
    return moves


# ---------------------------------------------------------------------------------------------------------------
# The sequencer's side
# ---------------------------------------------------------------------------------------------------------------


#: The move inputs that are the Plan's fields of the same name (besides l).
MOVE_INPUTS = ("sa", "sd", "c_first", "c_last", "c_sa", "c_sd", "accel_seed", "decel_seed", "cruise", "stop_ratio")


def drive_move(dut: Any, plan: Plan) -> None:
    dut.l.value = (plan.steps - 1) % (1 << 31)  # the engine's p_l = steps - 1 (all ones for N = 0)
    for name in MOVE_INPUTS:
        getattr(dut, name).value = getattr(plan, name)
    for name in SEGMENT_INPUTS:  # 0: a move from rest (tb/test_engine_segments.py plays segments through the engine)
        getattr(dut, name).value = 0


def read(dut: Any, name: str) -> int | None:
    """A port as an integer (None while it holds U or X)."""
    try:
        return int(getattr(dut, name).value)
    except ValueError:
        return None


def gap_after(plan: Plan, interval: Interval) -> int:
    """Clocks from the pulse edge that starts the interval to the next pulse edge (module docstring)."""
    return min(max(plan.prescale * interval.ticks, MIN_INTERVAL_CLKS), GAP_MAX)


class Sequencer:
    """Drives the strobes and records what differs from the model; counts what was covered."""

    def __init__(self, dut: Any, seed: int | None = None) -> None:
        self.dut = dut
        self.seed = seed
        self.failures: list[str] = []
        self.stats: Counter[str] = Counter()

    async def init(self) -> None:
        dut = self.dut
        for port in ("latch", "begin_move", "setup", "take", "advance", "take_alt", "finish"):
            getattr(dut, port).value = 0
        dut.stop_armed.value = 1
        drive_move(dut, plan_move(**PROFILES_BY_NAME["steps_0"].args()))
        await start_clock_and_reset(dut.clk, dut.rst)
        await FallingEdge(dut.clk)

    async def strobe(self, port: str, also: str | None = None) -> None:
        """port (and also) '1' at the next rising edge (called at a falling edge; returns at the falling edge after
        it)."""
        ports = (port,) if also is None else (port, also)
        for name in ports:
            getattr(self.dut, name).value = 1
        await FallingEdge(self.dut.clk)
        for name in ports:
            getattr(self.dut, name).value = 0

    def expect(self, where: str, got: dict[str, int | None], want: dict[str, int]) -> bool:
        wrong = {k: (got[k], v) for k, v in want.items() if got[k] != v}
        if wrong:
            self.failures.append(f"{where}: " + ", ".join(f"{k} = {g} (expected {w})" for k, (g, w) in wrong.items()))
        return not wrong

    def check_idle(self, where: str) -> None:
        """After begin_move or a reset: nothing offered, no stop in effect."""
        ports = ("nxt_ok", "alt_ok", "alt_kind", "stop_mode")
        self.expect(where, {p: read(self.dut, p) for p in ports}, {p: 0 for p in ports})

    def check_pulse(
        self,
        where: str,
        nxt: Interval | None,
        alt: Alternative,
        stop_mode: bool,
        early: bool = False,
        armed: bool = True,
        after: Interval | None = None,
    ) -> bool:
        """The outputs just before a pulse edge (and the internal accumulator fractions nxt_acc, alt_acc: a value one
        LSB off shows there at once, in the ticks only when it crosses a tick). early: the edge comes right after
        nxt_ok rose, so an alternative may still be in the making (alt_ok = '0': then only alt_kind is checked).
        armed False: no request is armed, so no alternative may be ready (alt_ok = '0'). after: the interval after
        nxt, which the second slot must hold by now (nx2_*, white box: two intervals ahead)."""
        ports = ("nxt_ok", "nxt_d", "nxt_state", "nxt_last", "nxt_code", "nxt_acc")
        ports += ("alt_ok", "alt_kind", "alt_d", "alt_one", "alt_code", "alt_acc", "stop_mode")
        got = {p: read(self.dut, p) for p in ports}
        want = {"alt_kind": alt.kind, "stop_mode": int(stop_mode)}
        if nxt is not None:
            want.update(nxt_ok=1, nxt_d=nxt.ticks, nxt_state=nxt.state, nxt_last=int(nxt.last), nxt_code=nxt.code)
            want.update(nxt_acc=nxt.frac)
            self.stats["intervals"] += 1
        if after is not None:
            slot_b = ("nx2_ok", "nx2_d", "nx2_state", "nx2_last", "nx2_acc")
            got.update({p: read(self.dut, p) for p in slot_b})
            want.update(nx2_ok=1, nx2_d=after.ticks, nx2_state=after.state, nx2_last=int(after.last))
            want.update(nx2_acc=after.frac)
            self.stats["two ahead"] += 1
        if alt.kind == ALT_LOAD and not armed:
            want.update(alt_ok=0)
            self.stats["alt not armed"] += 1
        elif alt.kind == ALT_LOAD and early and got["alt_ok"] == 0:
            self.stats["alt dropped in the making"] += 1
        elif alt.kind == ALT_LOAD:
            want.update(alt_ok=1, alt_d=alt.ticks, alt_one=int(alt.one), alt_code=alt.code, alt_acc=alt.frac)
            self.stats["alt m = 1" if alt.one else "alt m >= 2"] += 1
        self.stats[f"alt_kind {alt.kind:02b}"] += 1
        return self.expect(where, got, want)

    async def when_ready(self, where: str, port: str, ready: int, edge_ns: float) -> None:
        """Wait for port to rise; it must rise at edge E + ready - 1 (ready for a pulse at E + ready)."""
        limit = ClockCycles(self.dut.clk, GAP_MAX)
        if await First(RisingEdge(getattr(self.dut, port)), limit) is limit:
            self.failures.append(f"{where}: {port} not '1' within {GAP_MAX} clocks (budget: E + {ready})")
            return
        got = round((get_sim_time("ns") - edge_ns) / CLK_PERIOD_NS) + 1
        self.stats[f"{port} latency"] += 1
        if got != ready:
            self.failures.append(f"{where}: {port} ready for a pulse at E + {got}, the budget says E + {ready}")

    async def play(self, move: Move) -> None:
        """One move from edge 0 (called at a falling edge, returns at the falling edge after its last edge)."""
        dut, plan = self.dut, move.plan
        exp = Expect(plan)
        failures_before = len(self.failures)
        drive_move(dut, plan)
        dut.stop_armed.value = int(move.armed)
        if move.idle:
            await ClockCycles(dut.clk, move.idle, rising=False)
        await self.strobe("begin_move", also="latch")  # edge 0: the sequencer latches the move as it starts it
        self.check_idle(f"{move.name}: after begin_move")
        await self.strobe("setup")  # edge 1
        self.stats["moves"] += 1
        if plan.steps <= 1:  # the sequencer ends the move at edge 2, with pulse 0 (N = 1) or without
            await self.strobe("finish")
            self.expect(f"{move.name}: after finish", {"stop_mode": read(dut, "stop_mode")}, {"stop_mode": 0})
            return

        seq = exp.intervals  # the intervals of the move as it now goes (switched by a soft stop)
        stopped = False
        k = 0  # the next pulse; its edge is the next rising edge
        early = False  # this pulse edge comes one clock after nxt_ok rose
        while True:
            where = f"{move.name} (N = {plan.steps}, sa = {plan.sa}, sd = {plan.sd}): pulse {k}"
            last = k == len(seq)
            alt = exp.alternative(k) if k >= 1 and not stopped else Alternative(ALT_IGNORE)
            armed = move.armed or (move.arm_late and k == move.soft_at)
            # two ahead: from pulse 1 on (the second slot fills after pulse 0), where no request is armed
            after = seq[k + 1] if not armed and not stopped and k >= 1 and k + 1 < len(seq) else None
            ok = self.check_pulse(where, None if last else seq[k], alt, stopped, early, armed, after)
            abort = move.abort if move.abort is not None and move.abort[1] == k else None
            if len(self.failures) - failures_before >= MAX_FAILURES_PER_MOVE:
                self.failures.append(f"{move.name}: more failures not reported")
                abort = ("finish", k, 0)
            if last or seq[k].code != ERR_NONE:
                self.stats["ends" if last else "ends with an error code"] += 1
                await self.strobe("finish")
                break
            if abort is not None and abort[2] == 0:
                await self.strobe(abort[0])
                self.stats[f"abort {abort[0]}"] += 1
                self.stats[f"abort {abort[0]} during a soft stop"] += stopped
                break
            if k == move.soft_at and not stopped and ok:
                assert alt.kind in (ALT_END, ALT_LOAD) and alt.m is not None
                if alt.kind == ALT_END:
                    self.stats["soft stop m = 0 (finish)"] += 1
                    await self.strobe("finish")
                    break
                phase = phase_of(plan, k)
                self.stats[f"soft stop {phase} m {'= 1' if alt.one else '>= 2'}"] += 1
                seq, stopped = exp.stop_intervals(k), True
                assert len(seq) == k + alt.m
                port = "take_alt"
            else:
                port = "advance"
            gap = gap_after(plan, seq[k])
            offset = None if abort is None else min(abort[2], gap - 1)
            # the pulse edge E; the sequencer's registered strobe follows at E + 1 (with an abort one clock after
            # the pulse edge), and so does its armed request
            await FallingEdge(dut.clk)
            if move.arm_late and move.soft_at is not None and k in (move.soft_at - 1, move.soft_at):
                dut.stop_armed.value = int(k == move.soft_at - 1)
            await self.strobe(port, also=abort[0] if offset == 1 else None)
            if abort is not None:
                assert offset is not None
                if offset > 1:
                    if offset > 2:
                        await ClockCycles(dut.clk, offset - 2, rising=False)
                    await self.strobe(abort[0])
                self.stats[f"abort {abort[0]}"] += 1
                self.stats[f"abort {abort[0]} during a soft stop"] += stopped
                break
            k += 1
            early = move.early and k < len(seq)
            if early:
                # The sequencer's earliest pulse: the edge after the one at which nxt_ok rises (and alt_ok, where the
                # soft stop is to be taken), which must be exactly the edge "Latency budget" gives.
                # E: the pulse edge (the registered strobe's edge E + 1 just passed)
                edge = get_sim_time("ns") - 3 * CLK_PERIOD_NS // 2
                ready = seq[k].ready
                assert ready is not None
                await self.when_ready(f"{move.name}: pulse {k}: interval {k + 1}", "nxt_ok", ready, edge)
                nalt = exp.alternative(k) if k == move.soft_at and not stopped else None
                if nalt is not None and nalt.kind == ALT_LOAD:
                    await self.when_ready(f"{move.name}: pulse {k}: alternative", "alt_ok", nalt.ready, edge)
                await FallingEdge(dut.clk)
            else:
                await ClockCycles(dut.clk, gap - 2, rising=False)
        if move.abort is not None and move.abort[0] == "rst":
            self.check_idle(f"{move.name}: after the reset")
        else:
            self.expect(f"{move.name}: after finish", {"stop_mode": read(dut, "stop_mode")}, {"stop_mode": 0})

    async def run(self, moves: list[Move]) -> None:
        await self.init()
        for move in moves:
            await self.play(move)
            if len(self.failures) > 30:
                break
        await ClockCycles(self.dut.clk, 2, rising=False)
        self.dut._log.info("%d moves: %s", self.stats["moves"], dict(sorted(self.stats.items())))
        seed = "" if self.seed is None else f"{SEED_ENV}={self.seed}:\n"
        assert not self.failures, seed + "\n".join(self.failures[:40])
        assert self.stats["moves"] == len(moves), self.stats


def seed_from_env() -> int:
    return int(os.environ[SEED_ENV])


# ---------------------------------------------------------------------------------------------------------------
# cocotb tests
# ---------------------------------------------------------------------------------------------------------------


@cocotb.test(timeout_time=4, timeout_unit="ms")
async def plan_intervals(dut) -> None:
    """Trapezoids (m0 = 1 and 0, a cruise of one and of two intervals, sd = L) and triangles, back to back: every
    interval and every pulse's alternative as the model says."""
    moves = [
        named("trap_m0_one"),
        named("trap_cruise_two_intervals", idle=3),
        named("triangle_asym"),
        named("trap_m0_zero", idle=1),
        named("trap_run_to_stop"),
        named("trap_m0_one", armed=False),
        named("triangle_asym", armed=False, idle=2),
    ]
    seq = Sequencer(dut)
    await seq.run(moves)
    s = seq.stats
    assert s["alt_kind 01"] > 0 and s["alt m = 1"] > 0 and s["alt m >= 2"] > 100, s
    assert s["alt not armed"] > 50 and s["two ahead"] > 100, s


@cocotb.test(timeout_time=4, timeout_unit="ms")
async def short_moves(dut) -> None:
    """sa = 1 (run start, with sd = L too), sa = 2 and 3, sa = sd = L, sa = sd = 1, N = 0 .. 3, a first interval
    above 2^16 ticks, intervals of 1 .. 8 ticks (PRESCALE 1000)."""
    names = [
        "run_start",
        "steps_0",
        "trap_sa_two",
        "steps_1",
        "steps_2",
        "trap_sa_three",
        "steps_3",
        "steps_3_run",
        "triangle_sa_sd_one",
        "triangle_peak_last_interval",
        "long_first_delay",
        "steps_neg_2_asym",
        "trap_prescale_1000_neg",
        "run_start_short_ramps",
    ]
    moves = [named(n, idle=i % 3) for i, n in enumerate(names)]
    ticks = {m.name: Expect(m.plan).ticks for m in moves}
    assert max(ticks["trap_prescale_1000_neg"]) <= 8 and max(ticks["long_first_delay"]) > 1 << 16
    seq = Sequencer(dut)
    await seq.run(moves)
    assert seq.stats["alt m = 1"] > 0 and seq.stats["alt_kind 10"] > 50, seq.stats


@cocotb.test(timeout_time=2, timeout_unit="ms")
async def rule_order(dut) -> None:
    """Registers that differ where the spec's rule order decides (c_sa / c_sd at sa = sd, c_last at sa = sd = L,
    c_first and c_last with sa = 1 and sd = L), and an accel value below one tick (nxt_code ZERO_TICKS)."""
    seq = Sequencer(dut)
    await seq.run(rule_order_plans())
    assert seq.stats["ends with an error code"] == 1, seq.stats


@cocotb.test(timeout_time=4, timeout_unit="ms")
async def soft_stops(dut) -> None:
    """Soft stops taken: ACCEL with m >= 2 (at p = 1 from A_1, mid-ramp from A_p, at p = sa - 1 from c_sa), m = 1
    (c_last), m = 0 (finish); RUN with m >= 2 (also at p = 1 with sa = 1) and m = 1; a triangle; one at random. The
    stop's intervals to its end as soft_stop_values says."""
    seed = seed_from_env()
    dut._log.info("%s=%d", SEED_ENV, seed)
    rng = random.Random(seed)
    plans = {
        n: plan_move(**PROFILES_BY_NAME[n].args())
        for n in (
            "trap_cruise_one_interval",
            "ratio_accel_50",
            "ratio_decel_50",
            "trap_run_to_stop",
            "run_start",
            "triangle_asym",
            "trap_asym",
        )
    }
    moves = [
        soft("ratio_accel_50", plans["ratio_accel_50"], 1, ALT_LOAD, ACCEL, (2, 100)),
        soft("trap_cruise_one_interval", plans["trap_cruise_one_interval"], 9, ALT_LOAD, ACCEL, (2, 100)),
        soft("trap_cruise_one_interval", plans["trap_cruise_one_interval"], 20, ALT_LOAD, ACCEL, (2, 100)),  # sa - 1
        soft("trap_cruise_one_interval", plans["trap_cruise_one_interval"], 25, ALT_LOAD, RUN, (2, 100)),
        soft("ratio_decel_50", plans["ratio_decel_50"], 20, ALT_END, ACCEL, (0, 0)),
        soft("ratio_decel_50", plans["ratio_decel_50"], 55, ALT_LOAD, ACCEL, (1, 1)),
        soft("trap_run_to_stop", plans["trap_run_to_stop"], 40, ALT_LOAD, RUN, (1, 1)),
        soft("run_start", plans["run_start"], 1, ALT_LOAD, RUN, (2, 100)),
        soft("triangle_asym", plans["triangle_asym"], 12, ALT_LOAD, ACCEL, (2, 100)),
    ]
    assert plans["trap_cruise_one_interval"].sa == 21
    # one more at random: a pulse of trap_asym whose stop is not ignored
    trap = plans["trap_asym"]
    p = rng.choice([p for p in range(1, 80) if soft_stop_length(trap, p) is not None])
    moves.append(Move(f"trap_asym soft@{p} (random)", trap, soft_at=p, idle=rng.randint(0, 4)))
    # armed as the engine arms them (one pulse before the deciding pulse): the second slot is full at the arming
    # pulse, so the alternative is prepared from it (from pulse 1 on; at p = 1 slot A is still being prepared)
    late = [m for m in moves[:9] if m.plan is not trap]
    moves += [dataclasses.replace(m, name=m.name + " armed late", armed=False, arm_late=True) for m in late]
    seq = Sequencer(dut, seed)
    await seq.run(moves)
    s = seq.stats
    assert s["soft stop m = 0 (finish)"] == 2 and s["soft stop ACCEL m = 1"] == 2 and s["soft stop RUN m = 1"] == 2, s
    assert s["soft stop ACCEL m >= 2"] >= 8 and s["soft stop RUN m >= 2"] >= 4, s


@cocotb.test(timeout_time=4, timeout_unit="ms")
async def long_accel_ramp(dut) -> None:
    """A 300-interval accel ramp (to a cruise of 64.5 ticks: the pulse edges come at the engine's own 64 .. 80
    clocks at its end) with a soft stop near its end: c * stop_ratio summed over 300 pulses, the accel recurrence
    at large indices, the stop's ramp."""
    seed = seed_from_env()
    rng = random.Random(seed + 1)
    plan = plan_move(**designed("long_accel_ramp", 400, 64.5, 300.0, 30.0).args())
    assert plan.sa == 301 and min(Expect(plan).ticks) == 64
    p = rng.randint(260, 300)
    dut._log.info("%s=%d: soft stop at pulse %d", SEED_ENV, seed, p)
    seq = Sequencer(dut, seed)
    await seq.run([soft("long_accel_ramp", plan, p, ALT_LOAD, ACCEL, (20, 40))])
    assert seq.stats["intervals"] >= 280, seq.stats


@cocotb.test(timeout_time=6, timeout_unit="ms")
async def aborts_and_restarts(dut) -> None:
    """finish (a hard stop) or a reset at random clocks after a pulse edge (at the edge itself, while the next value
    or the alternative is being computed), also during a soft stop's ramp and at edge 2; each followed by a whole
    move checked from its edge 0 (nothing of the aborted move may leak into it)."""
    seed = seed_from_env()
    rng = random.Random(seed + 2)
    plans = [
        named("trap_sa_three").plan,
        named("ratio_accel_50").plan,
        named("triangle_asym").plan,
        named("trap_m0_one").plan,
    ]
    follow = [named("steps_3"), named("triangle_peak_last_interval"), named("trap_m0_one")]
    moves: list[Move] = []
    for trial in range(12):
        plan = plans[trial % len(plans)]
        kind = "rst" if trial in (3, 4, 11) else "finish"  # trial 4: a reset during a soft stop
        offset = rng.choice((0, 1, 2, 3, rng.randint(4, 40), rng.randint(40, 79)))
        m = soft_stop_length(plan, 3) or 0
        soft_at = 3 if trial % 3 == 1 and m >= 2 else None
        if trial == 0:
            k, offset = 0, 0  # at pulse 0's edge: the accel seed load may still be in flight
        elif soft_at is not None:
            k = rng.randint(4, 3 + min(m, 8) - 1)  # during the stop's ramp (pulse 3 + m is its last)
        else:
            k = rng.randint(1, 12)
        moves.append(
            Move(f"abort {trial}: {kind} at pulse {k} + {offset}", plan, soft_at=soft_at, abort=(kind, k, offset))
        )
        moves.append(dataclasses.replace(follow[trial % len(follow)], idle=rng.choice((0, 0, 1, 5))))
    # a move of one pulse ends at edge 2, with the accel seed load just requested: the next move is exact
    moves += [named("steps_1"), named("triangle_peak_last_interval"), named("steps_0"), named("triangle_sa_sd_one")]
    dut._log.info("%s=%d", SEED_ENV, seed)
    seq = Sequencer(dut, seed)
    await seq.run(moves)
    assert seq.stats["abort finish"] == 9 and seq.stats["abort rst"] == 3, seq.stats
    assert seq.stats["abort finish during a soft stop"] == 2, seq.stats
    assert seq.stats["abort rst during a soft stop"] == 1, seq.stats


@cocotb.test(timeout_time=3, timeout_unit="ms")
async def early_pulses(dut) -> None:
    """Pulse edges as early as the precompute allows: one clock after nxt_ok rises (after alt_ok where a soft stop
    is taken). nxt_ok and alt_ok must rise exactly when "Latency budget" says (a register E + 4, the decel seed
    E + 6, a recurrence step E + 8 + k, the alternative 3 + 2 + k after the normal value, c_last as the alternative
    1 after it); the alternative still in the making at an early pulse is dropped (the next-delay unit flushed),
    and every following interval and alternative is still the model's."""
    plans = {
        n: plan_move(**PROFILES_BY_NAME[n].args())
        for n in ("triangle_asym", "trap_asym", "trap_cruise_one_interval", "ratio_decel_50", "trap_run_to_stop")
    }
    moves = [
        Move("triangle_asym early", plans["triangle_asym"], early=True),
        named("trap_m0_one", early=True),
        named("run_start_short_ramps", early=True),
        soft("trap_asym early", plans["trap_asym"], 40, ALT_LOAD, RUN, (2, 100)),
        soft("trap_cruise_one_interval early", plans["trap_cruise_one_interval"], 15, ALT_LOAD, ACCEL, (2, 100)),
        soft("ratio_decel_50 early", plans["ratio_decel_50"], 55, ALT_LOAD, ACCEL, (1, 1)),
        soft("trap_run_to_stop early", plans["trap_run_to_stop"], 30, ALT_LOAD, RUN, (1, 1)),
    ]
    seq = Sequencer(dut)
    await seq.run([dataclasses.replace(m, early=True) for m in moves])
    s = seq.stats
    assert s["alt dropped in the making"] >= 100 and s["nxt_ok latency"] >= 400 and s["alt_ok latency"] == 4, s
    assert s["soft stop RUN m >= 2"] == 1 and s["soft stop ACCEL m >= 2"] == 1, s
    assert s["soft stop RUN m = 1"] == 1 and s["soft stop ACCEL m = 1"] == 1, s


def test_precompute() -> None:
    """The cocotb tests above in one simulation; the seed is random unless PRECOMPUTE_SEED is set."""
    run_seeded("stepramp_precompute", "test_precompute", SEED_ENV)
