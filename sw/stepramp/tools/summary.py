# SPDX-License-Identifier: MIT
"""A move's figures without its edge list: what `stepramp model|sim --summary` prints and `make demo` reports.

Fed chunk by chunk (docs/algorithm.md, "Long moves"), so a move of 2^31 - 1 pulses is summarised in bounded
memory: pulse count, last edge, move time, peak speed, the largest deviation from the ideal trajectory (its pulse
times computed chunk by chunk too, bit-identical to stepramp.models.ideal) and a SHA-256 checksum of the edges.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from stepramp.board.plan import Plan
from stepramp.models.engine import FIRST_PULSE_LATENCY, tick_chunks
from stepramp.models.ideal import c0, ideal_move

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

CHECKSUM_PREFIX = "sha256:"
_U64 = (1 << 64) - 1


def edge_checksum(edges: Sequence[int]) -> str:
    """The checksum of an edge list, plainly: SHA-256 over each edge mod 2^64 as 8 bytes little-endian."""
    digest = hashlib.sha256(b"".join((e & _U64).to_bytes(8, "little") for e in edges))
    return CHECKSUM_PREFIX + digest.hexdigest()


class MoveSummary:
    """Accumulates a move's edges in order (add_ticks for exact tick times, add_edges for clock edges) and gives
    the summary (result). inputs: the move in physical units, as plan_move and ideal_move take them."""

    def __init__(self, inputs: dict[str, Any]) -> None:
        self.prescale: int = inputs.get("prescale", 1)
        self.f_tick = inputs["fclk"] / self.prescale
        self.ideal = ideal_move(**inputs)
        self.alpha = 2 * math.pi / inputs["spr"]
        self.c0_slow = c0(min(inputs["accel"], inputs["decel"]), inputs["spr"], inputs["fclk"], self.prescale)
        self.pulses = 0
        self.last_edge: int | None = None
        self.last_tick = 0.0
        self.shortest = math.inf
        self.max_deviation = -1.0
        self.max_deviation_pulse = 0
        self._hash = hashlib.sha256()

    def add_ticks(self, ticks: NDArray[np.uint64]) -> None:
        """The next pulses, as tick times T_k (edges 2 + PRESCALE * T_k), exact: stepramp.models.engine.tick_chunks."""
        import numpy as np

        if len(ticks) == 0:
            return
        wrapped = ticks * np.uint64(self.prescale)  # the edges mod 2^64 (numpy arrays wrap)
        wrapped += np.uint64(FIRST_PULSE_LATENCY)
        last = FIRST_PULSE_LATENCY + self.prescale * int(ticks[-1])
        self._add(ticks.astype(np.float64), wrapped, last)

    def add_edges(self, edges: Sequence[int]) -> None:
        """The next pulses, as clock edges (any integers, as the RTL emitted them)."""
        import numpy as np

        if not edges:
            return
        ticks = np.array([(e - FIRST_PULSE_LATENCY) / self.prescale for e in edges], dtype=np.float64)
        wrapped = np.array([e & _U64 for e in edges], dtype=np.uint64)
        self._add(ticks, wrapped, edges[-1])

    def _add(self, ticks: NDArray[np.float64], wrapped: NDArray[np.uint64], last: int) -> None:
        import numpy as np

        self._hash.update(memoryview(wrapped.astype("<u8", copy=False)))  # no copy on a little-endian machine
        deviation = ticks - self.ideal.time_chunk(self.pulses, self.pulses + len(ticks))
        np.abs(deviation, out=deviation)
        worst = int(np.argmax(deviation))
        if deviation[worst] > self.max_deviation:  # the first pulse where the largest deviation occurs
            self.max_deviation = float(deviation[worst])
            self.max_deviation_pulse = self.pulses + worst
        del deviation
        if self.pulses:
            self.shortest = min(self.shortest, float(ticks[0] - self.last_tick))
        if len(ticks) > 1:
            self.shortest = min(self.shortest, float(np.min(np.diff(ticks))))
        self.pulses += len(ticks)
        self.last_tick = float(ticks[-1])
        self.last_edge = last

    def _peak_speed(self) -> float | None:
        """alpha * f_tick / the shortest interval in ticks: 0.0 with fewer than 2 pulses, None when an interval is
        0 or negative (edges out of order: no valid move has them)."""
        if self.pulses < 2:
            return 0.0
        return self.alpha * self.f_tick / self.shortest if self.shortest > 0 else None

    def checksum(self) -> str:
        return CHECKSUM_PREFIX + self._hash.hexdigest()

    def result(self) -> dict[str, Any]:
        """The summary object (docs/algorithm.md, "Long moves": the keys and what they mean)."""
        some = self.pulses > 0
        return {
            "pulses": self.pulses,
            "last_edge": self.last_edge,
            "move_time_s": self.last_tick / self.f_tick if some else 0.0,
            "ideal_move_time_s": self.ideal.t_end,
            "peak_speed_rad_s": self._peak_speed(),
            "ideal_peak_speed_rad_s": self.ideal.v_peak * self.alpha,
            "max_deviation_ticks": self.max_deviation if some else 0.0,
            "max_deviation_pulse": self.max_deviation_pulse,
            "max_deviation_c0": self.max_deviation / self.c0_slow if some else 0.0,
            "c0_slow_ticks": self.c0_slow,
            "checksum": self.checksum(),
        }


def summarise_model(inputs: dict[str, Any], plan: Plan) -> dict[str, Any]:
    """The summary of the model's move, chunk by chunk (bounded memory for any valid move)."""
    summary = MoveSummary(inputs)
    if summary.prescale != plan.prescale:
        raise ValueError(f"the plan's prescale {plan.prescale} is not the move's {summary.prescale}")
    for ticks in tick_chunks(plan):
        summary.add_ticks(ticks)
    return summary.result()


def summarise_edges(inputs: dict[str, Any], edges: Sequence[int]) -> dict[str, Any]:
    """The summary of a move given by its edge list (the RTL's)."""
    summary = MoveSummary(inputs)
    summary.add_edges(edges)
    return summary.result()
