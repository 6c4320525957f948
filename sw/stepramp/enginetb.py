# SPDX-License-Identifier: MIT
"""cocotb test module that plays a list of moves on stepramp_engine and records what the RTL does.

It is a driver and a monitor, not a checker: the request (a JSON file named by $STEPRAMP_SIM_REQUEST) lists the
moves as register values; for each move it drives the inputs, pulses start, timestamps every STEP rising edge in
clock cycles from the edge that sampled start, and writes the observations to $STEPRAMP_SIM_RESULT. The caller
compares them with the model. Only a hang (no done within the request's cycle budget) fails here.

A move may carry a stop: {"kind": "soft" | "hard", "at_cycle": e}. The strobe soft_stop / hard_stop is then '1'
for one clock, sampled by the rising edge e cycles after the start edge (the numbering of the step timestamps:
the start edge is 0, so e = 0 drives it together with start). "stop" may also be a list of such requests (at
distinct edges for one kind).

The move's registers are latched by `load`, driven with start (or, with "load_lead": k >= 1, k clocks before it,
after which the inputs carry "after_load", another move's registers, until start: the engine must run the values
it loaded). "min_gap" (default 2, a STEP_WIDTH and a STEP_SPACE of 1) is the step spacing input.
"""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path
from typing import Any

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, FallingEdge, First, ReadOnly, RisingEdge, Timer
from cocotb.utils import get_sim_time

from stepramp.gtkw import LAYOUTS, missing_in, signal_paths
from stepramp.plan import Plan

CLK_PERIOD_NS = 10

#: Engine inputs driven from a move's register values: the Plan's fields are the engine's port names.
INPUTS = tuple(field.name for field in dataclasses.fields(Plan))


def _edge() -> int:
    return round(get_sim_time("ns") / CLK_PERIOD_NS)


def _signed(value: Any, bits: int) -> int:
    raw = int(value)
    return raw - (1 << bits) if raw >> (bits - 1) else raw


STOP_PORTS = {"soft": "soft_stop", "hard": "hard_stop"}


async def _strobe(dut: Any, port: str, at_cycle: int, start_edge: int) -> None:
    """Drive port '1' for the clock cycle before rising edge start_edge + at_cycle (at_cycle >= 1)."""
    signal = getattr(dut, port)
    await Timer(at_cycle * CLK_PERIOD_NS - CLK_PERIOD_NS // 2, unit="ns")  # the falling edge before it
    signal.value = 1
    await RisingEdge(dut.clk)
    sampled = _edge() - start_edge
    await FallingEdge(dut.clk)
    signal.value = 0
    assert sampled == at_cycle, f"{port} sampled at edge {sampled}, requested {at_cycle}"


async def _play(dut: Any, move: dict[str, Any]) -> dict[str, Any]:
    regs: dict[str, int] = move["registers"]
    for name in INPUTS:
        getattr(dut, name).value = regs[name]
    dut.min_gap.value = int(move.get("min_gap", 2))
    lead = int(move.get("load_lead", 0))
    if lead > 0:
        await FallingEdge(dut.clk)
        dut.load.value = 1
        await FallingEdge(dut.clk)
        dut.load.value = 0
        for name in INPUTS:
            getattr(dut, name).value = move["after_load"][name]
        if lead > 1:
            await ClockCycles(dut.clk, lead - 1)
    raw_stop = move.get("stop")
    stops: list[dict[str, Any]] = [] if raw_stop is None else [raw_stop] if isinstance(raw_stop, dict) else raw_stop
    requests = [(STOP_PORTS[stop["kind"]], int(stop["at_cycle"])) for stop in stops]
    if any(at_cycle < 0 for _, at_cycle in requests):
        raise ValueError(f"stop at_cycle must be >= 0: {stops}")
    await FallingEdge(dut.clk)
    dut.start.value = 1
    dut.load.value = int(lead == 0)
    for port, at_cycle in requests:
        if at_cycle == 0:
            getattr(dut, port).value = 1
    await RisingEdge(dut.clk)
    start_edge = _edge()
    strobes = [
        cocotb.start_soon(_strobe(dut, port, at_cycle, start_edge)) for port, at_cycle in requests if at_cycle >= 1
    ]
    await FallingEdge(dut.clk)
    dut.start.value = 0
    dut.load.value = 0
    for port, at_cycle in requests:
        if at_cycle == 0:
            getattr(dut, port).value = 0

    edges: list[int] = []
    states: list[int] = []
    deadline = int(get_sim_time("ns")) + int(move["timeout_cycles"]) * CLK_PERIOD_NS
    offset = 0
    # done may already be high here: a hard stop at the start edge ends the move at edge 0
    while int(dut.done.value) != 1:
        remaining = deadline - int(get_sim_time("ns"))
        if remaining <= 0:
            return {"edges": edges, "states": states, "done": False}
        await First(RisingEdge(dut.step), RisingEdge(dut.done), Timer(remaining, unit="ns"))
        await ReadOnly()
        offset = _edge() - start_edge
        if int(dut.step.value) == 1 and (not edges or edges[-1] != offset):
            edges.append(offset)
            states.append(int(dut.state.value))
    result = {
        "edges": edges,
        "states": states,
        "done": True,
        "done_edge": offset,
        "error": int(dut.error.value),
        "err_code": int(dut.err_code.value),
        "final_position": _signed(dut.position.value, len(dut.position)),
        "step_count": int(dut.step_count.value),
    }
    await FallingEdge(dut.clk)
    result["busy_after"] = int(dut.busy.value)
    result["state_after"] = int(dut.state.value)
    for strobe in strobes:
        await strobe  # a stop requested after done is still driven (the engine must ignore it) and checked
    return result


@cocotb.test()
async def play_moves(dut: Any) -> None:
    """Play every move of the request, back to back, and write what was observed."""
    request = json.loads(Path(os.environ["STEPRAMP_SIM_REQUEST"]).read_text())
    Clock(dut.clk, CLK_PERIOD_NS, unit="ns").start()
    dut.start.value = 0
    dut.load.value = 0
    dut.min_gap.value = 2
    dut.soft_stop.value = 0
    dut.hard_stop.value = 0
    dut.pos_load.value = 0
    dut.pos_value.value = 0
    for name in INPUTS:
        getattr(dut, name).value = 0
    dut.rst.value = 1
    await ClockCycles(dut.clk, 3)
    await FallingEdge(dut.clk)
    dut.rst.value = 0
    await ClockCycles(dut.clk, 2)
    # The waveform layout (stepramp.gtkw) names signals of this design: they must exist.
    missing = missing_in(dut, signal_paths(LAYOUTS["stepramp_engine"]))
    assert not missing, f"the GTKWave layout names signals stepramp_engine does not have: {missing}"

    results = []
    for move in request["moves"]:
        result = await _play(dut, move)
        results.append(result)
        if not result["done"]:
            break  # the engine hung: report what was seen, the caller fails the test
        await ClockCycles(dut.clk, int(move.get("gap_cycles", 5)))
    Path(os.environ["STEPRAMP_SIM_RESULT"]).write_text(json.dumps({"results": results}))
    hung = [i for i, r in enumerate(results) if not r["done"]]
    assert not hung, f"no done within the cycle budget for move {hung[0]}"
