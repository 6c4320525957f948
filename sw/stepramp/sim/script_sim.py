# SPDX-License-Identifier: MIT
"""`stepramp sim --script`: command scripts on the RTL, through a bus top (GHDL through cocotb's runner).

The driver's planner (stepramp.board.script) turns each script into register writes and commits on the script's
clock axis; stepramp.sim.script_bench plays them on stepramp_plb or stepramp_axil and records every STEP edge with
POSITION after it. The RTL's edges are what this returns: the planner's own prediction (`stepramp model --script`)
is what they are compared with (tb/test_script_rtl.py).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from stepramp.board.script import PREP_CLOCKS, ScriptResult, core_rejections, load_script, plan_script
from stepramp.sim.runner import run_cocotb

#: The bus tops by their short names.
TOPS = {"plb": "stepramp_plb", "axil": "stepramp_axil"}


def simulate_planned(
    planned: Sequence[ScriptResult], build: Path, top: str = "plb", waves: Path | None = None
) -> list[dict[str, Any]]:
    """Play the planned scripts in one simulation (each from a reset); per script the RTL's {"edges", "positions",
    "core_errors", "commits"}."""
    build = build.resolve()
    build.mkdir(parents=True, exist_ok=True)
    request, result = build / "scripts.json", build / "scripts_result.json"
    result.unlink(missing_ok=True)
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
    request.write_text(json.dumps({"scripts": scripts}))
    run_cocotb(
        TOPS.get(top, top),
        "stepramp.sim.script_bench",
        build,
        waves=waves,
        extra_env={"STEPRAMP_SCRIPT_REQUEST": str(request), "STEPRAMP_SCRIPT_RESULT": str(result)},
        log_file=build / "sim.log",
    )
    if not result.exists():
        raise RuntimeError(f"the simulation wrote no result; see {build / 'sim.log'}")
    out: list[dict[str, Any]] = json.loads(result.read_text())["results"]
    return out


def simulate_script(script: dict[str, Any], build: Path, top: str = "plb", waves: Path | None = None) -> dict[str, Any]:
    """One script on the RTL: {"edges", "positions", "rejected"}: the driver's refusals, then each error the core
    flagged as {"at", "op": "core", "reason"}."""
    planned = plan_script(load_script(script))
    res = simulate_planned([planned], build, top, waves)[0]
    rejected = list(planned.rejected) + core_rejections(res["core_errors"])
    return {"edges": res["edges"], "positions": res["positions"], "rejected": rejected}
