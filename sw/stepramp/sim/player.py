# SPDX-License-Identifier: MIT
"""One player for a script's actions on the RTL, for every bench that plays one (stepramp.sim.script_bench, single-
and multi-axis) and for the shell's session (stepramp.sim.session).

A script's action (stepramp.board.script_schema.Action, or its JSON form) is a commit at clock `at`: its preparing
register writes from `prep` clocks before it, then a CTRL (or the multi-axis top's SYNC) write issued so that the
register file samples it exactly at `at`. The player calibrates the bus's latency once (the clocks from a write's
call to the edge the register file samples it), issues each commit that many clocks early, and checks, from the
register file's write strobe (WriteLog, which also sets the clock period all of it counts in), that it landed on
its clock; a commit that lands elsewhere fails the run, so that what the RTL did is compared with the model on the
model's own clocks.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import cocotb
from cocotb.triggers import ReadOnly, RisingEdge, Timer
from cocotb.utils import get_sim_time

from stepramp.sim.clocking import CLK_PERIOD_PS, now_cycles, now_periods


class WriteLog:
    """The clock edges at which a register file (or the multi-axis top) samples a write, with the word's byte offset:
    (edge, offset) from now on. wr rises after edge X and the write is sampled at X + 1 (single-word writes)."""

    def __init__(self, wr: Any, waddr: Any, period_ps: int = CLK_PERIOD_PS) -> None:
        self.wr, self.waddr, self.period_ps = wr, waddr, period_ps
        self.writes: list[tuple[int, int]] = []
        self._task = cocotb.start_soon(self._watch())

    async def _watch(self) -> None:
        while True:
            await RisingEdge(self.wr)
            await ReadOnly()
            # (wr may rise at a falling edge, from the bus's select: the last rising edge, floored, + 1)
            self.writes.append((math.floor(now_periods(self.period_ps)) + 1, int(self.waddr.value) & ~3))

    def stop(self) -> None:
        if not self._task.done():
            self._task.cancel()


@dataclass(frozen=True)
class Commit:
    """An action as the player plays it: `writes` ((byte offset, value), in order) from clock at - prep on, then
    `value` written to `address` (byte lane 0) so that it is sampled at clock `at` (clocks from the script's origin)."""

    at: int
    writes: tuple[tuple[int, int], ...]
    address: int
    value: int
    prep: int


async def at_edge(clk: Any, edge: int, late_ok: bool = False, period_ps: int = CLK_PERIOD_PS) -> None:
    """Return just after rising edge `edge` (absolute), as after `await RisingEdge(clk)` (the state in which the bus
    masters' own coroutines see the same edges). late_ok: return at once if that edge has passed."""
    now = get_sim_time("ps")
    if late_ok and now >= edge * period_ps:
        return
    assert now < edge * period_ps, f"edge {edge} has passed (now {now / period_ps:.2f})"
    quarter = (edge - 1) * period_ps + period_ps // 4
    if now < quarter:
        await Timer(quarter - now, unit="ps")
    await RisingEdge(clk)


async def calibrate(bus: Any, clk: Any, log: WriteLog, address: int) -> int:
    """Clock edges from the rising edge at which a write is called to the edge the register file samples it, measured
    with a write of byte 1 of `address` (give a CTRL whose byte 1 is the interrupt enables, off: it changes nothing)."""
    await RisingEdge(clk)
    issued = now_cycles(log.period_ps)
    seen = len(log.writes)
    await bus.write(address, 0, strobe=0x2)
    await Timer(5 * log.period_ps, unit="ps")
    assert len(log.writes) == seen + 1, "the calibration write was not seen once by the register file"
    return log.writes[seen][0] - issued


async def play(bus: Any, clk: Any, log: WriteLog, commits: Sequence[Commit], origin: int, latency: int) -> list[int]:
    """Play the commits from clock `origin` (absolute) on; each must land on its clock (AssertionError otherwise, and
    when its preparing writes run past the clock its commit is issued at). Returns the clocks they landed on."""
    period_ps = log.period_ps
    landed: list[int] = []
    for c in commits:
        at = origin + c.at
        if c.writes:  # (from its prep clock, or at once: the previous commit's answer may end in it)
            await at_edge(clk, at - c.prep, late_ok=True, period_ps=period_ps)
            for address, value in c.writes:
                await bus.write(address, value)
        issue = at - latency
        assert get_sim_time("ps") < issue * period_ps, (
            f"the preparing writes of the commit at {c.at} ran past its issue clock ({len(c.writes)} writes in "
            f"{c.prep} clocks)"
        )
        await at_edge(clk, issue, period_ps=period_ps)
        seen = len(log.writes)
        await bus.write(c.address, c.value, strobe=0x1)
        await Timer(2 * period_ps, unit="ps")
        where = next((e for e, a in log.writes[seen:] if a == c.address), None)
        assert where == at, f"the commit meant for clock {c.at} landed on {None if where is None else where - origin}"
        landed.append(where - origin)
    return landed


def commits_of(
    actions: Sequence[Mapping[str, Any]], prep: int, address: Callable[[Mapping[str, Any]], int]
) -> list[Commit]:
    """The JSON form of a script's actions ({"at", "writes", "ctrl"}, and a multi-axis action's "prep") as commits;
    address(action) gives the commit's register (the axis's CTRL, or the global window's SYNC word)."""
    return [
        Commit(
            at=int(a["at"]),
            writes=tuple((int(o), int(v)) for o, v in a["writes"]),
            address=address(a),
            value=int(a["ctrl"]),
            prep=int(a.get("prep", prep)),
        )
        for a in actions
    ]


__all__ = ["Commit", "WriteLog", "at_edge", "calibrate", "commits_of", "play"]
