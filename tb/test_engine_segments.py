# SPDX-License-Identifier: MIT
"""stepramp_engine running continuation segments from START (docs/algorithm.md, "Changes while moving"): up heads
from an index n0, down heads towards a virtual rest, endless moves (jog) and the soft stop within each, every STEP
edge against the bit-exact model (stepramp.models.engine.segment_edges), which sw/tests/test_change.py holds to
the ideal motion. Run from START a segment with a head at speed starts at that speed: the arithmetic is the one a
change will take over with.
"""

from __future__ import annotations

import dataclasses

from stepramp.board.change import DOWN, UP, Segment, plan_change
from stepramp.board.regmap import ERROR_CODES
from stepramp.models.engine import HARD, SOFT, segment_edges
from stepramp.sim.engine_sim import SimResult, Stop, simulate
from tbutil import build_dir, edges_differ

ERR = {name: code for name, (code, _) in ERROR_CODES.items()}

#: Fast ramps at 1 MHz (the intervals of a few hundred ticks, so that a move is a few tens of thousands of clocks).
SPR, FCLK = 200.0, 1e6
ALPHA = 6.283185307179586 / SPR


def change(u_rad: float, remaining: int | None, accel: float, decel: float, speed: float, prescale: int = 1) -> Segment:
    """plan_change from a speed in rad/s (the segment alone: the tests below never ask for a move back)."""
    result = plan_change(u_rad / ALPHA, remaining, accel, decel, speed, SPR, FCLK, prescale)
    assert result.back is None
    return result.segment


@dataclasses.dataclass(frozen=True)
class Case:
    name: str
    seg: Segment
    direction: int = 0
    stop: Stop | None = None
    code: int = 0

    def expected(self) -> list[int]:
        if self.code:
            return []
        stop = None if self.stop is None else (self.stop.kind, self.stop.at_cycle)
        return segment_edges(self.seg, self.seg.prescale, stop=stop)


def normal_edge(seg: Segment, k: int) -> int:
    """The model's edge of pulse k of the segment without a stop."""
    return segment_edges(seg, seg.prescale, count=k)[k]


def play(tag: str, cases: list[Case]) -> list[SimResult]:
    regs = [c.seg.registers(c.direction) for c in cases]
    budgets = [max([*c.expected(), 0, c.stop.at_cycle if c.stop else 0]) + 4000 for c in cases]
    assert sum(budgets) < 1_500_000, f"{tag}: {sum(budgets)} clocks, keep it short"
    results = simulate(
        [plan for plan, _ in regs],
        build_dir(f"engine_segments_{tag}"),
        budgets=budgets,
        stops=[c.stop for c in cases],
        extras=[{"segment": segment} for _, segment in regs],
    )
    assert len(results) == len(cases), f"only {len(results)} of {len(cases)} moves finished"
    problems = []
    for case, res in zip(cases, results, strict=True):
        want = case.expected()
        if res.edges != want:
            problems.append(f"{case.name}: {edges_differ(res.edges, want)}")
        if not res.done or res.err_code != case.code:
            problems.append(f"{case.name}: done={res.done} code={res.err_code}, expected {case.code}")
        if res.step_count != len(want):
            problems.append(f"{case.name}: step_count {res.step_count}, expected {len(want)}")
    assert not problems, "\n".join(problems)
    return results


def soft_after(seg: Segment, k: int) -> Stop:
    """A soft stop sampled one clock after pulse k's edge: decided at pulse k + 1."""
    return Stop(SOFT, normal_edge(seg, k) + 1)


def test_engine_segments_positioning() -> None:
    """Up heads from n0 > 0 (faster), down heads (slower), a cruise from interval 1; with and without soft stops in
    the head (a down head goes on to its rest; one decided at sa - 1, where the head gave way to c_sa, and at pulse 1
    of heads with sa = 2, where that value is the seed itself, and sa = 1), in the cruise, and ignored where the
    segment's own decel ends no later."""
    up = change(40.0, 60, 2000.0, 1500.0, 100.0)
    down = change(140.0, 260, 2000.0, 1500.0, 60.0)
    flat = change(100.0, 160, 2000.0, 1500.0, 100.0)
    assert up.head == UP and up.head_index >= 10 and up.sa >= 4
    assert down.head == DOWN and down.sa >= 6 and down.head_index < down.length
    assert flat.sa == 1
    down2 = change(140.0, 260, 2000.0, 48000.0, 110.0)
    down1 = change(140.0, 260, 2000.0, 24000.0, 130.0)
    assert down2.head == DOWN and down2.sa == 2 and down1.head == DOWN and down1.sa == 1
    cases = [
        Case("up", up),
        Case("up negative, prescale 2", change(40.0, 60, 2000.0, 1500.0, 100.0, prescale=2), direction=1),
        Case("down", down),
        Case("cruise from interval 1", flat),
        Case("up, soft stop in the head", up, stop=soft_after(up, 2)),
        Case("up, soft stop in the cruise", up, stop=soft_after(up, up.sa + 2)),
        Case("down, soft stop in the head", down, stop=soft_after(down, 2)),
        Case("down, soft stop at sa - 1", down, stop=soft_after(down, down.sa - 2)),
        Case("down, soft stop in the cruise", down, stop=soft_after(down, down.sa + 1)),
        Case("down, hard stop", down, stop=Stop(HARD, normal_edge(down, 5) + 3)),
        # sa = 2: interval 2 is c_sa, so a stop at pulse 1 takes the head's own interval 2 (its seed), not one beyond
        Case("down, sa = 2, soft stop at pulse 1", down2, stop=soft_after(down2, 0)),
        Case("down, sa = 1, soft stop at pulse 1", down1, stop=soft_after(down1, 0)),
    ]
    play("positioning", cases)


def test_engine_segments_endless() -> None:
    """Jogs: from rest, from speed up (n0 > 0) and down (a down head into an endless cruise); each ended by a soft
    stop in the head or in the cruise (run_stop), or by a hard stop."""
    jog = change(0.0, None, 2000.0, 1500.0, 100.0)
    jog_up = change(40.0, None, 2000.0, 1500.0, 100.0)
    jog_down = change(140.0, None, 2000.0, 1500.0, 60.0)
    jog_down2 = change(140.0, None, 2000.0, 48000.0, 110.0)
    assert jog_down2.head == DOWN and jog_down2.sa == 2
    assert jog.head_index == 0 and jog.run_stop > 0 and jog_down.head == DOWN
    cases = [
        Case("jog, soft stop in ACCEL", jog, stop=soft_after(jog, 3)),
        Case("jog, soft stop in RUN", jog, stop=soft_after(jog, jog.sa + 10), direction=1),
        Case("jog, hard stop in RUN", jog, stop=Stop(HARD, normal_edge(jog, jog.sa + 5) + 7)),
        Case("jog from speed, soft stop in the head", jog_up, stop=soft_after(jog_up, 1)),
        Case("jog from speed, soft stop in RUN", jog_up, stop=soft_after(jog_up, jog_up.sa + 4)),
        Case("jog down, soft stop in the head", jog_down, stop=soft_after(jog_down, 3)),
        Case("jog down, soft stop in RUN", jog_down, stop=soft_after(jog_down, jog_down.sa + 3)),
        Case("jog down, sa = 2, soft stop at pulse 1", jog_down2, stop=soft_after(jog_down2, 0)),
    ]
    play("endless", cases)


def test_engine_segment_errors() -> None:
    """The parameter check of a segment (docs/stepramp_engine.md, "Error codes"): SEGMENT for a down head that ends
    after its rest (K < sa) or an up head whose index passes 2^31 - 1, and an endless move's cruise and c_last
    checked as used; nothing moves."""
    down = change(140.0, 260, 2000.0, 1500.0, 60.0)
    up = change(40.0, 60, 2000.0, 1500.0, 100.0)
    jog = change(0.0, None, 2000.0, 1500.0, 100.0)
    rep = dataclasses.replace
    cases = [
        Case("down K < sa", rep(down, head_index=down.sa - 1), code=ERR["SEGMENT"]),
        Case("up n0 + sa - 1 > 2^31 - 1", rep(up, head_index=2**31 - up.sa + 1), code=ERR["SEGMENT"]),
        Case("endless, cruise 0", rep(jog, cruise=0), code=ERR["CRUISE"]),
        Case("endless, c_last 0", rep(jog, c_last=0), code=ERR["C_LAST"]),
        Case("up n0 + sa - 1 = 2^31 - 1 passes", rep(up, head_index=2**31 - up.sa), stop=Stop(HARD, 3000)),
    ]
    play("errors", cases)
