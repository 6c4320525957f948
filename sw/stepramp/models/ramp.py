# SPDX-License-Identifier: MIT
"""The ramp kinds: one implementation per ramp arithmetic behind one interface (RampKind), which the engine model's
rule order (stepramp.models.engine.segment_runs, docs/algorithm.md "Which value each interval gets") and its soft
stop (engine.segment_stop_runs) call.

* AVR446 (RAMP_AVR446): the recurrence with remainder, one step at a time through the next-delay unit's model
  (stepramp.models.blocks.recurrence_step, what blocks.next_delay answers);
* exact (RAMP_EXACT): differences of rounded square roots (stepramp.models.exact.value, docs/algorithm.md "Exact
  step times").

Every value is Q32.16. A ramp is read as an endless iterator; the rule order takes what it needs.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from typing import Protocol

from stepramp.models import exact
from stepramp.models.blocks import recurrence_step
from stepramp.spec import RAMP_AVR446, RAMP_EXACT, Segment, check_ramp


class RampKind(Protocol):
    """What the rule order asks of a ramp arithmetic."""

    def accel(self, seed: int, index: int) -> Iterator[int]:
        """The accel ramp from its value at `index`: A_(index+1), A_(index+2), ... (an up head's intervals 2, 3, ...;
        A_0 .. for a move from rest). seed: the ACCEL_SEED register."""
        ...

    def decel(self, seed: int, index: int) -> Iterator[int]:
        """The decel ramp from index `index` down: D_index, D_(index-1), ... (D_m: the interval that ends m steps
        before the rest). seed: the register that seeds it (DECEL_SEED, or for a head down head_seed)."""
        ...

    def head_seed(self, seg: Segment) -> int:
        """The register that seeds a down head's decel ramp."""
        ...

    def stop(self, seg: Segment, following: int, run: bool, m: int) -> list[int]:
        """The values of the intervals p + 1 .. p + max(m, 1) of a soft stop of m steps decided at pulse p, in the
        cruise (run) or not; following: the Q32.16 value interval p + 1 has without the stop. The last is c_last
        (docs/algorithm.md, "Soft stop", and "Exact step times" for the exact ramp)."""
        ...


class Avr446:
    """The AVR446 recurrence (docs/algorithm.md, "Accel recurrence", "Decel recurrence"): every ramp runs from its
    seed with remainder 0."""

    def accel(self, seed: int, index: int) -> Iterator[int]:
        value, rem = seed, 0
        for n in itertools.count(index + 1):  # A_n from A_(n-1), den 4 n + 1 at the absolute index
            value, rem = recurrence_step(False, n, value, rem)
            yield value

    def decel(self, seed: int, index: int) -> Iterator[int]:
        value, rem = seed, 0
        for m in itertools.count(index, -1):  # D_(m-1) from D_m, den 4 m - 1
            yield value
            value, rem = recurrence_step(True, m - 1, value, rem)

    def head_seed(self, seg: Segment) -> int:
        return seg.accel_seed

    def stop(self, seg: Segment, following: int, run: bool, m: int) -> list[int]:
        """The decel recurrence from D_m := following (remainder 0): interval p + j gets D_(m-j), j = 1 .. m - 1."""
        return [*itertools.islice(self.decel(following, m), 1, max(m, 1)), seg.c_last]


class Exact:
    """The exact ramp (docs/algorithm.md, "Exact step times"): the value of index x is the ramp's interval from
    position x to x + 1, of C_acc = accel_seed for accelerating and C_dec = decel_seed for every decelerating ramp."""

    def accel(self, seed: int, index: int) -> Iterator[int]:
        return (exact.value(seed, x) for x in itertools.count(index + 1))

    def decel(self, seed: int, index: int) -> Iterator[int]:
        return (exact.value(seed, x) for x in itertools.count(index, -1))

    def head_seed(self, seg: Segment) -> int:
        return seg.decel_seed

    def stop(self, seg: Segment, following: int, run: bool, m: int) -> list[int]:
        """The ramp values of C_dec from m - j to m - j + 1 steps before the rest (j = 1 .. m - 1); in the cruise the
        motion's own decel from sd - 1 moves to pulse p: c_sd first (alone, before no c_last, when m = 1)."""
        values = [*itertools.islice(self.decel(seg.decel_seed, m - 1), max(m - 1, 0)), seg.c_last]
        if run and m >= 1:
            values[0] = seg.c_sd
        return values


KINDS: dict[int, RampKind] = {RAMP_AVR446: Avr446(), RAMP_EXACT: Exact()}
"""The implementation of each ramp kind (Plan.ramp, Segment.ramp)."""


def kind_of(ramp: int) -> RampKind:
    """The implementation of a ramp kind; ValueError for one that is not."""
    return KINDS[check_ramp(ramp)]
