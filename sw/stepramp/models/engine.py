# SPDX-License-Identifier: MIT
"""Bit-exact integer model of the ramp engine (docs/algorithm.md, followed literally).

The RTL is compared edge for edge with :func:`edges`. The list functions are for short moves; any move, up to
2^31 - 1 steps, is read in bounded memory with value_runs, tick_chunks, edge_chunks, iter_edges and last_edge.
"""

from __future__ import annotations

import bisect
import dataclasses
import itertools
from collections.abc import Iterable, Iterator
from typing import TYPE_CHECKING

from stepramp.models.ramp import kind_of
from stepramp.spec import DOWN, FRAC_CRUISE, FRAC_RAMP, RAMP_EXACT, Plan, Segment

if TYPE_CHECKING:  # numpy is imported where the lazy functions need it (the list functions do not)
    import numpy as np
    from numpy.typing import NDArray

FIRST_PULSE_LATENCY = 2
"""Clock edges from the edge sampling start = '1' to the edge after which pulse 0 is high."""

ACCEL = "ACCEL"
RUN = "RUN"
DECEL = "DECEL"

_SHIFT = FRAC_CRUISE - FRAC_RAMP
_FRAC_MASK = (1 << FRAC_CRUISE) - 1
HALF = 1 << (FRAC_CRUISE - 1)
"""The accumulator's fraction at a START in exact mode: one half, so that every pulse lands on the tick nearest its
exact time (docs/algorithm.md, "Exact step times")."""


def start_acc(ramp: int) -> int:
    """The accumulator fraction a motion from rest (START or a queued start) begins with: HALF in exact mode, else 0."""
    return HALF if ramp == RAMP_EXACT else 0


def interval_values(plan: Plan) -> Iterator[int]:
    """The Q32.32 value of every interval i = 1 .. L, in order (rule order of the spec)."""
    for value, count in value_runs(plan):
        yield from itertools.repeat(value, count)


def value_runs(plan: Plan) -> Iterator[tuple[int, int]]:
    """interval_values run-length coded: (Q32.32 value, count) for intervals 1 .. L, in order.

    Every interval rule 7 gives (cruise, sa < i < sd) is in one run, the whole cruise at once; every other interval
    is a run of one, from the recurrences as the spec runs them. Time and memory are those of the ramps. (A move
    from rest is the segment with an up head at index 0: segment_runs.)
    """
    return segment_runs(Segment.of_move(plan))


def segment_runs(seg: Segment) -> Iterator[tuple[int, int]]:
    """A segment's interval values run-length coded, by the rules of docs/algorithm.md ("Which value each interval
    gets", and "Changes while moving" for the head and endless segments): c_first, c_last, c_sa, c_sd, the head (up:
    the accel ramp from index n0 = head_index, interval i gets A_(n0+i-1); down: the decel ramp towards a virtual
    rest at the end of interval K = head_index, interval i gets D_(K-i)), the final decel D_(L-i), cruise. The ramp
    values come from the segment's ramp kind (stepramp.models.ramp: the AVR446 recurrences, or the exact ramp's
    rounded square roots). An endless segment's cruise is one endless run of runs of 2^31 - 1."""
    kind = kind_of(seg.ramp)
    endless = seg.length is None
    length = -1 if seg.length is None else seg.length  # -1: no interval is the last, none is past sd
    sa, sd = seg.sa, (-1 if endless else seg.sd)
    if seg.head == DOWN:
        head = kind.decel(kind.head_seed(seg), seg.head_index - 2)  # interval 2 gets D_(K-2)
    else:
        head = kind.accel(seg.accel_seed, seg.head_index)  # interval 2 gets A_(n0+1)
    final: Iterator[int] | None = None  # the final decel from D_(m0), m0 = L - sd - 1, at interval sd + 1
    head_taken = final_taken = 0  # values read from each ramp: interval i is the (i - 1)-th of the head's
    value = 0
    i = 1
    while endless or i <= length:
        if i == 1:
            value = seg.c_first
        elif i == length:
            value = seg.c_last
        elif i == sa:
            value = seg.c_sa
        elif i == sd:
            value = seg.c_sd
        elif i < sa:
            while head_taken < i - 1:
                value = next(head)
                head_taken += 1
        elif not endless and i > sd:
            if final is None:
                final = kind.decel(seg.decel_seed, length - sd - 1)
            while final_taken < i - sd:  # interval i gets D_(L-i), the (i - sd)-th of the final decel
                value = next(final)
                final_taken += 1
        else:  # rule 7 holds for i .. min(sd, L) - 1 (i > sa, i > 1, and no rule before it matches up to there)
            count = (1 << 31) - 1 if endless else min(sd, length) - i
            yield seg.cruise, count
            i += count
            continue
        yield value << _SHIFT, 1
        i += 1


def accumulate(values: Iterable[int], acc: int = 0) -> list[int]:
    """Pulse times in ticks through the 32-bit fractional accumulator: 0 for the first pulse, then the pulse ending
    each Q32.32 interval value; acc is the fraction the accumulator starts with (0 at a START)."""
    times = [0]
    t = 0
    for value in values:
        s = acc + value
        t += s >> FRAC_CRUISE
        acc = s & _FRAC_MASK
        times.append(t)
    return times


def accumulate_runs(runs: Iterable[tuple[int, int]], acc: int = 0) -> list[int]:
    """accumulate() of a run-length coded value sequence ((value, count) runs): the same times, a run of equal values
    at once (after k intervals of v from fraction a, the time has grown by (a + k v) >> 32)."""
    times = [0]
    t = 0
    for value, count in runs:
        if count == 1:
            s = acc + value
            t += s >> FRAC_CRUISE
            acc = s & _FRAC_MASK
            times.append(t)
            continue
        base = acc
        times.extend([t + ((base + k * value) >> FRAC_CRUISE) for k in range(1, count + 1)])
        s = base + count * value
        t += s >> FRAC_CRUISE
        acc = s & _FRAC_MASK
    return times


def tick_times(plan: Plan) -> list[int]:
    """Pulse times T_k in ticks, k = 0 .. N-1 (T_0 = 0), through the 32-bit fractional accumulator."""
    if plan.steps == 0:
        return []
    return accumulate_runs(value_runs(plan), start_acc(plan.ramp))


def edges(plan: Plan) -> list[int]:
    """Clock edge after which pulse k is high: FIRST_PULSE_LATENCY + prescale * T_k."""
    return [FIRST_PULSE_LATENCY + plan.prescale * t for t in tick_times(plan)]


def phases(plan: Plan) -> list[str]:
    """FSM state during each interval i = 1 .. L: ACCEL, RUN or DECEL."""
    sa, sd = plan.sa, plan.sd
    low = min(sa, sd)
    out = []
    for i in range(1, plan.steps):
        if i < low:
            out.append(ACCEL)
        elif sa <= i < sd:
            out.append(RUN)
        else:
            out.append(DECEL)
    return out


# ---------------------------------------------------------------------------------------------------------------
# Long moves in bounded memory (docs/algorithm.md, "Long moves: the lazy model, streamed JSON, summary")
# ---------------------------------------------------------------------------------------------------------------

CHUNK = 1 << 18
"""Default (and largest useful) number of pulses in one chunk of tick_chunks and edge_chunks: 2 MB of uint64."""

_MAX_CHUNK = 1 << 31
_VECTOR_MIN = 64
"""Runs of at least this many intervals (the cruise) are computed in numpy, shorter ones interval by interval."""

StopRequest = tuple[str, int]
"""A stop for the lazy functions: (kind, request_edge) as edges_with_stop takes them ("soft" or "hard")."""


def _take_runs(runs: Iterable[tuple[int, int]], intervals: int) -> Iterator[tuple[int, int]]:
    """The first `intervals` intervals of a run-length coded value sequence."""
    if intervals <= 0:
        return
    for value, count in runs:
        if count >= intervals:
            yield value, intervals
            return
        yield value, count
        intervals -= count


def _advance(t: int, acc: int, value: int, count: int) -> tuple[int, int]:
    """Tick time and accumulator fraction after `count` intervals of `value` (the accumulator summed at once)."""
    s = acc + count * value
    return t + (s >> FRAC_CRUISE), s & _FRAC_MASK


def _first_pulse_from(plan: Plan, edge: int) -> int:
    """The first pulse k of the plan's move with edge E_k >= edge (N when there is none), in O(ramp) time."""
    if plan.steps <= 0:
        return 0
    if plan.prescale == 0:  # not a plan the driver makes: every pulse at edge FIRST_PULSE_LATENCY
        return 0 if edge <= FIRST_PULSE_LATENCY else plan.steps
    need = -(-(edge - FIRST_PULSE_LATENCY) // plan.prescale)  # E_k >= edge <=> T_k >= need
    if need <= 0:
        return 0
    k = t = 0
    acc = start_acc(plan.ramp)
    for value, count in value_runs(plan):
        reached, frac = _advance(t, acc, value, count)
        if reached >= need:  # the j-th interval of this run: acc + j * value >= (need - t) * 2^32
            return k + -(-(((need - t) << FRAC_CRUISE) - acc) // value)
        k, t, acc = k + count, reached, frac
    return plan.steps


def _soft_stop_runs(plan: Plan, p: int, m: int) -> Iterator[tuple[int, int]]:
    """soft_stop_values(plan, p) run-length coded, for the p and m of a soft stop that is not ignored."""
    return segment_stop_runs(Segment.of_move(plan), p, m)


def move_runs(plan: Plan, stop: StopRequest | None = None) -> tuple[int, Iterator[tuple[int, int]]]:
    """(N, runs): the number of pulses of the move and its interval values 1 .. N-1 run-length coded.

    Without a stop the plan's move (value_runs); with one, the move edges_with_stop(plan, *stop) describes.
    """
    if stop is None:
        return plan.steps, value_runs(plan)
    kind, request_edge = stop
    if kind == HARD:
        pulses = plan.steps if request_edge < 0 else _first_pulse_from(plan, request_edge)
        return pulses, _take_runs(value_runs(plan), pulses - 1)
    if kind != SOFT:
        raise ValueError(f"kind must be {SOFT!r} or {HARD!r}, got {kind!r}")
    p = soft_stop_pulse(plan, request_edge)
    m = None if p is None else soft_stop_length(plan, p)
    if p is None or m is None:
        return plan.steps, value_runs(plan)
    # m < 0 only for plans the driver does not make (sd > L); soft_stop_values then puts c_last alone after p
    return p + 1 + (max(m, 1) if m else 0), _soft_stop_runs(plan, p, m)


def _run_ticks(t: int, acc: int, value: int, count: int, chunk: int) -> Iterator[NDArray[np.uint64]]:
    """Tick times after each of `count` intervals of `value`, from time t and fraction acc, in numpy chunks.

    The j-th: t + ((acc + j * value) >> 32) = t + j * hi + ((acc + j * lo) >> 32), value = hi * 2^32 + lo, split
    per chunk into a base (Python int) and i * hi + ((r0 + i * lo) >> 32), i <= chunk <= 2^31: below 2^64, and the
    result is a tick time (< 2^63 for any Plan).
    """
    import numpy as np

    hi, lo = value >> FRAC_CRUISE, value & _FRAC_MASK
    steps = np.arange(1, min(chunk, count) + 1, dtype=np.uint64)
    lo_part = steps * np.uint64(lo)
    hi_part = steps * np.uint64(hi)
    del steps
    for j0 in range(0, count, chunk):
        n = min(chunk, count - j0)
        a0 = acc + j0 * lo
        out = lo_part[:n] + np.uint64(a0 & _FRAC_MASK)
        out >>= np.uint64(FRAC_CRUISE)
        out += hi_part[:n]
        out += np.uint64(t + j0 * hi + (a0 >> FRAC_CRUISE))
        yield out


def tick_chunks(plan: Plan, *, chunk: int = CHUNK, stop: StopRequest | None = None) -> Iterator[NDArray[np.uint64]]:
    """tick_times(plan) (or the stopped move's) as numpy uint64 arrays of at most `chunk` values, in order.

    Memory: a few chunks, whatever the move's length. The ramps run interval by interval in Python, the cruise in
    numpy (bit-identical: the same accumulator, summed in closed form).
    """
    import numpy as np

    if not 1 <= chunk <= _MAX_CHUNK:
        raise ValueError(f"chunk must be in 1 .. 2^31, got {chunk}")
    pulses, runs = move_runs(plan, stop)
    if pulses <= 0:
        return
    buf = [0]
    t, acc = 0, start_acc(plan.ramp)
    for value, count in runs:
        if count < _VECTOR_MIN:
            for _ in range(count):
                s = acc + value
                t += s >> FRAC_CRUISE
                acc = s & _FRAC_MASK
                buf.append(t)
            while len(buf) >= chunk:
                yield np.array(buf[:chunk], dtype=np.uint64)
                del buf[:chunk]
            continue
        if buf:
            yield np.array(buf, dtype=np.uint64)
            buf = []
        yield from _run_ticks(t, acc, value, count, chunk)
        t, acc = _advance(t, acc, value, count)
    if buf:
        yield np.array(buf, dtype=np.uint64)


def edge_chunks(plan: Plan, *, chunk: int = CHUNK, stop: StopRequest | None = None) -> Iterator[list[int]]:
    """edges(plan) (or edges_with_stop(plan, *stop)) as lists of at most `chunk` Python ints, in order."""
    import numpy as np

    last = last_edge(plan, stop=stop)
    narrow = last is not None and last < 1 << 64  # else exact Python ints (a move of 2^64 clocks or more)
    prescale, latency = np.uint64(plan.prescale), np.uint64(FIRST_PULSE_LATENCY)
    for ticks in tick_chunks(plan, chunk=chunk, stop=stop):
        if narrow:
            ticks *= prescale
            ticks += latency
            yield ticks.tolist()
        else:
            yield [FIRST_PULSE_LATENCY + plan.prescale * t for t in ticks.tolist()]


def iter_edges(plan: Plan, *, stop: StopRequest | None = None) -> Iterator[int]:
    """edges(plan) (or edges_with_stop(plan, *stop)) one by one, in bounded memory."""
    for part in edge_chunks(plan, stop=stop):
        yield from part


def last_edge(plan: Plan, *, stop: StopRequest | None = None) -> int | None:
    """The last pulse's edge (None without pulses), in closed form over the runs: O(ramp) time, no edge list."""
    pulses, runs = move_runs(plan, stop)
    if pulses <= 0:
        return None
    t, acc = 0, start_acc(plan.ramp)
    for value, count in runs:
        t, acc = _advance(t, acc, value, count)
    return FIRST_PULSE_LATENCY + plan.prescale * t


# ---------------------------------------------------------------------------------------------------------------
# Stops (docs/algorithm.md, "Soft stop"; docs/stepramp_engine.md for the hard stop)
# ---------------------------------------------------------------------------------------------------------------

SOFT = "soft"
HARD = "hard"

STOP_RATIO_FRAC = 16
"""Fraction bits of Plan.stop_ratio (Q16.16, accel / decel)."""


def phase_of(plan: Plan, i: int) -> str:
    """The spec's phase of interval i (also used for pulse i in the soft-stop rule): ACCEL, RUN or DECEL."""
    if i < min(plan.sa, plan.sd):
        return ACCEL
    if plan.sa <= i < plan.sd:
        return RUN
    return DECEL


def soft_stop_length(plan: Plan, p: int) -> int | None:
    """m, the number of intervals after pulse p of a soft stop decided at pulse p; None when it is ignored.

    0 means the move ends with pulse p. The new last pulse is p + m. The move's segment's (segment_stop_length): at
    or after the last pulse, or in DECEL (p >= sd), ignored; p = 0 (no request is decided there since issue 35): 0;
    ACCEL: floor(p * stop_ratio / 2^16); RUN: the plan's own decel ramp from cruise, L - sd + 1 (intervals sd .. L);
    ignored when p + m reaches L.
    """
    if p >= plan.steps - 1:  # pulse p is the last one (or there is none: the segment of N = 0 has L = 0, not -1)
        return None
    return segment_stop_length(Segment.of_move(plan), p)


def soft_stop_values(plan: Plan, p: int) -> list[int] | None:
    """Q32.32 values of intervals 1 .. p + m when a soft stop is decided at pulse p; None when it is ignored.

    Intervals 1 .. p are the plan's. D is the Q32.16 value of interval p + 1 in the plan (which exists: p + m < L
    with m >= 1): A_p (ACCEL, p + 1 < sa), c_sa (ACCEL, p + 1 = sa), cruise >> 16 (RUN; p + 1 < sd there). The
    reverse decel recurrence runs from D_m := D, remainder 0; interval p + j gets D_{m-j} (j = 1 .. m-1) and
    interval p + m gets c_last. In exact mode the ramp values of decel_seed instead (segment_stop_runs).
    """
    m = soft_stop_length(plan, p)
    if m is None:
        return None
    return _expand(segment_stop_runs(Segment.of_move(plan), p, m))


def _edges_of_values(plan: Plan, values: Iterable[int]) -> list[int]:
    """Edges of pulse 0 and of the pulse ending each interval value, through the fractional accumulator."""
    return [FIRST_PULSE_LATENCY + plan.prescale * t for t in accumulate(values, start_acc(plan.ramp))]


def soft_stop_pulse(plan: Plan, request_edge: int) -> int | None:
    """p, the pulse at which a soft stop sampled at request_edge is decided; None when the request is ignored.

    The request counts only while the engine is busy (edges 1 .. the last pulse's edge; edge 0, the start edge,
    is not busy). p is one pulse after q, the first pulse whose edge is strictly after request_edge (ignored when q
    is the last pulse): docs/algorithm.md, "Soft stop". O(ramp) time, no edge list.
    """
    last = last_edge(plan)
    if request_edge < 1 or last is None or request_edge >= last:
        return None
    q = _first_pulse_from(plan, request_edge + 1)
    return q + 1 if q + 1 < plan.steps else None


def _first_pulse_after(normal: list[int], request_edge: int) -> int | None:
    """The pulse at which a soft stop sampled at request_edge is decided, from the normal edges (soft_stop_pulse):
    one after the first pulse whose edge is after request_edge; None when that one is the last or there is none."""
    if request_edge < 1 or not normal or request_edge >= normal[-1]:
        return None
    q = bisect.bisect_right(normal, request_edge)
    return q + 1 if q + 1 < len(normal) else None


def edges_with_stop(plan: Plan, kind: str, request_edge: int) -> list[int]:
    """Edges of the pulses the engine emits when a stop strobe is sampled '1' at request_edge (edge 0 = start).

    kind "hard": every pulse whose edge is before request_edge (a pulse due at request_edge itself is suppressed);
    at the start edge (0) the hard stop wins and nothing is emitted; after the move it changes nothing.
    kind "soft": see soft_stop_pulse and soft_stop_values.
    """
    if kind not in (SOFT, HARD):
        raise ValueError(f"kind must be {SOFT!r} or {HARD!r}, got {kind!r}")
    normal = edges(plan)
    if kind == HARD:
        return normal if request_edge < 0 else normal[: bisect.bisect_left(normal, request_edge)]
    p = _first_pulse_after(normal, request_edge)
    values = None if p is None else soft_stop_values(plan, p)
    if values is None:
        return normal
    return _edges_of_values(plan, values)


# ---------------------------------------------------------------------------------------------------------------
# Step spacing (docs/algorithm.md, "Step spacing (STEP_SPACE)")
# ---------------------------------------------------------------------------------------------------------------


def min_gap(step_width: int, step_space: int) -> int:
    """Shortest distance in clocks between two STEP rising edges: max(step_width, 1) + max(step_space, 1)."""
    return max(step_width, 1) + max(step_space, 1)


def first_space_fault(move_edges: Iterable[int], gap: int) -> int | None:
    """Index k >= 1 of the first pulse closer than `gap` clocks to pulse k - 1 (the engine refuses it and ends the
    move there with error STEP_SPACE); None when every pulse keeps its distance. Reads the edges lazily."""
    previous: int | None = None
    for k, edge in enumerate(move_edges):
        if previous is not None and edge - previous < gap:
            return k
        previous = edge
    return None


# ---------------------------------------------------------------------------------------------------------------
# Continuation segments (docs/algorithm.md, "Changes while moving"): the first `count` intervals of a segment
# ---------------------------------------------------------------------------------------------------------------


def segment_values(seg: Segment, count: int) -> list[int]:
    """The Q32.32 values of the segment's intervals 1 .. count (at most its length): segment_runs, expanded."""
    return [value for value, n in _take_runs(segment_runs(seg), count) for _ in range(n)]


def segment_ticks(seg: Segment, count: int, acc: int = 0) -> list[int]:
    """Tick times of the segment's pulses 0 .. count (pulse 0 is pulse P, at tick 0), through the fractional
    accumulator that starts at `acc` (the fraction the running plan left at pulse P)."""
    return accumulate_runs(_take_runs(segment_runs(seg), count), acc)


def segment_stop_length(seg: Segment, p: int) -> int | None:
    """m of a soft stop decided at the segment's pulse p (the intervals after it), None when it is ignored: at or
    after the last pulse, in the final decel, or when p + m reaches the segment's own end. In an up head
    m = floor((n0 + p) stop_ratio / 2^16) (the ACCEL rule at the virtual index); in a down head m = K - p (the head
    goes on to its virtual rest); in the cruise L - sd + 1, or run_stop for an endless segment. ValueError for
    p < 0 (not a pulse)."""
    length = seg.length
    if p < 0:
        raise ValueError(f"a soft stop is decided at a pulse p >= 0, not {p}")
    if length is not None and (p >= length or p >= seg.sd):
        return None
    if p == 0:  # (no request is decided at pulse 0 since issue 35, p = q + 1 >= 1; the value of the ACCEL rule)
        return 0
    if p < seg.sa:
        m = seg.head_index - p if seg.head == "down" else (seg.head_index + p) * seg.stop_ratio >> STOP_RATIO_FRAC
    else:
        m = length - seg.sd + 1 if length is not None else seg.run_stop
    if (length is not None and p + m >= length) or m >= 1 << 31:  # m >= 2^31: the engine's "m too big"
        return None
    return m


def segment_stop_runs(seg: Segment, p: int, m: int) -> Iterator[tuple[int, int]]:
    """The values of the segment's intervals 1 .. p + max(m, 1) (1 .. p when m = 0) with a soft stop of m steps
    decided at its pulse p (m from segment_stop_length, not None), run-length coded: docs/algorithm.md, "Soft stop".

    Down head (p < sa): the head's decel ramp goes on to its virtual rest, interval K (= p + m) gets c_last.
    Otherwise intervals 1 .. p are the segment's, then its ramp kind's stop (stepramp.models.ramp, RampKind.stop)
    from D, the Q32.16 value of interval p + 1: AVR446: interval p + j gets D_(m-j) from D_m := D, remainder 0; exact:
    the ramp values of decel_seed (c_sd first in the cruise); c_last last."""
    if m == 0:
        yield from _take_runs(segment_runs(seg), p)
        return
    if seg.head == DOWN and p < seg.sa:
        end = p + m
        yield from segment_runs(dataclasses.replace(seg, length=end, sa=end, sd=end))
        return
    left, following = p, 0
    for value, count in segment_runs(seg):  # intervals 1 .. p, and D = the Q32.16 value of interval p + 1
        if count <= left:
            yield value, count
            left -= count
            continue
        if left:
            yield value, left
        following = value >> _SHIFT
        break
    for value in kind_of(seg.ramp).stop(seg, following, p >= seg.sa, m):
        yield value << _SHIFT, 1


def segment_stop_values(seg: Segment, p: int) -> list[int] | None:
    """Q32.32 values of the segment's intervals 1 .. p + m with a soft stop decided at its pulse p (None: ignored):
    segment_stop_runs, expanded."""
    m = segment_stop_length(seg, p)
    if m is None:
        return None
    return _expand(segment_stop_runs(seg, p, m))


def _expand(runs: Iterable[tuple[int, int]]) -> list[int]:
    """A run-length coded value sequence as a list."""
    return [value for value, n in runs for _ in range(n)]


def segment_edges(
    seg: Segment, prescale: int, *, count: int | None = None, stop: StopRequest | None = None
) -> list[int]:
    """Edges of a segment's pulses 0 .. when it runs from START (pulse 0 at FIRST_PULSE_LATENCY), as edges_with_stop
    gives them for a move: all of them (a positioning segment), the first `count` intervals (an endless one), or
    with a stop sampled at request_edge (hard: the pulses before it; soft: decided one pulse after the first pulse
    after it).
    An endless segment needs `count` or a stop that ends it."""

    def to_edges(values: list[int]) -> list[int]:
        return [FIRST_PULSE_LATENCY + prescale * t for t in accumulate(values, start_acc(seg.ramp))]

    def first_edges(count: int) -> list[int]:  # (to_edges of segment_values(seg, count), a run at once)
        ticks = accumulate_runs(_take_runs(segment_runs(seg), count), start_acc(seg.ramp))
        return [FIRST_PULSE_LATENCY + prescale * t for t in ticks]

    if stop is None:
        if seg.length is None and count is None:
            raise ValueError("an endless segment without a stop needs a count")
        return first_edges(seg.length if count is None else count)
    kind, request_edge = stop
    # enough of the normal edges to pass the request edge
    n = 64
    while True:
        normal = first_edges(n)
        if (len(normal) > 1 and normal[-2] > request_edge) or (seg.length is not None and n >= seg.length):
            break  # (the pulse after the first one after the request: where a soft stop is decided)
        n *= 2
    if kind == HARD:
        return normal if request_edge < 0 else normal[: bisect.bisect_left(normal, request_edge)]
    p = _first_pulse_after(normal, request_edge)
    values = None if p is None else segment_stop_values(seg, p)
    if values is None:
        if seg.length is None:
            raise ValueError(f"the soft stop at edge {request_edge} is ignored: the endless segment would not end")
        return normal
    return to_edges(values)


def change_edges(running: Segment, p: int, seg: Segment, prescale: int) -> list[int]:
    """Edges of a motion that starts as `running` (from START) and in which `seg` takes over at pulse p
    (docs/algorithm.md, "Changes while moving", the take-over's design): intervals 1 .. p are the running
    segment's, then the segment's 1 .. its length (an endless one is cut at its sa + 64), one accumulator throughout."""
    if not 1 <= p <= (running.length if running.length is not None else MAX_CHANGE_PULSE):
        raise ValueError(f"the take-over pulse {p} is not a pulse after pulse 0 of the running motion")
    count = seg.length if seg.length is not None else seg.sa + 64
    values = segment_values(running, p) + segment_values(seg, count)
    return [FIRST_PULSE_LATENCY + prescale * t for t in accumulate(values, start_acc(running.ramp))]


MAX_CHANGE_PULSE = (1 << 31) - 1
"""The largest pulse number a take-over can name (STEP_COUNT is 31 bits)."""
