# SPDX-License-Identifier: MIT
"""Inside a simulation (cocotb): every STEP rising edge and every engine start, stamped with its clock edge, so that
a move seen on the pins compares with the bit-exact model (`stepramp.models.engine.edges`) whatever the bus timing and
however long the stepping logic holds a start for DIR setup/hold. Used by `stepramp.sim.session` and the bus
testbenches.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import cocotb
from cocotb.triggers import RisingEdge

from stepramp.models.stepping import STEP_LATENCY
from stepramp.sim.clocking import now_cycles


class StepWatch:
    """Records the STEP pin's rising edges and the engine's starts (the rising edge of its busy: the model's edge 0)."""

    def __init__(self, step: Any, busy: Any, period_ps: int) -> None:
        """Watch from now on; edges are numbered as stepramp.sim.clocking.now_cycles numbers them (the clock started at
        time 0 with a period of period_ps)."""
        self.period_ps = period_ps
        self.step_edges: list[int] = []
        self.start_edges: list[int] = []
        #: Functions called at each STEP rising edge, after it is recorded, in the same wake (a bench's step counter:
        #: one task per pulse instead of two).
        self.on_step: list[Callable[[], None]] = []
        cocotb.start_soon(self.watch(step, self.step_edges, self.on_step))
        cocotb.start_soon(self.watch(busy, self.start_edges))

    async def watch(self, signal: Any, edges: list[int], hooks: list[Callable[[], None]] | None = None) -> None:
        """Record the clock edge of every rising edge of a signal, and call `hooks` at each."""
        while True:
            await RisingEdge(signal)
            edges.append(now_cycles(self.period_ps))
            for hook in hooks or ():
                hook()

    def mark(self) -> tuple[int, int]:
        """Where the next move's records will start: pass to `since` once it is done."""
        return len(self.step_edges), len(self.start_edges)

    def since(self, first_step: int, first_start: int) -> list[int]:
        """STEP edges of the move whose engine start is the first recorded at or after first_start, counted from
        that start edge and less the stepping logic's register stage (empty if the engine never started)."""
        if len(self.start_edges) <= first_start:
            return []
        start = self.start_edges[first_start]
        return [e - start - STEP_LATENCY for e in self.step_edges[first_step:]]
