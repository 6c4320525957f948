# SPDX-License-Identifier: MIT
"""The second simulator: `ghdl synth`'s Verilog netlist on Icarus Verilog, under the benches of the RTL.

stepramp.sim.netlist writes the netlist of a top (its generics baked in; the one-hot multiplexers' defaults that GHDL
2.0's Verilog writer drops are restored from its VHDL writer), and run_cocotb(..., netlist=True) simulates it with
Icarus. The benches are the RTL's own, the expectations the bit-exact model's:

- test_netlist_engine_profiles: stepramp_engine alone (stepramp.sim.engine_bench) plays profiles that expose each of
  AVR446's defects, and a few more: every STEP edge and FSM state as stepramp.models.engine says, position exact;
- test_netlist_bus_profiles: each top through its bus (tb/test_peripheral.py profiles_through_the_bus, the driver
  programming from physical units, the STEP/DIR/winding monitors on), the AXI4-Lite top with idle cycles and
  backpressure and the windings in PWM mode: every STEP edge as the model's.

A synthesis/simulation mismatch (a sensitivity list, a 'U' the RTL reads, a multiplexer synthesis gets wrong) shows
as an edge that differs. The first run found two: GHDL 2.0's dropped multiplexer defaults (a writer bug, restored
here), and the STEP pulse register that the reset reads before it has a value (docs/stepramp_stepper.md, "Reset").
"""

from __future__ import annotations

import json

import pytest

from stepramp.sim.engine_sim import simulate
from stepramp.sim.profiles import PROFILES_BY_NAME
from stepramp.sim.runner import run_cocotb
from tbutil import build_dir
from test_engine import check_moves, plans_of

#: One profile per AVR446 defect the engine bench guards against, and both directions, PRESCALE > 1, a 1-step move.
ENGINE_PROFILES = [
    "steps_1",
    "steps_neg_2_asym",
    "run_start_prescale_5",
    "trap_basic",
    "trap_asym",
    "trap_m0_one",
    "triangle_negative",
    "ratio_accel_50",
    "trap_prescale_4",
    "random_00",
]

#: Per top: profiles, stepping outputs, bus idle cycles.
BUS_RUNS = {
    "stepramp_plb": (
        ["trap_basic", "triangle_negative", "trap_prescale_4"],
        {"mode": "half", "step_width": 5, "dir_setup": 20, "dir_hold": 10},
        0,
    ),
    "stepramp_axil": (
        ["run_start", "trap_negative", "steps_2"],
        {"mode": "pwm", "ustep_log2": 4, "step_width": 10, "dir_setup": 7, "dir_hold": 3, "pwm_period": 40},
        1,
    ),
}


def test_netlist_engine_profiles() -> None:
    """The engine's netlist: edges, states and position of each profile as the model says."""
    profiles = [PROFILES_BY_NAME[name] for name in ENGINE_PROFILES]
    plans = plans_of(profiles)
    results = simulate(plans, build_dir("netlist_engine"), netlist=True)
    check_moves(ENGINE_PROFILES, plans, results)


@pytest.mark.parametrize("top", list(BUS_RUNS))
def test_netlist_bus_profiles(top: str) -> None:
    """Each top's netlist through its bus and the driver: every STEP edge as the model's, monitors on."""
    names, outputs, idle = BUS_RUNS[top]
    run_cocotb(
        top,
        "test_peripheral",
        build_dir(f"netlist_{top}"),
        testcase="profiles_through_the_bus",
        netlist=True,
        extra_env={
            "PROFILE_NAMES": json.dumps(names),
            "BUS_IDLE": str(idle),
            "BUS_SEED": "3",
            "OUTPUTS": json.dumps(outputs),
        },
    )
