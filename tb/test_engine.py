# SPDX-License-Identifier: MIT
"""stepramp_engine against the bit-exact model: every step edge, the step count, the position, done.

Each pytest test runs one GHDL simulation that plays a list of moves back to back (stepramp.enginetb drives and
records, the checks are here). The expected edges come from stepramp.model, which sw/tests holds to the ideal
trapezoid; nothing is taken from the RTL's own output.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import pytest

from stepramp.enginesim import SimResult, Stop, simulate
from stepramp.model import (
    FIRST_PULSE_LATENCY,
    edges_with_stop,
    first_space_fault,
    min_gap,
    phase_of,
    soft_stop_length,
    soft_stop_pulse,
)
from stepramp.model import edges as model_edges
from stepramp.model import phases as model_phases
from stepramp.plan import Plan, plan_move
from stepramp.profiles import PROFILES, PROFILES_BY_NAME, Profile, exact_plan
from stepramp.regmap import ERROR_CODES
from tbutil import build_dir

CHUNKS = 4
ERR = {name: code for name, (code, _) in ERROR_CODES.items()}


def plans_of(profiles: Sequence[Profile]) -> list[Plan]:
    return [plan_move(**p.args()) for p in profiles]


def check_moves(names: Sequence[str], plans: Sequence[Plan], results: Sequence[SimResult]) -> None:
    """Every move: edges equal to the model's, N pulses, done without error, position exact, back in STOP."""
    assert len(results) == len(plans), f"only {len(results)} of {len(plans)} moves finished"
    position = 0
    problems: list[str] = []
    for name, plan, res in zip(names, plans, results, strict=True):
        expected = model_edges(plan)
        position += -plan.steps if plan.direction else plan.steps
        if res.edges != expected:
            first = next(
                (k for k, (a, b) in enumerate(zip(res.edges, expected, strict=False)) if a != b),
                min(len(res.edges), len(expected)),
            )
            problems.append(
                f"{name}: {len(res.edges)} edges vs {len(expected)} expected; first difference at pulse {first}: "
                f"rtl {res.edges[first : first + 3]} model {expected[first : first + 3]}"
            )
            continue
        if any(b - a < plan.prescale for a, b in zip(res.edges, res.edges[1:], strict=False)):
            problems.append(f"{name}: an interval shorter than one tick")
        phases = model_phases(plan)
        if res.states[: len(phases)] != phases:
            problems.append(f"{name}: FSM states per interval {res.states[:12]}... vs model {phases[:12]}...")
        if res.error or not res.done:
            problems.append(f"{name}: done={res.done} error={res.error} code={res.err_code}")
        if res.final_position != position or res.step_count != plan.steps:
            problems.append(
                f"{name}: position {res.final_position} (expected {position}), "
                f"step_count {res.step_count} (expected {plan.steps})"
            )
        if res.busy_after != 0 or res.state_after != "STOP":
            problems.append(f"{name}: after done busy={res.busy_after} state={res.state_after}")
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
    what = f"{name} {stop.kind} stop at edge {stop.at_cycle}"
    problems = []
    if res.edges != expected:
        first = next(
            (k for k, (a, b) in enumerate(zip(res.edges, expected, strict=False)) if a != b),
            min(len(res.edges), len(expected)),
        )
        problems.append(
            f"{what}: {len(res.edges)} pulses vs {len(expected)} expected; first difference at pulse {first}: "
            f"rtl {res.edges[first : first + 3]} model {expected[first : first + 3]}"
        )
    if not res.done or res.error or res.err_code:
        problems.append(f"{what}: done={res.done} error={res.error} code={res.err_code}")
    if res.step_count != len(res.edges) or res.final_position != position:
        problems.append(
            f"{what}: step_count {res.step_count}, position {res.final_position} (expected {position}) "
            f"for {len(res.edges)} pulses seen"
        )
    if res.busy_after != 0 or res.state_after != "STOP":
        problems.append(f"{what}: after done busy={res.busy_after} state={res.state_after}")
    return problems


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
        cases += [(name, plan, Stop("hard", e)) for e in times]
    return cases


def test_engine_hard_stop() -> None:
    """Hard stop in ACCEL, RUN, DECEL, at the start edge, at a pulse edge, one cycle before one, after the move."""
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
        cases += [("ratio_accel_100_triangle", plan, Stop("soft", model_edges(plan)[k] - 1)) for k in (1, 2)]
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
        if p is None or p == 0:
            continue
        phase = phase_of(plan, p)
        m = soft_stop_length(plan, p)
        if m is not None:
            phases_seen.add(f"{phase} stopped")
        elif p < plan.steps - 1:
            phases_seen.add(f"{phase} ignored")
        if m and len(res.edges) >= 3:
            # the stop ends on its slowest interval, and the FSM shows DECEL from interval p + 1 on
            iv = [b - a for a, b in zip(res.edges, res.edges[1:], strict=False)]
            if iv[-1] < iv[-2]:
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
    return cases


def test_engine_stop_combinations() -> None:
    """A second soft stop is ignored (pending or in effect); a hard stop still ends a soft stop; hard beats soft."""
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
        if res.edges != expected:
            problems.append(
                f"{what}: {len(res.edges)} pulses, expected {len(expected)}: {res.edges[-3:]} vs {expected[-3:]}"
            )
        if not res.done or res.error or res.step_count != len(res.edges) or res.final_position != position:
            problems.append(
                f"{what}: done={res.done} error={res.error} count={res.step_count} pos={res.final_position}"
            )
        if res.busy_after != 0 or res.state_after != "STOP":
            problems.append(f"{what}: after done busy={res.busy_after} state={res.state_after}")
    assert not problems, "\n".join(problems)


# --------------------------------------------------------------------------------------------------------------
# The move is latched by `load` (the core's START acceptance), not by the later start; step spacing.
# --------------------------------------------------------------------------------------------------------------
def _ends_as(plan: Plan, expected: list[int], code: int, res: SimResult) -> list[str]:
    """What differs between a finished move and its expectation (edges, error code, step count)."""
    problems = []
    if res.edges != expected:
        problems.append(f"edges {res.edges[:8]}... vs model {expected[:8]}...")
    if not res.done or res.err_code != code or res.error != int(code != 0):
        problems.append(f"done={res.done} error={res.error} code={res.err_code}, expected code {code}")
    if res.step_count != len(expected):
        problems.append(f"step_count {res.step_count}, expected {len(expected)}")
    return problems


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
        # the direction comes with start (the stepping logic's start_dir), not with load
        {"load_lead": lead, "after_load": {**dataclasses.asdict(after), "direction": loaded.direction}}
        for loaded, after, lead, _ in cases
    ]
    results = simulate([c[0] for c in cases], build_dir("engine_load"), extras=extras)
    assert len(results) == len(cases)
    problems = []
    for i, ((loaded, _, lead, code), res) in enumerate(zip(cases, results, strict=True)):
        expected = [] if code else model_edges(loaded)
        problems += [f"case {i} (lead {lead}): {p}" for p in _ends_as(loaded, expected, code, res)]
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
        problems += [f"{label}: {p}" for p in _ends_as(plan, expected, 0 if k is None else ERR["STEP_SPACE"], res)]
        if res.final_position != position:
            problems.append(f"{label}: position {res.final_position}, expected {position}")
            position = res.final_position or 0
    assert not problems, "\n".join(problems)
    assert 0 < faults < len(cases), f"{faults} of {len(cases)} cases fault: the cases do not straddle min_gap"
