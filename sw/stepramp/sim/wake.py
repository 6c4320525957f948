# SPDX-License-Identifier: MIT
"""Inside a simulation (cocotb): wait for the first of several rising edges, or a deadline, cheaply.

cocotb 2.1's First() starts a Task per trigger and cancels the losers each time it is awaited, and a cancelled Timer
stays registered with GHDL until its time comes: measured on GHDL 2.0 (LLVM), `await First(RisingEdge(a),
RisingEdge(b))` costs 80 to 160 us of the simulator's time where `await RisingEdge(a)` costs 8 us, and a First() or
with_timeout() with a far Timer in a loop grows to 300 us per wait as the cancelled timers pile up. A bench that waits
this way for every STEP edge, or every division, runs at a tenth of the simulator's speed.

Wakeup keeps one watcher Task per signal for as long as it is used, each setting one Event on the signal's rising
edges, and at most one deadline Timer that is not cancelled before the end: a wait is then an Event's, pure Python.
"""

from __future__ import annotations

from typing import Any

import cocotb
from cocotb.triggers import Event, ReadOnly, RisingEdge, Timer
from cocotb.utils import get_sim_time


class Wakeup:
    """Wake one waiting coroutine at every rising edge of any of `signals`, and at an optional deadline.

    `await wake.wait()` returns in the ReadOnly phase of the first time step, from the call on, in which one of the
    signals rose (several rising together wake it once) or the deadline (set_deadline) passed: as `await
    First(RisingEdge(a), RisingEdge(b), Timer(...))` followed by `await ReadOnly()` would, without their cost.
    Call stop() when done (or use it as a context manager).
    """

    def __init__(self, *signals: Any) -> None:
        self._event = Event()
        self._tasks = [cocotb.start_soon(self._watch(s)) for s in signals]
        self._deadline: Any = None
        self.expired = False

    async def _watch(self, signal: Any) -> None:
        edge = RisingEdge(signal)
        while True:
            await edge
            self._event.set()

    async def _expire(self, delay_ns: float) -> None:
        await Timer(delay_ns, unit="ns", round_mode="round")
        self.expired = True
        self._event.set()

    def set_deadline(self, at_ns: float) -> None:
        """Wake (and set `expired`) when the simulated time reaches at_ns (absolute, ns); at most once per Wakeup."""
        assert self._deadline is None, "one deadline per Wakeup"
        delay = at_ns - get_sim_time("ns")
        if delay <= 0:
            self.expired = True
            self._event.set()
        else:
            self._deadline = cocotb.start_soon(self._expire(delay))

    async def wait(self) -> None:
        """Until a watched signal rises (or the deadline passes), then to the ReadOnly phase of that time step."""
        await self._event.wait()
        await ReadOnly()
        self._event.clear()  # (every edge of this time step is in: nothing changes in ReadOnly)

    def stop(self) -> None:
        for task in [*self._tasks, self._deadline]:
            if task is not None and not task.done():
                task.cancel()
        self._tasks, self._deadline = [], None

    def __enter__(self) -> Wakeup:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


__all__ = ["Wakeup"]
