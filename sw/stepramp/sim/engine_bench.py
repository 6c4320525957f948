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

Optional keys for the control inputs (none of them changes a move that does not use it):

* "events": [{"port": p, "at_cycle": e, "pos_value": v}]: port p ("pos_load", "rst", "start" or "load") is '1' for
  the one clock sampled by edge e of the move's numbering (e < 0: while idle, -e clocks before the start edge; e = 0:
  with start; e >= 1: during or after the move); "pos_value" goes with "pos_load". A "rst" at e >= 1 ends the
  observation there: the result's "reset" holds the outputs in the cycle after that edge and "stray", the first
  rising edge of step, done or busy seen in the "reset_watch_cycles" (default 100) that follow (None: none).
* "inputs_after_start": registers put on the inputs after the start edge (as "after_load" after a load).
* "start_only": true: start without load (the engine latches the inputs itself when no load came since the previous
  start).
* "start_held": true: the move's start is not given by itself: start and load stay '1' from the previous move's
  start edge on, with this move's registers on the inputs, so that the engine takes them in the previous move's done
  cycle. Its timestamps count from the edge after the previous move's done cycle, where the docs say it is accepted.

* "segment": the segment inputs (SEGMENT_INPUTS: head_down, endless, head_index, run_stop, head_prod), 0 when
  absent (a move from rest to rest).
* "record_counters": true: with each pulse, also record step_count and cur_delay as the pulse's edge leaves them
  (result keys "step_counts", "cur_delays").

Every result also records "origin" (the absolute index of the edge its timestamps count from), "before" (the outputs
in the cycle before the start edge; None for a held start) and "after_start" (the outputs in the cycle after it).
"""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path
from typing import Any

import cocotb
from cocotb.triggers import ClockCycles, FallingEdge, First, RisingEdge, SimTimeoutError, Timer, with_timeout
from cocotb.utils import get_sim_time

from stepramp.board.plan import REG_WIDTHS, Plan
from stepramp.sim import coverage
from stepramp.sim.clocking import CLK_PERIOD_NS, now_cycles, start_clock_and_reset
from stepramp.sim.wake import Wakeup
from stepramp.sim.waves import LAYOUTS, missing_in, signal_paths

#: Engine inputs driven from a move's register values: the Plan's fields are the engine's port names.
INPUTS = tuple(field.name for field in dataclasses.fields(Plan) if field.name in REG_WIDTHS)
#: The segment's inputs (stepramp.spec.Segment.registers), from a move's "segment" (0 when it has none).
SEGMENT_INPUTS = ("head_down", "endless", "head_index", "run_stop", "head_prod")


def _signed(value: Any, bits: int) -> int:
    raw = int(value)
    return raw - (1 << bits) if raw >> (bits - 1) else raw


STOP_PORTS = {"soft": "soft_stop", "hard": "hard_stop"}


#: Ports an "events" entry may drive.
EVENT_PORTS = ("pos_load", "rst", "start", "load")

#: Outputs recorded in the snapshots ("before", "after_start", "reset").
SNAPSHOT_PORTS = ("busy", "done", "error", "err_code", "state", "step_count", "dir", "step", "cur_delay")


def _snapshot(dut: Any) -> dict[str, int]:
    """The engine's outputs now (position as a signed number)."""
    snap = {name: int(getattr(dut, name).value) for name in SNAPSHOT_PORTS}
    snap["position"] = _signed(dut.position.value, len(dut.position))
    return snap


def _set_event(dut: Any, event: dict[str, Any]) -> None:
    getattr(dut, event["port"]).value = 1
    if "pos_value" in event:
        dut.pos_value.value = int(event["pos_value"]) & 0xFFFF_FFFF


async def _event(dut: Any, event: dict[str, Any], start_edge: int) -> None:
    """Drive an event's port '1' (or a stop's strobe) for the clock cycle before rising edge start_edge + at_cycle
    (at_cycle >= 1)."""
    at_cycle = int(event["at_cycle"])
    await Timer(at_cycle * CLK_PERIOD_NS - CLK_PERIOD_NS // 2, unit="ns")  # the falling edge before it
    _set_event(dut, event)
    await RisingEdge(dut.clk)
    sampled = now_cycles() - start_edge
    await FallingEdge(dut.clk)
    if not event.get("_keep"):  # an event at the next edge drives the same port now
        getattr(dut, event["port"]).value = 0
    assert sampled == at_cycle, f"{event['port']} sampled at edge {sampled}, requested {at_cycle}"


def _stops(move: dict[str, Any]) -> list[dict[str, Any]]:
    """A move's stop requests as a list ("stop" is one request or a list of them)."""
    raw = move.get("stop")
    return [] if raw is None else [raw] if isinstance(raw, dict) else list(raw)


def _events(move: dict[str, Any]) -> list[dict[str, Any]]:
    events: list[dict[str, Any]] = [dict(event) for event in move.get("events", [])]
    for event in events:
        if event["port"] not in EVENT_PORTS:
            raise ValueError(f"event port must be one of {EVENT_PORTS}: {event}")
        if event["port"] == "rst" and int(event["at_cycle"]) == 0:
            raise ValueError("a rst event needs at_cycle /= 0")
        event["_keep"] = any(
            other["port"] == event["port"] and int(other["at_cycle"]) == int(event["at_cycle"]) + 1 for other in events
        )
    return events


async def _watch_after_reset(dut: Any, move: dict[str, Any], start_edge: int) -> dict[str, Any]:
    """The outputs in the cycle after the reset edge, then the first stray step, done or busy edge (if any)."""
    await FallingEdge(dut.clk)
    snap: dict[str, Any] = _snapshot(dut)
    watch = int(move.get("reset_watch_cycles", 100)) * CLK_PERIOD_NS
    timer = Timer(watch, unit="ns")
    fired = await First(RisingEdge(dut.step), RisingEdge(dut.done), RisingEdge(dut.busy), timer)
    snap["stray"] = None if fired is timer else now_cycles() - start_edge
    if fired is not timer:
        await FallingEdge(dut.clk)
    return snap


async def _play(dut: Any, move: dict[str, Any], next_move: dict[str, Any] | None = None) -> dict[str, Any]:
    hold_next = bool(next_move and next_move.get("start_held"))
    if move.get("start_held"):
        return await _play_held(dut, move, hold_next, next_move)
    _put_inputs(dut, move)
    lead = int(move.get("load_lead", 0))
    events = _events(move)
    early = [e for e in events if int(e["at_cycle"]) < 0]
    if early and lead > 0:
        raise ValueError("events before the start cannot be combined with load_lead")
    if hold_next and ("inputs_after_start" in move or any(e["port"] in ("start", "load") for e in events)):
        raise ValueError("inputs_after_start or start / load events cannot be combined with a held next start")
    if early:
        # idle events: pos_load or rst '1' for one clock, -at_cycle clocks before the start edge
        for j in range(-min(int(e["at_cycle"]) for e in early), 0, -1):
            await FallingEdge(dut.clk)
            for port in EVENT_PORTS:
                getattr(dut, port).value = 0
            for event in early:
                if int(event["at_cycle"]) == -j:
                    _set_event(dut, event)
    if lead > 0:
        await FallingEdge(dut.clk)
        dut.load.value = 1
        await FallingEdge(dut.clk)
        dut.load.value = 0
        for name in INPUTS:
            getattr(dut, name).value = move["after_load"][name]
        if lead > 1:
            await ClockCycles(dut.clk, lead - 1)
    stops = _stops(move)
    requests = [(STOP_PORTS[stop["kind"]], int(stop["at_cycle"])) for stop in stops]
    if any(at_cycle < 0 for _, at_cycle in requests):
        raise ValueError(f"stop at_cycle must be >= 0: {stops}")
    await FallingEdge(dut.clk)
    if early:
        dut.pos_load.value = 0
        dut.rst.value = 0
    before = _snapshot(dut)
    dut.start.value = 1
    dut.load.value = int(lead == 0 and not move.get("start_only"))
    for port, at_cycle in requests:
        if at_cycle == 0:
            getattr(dut, port).value = 1
    for event in events:
        if int(event["at_cycle"]) == 0:
            _set_event(dut, event)
    await RisingEdge(dut.clk)
    start_edge = now_cycles()
    pulses: list[dict[str, Any]] = [{"port": port, "at_cycle": at_cycle} for port, at_cycle in requests] + events
    strobes = [cocotb.start_soon(_event(dut, e, start_edge)) for e in pulses if int(e["at_cycle"]) >= 1]
    await FallingEdge(dut.clk)
    after_start = _snapshot(dut)
    # an event at edge 1 drives its port '1' at this very falling edge: leave it to the event
    at_one = {e["port"] for e in events if int(e["at_cycle"]) == 1}
    dut.start.value = int(hold_next or "start" in at_one)
    dut.load.value = int(hold_next or "load" in at_one)
    for port, at_cycle in requests:
        if at_cycle == 0:
            getattr(dut, port).value = 0
    for event in events:
        if int(event["at_cycle"]) == 0 and event["port"] not in at_one:
            getattr(dut, event["port"]).value = 0
    if hold_next and next_move is not None:
        _put_inputs(dut, next_move)
    if "inputs_after_start" in move:
        for name in INPUTS:
            getattr(dut, name).value = move["inputs_after_start"][name]
    resets = [int(e["at_cycle"]) for e in events if e["port"] == "rst" and int(e["at_cycle"]) >= 1]
    return await _observe(dut, move, start_edge, strobes, before, after_start, min(resets, default=None))


def _put_inputs(dut: Any, move: dict[str, Any]) -> None:
    for name in INPUTS:
        getattr(dut, name).value = move["registers"][name]
    segment = move.get("segment", {})
    for name in SEGMENT_INPUTS:
        getattr(dut, name).value = int(segment.get(name, 0))
    dut.min_gap.value = int(move.get("min_gap", 2))


async def _play_held(
    dut: Any, move: dict[str, Any], hold_next: bool, next_move: dict[str, Any] | None
) -> dict[str, Any]:
    """A move whose start (and load) have been '1' since the previous move's start edge, with its registers on the
    inputs: here, in the previous move's done cycle, the engine takes it at the next edge."""
    if move.get("events") or move.get("stop") or move.get("load_lead") or "inputs_after_start" in move:
        raise ValueError("a held start takes no events, stops, load_lead or inputs_after_start")
    await RisingEdge(dut.clk)
    start_edge = now_cycles()
    await FallingEdge(dut.clk)
    after_start = _snapshot(dut)
    if hold_next and next_move is not None:
        _put_inputs(dut, next_move)
    else:
        dut.start.value = 0
        dut.load.value = 0
    return await _observe(dut, move, start_edge, [], None, after_start, None)


async def _observe(
    dut: Any,
    move: dict[str, Any],
    start_edge: int,
    strobes: list[Any],
    before: dict[str, int] | None,
    after_start: dict[str, int],
    reset_edge: int | None,
) -> dict[str, Any]:
    """Timestamp every STEP rising edge until done (or until a reset edge), then record the final outputs."""
    edges: list[int] = []
    states: list[int] = []
    counters: dict[str, list[int]] | None = (
        {"step_counts": [], "cur_delays": []} if move.get("record_counters") else None
    )
    deadline = int(get_sim_time("ns")) + int(move["timeout_cycles"]) * CLK_PERIOD_NS
    reset_ns = None if reset_edge is None else (start_edge + reset_edge) * CLK_PERIOD_NS
    offset = 0
    # Woken by STEP, done, or the deadline (the reset's edge, else the cycle budget): one watcher per signal and one
    # Timer for the whole move (stepramp.sim.wake: a First() per pulse costs ten times the simulation of a clock).
    now = get_sim_time("ns")
    wake = Wakeup(dut.step, dut.done)
    wake.set_deadline((deadline if reset_ns is None else min(deadline, reset_ns)) + now - int(now))
    try:
        # done may already be high here: a hard stop at the start edge ends the move at edge 0
        while int(dut.done.value) != 1:
            if reset_ns is not None and int(get_sim_time("ns")) >= reset_ns:
                break
            if wake.expired:
                return {"edges": edges, "states": states, "done": False}
            await wake.wait()
            offset = now_cycles() - start_edge
            if int(dut.step.value) == 1 and (not edges or edges[-1] != offset):
                edges.append(offset)
                states.append(int(dut.state.value))
                if counters is not None:
                    counters["step_counts"].append(int(dut.step_count.value))
                    counters["cur_delays"].append(int(dut.cur_delay.value))
    finally:
        wake.stop()
    common: dict[str, Any] = {"origin": start_edge, "before": before, "after_start": after_start, **(counters or {})}
    if reset_ns is not None and int(dut.done.value) != 1:
        reset = await _watch_after_reset(dut, move, start_edge)
        for strobe in strobes:
            await strobe
        return {"edges": edges, "states": states, "done": False, "reset": reset, **common}
    result = {
        "edges": edges,
        "states": states,
        "done": True,
        "done_edge": offset,
        "error": int(dut.error.value),
        "err_code": int(dut.err_code.value),
        "final_position": _signed(dut.position.value, len(dut.position)),
        "step_count": int(dut.step_count.value),
        **common,
    }
    await FallingEdge(dut.clk)
    result["busy_after"] = int(dut.busy.value)
    result["state_after"] = int(dut.state.value)
    for strobe in strobes:
        await strobe  # a stop requested after done is still driven (the engine must ignore it) and checked
    return result


def _limit_cycles(moves: list[dict[str, Any]]) -> int:
    """Clocks a whole request may take: each move's own budget (timeout_cycles) plus the clocks played around it
    (idle events, load lead, strobes after done, the reset watch, the gap) and 20 clocks of slack."""
    total = 0
    for move in moves:
        stops = _stops(move)
        at_cycles = [0, *(int(x["at_cycle"]) for x in [*stops, *move.get("events", [])])]
        total += int(move["timeout_cycles"]) + max(at_cycles) - min(at_cycles) + int(move.get("load_lead", 0))
        total += int(move.get("reset_watch_cycles", 100)) + int(move.get("gap_cycles", 5)) + 20
    return total


def _backstop_ns() -> int:
    """The decorator's limit: twice the body's (computed from the request the simulation is started with), or
    1000 s of simulated time when the module is imported without one."""
    path = os.environ.get("STEPRAMP_SIM_REQUEST")
    if not path or not Path(path).exists():
        return 1000 * 10**9
    return 2 * (_limit_cycles(json.loads(Path(path).read_text())["moves"]) + 1000) * CLK_PERIOD_NS


# A request holds any number of moves of any length: the body holds the moves to a limit computed from the request
# (with a clear message); the decorator is a backstop.
@cocotb.test(timeout_time=_backstop_ns(), timeout_unit="ns")
async def play_moves(dut: Any) -> None:
    """Play every move of the request, back to back, and write what was observed."""
    request = json.loads(Path(os.environ["STEPRAMP_SIM_REQUEST"]).read_text())
    for name in (
        "start",
        "load",
        "soft_stop",
        "hard_stop",
        "change",
        "change_at",
        "pos_load",
        "pos_value",
        *INPUTS,
        *SEGMENT_INPUTS,
    ):
        getattr(dut, name).value = 0
    dut.min_gap.value = 2
    await start_clock_and_reset(dut.clk, dut.rst, settle=2)
    coverage.watch_engine(dut)
    # The waveform layout (stepramp.sim.waves) names signals of this design: they must exist (in the RTL; a netlist,
    # STEPRAMP_NETLIST, keeps only some of them).
    netlist = bool(os.environ.get("STEPRAMP_NETLIST"))
    missing = [] if netlist else missing_in(dut, signal_paths(LAYOUTS["stepramp_engine"]))
    assert not missing, f"the GTKWave layout names signals stepramp_engine does not have: {missing}"

    results = []
    moves = request["moves"]

    async def play_all() -> None:
        for i, move in enumerate(moves):
            next_move = moves[i + 1] if i + 1 < len(moves) else None
            result = await _play(dut, move, next_move)
            results.append(result)
            if not result["done"] and "reset" not in result:
                break  # the engine hung: report what was seen, the caller fails the test
            if not (next_move and next_move.get("start_held")):
                await ClockCycles(dut.clk, int(move.get("gap_cycles", 5)))

    # Limit: the sum of the moves' cycle budgets and the clocks around them (_limit_cycles), at 10 ns a clock.
    limit_ns = _limit_cycles(moves) * CLK_PERIOD_NS
    try:
        await with_timeout(play_all(), limit_ns, "ns")
        timed_out = False
    except SimTimeoutError:
        timed_out = True
    Path(os.environ["STEPRAMP_SIM_RESULT"]).write_text(json.dumps({"results": results}))
    assert not timed_out, f"the moves ran past their sim-time limit of {limit_ns} ns (after {len(results)} moves)"
    hung = [i for i, r in enumerate(results) if not r["done"] and "reset" not in r]
    assert not hung, f"no done within the cycle budget for move {hung[0]}"
