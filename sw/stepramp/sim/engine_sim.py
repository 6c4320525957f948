# SPDX-License-Identifier: MIT
"""Run moves on the RTL engine (GHDL through cocotb's runner) and return what it did, move by move."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stepramp.board.driver import STATE_NAMES  # the engine's `state` port is STATUS.STATE's encoding
from stepramp.board.plan import Plan
from stepramp.models.engine import last_edge
from stepramp.sim.runner import run_cocotb


@dataclass(frozen=True)
class SimResult:
    """What the RTL did for one move."""

    edges: list[int]
    states: list[str]
    done: bool
    error: int | None = None
    err_code: int | None = None
    final_position: int | None = None
    step_count: int | None = None
    done_edge: int | None = None
    busy_after: int | None = None
    state_after: str | None = None
    #: the absolute index of the edge the timestamps count from (the start edge; for a held start, the edge after
    #: the previous move's done cycle)
    origin: int | None = None
    #: the outputs (stepramp.sim.engine_bench.SNAPSHOT_PORTS and position, state by name) in the cycle before the start
    #: edge (None for a held start) and in the cycle after it
    before: dict[str, Any] | None = None
    after_start: dict[str, Any] | None = None
    #: a move ended by a "rst" event: the outputs in the cycle after the reset edge, and "stray", the first step,
    #: done or busy rising edge seen after it (None: none)
    reset: dict[str, Any] | None = None
    #: with "record_counters": step_count and cur_delay as each pulse's edge leaves them
    step_counts: list[int] | None = None
    cur_delays: list[int] | None = None


@dataclass(frozen=True)
class Stop:
    """A stop strobe for one move: kind "soft" or "hard", sampled '1' at edge at_cycle (the start edge is 0)."""

    kind: str
    at_cycle: int

    def __post_init__(self) -> None:
        if self.kind not in ("soft", "hard"):
            raise ValueError(f"Stop.kind must be 'soft' or 'hard', got {self.kind!r}")
        if self.at_cycle < 0:
            raise ValueError(f"Stop.at_cycle must be >= 0, got {self.at_cycle}")


def timeout_cycles(plan: Plan, stop: Stop | Sequence[Stop] | None = None) -> int:
    """A generous cycle budget for one move: the model's last edge plus slack (a hang fails after this).

    With stops, the longest of the model's stopped moves (a soft stop can make a move last longer) and the edge of
    the last request (a hard stop ends the move there, after its last pulse). The last edges come from the model in
    closed form (stepramp.models.engine.last_edge): no edge list, whatever the move's length.
    """
    stops = [] if stop is None else [stop] if isinstance(stop, Stop) else list(stop)
    last = last_edge(plan) or 0
    for s in stops:
        last = max(last, s.at_cycle, last_edge(plan, stop=(s.kind, s.at_cycle)) or 0)
    return last + 2000 + 4 * plan.prescale


def simulate(
    plans: Sequence[Plan],
    build_dir: Path,
    waves: Path | None = None,
    budgets: Sequence[int] | None = None,
    log_file: Path | None = None,
    stops: Sequence[Stop | Sequence[Stop] | None] | None = None,
    extras: Sequence[dict[str, Any]] | None = None,
    netlist: bool = False,
) -> list[SimResult]:
    """Play the moves back to back in one simulation; one SimResult per move (fewer if the engine hung).

    stops: an optional stop (or list of stops) per move (None: no stop). Under pytest a hang (or any failure inside
    the simulation) raises SystemExit from the runner. extras: per move, more keys of the request
    (stepramp.sim.engine_bench: "min_gap", "load_lead" with "after_load", "gap_cycles", "events", "reset_watch_cycles",
    "inputs_after_start", "start_held", "record_counters"). netlist: simulate ghdl synth's Verilog netlist of the
    engine on Icarus Verilog instead (stepramp.sim.netlist).
    """
    if stops is not None and len(stops) != len(plans):
        raise ValueError(f"{len(stops)} stops for {len(plans)} plans")
    build_dir = build_dir.resolve()
    build_dir.mkdir(parents=True, exist_ok=True)
    request = build_dir / "request.json"
    result_file = build_dir / "result.json"
    result_file.unlink(missing_ok=True)
    moves: list[dict[str, Any]] = []
    for i, plan in enumerate(plans):
        stop = stops[i] if stops is not None else None
        move: dict[str, Any] = {
            "registers": dataclasses.asdict(plan),
            "timeout_cycles": budgets[i] if budgets else timeout_cycles(plan, stop),
        }
        if isinstance(stop, Stop):
            move["stop"] = {"kind": stop.kind, "at_cycle": stop.at_cycle}
        elif stop is not None:
            move["stop"] = [{"kind": s.kind, "at_cycle": s.at_cycle} for s in stop]
        if extras is not None:
            move.update(extras[i])
        moves.append(move)
    request.write_text(json.dumps({"moves": moves}))
    ramps = {plan.ramp for plan in plans}
    if len(ramps) > 1:
        raise ValueError("the moves of one simulation must all be for the same ramp arithmetic (G_RAMP)")
    ramp = ramps.pop() if ramps else 0
    run_cocotb(
        "stepramp_engine",
        "stepramp.sim.engine_bench",
        build_dir,
        parameters={"G_RAMP": ramp} if ramp else None,
        waves=waves,
        extra_env={"STEPRAMP_SIM_REQUEST": str(request), "STEPRAMP_SIM_RESULT": str(result_file)},
        log_file=log_file,
        netlist=netlist,
    )
    if not result_file.exists():
        raise RuntimeError(f"the simulation wrote no result; see the log in {build_dir}")
    raw: list[dict[str, Any]] = json.loads(result_file.read_text())["results"]
    out = []
    for r in raw:
        r["states"] = [STATE_NAMES[s] for s in r["states"]]
        if "state_after" in r:
            r["state_after"] = STATE_NAMES[r["state_after"]]
        for key in ("before", "after_start", "reset"):
            if r.get(key) is not None:
                r[key]["state"] = STATE_NAMES[r[key]["state"]]
        out.append(SimResult(**r))
    return out
