# SPDX-License-Identifier: MIT
"""The shared ramp computer's service order (docs/ramp_computer.md, "The scheduler"), as a clocked model.

One ramp computer serves every axis. An axis raises a request at a pulse edge (the value of a later interval is
due); the computer serves one request at a time, each for a given number of clocks, and picks the next one round
robin: the first waiting axis after the one it served last, in axis order. Nothing here knows the ramp arithmetic:
a request is an axis, the clock edge at which it is raised, the clocks its service takes and the edge by which it
must be done. The model answers when each service ends, so that a test can hold the bound of the documented rule
(an axis whose requests are at least ``axes * longest_service`` clocks apart is always served in time) against
every arrival pattern it can draw, and show that one clock less is not enough.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class Request:
    """A service an axis asks for: raised at clock edge ``at``, ``length`` clocks of service, due at ``due``."""

    axis: int
    at: int
    length: int
    due: int


@dataclass(frozen=True)
class Served:
    """A request and the clock edges at which its service starts and ends (the result is there at ``end``)."""

    request: Request
    start: int
    end: int

    @property
    def late(self) -> bool:
        """The service ended after its due edge."""
        return self.end > self.request.due


def round_robin(requests: Iterable[Request], axes: int) -> list[Served]:
    """Serve the requests one at a time, round robin over the axes that wait.

    A service starts at the edge at which the computer is free and a request waits (a request raised at edge ``t``
    can start at ``t``); the next one is the waiting request of the first axis after the last served, cyclically
    (axis 0 first at the start), and an axis's own requests are served in the order they were raised. Returns the
    services in the order they ran."""
    pending: list[list[Request]] = [[] for _ in range(axes)]
    todo = sorted(requests, key=lambda r: (r.at, r.axis))
    for r in todo:
        if not 0 <= r.axis < axes:
            raise ValueError(f"axis {r.axis} of {axes}")
        if r.length < 1:
            raise ValueError(f"a service takes at least one clock: {r}")
    out: list[Served] = []
    now, last, nxt = 0, axes - 1, 0
    while nxt < len(todo) or any(pending):
        while nxt < len(todo) and todo[nxt].at <= now:
            pending[todo[nxt].axis].append(todo[nxt])
            nxt += 1
        waiting = [a for a in range(axes) if pending[a]]
        if not waiting:
            now = todo[nxt].at
            continue
        axis = min(waiting, key=lambda a: (a - last - 1) % axes)
        req = pending[axis].pop(0)
        out.append(Served(req, now, now + req.length))
        now, last = now + req.length, axis
    return out


def periodic_requests(
    axes: int, intervals: Sequence[Sequence[int]], lengths: Sequence[Sequence[int]], phases: Sequence[int]
) -> list[Request]:
    """The requests of axes that pulse at the given intervals: axis ``a`` raises one at each pulse edge (the first
    at ``phases[a]``, the next ``intervals[a][k]`` clocks later), with service ``lengths[a][k]``, due at the axis's
    next pulse edge."""
    out: list[Request] = []
    for a in range(axes):
        t = phases[a]
        for iv, length in zip(intervals[a], lengths[a], strict=True):
            out.append(Request(a, t, length, t + iv))
            t += iv
    return out


def shortest_interval(axes: int, longest_service: int) -> int:
    """The shortest interval (clocks) that round robin guarantees to every axis whatever the others do: an axis
    waits for at most one service of each other axis and then takes its own."""
    if axes < 1 or longest_service < 1:
        raise ValueError(f"axes {axes}, longest service {longest_service}")
    return axes * longest_service
