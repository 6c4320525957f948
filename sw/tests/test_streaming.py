# SPDX-License-Identifier: MIT
"""Long moves in bounded memory (docs/algorithm.md, "Long moves"): the lazy model, the streamed JSON, the summary.

Expected values come from the spec's literal per-interval loop (copied below, independent of the model's run-length
code), plain Python lists and sums, the list functions as they were, and hashlib; never from the lazy code itself.
The memory test runs the command line in a subprocess under an address-space limit of the memory budget.
"""

from __future__ import annotations

import bisect
import hashlib
import itertools
import json
import math
import os
import resource
import subprocess
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from stepramp.board.plan import Plan, plan_move
from stepramp.models import engine as model
from stepramp.models.ideal import c0, ideal_move, pulse_times
from stepramp.sim.profiles import PROFILES, Profile
from stepramp.tools.cli import MEMORY_BUDGET_MB, PLOT_MAX_PULSES, SIM_MAX_PULSES, main
from stepramp.tools.summary import MoveSummary, edge_checksum, summarise_edges, summarise_model

DEMO = {"accel": 40.0, "decel": 40.0, "speed": 20.0, "spr": 400.0, "fclk": 1e6, "prescale": 1}
"""The AVR446 demo's settings at 1 MHz (the issue's long moves)."""

# ---------------------------------------------------------------------------------------------------------------
# Independent references
# ---------------------------------------------------------------------------------------------------------------


def spec_values(plan: Plan, indices: Iterable[int] | None = None) -> Iterator[int]:
    """The Q32.32 value of interval i for each i (ascending; default 1 .. L): docs/algorithm.md's rules literally,
    one interval at a time (the model's loop before run-length coding)."""
    length = plan.steps - 1
    sa, sd = plan.sa, plan.sd
    acc_n, acc_val, acc_r = 0, plan.accel_seed, 0
    dec_m: int | None = None
    dec_val, dec_r = plan.decel_seed, 0
    for i in range(1, length + 1) if indices is None else indices:
        if i == 1:
            value = plan.c_first << 16
        elif i == length:
            value = plan.c_last << 16
        elif i == sa:
            value = plan.c_sa << 16
        elif i == sd:
            value = plan.c_sd << 16
        elif i < sa:
            while acc_n < i - 1:
                acc_n += 1
                q, acc_r = divmod(2 * acc_val + acc_r, 4 * acc_n + 1)
                acc_val -= q
            value = acc_val << 16
        elif i > sd:
            if dec_m is None:
                dec_m = length - sd - 1
            while dec_m > length - i:
                q, dec_r = divmod(2 * dec_val + dec_r, 4 * dec_m - 1)
                dec_val += q
                dec_m -= 1
            value = dec_val << 16
        else:
            value = plan.cruise
        yield value


def ticks_of(values: Iterable[int]) -> list[int]:
    """T_k = floor(sum_{i <= k} v_i / 2^32), k = 0 .. (the spec's closed form of the accumulator)."""
    out, total = [0], 0
    for v in values:
        total += v
        out.append(total >> 32)
    return out


def spec_edges(plan: Plan) -> list[int]:
    if plan.steps == 0:
        return []
    return [2 + plan.prescale * t for t in ticks_of(spec_values(plan))]


def spec_last_edge(plan: Plan) -> int:
    """The last edge of a long move without its list: the sum of every interval value, the cruise ones counted."""
    length = plan.steps - 1
    cruise_from, cruise_to = plan.sa + 1, min(plan.sd, length) - 1  # rule 7 intervals (a trapezoid: sa >= 1)
    others = itertools.chain(range(1, cruise_from), range(cruise_to + 1, length + 1))
    total = sum(spec_values(plan, others)) + (cruise_to - cruise_from + 1) * plan.cruise
    return 2 + plan.prescale * (total >> 32)


def plain_checksum(edges: list[int]) -> str:
    return "sha256:" + hashlib.sha256(b"".join((e % 2**64).to_bytes(8, "little") for e in edges)).hexdigest()


def plain_summary(inputs: dict[str, Any], edges: list[int]) -> dict[str, Any]:
    """The figures of docs/algorithm.md's summary table from the whole list (the demo's computation, as it was)."""
    prescale = inputs["prescale"]
    f_tick = inputs["fclk"] / prescale
    ideal = ideal_move(**inputs)
    ticks = [(e - 2) / prescale for e in edges]
    deviation = [t - ti for t, ti in zip(ticks, pulse_times(**inputs), strict=True)]
    intervals = [b - a for a, b in itertools.pairwise(ticks)]
    c0_slow = c0(min(inputs["accel"], inputs["decel"]), inputs["spr"], inputs["fclk"], prescale)
    alpha = 2 * math.pi / inputs["spr"]
    worst = max(range(len(deviation)), key=lambda k: abs(deviation[k])) if deviation else 0
    return {
        "pulses": len(edges),
        "last_edge": edges[-1] if edges else None,
        "move_time_s": ticks[-1] / f_tick if ticks else 0.0,
        "ideal_move_time_s": ideal.t_end,
        "peak_speed_rad_s": alpha * f_tick / min(intervals) if intervals else 0.0,
        "ideal_peak_speed_rad_s": ideal.v_peak * alpha,
        "max_deviation_ticks": abs(deviation[worst]) if deviation else 0.0,
        "max_deviation_pulse": worst,
        "max_deviation_c0": abs(deviation[worst]) / c0_slow if deviation else 0.0,
        "c0_slow_ticks": c0_slow,
        "checksum": plain_checksum(edges),
    }


def hand_plan(**changes: int) -> Plan:
    """A plan the driver would not make (for the rules' corners): every value set by hand."""
    base = {
        "steps": 40,
        "direction": 0,
        "prescale": 3,
        "c_first": 900 << 16,
        "c_last": 800 << 16,
        "sa": 10,
        "c_sa": 300 << 16,
        "sd": 30,
        "c_sd": 310 << 16,
        "accel_seed": 700 << 16,
        "decel_seed": 600 << 16,
        "cruise": (250 << 32) + 0x9E3779B9,
        "stop_ratio": 3 << 15,
    }
    return Plan(**{**base, **changes})


HAND_PLANS = [
    hand_plan(),
    hand_plan(sa=1, sd=39),  # all cruise between the two exact ends
    hand_plan(sa=20, sd=20),  # no cruise
    hand_plan(sa=35, sd=5),  # sa > sd: rule 5 before rule 6, no cruise
    hand_plan(sa=0, sd=60),  # sd beyond L: cruise up to L - 1
    hand_plan(steps=2, sa=1, sd=1),
    hand_plan(steps=1, sa=0, sd=0),
    hand_plan(steps=0, sa=0, sd=0),
    hand_plan(prescale=0),  # every pulse at edge 2
    hand_plan(steps=500, sa=3, sd=497, cruise=1 << 31),  # a cruise of half a tick: every other interval is 0
]

# A move with a long cruise (the numpy path) and chunk boundaries everywhere; short enough for the list functions.
MEDIUM = plan_move(300_001, 900.0, 700.0, 40.0, 200.0, 1e6, 3)


def plans() -> list[tuple[str, Plan, dict[str, Any] | None]]:
    out: list[tuple[str, Plan, dict[str, Any] | None]] = [(p.name, plan_move(**p.args()), p.args()) for p in PROFILES]
    out += [(f"hand_{n}", p, None) for n, p in enumerate(HAND_PLANS)]
    return out


PLANS = plans()
CHUNKS = (1, 3, 64, 1000, model.CHUNK)

# ---------------------------------------------------------------------------------------------------------------
# The lazy model against the lists
# ---------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("name", "plan"), [(n, p) for n, p, _ in PLANS], ids=[n for n, _, _ in PLANS])
def test_runs_and_chunks_equal_the_spec_loop(name: str, plan: Plan) -> None:
    values = list(spec_values(plan))
    assert list(model.interval_values(plan)) == values
    runs = list(model.value_runs(plan))
    assert all(count >= 1 for _, count in runs)
    assert [v for v, count in runs for _ in range(count)] == values
    long_runs = [(v, count) for v, count in runs if count > 1]
    assert len(long_runs) <= 1 and all(v == plan.cruise for v, _ in long_runs)  # only the cruise is one run
    ticks = ticks_of(values) if plan.steps else []
    edges = spec_edges(plan)
    assert model.tick_times(plan) == ticks  # the list functions are unchanged
    assert model.edges(plan) == edges
    for chunk in CHUNKS:
        parts = list(model.tick_chunks(plan, chunk=chunk))
        assert all(0 < len(part) <= chunk and part.dtype == np.uint64 for part in parts)
        assert [t for part in parts for t in part.tolist()] == ticks, chunk
        edge_parts = list(model.edge_chunks(plan, chunk=chunk))
        assert all(isinstance(e, int) for part in edge_parts for e in part)
        assert [e for part in edge_parts for e in part] == edges, chunk
    assert list(model.iter_edges(plan)) == edges
    assert model.last_edge(plan) == (edges[-1] if edges else None)


def test_the_numpy_path_is_exercised() -> None:
    """The profiles' cruise runs go through numpy, and a 300,000-step move across many chunk boundaries."""
    vectorised = [name for name, plan, _ in PLANS if any(c >= 64 for _, c in model.value_runs(plan))]
    assert len(vectorised) >= 20, vectorised
    edges = spec_edges(MEDIUM)
    assert edges == model.edges(MEDIUM)
    for chunk in (1000, 4099, model.CHUNK):
        assert list(itertools.chain.from_iterable(model.edge_chunks(MEDIUM, chunk=chunk))) == edges
    assert model.last_edge(MEDIUM) == edges[-1] == spec_last_edge(MEDIUM)
    with pytest.raises(ValueError, match="chunk"):
        next(model.tick_chunks(MEDIUM, chunk=0))


def test_edges_beyond_64_bits() -> None:
    """Edges up to 2^79 are valid register contents: exact Python ints, and the checksum takes them mod 2^64."""
    top = (1 << 48) - 1
    plan = hand_plan(
        steps=70_000, prescale=65535, sa=1, sd=69_999, c_first=top, c_last=top, c_sa=top, c_sd=top, cruise=2**64 - 1
    )
    edges = spec_edges(plan)
    assert edges[-1] >= 2**64 > edges[0]
    assert list(itertools.chain.from_iterable(model.edge_chunks(plan, chunk=5000))) == edges
    assert model.last_edge(plan) == edges[-1]
    inputs = {"steps": 70_000, **DEMO, "prescale": 65535}  # only the checksum, count and last edge are checked here
    summary = MoveSummary(inputs)
    for ticks in model.tick_chunks(plan, chunk=5000):
        summary.add_ticks(ticks)
    assert summary.checksum() == plain_checksum(edges) == edge_checksum(edges)
    assert (summary.pulses, summary.last_edge) == (70_000, edges[-1])
    assert summarise_edges(inputs, edges)["checksum"] == plain_checksum(edges)


def stop_requests(edges: list[int], plan: Plan) -> list[int]:
    """Request edges around every place a stop changes its meaning: the start, pulses, boundaries, the end."""
    if not edges:
        return [-1, 0, 1, 2, 3]
    near = {0, 1, 2, 3, len(edges) // 3, len(edges) // 2, len(edges) - 2, len(edges) - 1}
    near |= {k for b in (plan.sa, plan.sd) for k in (b - 2, b - 1, b, b + 1)}
    out = {-1, 0, 1}
    for k in near:
        edge = edges[min(max(k, 0), len(edges) - 1)]
        out |= {edge - 1, edge, edge + 1}
    out.add(edges[-1] + 10)
    return sorted(out)


@pytest.mark.parametrize(("name", "plan"), [(n, p) for n, p, _ in PLANS], ids=[n for n, _, _ in PLANS])
def test_stops_lazy_equal_the_lists(name: str, plan: Plan) -> None:
    normal = spec_edges(plan)
    for request in stop_requests(normal, plan):
        busy = request >= 1 and normal and request < normal[-1]
        # decided one pulse after q, the first pulse after the request; ignored when q is the last pulse
        q = bisect.bisect_right(normal, request)
        assert model.soft_stop_pulse(plan, request) == (q + 1 if busy and q + 1 < len(normal) else None)
        for kind in (model.SOFT, model.HARD):
            expected = model.edges_with_stop(plan, kind, request)
            stop = (kind, request)
            assert list(itertools.chain.from_iterable(model.edge_chunks(plan, chunk=7, stop=stop))) == expected
            assert list(model.iter_edges(plan, stop=stop)) == expected
            assert model.last_edge(plan, stop=stop) == (expected[-1] if expected else None)
            pulses, runs = model.move_runs(plan, stop)
            assert pulses == len(expected)
            assert sum(count for _, count in runs) == max(pulses - 1, 0)
    with pytest.raises(ValueError, match="kind"):
        model.last_edge(plan, stop=("gentle", 5))


def test_long_stops_without_lists() -> None:
    """A soft stop in the cruise of a 2^31 - 1 step move: decided, ended and budgeted in closed form."""
    plan = plan_move(2**31 - 1, **DEMO)
    cruise_edge = 10**12
    p = model.soft_stop_pulse(plan, cruise_edge)
    assert p is not None and plan.sa <= p < plan.sd
    m = model.soft_stop_length(plan, p)
    assert m == plan.steps - 1 - plan.sd + 1  # in RUN: the plan's own decel ramp
    assert m is not None
    last = model.last_edge(plan, stop=("soft", cruise_edge))
    assert last is not None and cruise_edge < last < cruise_edge + 10**8
    assert model.last_edge(plan, stop=("hard", cruise_edge)) is not None
    hard = list(itertools.islice(model.edge_chunks(plan, stop=("hard", 50_000_000)), 3))
    assert hard[-1][-1] < 50_000_000


def test_bench_budgets_without_lists() -> None:
    """enginesim.timeout_cycles from the closed form is the list-based budget it was, stops included."""
    from stepramp.sim.engine_sim import Stop, timeout_cycles

    for _, plan, _ in PLANS[::3]:
        normal = spec_edges(plan)
        requests = stop_requests(normal, plan)[::2]
        stops = [Stop(kind, r) for r in requests if r >= 0 for kind in ("soft", "hard")]
        last = max([0, *normal[-1:]])
        slack = 2000 + 4 * plan.prescale
        assert timeout_cycles(plan) == last + slack
        ends = [max([last, s.at_cycle, *model.edges_with_stop(plan, s.kind, s.at_cycle)]) for s in stops]
        for stop, end in zip(stops, ends, strict=True):
            assert timeout_cycles(plan, stop) == end + slack
        assert timeout_cycles(plan, stops) == max([last, *ends]) + slack
    long = plan_move(2**31 - 1, **DEMO)
    assert timeout_cycles(long, Stop("soft", 10**12)) == spec_last_edge(long) + 2000 + 4


# ---------------------------------------------------------------------------------------------------------------
# The ideal in chunks and the summary
# ---------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("profile", PROFILES, ids=[p.name for p in PROFILES])
def test_ideal_time_chunk_is_bit_identical(profile: Profile) -> None:
    move = ideal_move(**profile.args())
    times = move.pulse_times()
    for size in (1, 7, 1000):
        got = [t for k in range(0, len(times), size) for t in move.time_chunk(k, min(k + size, len(times))).tolist()]
        assert got == times, size
    assert move.time_chunk(3, 3).tolist() == []


@pytest.mark.parametrize("profile", PROFILES, ids=[p.name for p in PROFILES])
def test_summary_equals_the_plain_computation(profile: Profile) -> None:
    inputs = profile.args()
    plan = plan_move(**inputs)
    edges = spec_edges(plan)
    expected = plain_summary(inputs, edges)
    assert summarise_model(inputs, plan) == expected
    assert summarise_edges(inputs, edges) == expected  # the sim path: from the RTL's list
    summary = MoveSummary(inputs)
    for ticks in model.tick_chunks(plan, chunk=7):
        summary.add_ticks(ticks)
    assert summary.result() == expected


def test_summary_of_a_medium_move() -> None:
    inputs = {"steps": 300_001, "accel": 900.0, "decel": 700.0, "speed": 40.0, "spr": 200.0, "fclk": 1e6}
    inputs["prescale"] = 3
    assert summarise_model(inputs, MEDIUM) == plain_summary(inputs, spec_edges(MEDIUM))


def test_summary_of_edges_out_of_order() -> None:
    """An RTL that emitted two pulses at one edge: no peak speed, rather than a division by zero."""
    inputs = {"steps": 3, **DEMO}
    got = summarise_edges(inputs, [2, 5000, 5000])
    assert got["peak_speed_rad_s"] is None
    assert got["pulses"] == 3
    assert got["checksum"] == plain_checksum([2, 5000, 5000])


# ---------------------------------------------------------------------------------------------------------------
# The command line
# ---------------------------------------------------------------------------------------------------------------

CLI_MOVES = [
    ["--steps", "-150", "--accel", "900", "--decel", "700", "--speed", "40", "--spr", "200", "--fclk", "1e6"],
    ["--steps", "400", "--accel", "40", "--decel", "40", "--speed", "20", "--spr", "400", "--fclk", "250e3"],
    ["--steps", "40", "--accel", "50", "--decel", "80", "--speed", "5", "--spr", "400", "--fclk", "2e6"],
    ["--steps", "2", "--accel", "500", "--decel", "300", "--speed", "20", "--spr", "200", "--fclk", "1e6"],
    ["--steps", "1", "--accel", "500", "--decel", "300", "--speed", "20", "--spr", "200", "--fclk", "1e6"],
    ["--steps", "0", "--accel", "500", "--decel", "300", "--speed", "20", "--spr", "200", "--fclk", "1e6"],
    ["--steps", "-300001", "--accel", "900", "--decel", "700", "--speed", "40", "--spr", "200", "--fclk", "1e6"],
]


def cli_inputs(argv: list[str], prescale: int = 1) -> dict[str, Any]:
    opts = dict(zip(argv[::2], argv[1::2], strict=True))
    inputs: dict[str, Any] = {"steps": int(opts["--steps"])}
    inputs |= {k: float(opts[f"--{k}"]) for k in ("accel", "decel", "speed", "spr", "fclk")}
    return {**inputs, "prescale": prescale}


@pytest.mark.parametrize("prescale", [1, 3])
@pytest.mark.parametrize("argv", CLI_MOVES, ids=[m[1] for m in CLI_MOVES])
def test_streamed_json_is_the_old_text(
    argv: list[str], prescale: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Byte for byte json.dumps of the whole object, as the command line printed it before it streamed."""
    inputs = cli_inputs(argv, prescale)
    plan = plan_move(**inputs)
    old = {
        "tool": "model",
        "inputs": inputs,
        "registers": plan.to_dict(),
        "edges": spec_edges(plan),
        "final_position": inputs["steps"],
        "error": None,
    }
    expected = json.dumps(old, indent=None) + "\n"
    args = ["model", *argv, "--prescale", str(prescale)]
    assert main(args) == 0
    assert capsys.readouterr().out == expected
    out = tmp_path / "sub" / "move.json"
    assert main([*args, "--json", str(out)]) == 0
    assert capsys.readouterr().out == ""
    assert out.read_text() == expected
    assert main([*args, "--summary"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert list(got) == ["tool", "inputs", "registers", "summary", "final_position", "error"]
    assert got["summary"] == plain_summary(inputs, old["edges"])
    assert {k: v for k, v in got.items() if k != "summary"} == {k: v for k, v in old.items() if k != "edges"}


def test_invalid_input_with_summary(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["model", *CLI_MOVES[0][:-2], "--fclk", "-1", "--summary"]) == 2
    captured = capsys.readouterr()
    got = json.loads(captured.out)
    assert got["summary"] is None and got["registers"] is None
    assert "fclk must be finite and > 0" in got["error"]
    assert "fclk must be finite and > 0" in captured.err


def test_sim_refuses_a_move_over_its_memory_budget(capsys: pytest.CaptureFixture[str]) -> None:
    """Refused before anything is simulated (no simulator needed here), with status 2 and the reason."""
    steps = SIM_MAX_PULSES + 1
    argv = ["sim", "--steps", str(-steps), *CLI_MOVES[0][2:]]
    for extra in ([], ["--summary"]):
        assert main([*argv, *extra]) == 2
        captured = capsys.readouterr()
        got = json.loads(captured.out)
        assert got["tool"] == "sim"
        assert f"{steps} pulses are more than its {SIM_MAX_PULSES}" in got["error"]
        assert got["registers"]["steps"] == steps
        assert "Traceback" not in captured.err


def test_plot_refuses_what_it_cannot_draw(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    summary = tmp_path / "summary.json"
    assert main(["model", *CLI_MOVES[0], "--summary", "--json", str(summary)]) == 0
    assert main(["plot", str(summary)]) == 2
    assert "holds no edges" in capsys.readouterr().err
    long = tmp_path / "long.json"
    assert main(["model", *CLI_MOVES[0], "--json", str(long)]) == 0
    move = json.loads(long.read_text())
    move["inputs"]["steps"] = PLOT_MAX_PULSES + 1
    long.write_text(json.dumps(move))
    assert main(["plot", str(long)]) == 2
    assert f"more than the {PLOT_MAX_PULSES} a plot draws" in capsys.readouterr().err
    assert not long.with_suffix(".png").exists()


def _env() -> dict[str, str]:
    """One thread for numpy's BLAS (else its import reserves hundreds of MB of address space per core)."""
    threads = {k: "1" for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS")}
    return {**os.environ, **threads}


def test_a_closed_pipe_is_no_traceback() -> None:
    """`stepramp model ... | head`: the reader goes away; the command stops quietly."""
    argv = ["--steps", "3000000", *[f"--{k}={v}" for k, v in DEMO.items()]]
    cmd = [sys.executable, "-c", "import sys; from stepramp.tools.cli import main; sys.exit(main())", "model", *argv]
    with subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env()) as proc:
        assert proc.stdout is not None and proc.stderr is not None
        head = proc.stdout.read(100)
        proc.stdout.close()
        err = proc.stderr.read().decode()
        assert proc.wait(timeout=60) == 1
    assert head.startswith(b'{"tool": "model"')
    assert err == ""


# ---------------------------------------------------------------------------------------------------------------
# Long moves under a memory limit
# ---------------------------------------------------------------------------------------------------------------

LIMIT = MEMORY_BUDGET_MB << 20
"""RLIMIT_AS of the child: the whole address space (Python, numpy, the chunks) within the memory budget."""

_RUN = "import sys; from stepramp.tools.cli import main; sys.exit(main())"
_LIST = (
    "import sys, json; from stepramp.models import engine as model; from stepramp.board import plan;"
    " model.edges(plan.plan_move(**json.loads(sys.argv[1])))"
)


def _limited() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT, LIMIT))


def run_limited(code: str, *args: str, stdout: int | None = subprocess.PIPE) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [sys.executable, "-c", code, *args],
        stdout=stdout,
        stderr=subprocess.PIPE,
        env=_env(),
        preexec_fn=_limited,
    )


def test_long_moves_under_a_memory_limit() -> None:
    """200,000,000 steps summarised and 10,000,000 streamed as JSON under an address-space limit of the budget;
    the list version of the shorter move hits the same limit (so the limit bites)."""
    demo = [f"--{k}={v}" for k, v in DEMO.items()]
    long_steps, json_steps = 200_000_000, 10_000_000

    with run_limited(_RUN, "model", f"--steps={long_steps}", *demo, "--summary") as proc:
        out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err.decode()[-2000:]
    got = json.loads(out)
    plan = plan_move(long_steps, **DEMO)
    assert got["registers"] == plan.to_dict()
    assert got["summary"]["pulses"] == long_steps == got["final_position"]
    assert got["summary"]["last_edge"] == spec_last_edge(plan)
    assert got["summary"]["max_deviation_c0"] < 0.008
    assert got["summary"]["checksum"].startswith("sha256:")

    json_plan = plan_move(json_steps, **DEMO)
    head = [str(e).encode() for e in spec_edges_head(json_plan, 1000)]
    with run_limited(_RUN, "model", f"--steps={json_steps}", *demo) as proc:
        assert proc.stdout is not None and proc.stderr is not None
        text = proc.stdout.read(1 << 16)
        start = text.index(b'"edges": [') + len(b'"edges": [')
        assert text[start:].split(b", ")[:1000] == head
        commas, tail = text[start:].count(b","), text[-100:]
        while block := proc.stdout.read(1 << 20):
            commas += block.count(b",")
            tail = (tail + block)[-100:]
        err = proc.stderr.read()
    assert proc.returncode == 0, err.decode()[-2000:]
    edges_text, after = tail.rsplit(b"]", 1)
    assert edges_text.rsplit(b", ", 1)[-1] == str(spec_last_edge(json_plan)).encode()
    assert after == b', "final_position": 10000000, "error": null}\n'
    assert commas - after.count(b",") == json_steps - 1  # the separators of the edges array

    with run_limited(_LIST, json.dumps({"steps": json_steps, **DEMO}), stdout=subprocess.DEVNULL) as proc:
        _, err = proc.communicate(timeout=120)
    assert proc.returncode != 0 and b"MemoryError" in err, "the list version fits the limit: it proves nothing"


def spec_edges_head(plan: Plan, count: int) -> list[int]:
    values = itertools.islice(spec_values(plan), count - 1)
    return [2 + plan.prescale * t for t in ticks_of(values)]
