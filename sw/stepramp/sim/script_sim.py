# SPDX-License-Identifier: MIT
"""`stepramp sim --script`: command scripts on the RTL, through a bus top (GHDL through cocotb's runner).

The driver's planner (stepramp.board.script) turns each script into register writes and commits on the script's
clock axis; stepramp.sim.script_bench plays them on stepramp_plb or stepramp_axil and records every STEP edge with
POSITION after it. The RTL's edges are what this returns: the planner's own prediction (`stepramp model --script`)
is what they are compared with (tb/test_script_rtl.py).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from stepramp.board.multi_script import MultiResult, played_actions
from stepramp.board.script import PREP_CLOCKS, ScriptResult, core_rejections, load_script, plan_script
from stepramp.sim.runner import run_cocotb

#: The bus tops by their short names.
TOPS = {"plb": "stepramp_plb", "axil": "stepramp_axil"}


def _play(
    entity: str,
    testcase: str,
    scripts: list[dict[str, Any]],
    build: Path,
    parameters: Mapping[str, object] | None,
    waves: Path | None = None,
) -> list[dict[str, Any]]:
    """Run stepramp.sim.script_bench's `testcase` on the top `entity` built with `parameters`, with the request
    {"scripts": scripts} in build; the "results" it wrote (RuntimeError when it wrote none)."""
    build = build.resolve()
    build.mkdir(parents=True, exist_ok=True)
    request, result = build / "scripts.json", build / "scripts_result.json"
    result.unlink(missing_ok=True)
    request.write_text(json.dumps({"scripts": scripts}))
    run_cocotb(
        entity,
        "stepramp.sim.script_bench",
        build,
        parameters=parameters,
        waves=waves,
        extra_env={"STEPRAMP_SCRIPT_REQUEST": str(request), "STEPRAMP_SCRIPT_RESULT": str(result)},
        testcase=testcase,
        log_file=build / "sim.log",
    )
    if not result.exists():
        raise RuntimeError(f"the simulation wrote no result; see {build / 'sim.log'}")
    out: list[dict[str, Any]] = json.loads(result.read_text())["results"]
    return out


def simulate_planned(
    planned: Sequence[ScriptResult], build: Path, top: str = "plb", waves: Path | None = None, ramp: int = 0
) -> list[dict[str, Any]]:
    """Play the planned scripts in one simulation (each from a reset) on a top built with G_RAMP = ramp (the scripts'
    "ramp"); per script the RTL's {"edges", "positions", "core_errors", "commits"}."""
    scripts = [
        {
            "actions": [{"at": a.at, "writes": [list(w) for w in a.writes], "ctrl": a.ctrl} for a in p.actions],
            "until": p.until,
            "prep_clocks": PREP_CLOCKS,
            "pins": [list(pin) for pin in p.pins],
            "input_filter": p.input_filter,
            "limit_hard": p.limit_hard,
        }
        for p in planned
    ]
    return _play(TOPS.get(top, top), "play_scripts", scripts, build, {"G_RAMP": ramp} if ramp else None, waves)


def simulate_script(script: dict[str, Any], build: Path, top: str = "plb", waves: Path | None = None) -> dict[str, Any]:
    """One script on the RTL: {"edges", "positions", "rejected"}: the driver's refusals, then each error the core
    flagged as {"at", "op": "core", "reason"}."""
    loaded = load_script(script)
    planned = plan_script(loaded)
    res = simulate_planned([planned], build, top, waves, loaded.ramp)[0]
    rejected = list(planned.rejected) + core_rejections(res["core_errors"])
    return {"edges": res["edges"], "positions": res["positions"], "rejected": rejected}


#: The multi-axis tops by their short names.
MULTI_TOPS = {"plb": "stepramp_multi_plb", "axil": "stepramp_multi_axil"}


def simulate_multi(planned: Sequence[MultiResult], build: Path, top: str = "plb") -> list[dict[str, Any]]:
    """Play planned multi-axis scripts (stepramp.board.multi_script) in one simulation of stepramp_multi_plb or
    _axil at the scripts' axis count (all the same), each from a reset; per script {"edges", "positions": one list
    per axis, "status": each axis's STATUS at the end, "commits"}."""
    axes = {p.axes for p in planned}
    if len(axes) != 1:
        raise ValueError(f"the scripts of one simulation need one axis count, got {sorted(axes)}")
    scripts = []
    for p in planned:
        actions = played_actions(p)
        pins = sorted(
            [[a, name, axis, level] for axis, r in enumerate(p.results) for a, name, level in r.pins if name != "estop"]
            + [[a, "estop", 0, level] for a, level in p.estop],
            key=lambda pin: pin[0],
        )
        first = p.results[0]
        scripts.append(
            {
                "axes": p.axes,
                "actions": actions,
                "until": p.until,
                "prep_clocks": PREP_CLOCKS,
                "pins": pins,
                "input_filter": first.input_filter,
                "limit_hard": first.limit_hard,
            }
        )
    return _play(MULTI_TOPS.get(top, top), "play_multi_scripts", scripts, build, {"G_AXES": axes.pop()})
