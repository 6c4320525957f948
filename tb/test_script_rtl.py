# SPDX-License-Identifier: MIT
"""Command scripts on the RTL through both bus tops, against the model (issue 15).

The driver's planner (stepramp.board.script.plan_script) turns a script into register writes and commits on the
script's clock axis and predicts every STEP edge and POSITION after it; stepramp.sim.script_sim plays the same
commits on stepramp_plb or stepramp_axil (each commit checked to land on its clock edge) and records what the RTL
does. Every edge and position must be equal, and the core must flag exactly the errors the model predicts (none
from a commit: the planner never commits what the core would refuse; LIMIT and ESTOP from the machine inputs,
issue 16), and no STEP edge may come more than 2 clocks after a filtered ESTOP edge.

* test_named_scripts: stepramp.sim.scripts.NAMED_SCRIPTS (speed up and slow down in RUN, a change in ACCEL and in
  DECEL, a retarget inside the stop distance and behind the motor, jog through zero, queued moves in the same and
  in the opposite direction, a soft and a hard stop during a jog), through each top;
* test_random_scripts: SCRIPT_COUNT (100) random scripts per chunk and top (stepramp.sim.scripts.random_script),
  two chunks per top: 200 scripts through each top.
  SCRIPT_SEED (printed; random unless set) seeds them: replay a failure with
  SCRIPT_SEED=<seed> .venv/bin/pytest tb/test_script_rtl.py -k random;
* test_cli_sim_and_model_agree: `stepramp sim --script` and `stepramp model --script` on two named scripts and two
  named multi-axis scripts (three_axes_limit_and_estop, coordinated_stop_on_the_line) print the same edges and
  positions (and refusals);
* test_multi_axis_scripts: scripts with "axis" on their commands on stepramp_multi_plb / _axil at 3 axes (the named
  three_axes_limit_and_estop, sync_soft_stop, coordinated_stop_on_the_line: coordinated moves by SYNC_START and a
  coordinated stop on the line by one CHANGE per axis, and MULTI_COUNT (10) random ones): every axis's edges and
  positions equal to the model's, its final error too, and no STEP edge of any axis more than 2 clocks after the
  filtered ESTOP edge.
"""

from __future__ import annotations

import json
import random
import sys
from pathlib import Path
from typing import Any

import pytest

from stepramp.board.multi_script import MultiResult, plan_multi_script
from stepramp.board.script import PREP_CLOCKS, ScriptResult, load_script, plan_script
from stepramp.models.inputs import filtered_edges
from stepramp.sim.multi_scripts import NAMED_MULTI_SCRIPTS, random_multi_script
from stepramp.sim.script_sim import simulate_multi, simulate_planned
from stepramp.sim.scripts import NAMED_SCRIPTS, random_script
from tbutil import build_dir, edges_differ, env_int

TOPS = ("plb", "axil")
CHUNKS = 2


def _check(name: str, planned: ScriptResult, rtl: dict[str, Any]) -> None:
    errors = [tuple(e) for e in rtl["core_errors"]]
    assert errors == planned.errors, f"{name}: the core flagged (edge, code) {errors}, the model {planned.errors}"
    assert not rtl["estop_violations"], f"{name}: {rtl['estop_violations']}"
    assert rtl["edges"] == planned.edges, f"{name}: STEP edges: {edges_differ(rtl['edges'], planned.edges)}"
    assert rtl["positions"] == planned.positions, f"{name}: positions differ from the model"


@pytest.mark.parametrize("top", TOPS)
def test_named_scripts(top: str) -> None:
    names = sorted(NAMED_SCRIPTS)
    planned = [plan_script(load_script(NAMED_SCRIPTS[n])) for n in names]
    for name, p in zip(names, planned, strict=True):
        assert p.edges, f"{name}: the script moves nothing"
    results = simulate_planned(planned, build_dir(f"script_named_{top}"), top)
    assert len(results) == len(planned)
    for name, p, r in zip(names, planned, results, strict=True):
        _check(name, p, r)


def _seed() -> int:
    seed = env_int("SCRIPT_SEED", random.SystemRandom().randrange(1 << 32))
    print(f"SCRIPT_SEED={seed}", file=sys.stderr)
    return seed


SEED = _seed()


@pytest.mark.parametrize("chunk", range(CHUNKS))
@pytest.mark.parametrize("top", TOPS)
def test_random_scripts(top: str, chunk: int) -> None:
    count = env_int("SCRIPT_COUNT", 100)
    print(f"SCRIPT_SEED={SEED} (replays this test)")  # shown with a failure, whatever fails
    rng = random.Random(f"{SEED}:{top}:{chunk}")
    scripts = [random_script(rng) for _ in range(count)]
    planned = [plan_script(load_script(s)) for s in scripts]
    # An input effect the model cannot time (within MARGIN of a START being taken, of a soft stop's decision): the
    # script is not played (about 1 in 40; printed).
    keep = [i for i, p in enumerate(planned) if not p.unsure]
    with_inputs = sum(1 for i in keep if planned[i].pins)
    print(f"{len(keep)} of {count} scripts played ({with_inputs} with inputs); not played: {count - len(keep)}")
    assert len(keep) >= 0.8 * count
    results = simulate_planned([planned[i] for i in keep], build_dir(f"script_random_{top}_{chunk}"), top)
    assert len(results) == len(keep)
    for i, r in zip(keep, results, strict=True):
        _check(f"SCRIPT_SEED={SEED} {top} chunk {chunk} script {i}: {json.dumps(scripts[i])}", planned[i], r)


def _cli_model_and_sim(tmp_path: Path, name: str, script: dict[str, Any], keys: tuple[str, ...]) -> dict[str, Any]:
    """`stepramp model` and `stepramp sim` of the script (each exits 0), their JSON outputs' keys the same; returns the
    model's output."""
    from stepramp.tools.cli import main

    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(script))
    out = {}
    for tool in ("model", "sim"):
        target = tmp_path / f"{name}_{tool}.json"
        extra = ["--build", str(build_dir(f"script_cli_{name}"))] if tool == "sim" else []
        assert main([tool, "--script", str(path), "--json", str(target), *extra]) == 0, f"{tool} {name}"
        out[tool] = json.loads(target.read_text())
    for key in keys:
        assert out["sim"][key] == out["model"][key], f"{name}: {key} of sim and model differ"
    return out["model"]


def test_cli_sim_and_model_agree(tmp_path: Path) -> None:
    for name in ("jog_through_zero", "retarget_behind"):
        model = _cli_model_and_sim(tmp_path, name, NAMED_SCRIPTS[name], ("edges", "positions"))
        assert model["edges"], f"{name}: no edges"
    # multi-axis scripts: one list of edges and positions per axis, and the same refusals and final errors (a limit
    # and ESTOP; a coordinated move stopped on the line)
    for name in ("three_axes_limit_and_estop", "coordinated_stop_on_the_line"):
        model = _cli_model_and_sim(tmp_path, name, NAMED_MULTI_SCRIPTS[name], ("edges", "positions", "rejected"))
        assert len(model["edges"]) == 3 and all(model["edges"])
        reasons = {r["reason"] for r in model["rejected"]}
        assert reasons == ({"the core flagged ESTOP"} if name.startswith("three") else set()), f"{name}: {reasons}"


# ---------------------------------------------------------------------------------------------------------------
# The multi-axis top (issue 16: "axis" on any command; stepramp.board.multi_script)
# ---------------------------------------------------------------------------------------------------------------

MULTI_COUNT = 10


def _check_multi(name: str, planned: MultiResult, rtl: dict[str, Any]) -> None:
    """Every axis's edges and positions as the model's, STATUS's error at the end as the model's last, and no STEP
    edge of any axis more than 2 clocks after the filtered ESTOP edge (the rule of docs/algorithm.md, from the pin's
    changes and the filter alone) until the first fault clear is prepared."""
    n = planned.results[0].input_filter
    clears = sorted(a.at - PREP_CLOCKS for r in planned.results for a in r.actions if a.ctrl == 0 and a.writes)
    for f, level in filtered_edges(planned.estop, n):
        if level:
            until = next((c for c in clears if c > f), planned.until)
            late = [(axis, e) for axis, edges in enumerate(rtl["edges"]) for e in edges if f + 2 < e <= until]
            assert not late, f"{name}: STEP edges (axis, edge) after the ESTOP edge {f}: {late[:5]}"
    for axis, (p, edges, positions, status) in enumerate(
        zip(planned.results, rtl["edges"], rtl["positions"], rtl["status"], strict=True)
    ):
        what = f"{name}, axis {axis}"
        assert edges == p.edges, f"{what}: STEP edges: {edges_differ(edges, p.edges)}"
        assert positions == p.positions, f"{what}: positions differ from the model"
        want = (1, p.errors[-1][1]) if p.errors else (0, 0)
        got = (status >> 5 & 1, status >> 8 & 0x1F if status >> 5 & 1 else 0)
        assert got == want, f"{what}: STATUS (ERROR, ERR_CODE) {got}, the model {want}"


@pytest.mark.parametrize("top", TOPS)
def test_multi_axis_scripts(top: str) -> None:
    """The named three-axis scripts (a limit on one axis, ESTOP on all; a SYNC_SOFT_STOP; coordinated moves and a
    coordinated stop on the line) and MULTI_COUNT random three-axis scripts (a short random script per axis,
    staggered; SCRIPT_SEED) on the multi-axis top of each bus."""
    print(f"SCRIPT_SEED={SEED} (replays this test)")
    rng = random.Random(f"{SEED}:multi:{top}")
    scripts = dict(NAMED_MULTI_SCRIPTS)
    while len(scripts) < len(NAMED_MULTI_SCRIPTS) + env_int("MULTI_COUNT", MULTI_COUNT):
        s = random_multi_script(rng)
        p = plan_multi_script(s)
        if not p.conflicts and not p.unsure:
            scripts[f"random {len(scripts)}: {json.dumps(s)}"] = s
    planned = {name: plan_multi_script(s) for name, s in scripts.items()}
    for name in NAMED_MULTI_SCRIPTS:
        named = planned[name]
        assert not named.conflicts and not named.unsure and all(r.edges for r in named.results), name
    line = planned["coordinated_stop_on_the_line"]
    assert line.sync_starts and [s.fallback for s in line.line_stops] == [None], "not a coordinated stop on the line"
    results = simulate_multi(list(planned.values()), build_dir(f"script_multi_{top}"), top)
    for (name, p), r in zip(planned.items(), results, strict=True):
        _check_multi(f"SCRIPT_SEED={SEED} {top} {name}", p, r)
