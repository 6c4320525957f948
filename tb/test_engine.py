# SPDX-License-Identifier: MIT
"""stepramp_engine against the bit-exact model: every step edge, the step count, the position, done.

Each pytest test runs one GHDL simulation that plays a list of moves back to back (stepramp.sim.engine_bench drives and
records, the checks are here). The expected edges come from stepramp.models.engine, which sw/tests holds to the ideal
trapezoid; nothing is taken from the RTL's own output.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable, Sequence
from typing import Any

import pytest

from stepramp.board.plan import Plan, plan_move
from stepramp.board.regmap import ERROR_CODES
from stepramp.models.blocks import recurrence_iterations
from stepramp.models.engine import (
    FIRST_PULSE_LATENCY,
    edges_with_stop,
    first_space_fault,
    min_gap,
    phase_of,
    soft_stop_length,
    soft_stop_pulse,
    soft_stop_values,
    tick_times,
)
from stepramp.models.engine import edges as model_edges
from stepramp.models.engine import phases as model_phases
from stepramp.sim.engine_sim import SimResult, Stop, simulate
from stepramp.sim.profiles import PROFILES, PROFILES_BY_NAME, Profile, exact_plan
from tbutil import build_dir, edges_differ, first_mismatch

CHUNKS = 4
ERR = {name: code for name, (code, _) in ERROR_CODES.items()}


def plans_of(profiles: Sequence[Profile]) -> list[Plan]:
    return [plan_move(**p.args()) for p in profiles]


def move_problems(
    res: SimResult, expected: list[int], *, code: int = 0, position: int | None = None, idle_after: bool = False
) -> list[str]:
    """What differs between a finished move and its expectation: the pulse edges (the first difference shown), done
    with error code `code` (0: without error), step_count = the pulses expected; with `position`, the final position;
    with idle_after, busy low and the FSM back in STOP in the cycle after done."""
    problems = []
    if res.edges != expected:
        problems.append(edges_differ(res.edges, expected))
    if not res.done or res.err_code != code or res.error != int(code != 0):
        problems.append(f"done={res.done} error={res.error} code={res.err_code}, expected code {code}")
    if res.step_count != len(expected):
        problems.append(f"step_count {res.step_count}, expected {len(expected)}")
    if position is not None and res.final_position != position:
        problems.append(f"position {res.final_position}, expected {position}")
    if idle_after and (res.busy_after != 0 or res.state_after != "STOP"):
        problems.append(f"after done busy={res.busy_after} state={res.state_after}")
    return problems


def check_moves(names: Sequence[str], plans: Sequence[Plan], results: Sequence[SimResult]) -> None:
    """Every move: edges and FSM states equal to the model's, N pulses, done without error, position exact, back
    in STOP."""
    assert len(results) == len(plans), f"only {len(results)} of {len(plans)} moves finished"
    position = 0
    problems: list[str] = []
    for name, plan, res in zip(names, plans, results, strict=True):
        expected = model_edges(plan)
        position += signed_steps(plan, plan.steps)
        problems += [f"{name}: {p}" for p in move_problems(res, expected, position=position, idle_after=True)]
        if res.edges != expected:
            continue
        if any(b - a < plan.prescale for a, b in zip(res.edges, res.edges[1:], strict=False)):
            problems.append(f"{name}: an interval shorter than one tick")
        phases = model_phases(plan)
        if res.states[: len(phases)] != phases:
            problems.append(f"{name}: FSM states per interval {res.states[:12]}... vs model {phases[:12]}...")
    assert not problems, "\n".join(problems)


def run_profiles(tag: str, profiles: Sequence[Profile]) -> None:
    plans = plans_of(profiles)
    results = simulate(plans, build_dir(f"engine_{tag}"))
    check_moves([p.name for p in profiles], plans, results)


#: AVR446's known defects, each with the profiles that would expose it.
DEFECTS: dict[str, list[str]] = {
    # AVR446 computes a garbage delay when accel_count is 0 (1-step moves and the first step).
    "garbage_final_delay_at_accel_count_zero": ["steps_1", "steps_neg_1", "steps_2", "steps_neg_2_asym"],
    # Speed reached within the first step: AVR446 enters RUN with a stale or zero last_accel_delay.
    "start_in_run_stale_delay": ["run_start", "run_start_short_ramps", "run_start_negative", "run_start_prescale_5"],
    # RUN -> DECEL restarted the recurrence from a faster delay than cruise (up to +55 % overspeed).
    "run_to_decel_overspeed": ["trap_basic", "trap_long_cruise", "trap_run_to_stop", "trap_speed_limit_edge"],
    # The decel ramp shifted by one index: the move ends early, stopping from about 2.5x the final speed.
    "decel_ramp_shifted": ["trap_asym", "trap_m0_zero", "trap_m0_one", "triangle_asym"],
    # The remainder not cleared at ACCEL -> DECEL: decel far too soft after a long ramp.
    "remainder_not_cleared_accel_to_decel": ["triangle_long_ramp", "triangle_sym", "triangle_negative"],
    # accel_lim rounding to 0 and clamped to 1 when accel >> decel (braking far too hard), and the reverse.
    "accel_much_greater_than_decel": [
        "ratio_accel_50",
        "ratio_decel_50",
        "ratio_accel_100_triangle",
        "ratio_decel_100_triangle",
    ],
    # 16-bit limits in the original: delays above 2^16 ticks here, and the signed direction arithmetic.
    "sixteen_bit_limits_and_unsigned_decel": ["long_first_delay", "trap_negative", "triangle_prescale_3_neg"],
    # 1-, 2- and 3-step moves, and never a zero or negative interval (checked on every profile too).
    "one_two_three_step_moves": ["steps_0", "steps_1", "steps_2", "steps_3", "steps_3_run", "steps_neg_3_prescale_2"],
}


@pytest.mark.parametrize("defect", sorted(DEFECTS))
def test_avr446_defect_fixed(defect: str) -> None:
    """The RTL matches the model on the profiles that expose each AVR446 defect (the model is held to the ideal)."""
    run_profiles(f"defect_{defect}", [PROFILES_BY_NAME[name] for name in DEFECTS[defect]])


#: The profiles not already played by a defect test.
OTHER_PROFILES = [p for p in PROFILES if not any(p.name in names for names in DEFECTS.values())]


@pytest.mark.parametrize("chunk", range(CHUNKS))
def test_engine_profiles(chunk: int) -> None:
    """Every other named and random profile (both directions, PRESCALE 1 and > 1, every transition)."""
    run_profiles(f"profiles_{chunk}", OTHER_PROFILES[chunk::CHUNKS])


# --------------------------------------------------------------------------------------------------------
# Stops (docs/algorithm.md "Soft stop", docs/stepramp_engine.md): the model's edges_with_stop is the reference
# --------------------------------------------------------------------------------------------------------

#: The most cycles one stop test may simulate (each test is one simulation, moves back to back).
STOP_TEST_CYCLES = 1_000_000


def signed_steps(plan: Plan, pulses: int) -> int:
    return -pulses if plan.direction else pulses


def play_stops(tag: str, cases: Sequence[tuple[str, Plan, Stop]]) -> list[SimResult]:
    """Simulate the cases back to back (one simulation) after checking the cycle budget of the test."""
    cycles = 0
    for _, plan, stop in cases:
        expected = edges_with_stop(plan, stop.kind, stop.at_cycle)
        cycles += max([stop.at_cycle, *expected]) + 10
    assert cycles < STOP_TEST_CYCLES, f"{tag}: {cycles} simulated cycles, keep it under {STOP_TEST_CYCLES}"
    results = simulate([c[1] for c in cases], build_dir(f"engine_{tag}"), stops=[c[2] for c in cases])
    assert len(results) == len(cases), f"only {len(results)} of {len(cases)} moves finished"
    return results


def check_stopped_move(name: str, plan: Plan, stop: Stop, res: SimResult, position: int) -> list[str]:
    """Common checks: edges as the model says, done without error, counters exact, back in STOP."""
    expected = edges_with_stop(plan, stop.kind, stop.at_cycle)
    problems = move_problems(res, expected, position=position, idle_after=True)
    return [f"{name} {stop.kind} stop at edge {stop.at_cycle}: {p}" for p in problems]


def hard_stop_cases() -> list[tuple[str, Plan, Stop]]:
    cases: list[tuple[str, Plan, Stop]] = []
    for name in ("trap_basic", "trap_prescale_4", "triangle_prescale_3_neg", "run_start_negative", "steps_1"):
        plan = plan_move(**PROFILES_BY_NAME[name].args())
        normal = model_edges(plan)
        if plan.steps < 2:
            times = [0, 1, 2, 3]
        else:
            in_accel = normal[min(5, plan.sa - 1)] + 7
            in_run = normal[(plan.sa + plan.sd) // 2] + 3
            in_decel = normal[min(plan.sd + 3, plan.steps - 2)] + 1
            k = min(12, plan.steps - 1)
            times = [0, 1, 2, in_accel, in_run, in_decel, normal[k], normal[k] - 1, normal[-1]]
            if name == "trap_basic":
                times.append(normal[-1] + 1)  # after the last pulse: not busy any more, ignored
                # at the phase boundaries: late in the last interval of ACCEL and of RUN (the next interval is of
                # the next phase), and early in the first interval of RUN and of DECEL (pulses sa - 1 and sd - 1)
                times += [normal[b - 1] + d for b in (plan.sa, plan.sd) for d in (-3, 3)]
        cases += [(name, plan, Stop("hard", e)) for e in times]
    return cases


def test_engine_hard_stop() -> None:
    """Hard stop in ACCEL, RUN, DECEL, at the start edge, at a pulse edge, one cycle before one, after the move, and on
    both sides of the ACCEL -> RUN and RUN -> DECEL boundaries."""
    cases = hard_stop_cases()
    results = play_stops("hard_stop", cases)
    position = 0
    problems: list[str] = []
    for (name, plan, stop), res in zip(cases, results, strict=True):
        position += signed_steps(plan, len(res.edges))
        problems += check_stopped_move(name, plan, stop, res, position)
        last = model_edges(plan)[-1] if plan.steps else FIRST_PULSE_LATENCY
        if any(e >= stop.at_cycle for e in res.edges):
            problems.append(f"{name}: a pulse at or after the hard stop at edge {stop.at_cycle}: {res.edges[-3:]}")
        # done comes at the request's edge (or with the last pulse when the request comes after the move)
        if res.done_edge != min(stop.at_cycle, last):
            problems.append(f"{name}: done at edge {res.done_edge}, hard stop at {stop.at_cycle}")
    assert not problems, "\n".join(problems)
    # the cases cover: a pulse suppressed, none at all, and a request after the move (nothing changes)
    kept = [len(r.edges) for r in results]
    assert 0 in kept
    assert any(len(r.edges) == c[1].steps for c, r in zip(cases, results, strict=True))


#: Soft stop profiles: P = 1 and > 1, both directions, start in RUN, accel >> decel and decel >> accel, and the
#: tightest budget (ACCEL intervals near MIN_INTERVAL_CLKS, two divisions per interval).
SOFT_PROFILES = (
    "trap_basic",
    "trap_prescale_4",
    "triangle_prescale_3_neg",
    "trap_negative",
    "run_start",
    "ratio_decel_50",
    "trap_speed_limit_edge",
    "trap_prescale_100",
    "trap_run_to_stop",
)


SOFT_CHUNKS = 3


def soft_stop_cases(chunk: int) -> list[tuple[str, Plan, Stop]]:
    """Per profile: around the edges of a pulse early in ACCEL, late in ACCEL and in RUN (e = edge - 1, edge,
    edge + 1), and before pulse 0; in DECEL and at the start edge (full moves, so fewer of them)."""
    cases: list[tuple[str, Plan, Stop]] = []
    for j, name in enumerate(SOFT_PROFILES):
        if j % SOFT_CHUNKS != chunk:
            continue
        plan = plan_move(**PROFILES_BY_NAME[name].args())
        normal = model_edges(plan)
        length = plan.steps - 1
        times = {1}
        for k in (2, plan.sa - 1, min(plan.sa + 2, (plan.sa + plan.sd) // 2)):
            if 1 <= k <= length:
                times.update((normal[k] - 1, normal[k], normal[k] + 1))
        if j % 2 == 0:
            times.add(normal[min(plan.sd + 1, length)] - 1)  # decided in DECEL: ignored
        elif plan.sd >= 2:
            times.add(normal[plan.sd - 1] - 1)  # the last RUN (or ACCEL) pulse: p + m >= L, mostly ignored
        if j < SOFT_CHUNKS:
            times.add(0)  # the start edge: not busy, ignored
        cases += [(name, plan, Stop("soft", e)) for e in sorted(times)]
    if chunk == SOFT_CHUNKS - 1:
        # accel = 100 * decel, stop decided at pulse 1 (D = A_1, m = 100), and at pulse 2 (DECEL already)
        plan = plan_move(**PROFILES_BY_NAME["ratio_accel_100_triangle"].args())
        cases += [("ratio_accel_100_triangle", plan, Stop("soft", model_edges(plan)[k - 1] - 1)) for k in (1, 2)]
    return cases


@pytest.mark.parametrize("chunk", range(SOFT_CHUNKS))
def test_engine_soft_stop(chunk: int) -> None:
    """Soft stop in ACCEL, RUN and DECEL, around pulse edges, P = 1 and > 1, both directions: as the model says."""
    cases = soft_stop_cases(chunk)
    results = play_stops(f"soft_stop_{chunk}", cases)
    position = 0
    problems: list[str] = []
    phases_seen: set[str] = set()
    for (name, plan, stop), res in zip(cases, results, strict=True):
        position += signed_steps(plan, len(res.edges))
        problems += check_stopped_move(name, plan, stop, res, position)
        p = soft_stop_pulse(plan, stop.at_cycle)
        if p is None:
            continue
        phase = phase_of(plan, p)
        m = soft_stop_length(plan, p)
        if m is not None:
            phases_seen.add(f"{phase} stopped")
        elif p < plan.steps - 1:
            phases_seen.add(f"{phase} ignored")
        if m and len(res.edges) >= 3:
            # the stop's ramp ends on its slowest interval (m >= 2: intervals p + 1 .. p + m are the stop's; with
            # m = 1 its one interval is c_last, after the plan's interval p), and the FSM shows DECEL from interval
            # p + 1 on
            iv = [b - a for a, b in zip(res.edges, res.edges[1:], strict=False)]
            if m >= 2 and iv[-1] < iv[-2]:
                problems.append(f"{name} soft stop at edge {stop.at_cycle}: last interval {iv[-1]} < {iv[-2]}")
            if any(s != "DECEL" for s in res.states[p:-1]):
                problems.append(f"{name} soft stop at edge {stop.at_cycle}: states {res.states[p:]}")
    assert not problems, "\n".join(problems)
    assert {"ACCEL stopped", "RUN stopped"} <= phases_seen, phases_seen


def stop_combination_cases() -> list[tuple[str, Plan, list[Stop], list[int]]]:
    """Two requests in one move, with the pulses expected (composed from the model's single-request edges)."""
    cases: list[tuple[str, Plan, list[Stop], list[int]]] = []
    for name in ("trap_basic", "triangle_prescale_3_neg"):
        plan = plan_move(**PROFILES_BY_NAME[name].args())
        normal = model_edges(plan)
        k = plan.sa // 2  # decided in ACCEL
        e1 = normal[k - 1] + 5
        soft = edges_with_stop(plan, "soft", e1)
        assert len(soft) > k + 3, name
        # a second soft stop while the first waits for its pulse, and one after it took effect: both ignored
        cases.append((name, plan, [Stop("soft", e1), Stop("soft", normal[k] - 1)], soft))
        cases.append((name, plan, [Stop("soft", e1), Stop("soft", soft[k + 2] - 1)], soft))
        # a hard stop during the stop's ramp (one cycle before one of its pulses), and at the edge of its last pulse
        for e2 in (soft[k + 2] - 1, soft[-1]):
            cases.append((name, plan, [Stop("soft", e1), Stop("hard", e2)], [x for x in soft if x < e2]))
        # soft and hard at the same edge: the hard stop wins
        cases.append((name, plan, [Stop("soft", e1), Stop("hard", e1)], [x for x in normal if x < e1]))
    # A stop decided in ACCEL that its rule ignores (p + m >= L) where one decided a pulse later, in RUN, would act (a
    # hand-made move: STOP_RATIO 10, sa 3, sd 10, L 19): a second request while the first is armed (after pulse 1,
    # before pulse 2, which decides it) changes nothing; one sampled at pulse 2's edge, where the first is decided
    # and ignored, is a request of its own, decided at pulse 4.
    plan = hand_plan(
        20,
        sa=3,
        sd=10,
        accel_seed=100 * Q16,
        c_sa=60 * Q16,
        cruise=60 * Q32,
        c_sd=60 * Q16,
        decel_seed=60 * Q16,
        stop_ratio=10 * Q16,
    )
    normal = model_edges(plan)
    first = Stop("soft", normal[0] + 1)
    assert soft_stop_pulse(plan, first.at_cycle) == 2 and soft_stop_length(plan, 2) is None
    assert phase_of(plan, 4) == "RUN" and soft_stop_length(plan, 4) == 10
    cases.append(("ignored stop, then one while it is armed", plan, [first, Stop("soft", normal[1] + 1)], normal))
    at_decision = edges_with_stop(plan, "soft", normal[2])
    assert len(at_decision) < len(normal)
    cases.append(("ignored stop, then one at its deciding pulse", plan, [first, Stop("soft", normal[2])], at_decision))
    return cases


def test_engine_stop_combinations() -> None:
    """A second soft stop is ignored (pending, armed or in effect), but not one at the pulse that decided and ignored
    the first; a hard stop still ends a soft stop; hard beats soft."""
    cases = stop_combination_cases()
    cycles = sum(max([s.at_cycle for s in stops] + expected) for _, _, stops, expected in cases)
    assert cycles < STOP_TEST_CYCLES
    results = simulate([c[1] for c in cases], build_dir("engine_stop_combinations"), stops=[c[2] for c in cases])
    assert len(results) == len(cases), f"only {len(results)} of {len(cases)} moves finished"
    position = 0
    problems: list[str] = []
    for (name, plan, stops, expected), res in zip(cases, results, strict=True):
        position += signed_steps(plan, len(res.edges))
        what = f"{name} {[(s.kind, s.at_cycle) for s in stops]}"
        problems += [f"{what}: {p}" for p in move_problems(res, expected, position=position, idle_after=True)]
    assert not problems, "\n".join(problems)


# --------------------------------------------------------------------------------------------------------------
# The move is latched by `load` (the core's START acceptance), not by the later start; step spacing.
# --------------------------------------------------------------------------------------------------------------
def test_engine_runs_the_loaded_move() -> None:
    """load latches the move: whatever the inputs carry afterwards (another move, or bad values: PRESCALE 0, a
    zero C_FIRST), the start runs the loaded one, edge for edge as the model, with its checks. And a bad move that
    was loaded is rejected although good values sit on the inputs at start."""
    good = plan_move(**PROFILES_BY_NAME["trap_basic"].args())
    other = plan_move(**PROFILES_BY_NAME["triangle_asym"].args())
    bad_prescale = dataclasses.replace(good, prescale=0)
    bad_first = dataclasses.replace(good, c_first=0)
    # (loaded, on the inputs after load, load_lead, expected error code)
    cases = [
        (good, other, 1, 0),
        (other, good, 7, 0),
        (good, bad_prescale, 3, 0),
        (good, bad_first, 300, 0),
        (bad_prescale, good, 2, ERR["PRESCALE"]),
        (bad_first, good, 5, ERR["C_FIRST"]),
    ]
    extras = [
        # the direction comes with start (the stepping logic's eng_direction), not with load
        {"load_lead": lead, "after_load": {**dataclasses.asdict(after), "direction": loaded.direction}}
        for loaded, after, lead, _ in cases
    ]
    results = simulate([c[0] for c in cases], build_dir("engine_load"), extras=extras)
    assert len(results) == len(cases)
    problems = []
    for i, ((loaded, _, lead, code), res) in enumerate(zip(cases, results, strict=True)):
        expected = [] if code else model_edges(loaded)
        problems += [f"case {i} (lead {lead}): {p}" for p in move_problems(res, expected, code=code)]
    assert not problems, "\n".join(problems)


def test_engine_start_without_load() -> None:
    """A start without a load since the previous start latches the inputs as a load would (docs/stepramp_engine.md,
    Ports): each move below is started alone, with its own registers on the inputs, after a move that was loaded and
    ran, so interval 1 (c_first) and the accel seed, which the precompute latches, and the checks must be this
    move's."""
    trap = plan_move(**PROFILES_BY_NAME["trap_basic"].args())
    tri = plan_move(**PROFILES_BY_NAME["triangle_asym"].args())
    bad_first = dataclasses.replace(trap, c_first=0)
    # (move, started without load, expected error code)
    cases = [(trap, False, 0), (tri, True, 0), (trap, True, 0), (bad_first, True, ERR["C_FIRST"]), (tri, True, 0)]
    extras = [{"start_only": True} if alone else {} for _, alone, _ in cases]
    results = simulate([c[0] for c in cases], build_dir("engine_start_only"), extras=extras)
    assert len(results) == len(cases)
    problems = []
    for i, ((plan, _, code), res) in enumerate(zip(cases, results, strict=True)):
        expected = [] if code else model_edges(plan)
        problems += [f"move {i}: {p}" for p in move_problems(res, expected, code=code)]
    assert not problems, "\n".join(problems)


def spacing_cases() -> list[tuple[Plan, int, int]]:
    """(plan, step_width, step_space): 1-, 2- and 3-tick intervals (first, cruise with a fraction, last) at
    PRESCALE 1, 4, 5 and 8 against min_gap = max(W, 1) + max(S, 1) from 2 to 25 clocks, on both sides of it."""
    cases = [(exact_plan(2, 1, 1.0), 1, 1)]  # the adversarial case: pulses at edges 2 and 3 would merge
    for first in (1, 2, 3):  # the only interval of 2-step moves at PRESCALE 1 (a later one would be LATE)
        for width, space in ((1, 1), (1, 2), (2, 1), (0, 0), (1, 0), (2, 2)):
            cases.append((exact_plan(2, 1, first), width, space))
    for cruise in (1.0, 2.0, 3.0):  # cruise intervals at PRESCALE 8: 8, 16, 24 clocks
        for width, space in ((4, 4), (5, 4), (8, 8), (8, 9), (12, 12), (12, 13)):
            cases.append((exact_plan(6, 8, 20, cruise), width, space))
    for last in (1.0, 2.0, 3.0):  # the last interval at PRESCALE 5: 5, 10, 15 clocks
        for width, space in ((2, 3), (3, 3), (7, 3), (8, 3), (10, 5), (10, 6)):
            cases.append((exact_plan(5, 5, 30, 30, last, direction=1), width, space))
    for width, space in ((3, 1), (3, 2), (2, 3), (4, 2), (4, 4), (4, 5)):  # 1.5 ticks at PRESCALE 4: 4, 8, 4, ..
        cases.append((exact_plan(9, 4, 20, 1.5), width, space))
    return cases


def test_engine_step_spacing() -> None:
    """A pulse closer than min_gap clocks to the previous one is not emitted: the move ends at its edge with error
    STEP_SPACE, position and step count exact for the pulses before it; the model (first_space_fault) names the
    pulse. Pulses that keep the distance, even by exactly min_gap, are untouched."""
    cases = spacing_cases()
    plans = [plan for plan, _, _ in cases]
    extras = [{"min_gap": min_gap(width, space)} for _, width, space in cases]
    results = simulate(plans, build_dir("engine_step_spacing"), extras=extras)
    assert len(results) == len(cases)
    problems = []
    position = 0
    faults = 0
    for (plan, width, space), res in zip(cases, results, strict=True):
        normal = model_edges(plan)
        k = first_space_fault(normal, min_gap(width, space))
        expected = normal if k is None else normal[:k]
        faults += k is not None
        position += -len(expected) if plan.direction else len(expected)
        label = f"P={plan.prescale} N={plan.steps} W={width} S={space} model {normal}"
        code = 0 if k is None else ERR["STEP_SPACE"]
        problems += [f"{label}: {p}" for p in move_problems(res, expected, code=code)]
        if res.final_position != position:
            problems.append(f"{label}: position {res.final_position}, expected {position}")
            position = res.final_position or 0
    assert not problems, "\n".join(problems)
    assert 0 < faults < len(cases), f"{faults} of {len(cases)} cases fault: the cases do not straddle min_gap"


# --------------------------------------------------------------------------------------------------------------
# Error codes, the control inputs (pos_load, start, rst) and the latency budget (docs/stepramp_engine.md). The
# expectations are the docs' tables written out in plain Python below, and stepramp.models.engine.
# --------------------------------------------------------------------------------------------------------------
Q16 = 1 << 16  # one tick in Q32.16
Q32 = 1 << 32  # one tick in Q32.32
Q48_TOP = (1 << 48) - 1  # the largest Q32.16 value

#: Outputs in their reset state (docs/stepramp_engine.md, ports: rst stops any move, position 0, err_code 0).
RESET_STATE = {
    "busy": 0,
    "done": 0,
    "error": 0,
    "err_code": 0,
    "state": "STOP",
    "position": 0,
    "step_count": 0,
    "cur_delay": 0,
    "step": 0,
}


def documented_check(plan: Plan) -> int:
    """The parameter check of docs/stepramp_engine.md, "Error codes", codes 1 .. 9: the lowest code whose cause
    applies (0: none). Only the values the move uses are checked."""
    length = plan.steps - 1
    sa, sd = plan.sa, plan.sd
    ramp = plan.steps >= 2
    rules = (
        (ERR["PRESCALE"], plan.prescale == 0),
        (ERR["BOUNDS"], ramp and not 1 <= sa <= sd <= length),
        (ERR["C_FIRST"], ramp and plan.c_first < Q16),
        (ERR["C_LAST"], plan.steps >= 3 and plan.c_last < Q16),
        (ERR["C_SA"], ramp and 1 < sa < length and plan.c_sa < Q16),
        (ERR["C_SD"], ramp and 1 < sd < length and sd != sa and plan.c_sd < Q16),
        (ERR["CRUISE"], ramp and sd - sa >= 2 and plan.cruise < Q32),
        (ERR["ACCEL_SEED"], ramp and sa >= 3 and plan.accel_seed < Q16),
        (ERR["DECEL_SEED"], ramp and length - sd >= 2 and plan.decel_seed < Q16),
    )
    return next((code for code, applies in rules if applies), 0)


def unused_zeroed(plan: Plan) -> Plan:
    """The plan with every register its move does not use (the conditions of the same table) set to 0; stop_ratio
    serves only a soft stop."""
    keep = ("steps", "direction", "prescale")
    if plan.steps <= 1:
        return dataclasses.replace(plan, **{f.name: 0 for f in dataclasses.fields(Plan) if f.name not in keep})
    length = plan.steps - 1
    sa, sd = plan.sa, plan.sd
    unused = {
        "stop_ratio": True,
        "c_last": plan.steps == 2,
        "c_sa": not 1 < sa < length,
        "c_sd": not (1 < sd < length and sd != sa),
        "cruise": sd - sa < 2,
        "accel_seed": sa < 3,
        "decel_seed": length - sd < 2,
    }
    return dataclasses.replace(plan, **{name: 0 for name, zero in unused.items() if zero})


def hand_plan(steps: int, *, sa: int = 1, sd: int | None = None, **regs: int) -> Plan:
    """A hand-made move, register values raw (Q32.16, cruise Q32.32): PRESCALE 1, c_first and c_last 100 ticks,
    sa = 1 and sd = L unless given, every other register 0 unless given."""
    fields = {f.name: 0 for f in dataclasses.fields(Plan)}
    fields.update(prescale=1, c_first=100 * Q16, c_last=100 * Q16)
    fields.update(regs, steps=steps, sa=sa, sd=steps - 1 if sd is None else sd)
    return Plan(**fields)


#: Short moves from plan_move with every phase (ACCEL and DECEL on the recurrences, RUN), about 15,000 clocks.
SHORT_TRAP = plan_move(steps=30, accel=20000, decel=15000, speed=100, spr=200, fclk=1e6)
SHORT_TRAP_P3_NEG = plan_move(steps=-28, accel=12000, decel=20000, speed=100, spr=200, fclk=1e6, prescale=3)

#: Short profiles with many unused registers: N = 0, 1, 2, 3, sa = sd = 1.
ZEROED_PROFILES = ("steps_0", "steps_1", "steps_neg_1", "steps_2", "steps_3", "steps_3_run", "triangle_sa_sd_one")


def profile_plan(name: str) -> Plan:
    return plan_move(**PROFILES_BY_NAME[name].args())


def check_error_cases() -> list[tuple[str, Plan, int]]:
    """(label, plan, code): each parameter check alone, several at once (the lowest code wins), integer parts of
    exactly 1, and moves whose unused registers are 0 (accepted: code 0)."""
    good = profile_plan("trap_basic")
    length = good.steps - 1
    # every check of the table is live on this move
    assert good.sa >= 3 and good.sd - good.sa >= 2 and length - good.sd >= 2 and documented_check(good) == 0
    rep = dataclasses.replace
    neg = rep(good, direction=1)
    cases: list[tuple[str, Plan, int]] = [
        ("PRESCALE N=0", hand_plan(0, prescale=0, sa=0, sd=0, c_first=0, c_last=0), ERR["PRESCALE"]),
        ("PRESCALE N=1", hand_plan(1, prescale=0, sa=0, sd=0, c_first=0, c_last=0), ERR["PRESCALE"]),
        ("PRESCALE", rep(good, prescale=0), ERR["PRESCALE"]),
        ("BOUNDS sa=0", rep(good, sa=0), ERR["BOUNDS"]),
        ("BOUNDS sd=0", rep(neg, sd=0), ERR["BOUNDS"]),
        ("BOUNDS sa>sd", rep(good, sa=good.sd + 1), ERR["BOUNDS"]),
        ("BOUNDS sd>L", rep(good, sd=length + 1), ERR["BOUNDS"]),
        ("BOUNDS sa=sd>L", rep(neg, sa=length + 1, sd=length + 1), ERR["BOUNDS"]),
        ("BOUNDS all-ones sa", rep(good, sa=2**31 - 1), ERR["BOUNDS"]),
        ("BOUNDS N=2 sa=2", hand_plan(2, sa=2, sd=2), ERR["BOUNDS"]),
        ("C_FIRST", rep(good, c_first=Q16 - 1), ERR["C_FIRST"]),
        ("C_FIRST N=2", hand_plan(2, c_first=0, c_last=0), ERR["C_FIRST"]),
        ("C_LAST", rep(neg, c_last=Q16 - 1), ERR["C_LAST"]),
        ("C_LAST N=3", hand_plan(3, c_last=0), ERR["C_LAST"]),
        ("C_SA", rep(good, c_sa=Q16 - 1), ERR["C_SA"]),
        ("C_SD", rep(neg, c_sd=0), ERR["C_SD"]),
        ("CRUISE", rep(good, cruise=Q32 - 1), ERR["CRUISE"]),
        ("ACCEL_SEED", rep(good, accel_seed=Q16 - 1), ERR["ACCEL_SEED"]),
        # sa = 3 and sa = 4: each side of the check's "sa >= 3" split into bits (trap_basic's sa = 31 has both)
        ("ACCEL_SEED sa=3", rep(good, sa=3, accel_seed=Q16 - 1), ERR["ACCEL_SEED"]),
        ("ACCEL_SEED sa=4", rep(good, sa=4, accel_seed=Q16 - 1), ERR["ACCEL_SEED"]),
        ("DECEL_SEED", rep(neg, decel_seed=0), ERR["DECEL_SEED"]),
        ("all of them", rep(good, prescale=0, sa=0, c_first=0, c_last=0, cruise=0, decel_seed=0), ERR["PRESCALE"]),
        ("all zero but PRESCALE", hand_plan(5, c_first=0, c_last=0, sa=0, sd=0), ERR["BOUNDS"]),
        ("BOUNDS + C_FIRST", rep(good, sd=length + 1, c_first=0), ERR["BOUNDS"]),
        ("C_FIRST + C_LAST + CRUISE", rep(good, c_first=0, c_last=0, cruise=0), ERR["C_FIRST"]),
        (
            "C_LAST .. DECEL_SEED",
            rep(neg, c_last=0, c_sa=0, c_sd=0, cruise=0, accel_seed=0, decel_seed=0),
            ERR["C_LAST"],
        ),
        ("C_SA + C_SD + CRUISE", rep(good, c_sa=0, c_sd=0, cruise=0), ERR["C_SA"]),
        ("C_SD + CRUISE + seeds", rep(good, c_sd=0, cruise=0, accel_seed=0, decel_seed=0), ERR["C_SD"]),
        ("CRUISE + seeds", rep(neg, cruise=0, accel_seed=0, decel_seed=0), ERR["CRUISE"]),
        ("ACCEL_SEED + DECEL_SEED", rep(good, accel_seed=0, decel_seed=0), ERR["ACCEL_SEED"]),
        # an integer part of exactly 1 passes (PRESCALE 64: no interval is late)
        ("one tick each", hand_plan(6, prescale=64, c_first=Q16, c_last=Q16, cruise=Q32), 0),
    ]
    unused = [profile_plan(name) for name in ZEROED_PROFILES]
    unused += [SHORT_TRAP, SHORT_TRAP_P3_NEG, rep(SHORT_TRAP, sd=SHORT_TRAP.steps - 2)]  # the last: m0 = 0
    for plan in unused:
        zeroed = unused_zeroed(plan)
        assert model_edges(zeroed) == model_edges(plan), "the model uses a register the docs call unused"
        cases.append((f"N={plan.steps} sa={plan.sa} sd={plan.sd} P={plan.prescale}, unused registers 0", zeroed, 0))
    for label, plan, code in cases:
        assert documented_check(plan) == code, f"{label}: the case does not test what it says"
    return cases


def runtime_error_cases() -> list[tuple[str, Plan, Stop | None, int, int]]:
    """(label, plan, soft stop or None, code, k): the move ends with `code` at pulse k, pulses 0 .. k emitted (for
    ZERO_TICKS k is the model's; -1 here)."""
    # LATE: c_last is ready 4 clocks after the pulse edge that starts the interval before it (budget below).
    # Later: interval 1 of 4 clocks (interval 2, the cruise, just in time), then cruises of 2 clocks: interval 3 is
    # prepared after interval 2 (a register value every 3 clocks: IDX, DECIDE, ADD), ready 3 clocks after pulse 1.
    late_first = hand_plan(3, c_first=2 * Q16)
    late_later = hand_plan(6, direction=1, c_first=4 * Q16, cruise=2 * Q32)
    # ZERO_TICKS: A_1 = A_0 - 2 A_0 div 5 is 0.6 tick from a seed of 1 tick, after a c_first without fraction
    zero_first = hand_plan(4, prescale=8, sa=3, sd=3, accel_seed=Q16)
    zero_later = hand_plan(6, prescale=64, direction=1, sa=5, sd=5, accel_seed=2 * Q16)
    # RANGE: a soft stop's first value D_1 = D + 2D div 7 (m = 2) leaves Q32.16 from a D near 2^48, the plan's next
    # interval (a register): D = c_sa in ACCEL (p = 1, sa = 2, m = p * stop_ratio = 2), D = cruise >> 16 in RUN
    # (p = sa = 2, m = L - sd + 1 = 2). The decel recurrence itself cannot get there in a simulation: its value
    # before the one out of range is an interval of more than 0.6 * 2^32 ticks.
    range_accel = hand_plan(6, sa=2, sd=2, c_first=200 * Q16, c_sa=Q48_TOP, decel_seed=100 * Q16, stop_ratio=2 * Q16)
    range_run = hand_plan(10, sa=2, sd=8, c_first=200 * Q16, c_sa=200 * Q16, c_sd=100 * Q16, cruise=2**64 - 1)
    return [
        ("LATE at pulse 1", late_first, None, ERR["LATE"], 1),
        ("LATE at pulse 2, negative", late_later, None, ERR["LATE"], 2),
        ("ZERO_TICKS at pulse 1", zero_first, None, ERR["ZERO_TICKS"], -1),
        ("ZERO_TICKS later, negative", zero_later, None, ERR["ZERO_TICKS"], -1),
        ("RANGE, soft stop in ACCEL", range_accel, Stop("soft", 1), ERR["RANGE"], 1),
        ("RANGE, soft stop in RUN", range_run, Stop("soft", 2 + 200 - 1), ERR["RANGE"], 2),
    ]


def runtime_expected(label: str, plan: Plan, stop: Stop | None, code: int, k: int) -> list[int]:
    """Pulses 0 .. k of the model's move, after checking that the model agrees with the case's cause."""
    normal = model_edges(plan)
    if code == ERR["ZERO_TICKS"]:
        # the first interval of 0 ticks, j + 1, ends the move at pulse j (only a recurrence value can have 0 ticks)
        k = next(j for j in range(1, plan.steps - 1) if normal[j + 1] == normal[j])
    if stop is not None:
        assert soft_stop_pulse(plan, stop.at_cycle) == k and phase_of(plan, k) in ("ACCEL", "RUN"), label
        values = soft_stop_values(plan, k)
        assert values is not None and values[k] >> 32 > Q48_TOP >> 16, f"{label}: D_(m-1) is in range"
    return normal[: k + 1]


def test_engine_error_codes() -> None:
    """Every error code the engine raises (1 .. 12) with its documented timing. Codes 1 .. 9: done + error after
    edge 2, no pulse, position unchanged, the lowest code wins. LATE, ZERO_TICKS, RANGE: done + error at the edge of
    the pulse whose successor is missing or unusable, that pulse emitted and counted. err_code is held until the
    next accepted start clears it (at its edge 0); moves whose unused registers are 0 run as the model says."""
    checks = check_error_cases()
    runtime = runtime_error_cases()
    cases: list[tuple[str, Plan, Stop | None, int, list[int]]] = [
        (label, plan, None, code, [] if code else model_edges(plan)) for label, plan, code in checks
    ]
    cases += [
        (label, plan, stop, code, runtime_expected(label, plan, stop, code, k))
        for label, plan, stop, code, k in runtime
    ]
    assert {code for *_, code, _ in cases} == set(range(13))
    # Each move's cycle budget from where it is expected to end (a move rejected at edge 2 may hold intervals of
    # 2^32 ticks, which the model-based default budget would wait for): a hang fails within a few thousand clocks.
    budgets = [
        max([FIRST_PULSE_LATENCY, *expected[-1:], *([stop.at_cycle] if stop else [])]) + 2000 + 4 * plan.prescale
        for _, plan, stop, _, expected in cases
    ]
    results = simulate(
        [c[1] for c in cases],
        build_dir("engine_error_codes"),
        budgets=budgets,
        stops=[c[2] for c in cases],
        extras=[{"gap_cycles": 20} for _ in cases],
    )
    assert len(results) == len(cases), f"only {len(results)} of {len(cases)} moves finished"
    problems: list[str] = []
    position = 0
    previous_code = 0
    for i, ((label, plan, _, code, expected), res) in enumerate(zip(cases, results, strict=True)):
        what = f"{label} (move {i})"
        # the previous move's code is held 20 clocks after its done, up to this start, which clears it at edge 0
        if (res.before or {}).get("err_code") != previous_code:
            problems.append(f"{what}: before the start {res.before}, expected err_code {previous_code}")
        after = res.after_start or {}
        if [after.get(key) for key in ("busy", "err_code", "step_count", "dir")] != [1, 0, 0, plan.direction]:
            problems.append(f"{what}: after edge 0 {after}")
        problems += [f"{what}: {p}" for p in move_problems(res, expected, code=code, idle_after=True)]
        done_edge = expected[-1] if expected else FIRST_PULSE_LATENCY
        if res.done_edge != done_edge:
            problems.append(f"{what}: done at edge {res.done_edge}, expected {done_edge}")
        position += signed_steps(plan, len(expected))
        if res.final_position != position:
            problems.append(f"{what}: position {res.final_position}, expected {position}")
            position = res.final_position or 0
        previous_code = code
    assert not problems, "\n".join(problems)


#: The thresholds docs/stepramp_engine.md gives (section "Latency budget", "measured on the RTL"): clocks of interval
#: 1 from which the next value is in time, per case and operand.
DOC_BUDGET = {
    "register": 4,
    "decel seed": 6,
    "accel step": {2**20: 19, 2**24: 21, 2**30: 24},
    "soft stop in RUN": {20: 20, 1024: 23, 16384: 25},
    "soft stop at sa - 1": {30: 20, 4096: 24},
    "soft stop in ACCEL": {2**20: 35, 2**24: 39, 2**30: 45},
}


def budget_cases() -> list[tuple[str, Plan, Stop | None, int | None]]:
    """(label, plan, stop or None, late pulse or None): the interval before the value in question lasts need - 1
    clocks (the move ends with LATE at that interval's last pulse) and need clocks (in time), need being the
    budget's formula: for interval 2 (or the soft-stop alternative of pulse 1; a soft stop sampled at edge 1, before
    pulse 0, is decided at pulse 1) while interval 1 = c_first counts, and for a decel step after the decel seed's
    interval."""
    cases: list[tuple[str, Plan, Stop | None, int | None]] = []

    def both_sides(label: str, need: int, doc: int | None, make: Callable[[int], Plan], stop: str | None) -> None:
        assert doc is None or need == doc, f"{label}: the budget says {need} clocks, the docs' table {doc}"
        for clocks in (need - 1, need):
            # a hard stop right after pulse 1 (at edge 2 + clocks) keeps long intervals out of the simulation
            at = {"soft": 1, "hard": 3 + clocks}.get(stop or "")
            halt = None if stop is None or at is None else Stop(stop, at)
            late = 1 if clocks < need else None
            cases.append((f"{label}: {clocks} clocks, need {need}", make(clocks * Q16), halt, late))

    # a register (c_last) is ready for a pulse at E + 4, the decel seed at E + 6, a recurrence step at E + 8 + k
    both_sides("register c_last", 4, DOC_BUDGET["register"], lambda c1: hand_plan(3, c_first=c1), None)
    both_sides(
        "decel seed",
        6,
        DOC_BUDGET["decel seed"],
        lambda c1: hand_plan(4, sa=1, sd=1, c_first=c1, decel_seed=50 * Q16),
        None,
    )
    for a0 in (2**19, 2**20, 2**21, 2**24, 2**30, 2**47):  # k = 11, 11, 12, 13, 16, 24
        k = recurrence_iterations(2 * a0)
        both_sides(
            f"accel step A_1 from A_0 = 2^{a0.bit_length() - 1} (k = {k})",
            8 + k,
            DOC_BUDGET["accel step"].get(a0),
            lambda c1, a0=a0: hand_plan(4, sa=3, sd=3, c_first=c1, accel_seed=a0),
            "hard",
        )
    # a decel step D_1 from D_2 (den 7), prepared for slot B right after the decel seed (interval 2): with interval 1
    # at the seed's budget (6 clocks), the seed's ADD is at E + 5 and the step's IDX at E + 6, one clock after
    # it, so the step is ready for a pulse at E + 5 + 8 + k; interval 2 (D_2 ticks) must last 7 + k: late at pulse 2
    for ticks in (17, 18):
        need = 7 + recurrence_iterations(2 * ticks * Q16)
        assert need == 18
        late = 2 if ticks < need else None
        cases.append(
            (
                f"decel step D_1 from D_2 after the seed: interval 1 of 6 clocks, {ticks} clocks, need {need}",
                hand_plan(5, sa=1, sd=1, c_first=6 * Q16, decel_seed=ticks * Q16),
                None,
                late,
            )
        )
    # the soft-stop alternative with m = 1 is c_last, added 2 clocks after the normal value (a register: ADD at
    # E + 3), so ready for a pulse at E + 5
    both_sides(
        "soft stop in RUN with m = 1 (c_last)",
        3 + 2,
        None,
        lambda c1: hand_plan(6, sa=1, sd=5, c_first=c1, cruise=100 * Q32),
        "soft",
    )
    # with m = 2, D_1 = D + 2D div 7: from a register as D at E + 9 + k
    for ticks in (20, 1024, 16384):
        k = recurrence_iterations(2 * ticks * Q16)
        both_sides(
            f"soft stop in RUN, D = cruise = {ticks} ticks (k = {k})",
            9 + k,
            DOC_BUDGET["soft stop in RUN"].get(ticks),
            lambda c1, t=ticks: hand_plan(6, sa=1, sd=4, c_first=c1, c_sd=t * Q16, cruise=t * Q32),
            "soft",
        )
    for ticks in (30, 4096):
        k = recurrence_iterations(2 * ticks * Q16)
        both_sides(
            f"soft stop at pulse sa - 1, D = c_sa = {ticks} ticks (k = {k})",
            9 + k,
            DOC_BUDGET["soft stop at sa - 1"].get(ticks),
            lambda c1, t=ticks: hand_plan(
                6, sa=2, sd=4, c_first=c1, c_sa=t * Q16, c_sd=t * Q16, cruise=t * Q32, stop_ratio=2 * Q16
            ),
            "soft",
        )
    # ... and from an accel step as D (two divisions) at E + 13 + k1 + k2
    for a0 in (2**20, 2**24, 2**30):
        a1 = a0 - 2 * a0 // 5
        k1, k2 = recurrence_iterations(2 * a0), recurrence_iterations(2 * a1)
        both_sides(
            f"soft stop in ACCEL, D = A_1 from A_0 = 2^{a0.bit_length() - 1} (k1 + k2 = {k1} + {k2})",
            13 + k1 + k2,
            DOC_BUDGET["soft stop in ACCEL"].get(a0),
            lambda c1, a0=a0: hand_plan(6, sa=4, sd=4, c_first=c1, c_sa=100 * Q16, accel_seed=a0, stop_ratio=2 * Q16),
            "soft",
        )
    return cases


def test_engine_latency_budget() -> None:
    """The latency budget of docs/stepramp_engine.md at its edges (PRESCALE 1): one clock less than the budget of
    the next value (a register, the decel seed, an accel step with k = 11 .. 24, a decel step, the soft-stop
    alternative from a register or from an accel step) ends the move with LATE at the pulse that needed it (that
    pulse emitted), the budget itself runs the move as the model says. Thresholds from the docs' formulas with k
    from the operands (and equal to the docs' table where it has the case), edges from the model."""
    cases = budget_cases()
    results = simulate([c[1] for c in cases], build_dir("engine_latency_budget"), stops=[c[2] for c in cases])
    assert len(results) == len(cases), f"only {len(results)} of {len(cases)} moves finished"
    problems: list[str] = []
    for (label, plan, stop, late), res in zip(cases, results, strict=True):
        full = model_edges(plan) if stop is None else edges_with_stop(plan, stop.kind, stop.at_cycle)
        expected = full if late is None else full[: late + 1]
        code = 0 if late is None else ERR["LATE"]
        problems += [f"{label}: {p}" for p in move_problems(res, expected, code=code)]
        # done with the last pulse, or at the hard stop's edge after pulse 1 when in time
        done_edge = stop.at_cycle if stop is not None and stop.kind == "hard" and late is None else expected[-1]
        if res.done_edge != done_edge:
            problems.append(f"{label}: done at edge {res.done_edge}, expected {done_edge}")
    assert not problems, "\n".join(problems)
    assert sum(late is not None for *_, late in cases) == len(cases) // 2


def test_engine_pulse_one_clock_after_a_load() -> None:
    """A pulse due one clock after the pulse edge that loaded its interval (a 1-tick interval at PRESCALE 1) finds no
    next interval: the move ends with LATE at that pulse (emitted), as the latency budget says (a register is ready
    4 clocks after its pulse edge). The precompute sees the load one clock late (the sequencer registers advance and
    take_alt), so in that clock it still shows what the load consumed (nxt_ok, and the soft-stop alternative of the
    previous pulse): the decision must not take them. Cases: interval 1 of 1 tick; and interval 2 of 1 tick with a
    soft stop sampled at pulse 0's edge (so decided at pulse 2) while pulse 1's alternative was "end" (m = 0). The
    step spacing is off (min_gap 1), so that the 1-clock gap is the engine's own case."""
    first = hand_plan(3, c_first=1 * Q16)
    second = hand_plan(4, sa=2, sd=2, c_sa=1 * Q16, stop_ratio=0)
    pulse0 = model_edges(second)[0]
    cases = [("interval 1 of 1 tick", first, None), ("interval 2 of 1 tick, soft stop at pulse 0", second, pulse0)]
    stops = [None if at is None else Stop("soft", at) for _, _, at in cases]
    # min_gap 1: no step spacing (the real core's is at least 2, which would stop these moves with STEP_SPACE)
    extras = [{"min_gap": 1} for _ in cases]
    results = simulate([c[1] for c in cases], build_dir("engine_pulse_after_load"), stops=stops, extras=extras)
    assert len(results) == len(cases)
    problems: list[str] = []
    for (label, plan, _), res, late in zip(cases, results, (1, 2), strict=True):
        expected = model_edges(plan)[: late + 1]
        assert expected[late] - expected[late - 1] == 1, f"{label}: the case needs a 1-clock interval"
        problems += [f"{label}: {p}" for p in move_problems(res, expected, code=ERR["LATE"])]
        if res.done_edge != expected[-1]:
            problems.append(f"{label}: done at edge {res.done_edge}, expected {expected[-1]}")
    assert not problems, "\n".join(problems)


#: Profiles whose step_count and cur_delay are checked at every pulse: trapezoids (m0 = 1, sa = 2, a fractional
#: period, two cruise intervals), triangles, sa = 1, sd = L, PRESCALE 3 and 5, both directions, N = 1, 2, 3.
COUNTER_PROFILES = (
    "trap_m0_one",
    "trap_sa_two",
    "trap_fractional_period",
    "trap_cruise_two_intervals",
    "triangle_sym",
    "triangle_prescale_3_neg",
    "run_start_short_ramps",
    "run_start_prescale_5",
    "random_01",
    "steps_1",
    "steps_neg_2_asym",
    "steps_3_run",
    "steps_neg_3_prescale_2",
)


def test_engine_counters_per_pulse() -> None:
    """At every pulse k: step_count = k + 1 and cur_delay = T_(k+1) - T_k, the ticks of the interval that starts
    there (0 with the last pulse), besides edges, states and the end of the move as check_moves checks them."""
    names = [*COUNTER_PROFILES, "short trapezoid", "short trapezoid P=3 negative"]
    plans = [profile_plan(name) for name in COUNTER_PROFILES] + [SHORT_TRAP, SHORT_TRAP_P3_NEG]
    results = simulate(plans, build_dir("engine_counters"), extras=[{"record_counters": True} for _ in plans])
    check_moves(names, plans, results)
    problems: list[str] = []
    for name, plan, res in zip(names, plans, results, strict=True):
        ticks = tick_times(plan)
        delays = [b - a for a, b in itertools.pairwise(ticks)] + [0]
        if res.step_counts != list(range(1, plan.steps + 1)):
            problems.append(f"{name}: step_count per pulse {res.step_counts[:8]}...")
        if res.cur_delays != delays:
            got = res.cur_delays or []
            k = first_mismatch(got, delays)
            problems.append(f"{name}: cur_delay from pulse {k} {got[k : k + 3]}, model {delays[k : k + 3]}")
    assert not problems, "\n".join(problems)


def event(port: str, at_cycle: int, pos_value: int | None = None) -> dict[str, int | str]:
    """An "events" entry of stepramp.sim.engine_bench: port '1' for the clock sampled by edge at_cycle of the move."""
    out: dict[str, int | str] = {"port": port, "at_cycle": at_cycle}
    if pos_value is not None:
        out["pos_value"] = pos_value
    return out


def test_engine_pos_load_and_start() -> None:
    """pos_load while idle (position takes pos_value), with start (the move counts from it), ignored while busy
    (also at the last pulse's edge) and taken again at the edge after done; start (and load) ignored while busy,
    with another move on the inputs; start held high across back-to-back moves: each next move accepted at the
    edge after the done cycle (pulse 0 three clocks after the last pulse), err_code cleared there."""
    x = SHORT_TRAP
    x_edges = model_edges(x)
    last = x_edges[-1]
    other = dataclasses.replace(SHORT_TRAP_P3_NEG, direction=1)
    s3 = profile_plan("steps_3_run")
    t3 = profile_plan("triangle_sa_sd_one")
    n1 = profile_plan("steps_neg_1")
    n0 = profile_plan("steps_0")
    bad = dataclasses.replace(s3, c_first=0)
    moves: list[tuple[str, Plan, dict[str, Any]]] = [
        ("pos_load idle", x, {"events": [event("pos_load", -4, 5), event("pos_load", -2, 1000)]}),
        ("pos_load with start", dataclasses.replace(x, direction=1), {"events": [event("pos_load", 0, -5000)]}),
        (
            "pos_load while busy",
            x,
            {
                "events": [
                    event("pos_load", at, value)
                    for at, value in ((1, 11), (2, 22), (x_edges[5], 33), (x_edges[5] + 2, 44), (last, 55))
                ]
                + [event("pos_load", last + 1, 777)]  # the edge after done: idle again
            },
        ),
        (
            "start while busy",
            x,
            {
                "events": [
                    event(port, at) for port in ("start", "load") for at in (1, 2, x_edges[3], x_edges[3] + 7, last)
                ],
                "inputs_after_start": dataclasses.asdict(other),
            },
        ),
        # start held high from here on: each next move is taken in the previous one's done cycle
        ("chain start", s3, {}),
        ("held: trapezoid", x, {"start_held": True}),
        ("held: N=1", n1, {"start_held": True}),
        ("held: N=3", t3, {"start_held": True}),
        ("held: N=0", n0, {"start_held": True}),
        ("held: C_FIRST", bad, {"start_held": True}),
        ("held: after an error", s3, {"start_held": True}),
        ("after the chain", s3, {}),
    ]
    results = simulate([m[1] for m in moves], build_dir("engine_pos_load_start"), extras=[m[2] for m in moves])
    assert len(results) == len(moves), f"only {len(results)} of {len(moves)} moves finished"
    problems: list[str] = []
    position = 0  # the model's position after the previous move
    previous: tuple[Plan, list[int], SimResult] | None = None
    for i, ((label, plan, extra), res) in enumerate(zip(moves, results, strict=True)):
        what = f"move {i} ({label})"
        code = documented_check(plan)
        expected = [] if code else model_edges(plan)
        problems += [f"{what}: {p}" for p in move_problems(res, expected, code=code)]
        if res.done_edge != (expected[-1] if expected else FIRST_PULSE_LATENCY):
            problems.append(f"{what}: done at edge {res.done_edge}")
        # pos_load while idle: at move 0's edge -2, and at the edge after move 2's done; move 1's with its start
        before_position = {0: 1000, 3: 777}.get(i, position)
        start_position = {1: -5000}.get(i, before_position)
        if extra.get("start_held"):
            assert previous is not None
            _, prev_edges, prev = previous
            # accepted at the edge after the previous move's done cycle, pulse 0 three clocks after its last pulse
            if res.origin != (prev.origin or 0) + (prev.done_edge or 0) + 1:
                problems.append(f"{what}: origin {res.origin}, previous done at {prev.origin} + {prev.done_edge}")
            if prev_edges and res.edges and res.origin + res.edges[0] - (prev.origin + prev.edges[-1]) != 3:
                problems.append(f"{what}: pulse 0 not 3 clocks after the previous move's last pulse")
        else:
            # idle since the previous move: its step count, code and direction kept, nothing started since
            want: dict[str, Any] = {"busy": 0, "position": before_position}
            if previous is not None:
                prev_plan, prev_edges, _ = previous
                want |= {"step_count": len(prev_edges), "err_code": documented_check(prev_plan)}
                want |= {"dir": prev_plan.direction}
            if {key: (res.before or {}).get(key) for key in want} != want:
                problems.append(f"{what}: before the start {res.before}, expected {want}")
        want = {"busy": 1, "err_code": 0, "step_count": 0, "dir": plan.direction, "position": start_position}
        if {key: (res.after_start or {}).get(key) for key in want} != want:
            problems.append(f"{what}: after edge 0 {res.after_start}, expected {want}")
        position = start_position + signed_steps(plan, len(expected))
        if res.final_position != position:
            problems.append(f"{what}: position {res.final_position}, expected {position}")
        previous = (plan, expected, res)
    assert not problems, "\n".join(problems)


def reset_cases() -> list[tuple[str, Plan, Stop | None, int | None, list[int]]]:
    """(label, plan, soft stop or None, reset edge or None, pulses expected): rst at edge e ends the move with the
    pulses before e; each reset move is followed by a whole move, which must run as the model says."""
    x, y = SHORT_TRAP, SHORT_TRAP_P3_NEG
    xe, ye = model_edges(x), model_edges(y)
    k_run = (y.sa + y.sd) // 2
    soft = Stop("soft", xe[2] + 5)  # decided at pulse 4, in ACCEL
    p = soft_stop_pulse(x, soft.at_cycle)
    stopped = edges_with_stop(x, "soft", soft.at_cycle)
    assert p == 4 and phase_of(x, p) == "ACCEL" and len(stopped) < len(xe) - 3
    s3 = profile_plan("steps_3_run")
    cases: list[tuple[str, Plan, Stop | None, int | None, list[int]]] = [
        ("rst at a pulse edge in ACCEL", x, None, xe[4], xe[:4]),
        ("whole move", x, None, None, xe),
        ("rst one clock before a RUN pulse, P=3, negative", y, None, ye[k_run] - 1, ye[:k_run]),
        ("whole move", y, None, None, ye),
        ("rst at edge 1", x, None, 1, []),
        ("rst at edge 2 (pulse 0's)", x, None, 2, []),
        ("rst while a soft stop waits for its pulse", x, soft, xe[p] - 1, xe[:p]),
        ("whole move (no stop left over)", x, None, None, xe),
        ("rst during a soft stop's ramp", x, soft, stopped[p + 2] - 1, stopped[: p + 2]),
        ("whole move", x, None, None, xe),
        ("rst at the last pulse's edge", y, None, ye[-1], ye[:-1]),
        ("whole move", s3, None, None, model_edges(s3)),
        ("an error", dataclasses.replace(s3, c_first=0), None, None, []),
    ]
    return cases


def test_engine_reset() -> None:
    """rst during a move (ACCEL, RUN, edges 1 and 2, a pending soft stop, a soft stop's ramp, the last pulse's edge):
    no pulse from the reset edge on (none in a window of two of the move's longest intervals), busy, state,
    position, step_count, err_code (and done, error, cur_delay, step) in their reset state after it, and the next
    move runs as the model says from position 0. A reset while idle clears a held err_code and the position."""
    cases = reset_cases()
    plans = [c[1] for c in cases] + [cases[-2][1]]
    stops = [c[2] for c in cases] + [None]
    extras: list[dict[str, Any]] = []
    for _, plan, _, at, _ in cases:
        edges = model_edges(plan)
        watch = 2 * max(b - a for a, b in itertools.pairwise(edges)) + 20
        extras.append({"events": [event("rst", at)], "reset_watch_cycles": watch} if at is not None else {})
    extras.append({"events": [event("rst", -3)]})  # a reset while idle, after the error
    results = simulate(plans, build_dir("engine_reset"), stops=stops, extras=extras)
    assert len(results) == len(plans), f"only {len(results)} of {len(plans)} moves finished"
    problems: list[str] = []
    position = 0
    for (label, plan, _, at, expected), res in zip(cases, results, strict=False):
        what = f"{label}" + (f" (rst at edge {at})" if at is not None else "")
        if at is None:
            position += signed_steps(plan, len(expected))
            code = documented_check(plan)
            problems += [f"{what}: {p}" for p in move_problems(res, expected, code=code, position=position)]
            continue
        if res.edges != expected:
            problems.append(f"{what}: pulses at {res.edges[-4:]}, expected ... {expected[-4:]}")
        state = dict(res.reset or {})
        stray = state.pop("stray", "no reset seen")
        state.pop("dir", None)  # not part of the documented reset state
        if res.done or state != RESET_STATE or stray is not None:
            problems.append(f"{what}: done={res.done}, after the reset {state}, stray edge {stray}")
        position = 0
    # the idle reset: err_code and position back to 0 before the last move's start, which runs from 0
    last, res = plans[-1], results[-1]
    if res.before is None or (res.before["err_code"], res.before["position"]) != (0, 0):
        problems.append(f"idle reset: before the start {res.before}")
    if res.edges != model_edges(last) or res.final_position != last.steps or res.error:
        problems.append(f"after the idle reset: {res}")
    assert not problems, "\n".join(problems)
    assert position != 0  # the error move left a position (and a code) for the idle reset to clear
