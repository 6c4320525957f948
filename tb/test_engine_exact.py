# SPDX-License-Identifier: MIT
"""stepramp_engine with G_RAMP = 1 (the exact ramp, docs/algorithm.md "Exact step times") alone, against the model.

* test_exact_latency_budget: the latency budget of docs/stepramp_engine.md, "Latency budget in exact mode", at its
  edges (PRESCALE 1, hand-made plans): a ramp value one clock later than the budget ends the move with LATE at the
  pulse that needed it (that pulse emitted), the budget itself runs as the model says. The thresholds come from the
  page's formulas and the unit's documented latencies (stepramp.models.exact_unit), the edges from the model. The
  worst case of the page, a soft stop decided in ACCEL whose normal value and alternative are both fresh requests
  with the largest constants and indices, is one of them: it measures the shortest interval the exact mode
  sustains at PRESCALE 1.
* test_exact_engine_segments: segments from START in exact mode (an up head from n0 > 0, a down head, an endless
  jog) with soft stops in the head and in the cruise (the run stop's c_sd), and a move whose soft stop comes at the
  ACCEL / RUN junction: every edge as segment_edges / edges_with_stop say; slow ramps (ramp constants of 2^48 or
  more, seed words of scale 0, 3 and 6: c0 of 2^22, 2^28 and 2^31 ticks) taken at large head indices, where their
  intervals are a few hundred to 23,000 clocks: an up head with a soft stop, a down head. The parameter check: ramp
  constants below 2^16 (c0 under 16 ticks) run, a ramp constant of 0, a mantissa of 0 at scale 3 and a scale of 7
  are refused with ACCEL_SEED / DECEL_SEED (no pulse).
"""

from __future__ import annotations

from stepramp.board.change import DOWN, UP, Segment
from stepramp.board.plan import RAMP_EXACT, Plan, plan_move
from stepramp.board.regmap import ERROR_CODES
from stepramp.models import exact
from stepramp.models.engine import HALF, accumulate, edges_with_stop, segment_edges
from stepramp.models.engine import edges as model_edges
from stepramp.models.exact_unit import FRESH_WORST, FRESH_WORST_NARROW, fresh_latency
from stepramp.sim.engine_sim import Stop, simulate
from stepramp.sim.profiles import EXACT_PROFILES
from tbutil import build_dir
from test_engine import move_problems

ERR = {name: code for name, (code, _) in ERROR_CODES.items()}
Q16 = 1 << 16
C_NARROW_MAX = (1 << 48) - 1
"""The largest constant below 2^48 (a seed word of scale 0)."""
C_MAX = exact.seed_word(exact.C_MAX >> 12, exact.SCALE_MAX)
"""The largest constant the driver writes, 2^72 - 2^36 (a seed word of scale 6)."""

#: docs/stepramp_engine.md, "Latency budget in exact mode": a value the unit answers `lat` edges after the edge
#: that samples its request is ready for a pulse at E + NORMAL + lat (E the pulse edge that starts the interval
#: before it); the soft-stop alternative of an ACCEL interval at E + ALT + lat_normal + lat_alt.
NORMAL = 6
ALT = 9
#: The value-independent worst case: both requests fresh at C = 2^72 - 2^36 and an index near 2^31; with constants
#: below 2^48 (FRESH_WORST_NARROW) the driver's shorter limit.
WORST = ALT + 2 * FRESH_WORST
WORST_NARROW = ALT + 2 * FRESH_WORST_NARROW


def _segment(length: int, head: str, n0: int, c_first_ticks: int, **regs: int) -> tuple[Plan, dict[str, int], Segment]:
    seg = Segment(
        length=length,
        head=head,
        head_index=n0,
        prescale=1,
        sa=regs.pop("sa", length),
        sd=regs.pop("sd", length),
        c_first=c_first_ticks * Q16,
        c_sa=regs.pop("c_sa", 100 * Q16),
        c_sd=regs.pop("c_sd", 100 * Q16),
        c_last=regs.pop("c_last", 100 * Q16),
        accel_seed=regs.pop("accel_seed", C_MAX),
        decel_seed=regs.pop("decel_seed", C_MAX),
        cruise=regs.pop("cruise", 100 << 32),
        stop_ratio=regs.pop("stop_ratio", 0),
        ramp=RAMP_EXACT,
    )
    assert not regs, regs
    plan, fields = seg.registers(direction=0)
    return plan, fields, seg


def budget_cases() -> list[tuple[str, Plan, dict[str, int], list[Stop], list[int], int]]:
    """(label, plan, segment fields, stops, expected edges, error code) on both sides of each threshold."""
    cases = []

    # 1. The first value of a move's accel ramp (interval 2: index 1, a fresh request sampled at the edge after pulse
    # 0's) is ready for a pulse at E + NORMAL + lat: interval 1 of c1 clocks must reach that. A hard stop after
    # pulse 2 ends the move that is in time.
    for c_acc in (1 << 20, 1 << 47, C_NARROW_MAX, C_MAX):
        need = NORMAL + fresh_latency(exact.constant_of(c_acc), 1)
        for c1 in (need - 1, need):
            plan, fields, _ = _segment(1000, UP, 0, c1, sa=900, sd=950, accel_seed=c_acc)
            values = [plan.c_first << 16, exact.value(c_acc, 1) << 16]
            edges = [2 + t for t in accumulate(values, HALF)]
            if c1 < need:
                cases.append(
                    (f"first accel value, C = {c_acc:#x}: {c1} clocks", plan, fields, [], edges[:2], ERR["LATE"])
                )
            elif exact.narrow(c_acc):
                hard = Stop("hard", edges[2] + 1)
                cases.append((f"first accel value, C = {c_acc:#x}: {c1} clocks", plan, fields, [hard], edges, 0))
            else:
                # the value itself is 0.41 c0 ticks (1.8e9 at C = 2^72 - 2^36): a hard stop right after pulse 1,
                # which would have ended the move with LATE had the value not been ready
                hard = Stop("hard", edges[1] + 1)
                cases.append((f"first accel value, C = {c_acc:#x}: {c1} clocks", plan, fields, [hard], edges[:2], 0))

    # 2. A soft stop decided at pulse 1 of an up head (sampled at edge 2): the normal value of interval 2 (index n0 + 1)
    # and then the alternative (index m - 1, m = floor((n0 + 1) stop_ratio / 2^16)), both fresh requests, ready at
    # E + ALT + lat_normal + lat_alt. In time, the stop runs (a hard stop after its second value ends the move).
    corners = (
        (1 << 20, 1 << 16, 1 << 30, 1 << 30),  # small indices
        # the worst case below 2^48: both near 2^31 at C = 2^48 - 1
        ((1 << 31) - (1 << 10), (1 << 16) - 1, C_NARROW_MAX, C_NARROW_MAX),
        ((1 << 31) - (1 << 10), (1 << 16) - 1, C_MAX, C_MAX),  # the worst case: at C = 2^72 - 2^36
    )
    for n0, ratio, c_acc, c_dec in corners:
        m = (n0 + 1) * ratio >> 16
        need = ALT + fresh_latency(exact.constant_of(c_acc), n0 + 1) + fresh_latency(exact.constant_of(c_dec), m - 1)
        for c1 in (need - 1, need):
            length = (1 << 31) - 2  # STEPS = length + 1 <= 2^31 - 1
            plan, fields, _ = _segment(
                length, UP, n0, c1, sa=3, sd=length - 5, stop_ratio=ratio, accel_seed=c_acc, decel_seed=c_dec
            )
            values = [plan.c_first << 16, exact.value(c_dec, m - 1) << 16, exact.value(c_dec, m - 2) << 16]
            edges = [2 + t for t in accumulate(values, HALF)]
            label = f"ACCEL alternative, n0 = {n0:#x}, m = {m:#x}: {c1} clocks (need {need})"
            soft = Stop("soft", 1)  # before pulse 0: decided at pulse 1
            if c1 < need:
                cases.append((label, plan, fields, [soft], edges[:2], ERR["LATE"]))
            else:
                # In time, pulse 2 ends the alternative's interval. The stop's next value is a fresh request far
                # longer than these hand-made intervals (11 ticks at the worst case; the driver's limit keeps
                # every interval at 256 clocks or more): the move then ends with LATE at pulse 2, a pulse later.
                if exact.narrow(c_dec):
                    cases.append((label, plan, fields, [soft], edges[:3], ERR["LATE"]))
                else:
                    # at C = 2^72 - 2^36 the stop's values are 46,000 ticks: the next one is in time, and a hard
                    # stop after pulse 2 ends the move (the stop would run 2^31 steps)
                    hard = Stop("hard", edges[2] + 1)
                    cases.append((label, plan, fields, [soft, hard], edges[:3], 0))
    return cases


def test_exact_latency_budget() -> None:
    cases = budget_cases()
    needs = [_need(label) for label, *_ in cases]
    assert WORST in needs and WORST_NARROW in needs, "the worst cases are not among them"
    assert (WORST, WORST_NARROW) == (299, 251)
    results = simulate(
        [c[1] for c in cases],
        build_dir("engine_exact_budget"),
        stops=[c[3] or None for c in cases],
        extras=[{"segment": c[2], "min_gap": 1} for c in cases],  # hand-made values as short as 1 tick
        budgets=[c[4][-1] + 3000 for c in cases],  # the model's last edge of a 2^31-step segment is not computed
    )
    assert len(results) == len(cases), f"only {len(results)} of {len(cases)} moves finished"
    problems: list[str] = []
    for (label, _, _, _, expected, code), res in zip(cases, results, strict=True):
        problems += [f"{label}: {p}" for p in move_problems(res, expected, code=code)]
    assert not problems, "\n".join(problems)
    print(
        f"exact mode: the worst case needs an interval of {WORST} clocks at PRESCALE 1 (late at {WORST - 1}), "
        f"{WORST_NARROW} with constants below 2^48"
    )


def _need(label: str) -> int | None:
    return int(label.split("need ")[1].rstrip(")")) if "need " in label else None


def test_exact_engine_segments() -> None:
    """Segments from START and moves with soft stops, exact mode, edge for edge as the model says."""
    runs: list[tuple[str, Plan, dict[str, int], Stop | None, list[int]]] = []
    f_tick, a, d = 1e6, 20_000.0 * 200 / 6.283185307179586, 15_000.0 * 200 / 6.283185307179586
    c_acc = exact.ramp_constant(f_tick * (2.0 / a) ** 0.5)
    c_dec = exact.ramp_constant(f_tick * (2.0 / d) ** 0.5)
    ups = _segment(120, UP, 30, 400, sa=60, sd=90, accel_seed=c_acc, decel_seed=c_dec, cruise=300 << 32)
    downs = _segment(150, DOWN, 140, 300, sa=40, sd=120, accel_seed=c_dec, decel_seed=c_dec, cruise=500 << 32)
    # sa = 2: interval 2 is c_sa, so a stop decided at pulse 1 takes the head's own interval 2
    down2 = _segment(150, DOWN, 140, 300, sa=2, sd=120, accel_seed=c_dec, decel_seed=c_dec, cruise=500 << 32)
    pulse0 = segment_edges(down2[2], 1, count=1)[0]
    jog = Segment(
        length=None,
        head=UP,
        head_index=0,
        prescale=1,
        sa=50,
        sd=0,
        c_first=2000 * Q16,
        c_sa=400 * Q16,
        c_sd=420 * Q16,
        c_last=2500 * Q16,
        accel_seed=c_acc,
        decel_seed=c_dec,
        cruise=400 << 32,
        stop_ratio=90_000,
        run_stop=40,
        ramp=RAMP_EXACT,
    )
    for label, (plan, fields, seg), stop in (
        ("up head from n0 = 30", ups, None),
        ("up head, soft stop in the head", ups, Stop("soft", 8_000)),
        ("up head, soft stop in the cruise", ups, Stop("soft", 25_000)),
        ("down head", downs, None),
        ("down head, soft stop in the head", downs, Stop("soft", 4_000)),
        ("down head with sa = 2, soft stop at pulse 1", down2, Stop("soft", pulse0 - 1)),
    ):
        want = segment_edges(seg, 1, stop=None if stop is None else (stop.kind, stop.at_cycle))
        runs.append((label, plan, fields, stop, want))
    jog_plan, jog_fields = jog.registers(direction=1)
    for at in (15_000, 60_000):
        runs.append(
            (
                f"jog, soft stop at {at}",
                jog_plan,
                jog_fields,
                Stop("soft", at),
                segment_edges(jog, 1, stop=("soft", at)),
            )
        )
    # slow ramps: wide constants at large head indices, where their intervals are short enough to simulate; a hard
    # stop after pulse 40 (12 at c0 = 2^31: 23,000 ticks a step) ends each (the rest of such a segment, its decel to
    # rest, takes about c0 ticks and more)
    slow = (
        # (label, head, c0 in ticks, head index, cruise ticks)
        ("scale 0, c0 = 2^22: up head from 2^26", UP, 2.0**22, 1 << 26, 250),
        ("scale 3, c0 = 2^28: down head from 2^30", DOWN, 2.0**28, 1 << 30, 4000),
        ("scale 6, c0 = 2^31: up head from 2^31 - 2^13", UP, 2.0**31, (1 << 31) - (1 << 13), 20000),
    )
    for label, head, c0, n0, cruise in slow:
        seed = exact.ramp_constant(c0)
        assert exact.mantissa_scale(seed)[1] == int(label.split()[1].rstrip(","))
        assert exact.constant_of(seed) >= 1 << 48
        plan, fields, seg = _segment(
            5000,
            head,
            n0,
            cruise * 2,
            sa=2000,
            sd=4000,
            accel_seed=seed,
            decel_seed=seed,
            cruise=cruise << 32,
            c_sa=cruise * Q16,
            c_sd=cruise * Q16,
            c_last=cruise * 3 * Q16,
        )
        hard = ("hard", segment_edges(seg, 1)[12 if head == UP and c0 > 2**30 else 40] + 1)
        runs.append((label, plan, fields, Stop(*hard), segment_edges(seg, 1, stop=hard)))
    move = plan_move(**EXACT_PROFILES[0].args(), ramp=RAMP_EXACT)
    edges = model_edges(move)
    for pulse in (move.sa - 1, move.sa, move.sd - 1):  # decided one pulse after the first pulse after the sample
        runs.append(
            (
                f"move, soft stop at pulse {pulse + 1}",
                move,
                {},
                Stop("soft", edges[pulse - 1]),
                edges_with_stop(move, "soft", edges[pulse - 1]),
            )
        )
    # the parameter check in exact mode: a ramp constant below 2^16 (c0 under 16 ticks) is valid, 0 is not
    small = plan_move(**next(p for p in EXACT_PROFILES if p.name == "trap_prescale_1000_neg").args(), ramp=RAMP_EXACT)
    assert 0 < small.accel_seed < Q16 and 0 < small.decel_seed < Q16
    runs.append(("move with ramp constants below 2^16", small, {}, None, model_edges(small)))
    codes = [0] * len(runs)
    for name in ("accel_seed", "decel_seed"):
        for word in (0, exact.seed_word(0, 3), exact.seed_word(getattr(move, name), 7)):
            bad = Plan(**{**move.to_dict(), name: word, "ramp": RAMP_EXACT})
            runs.append((f"move with {name} {word:#x}", bad, {}, None, []))
            codes.append(ERR[name.upper()])
    results = simulate(
        [r[1] for r in runs],
        build_dir("engine_exact_segments"),
        stops=[r[3] for r in runs],
        extras=[{"segment": r[2]} for r in runs],
        budgets=[(r[4][-1] if r[4] else 0) + 3000 for r in runs],  # a segment's budget from its own edges
    )
    assert len(results) == len(runs)
    problems: list[str] = []
    for (label, *_, want), code, res in zip(runs, codes, results, strict=True):
        problems += [f"{label}: {p}" for p in move_problems(res, want, code=code)]
    assert not problems, "\n".join(problems)
