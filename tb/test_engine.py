# SPDX-License-Identifier: MIT
"""stepramp_engine against the bit-exact model: every step edge, the step count, the position, done.

Each pytest test runs one GHDL simulation that plays a list of moves back to back (stepramp.enginetb drives and
records, the checks are here). The expected edges come from stepramp.model, which sw/tests holds to the ideal
trapezoid; nothing is taken from the RTL's own output.
"""

from __future__ import annotations

from collections.abc import Sequence

import pytest

from stepramp.enginesim import SimResult, simulate
from stepramp.model import edges as model_edges
from stepramp.model import phases as model_phases
from stepramp.plan import Plan, plan_move
from stepramp.profiles import PROFILES, PROFILES_BY_NAME, Profile
from tbutil import build_dir

CHUNKS = 4


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
