# SPDX-License-Identifier: MIT
"""`make demo`'s job (python -m stepramp.tools.demo): the artefacts exist, and the report's numbers are those of
the JSON.

The figures are recomputed here from move.json's edges and the ideal trapezoid's closed form (stepramp.models.ideal),
not taken from the demo's own summary; the PNG is checked by its header, the GTKWave layout by its dump file and the
demo's own check of every layout signal against the simulator (report.json's missing_waveform_signals).
"""

from __future__ import annotations

import itertools
import json
import math
import re
import struct
import subprocess
import sys
from pathlib import Path

from stepramp.board.plan import plan_move
from stepramp.models.engine import FIRST_PULSE_LATENCY
from stepramp.models.engine import edges as model_edges
from stepramp.models.ideal import ideal_move


def number(report: str, label: str) -> list[float]:
    line = next(line for line in report.splitlines() if line.startswith(label))
    return [float(x) for x in re.findall(r"(?<![A-Za-z_])-?\d+(?:\.\d+)?", line[len(label) :])]


def test_demo_artefacts_and_report(tmp_path: Path) -> None:
    out = tmp_path / "demo"
    run = subprocess.run(
        [sys.executable, "-m", "stepramp.tools.demo", "--out", str(out)], capture_output=True, text=True, timeout=900
    )
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    for name in ("stepramp_demo.ghw", "stepramp_demo.gtkw", "profile.png", "report.txt", "move.json"):
        assert (out / name).stat().st_size > 0, name
        assert str(out / name) in run.stdout, name  # the paths are printed

    png = (out / "profile.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = struct.unpack(">II", png[16:24])
    assert width > 400 and height > 300

    gtkw = (out / "stepramp_demo.gtkw").read_text()
    assert f'[dumpfile] "{(out / "stepramp_demo.ghw").resolve()}"' in gtkw
    figures = json.loads((out / "report.json").read_text())
    assert figures["missing_waveform_signals"] == []

    move = json.loads((out / "move.json").read_text())
    inputs, edges = move["inputs"], move["edges"]
    assert (inputs["steps"], inputs["accel"], inputs["decel"], inputs["speed"], inputs["spr"]) == (
        400,
        40.0,
        40.0,
        20.0,
        400.0,
    )
    plan = plan_move(**inputs)
    assert edges == model_edges(plan)
    assert move["final_position"] == 400

    report = (out / "report.txt").read_text()
    f_tick = inputs["fclk"] / inputs["prescale"]
    ticks = [(e - FIRST_PULSE_LATENCY) / inputs["prescale"] for e in edges]
    ideal = ideal_move(**inputs)
    steps, position = number(report, "steps emitted")
    assert (steps, position) == (len(edges), move["final_position"])
    move_ms, ideal_ms = number(report, "move time")
    assert math.isclose(move_ms, ticks[-1] / f_tick * 1e3, abs_tol=5e-4)
    assert math.isclose(ideal_ms, ideal.t_end * 1e3, abs_tol=5e-4)
    peak, _ = number(report, "peak speed")
    shortest = min(b - a for a, b in itertools.pairwise(ticks))
    assert math.isclose(peak, 2 * math.pi / inputs["spr"] * f_tick / shortest, abs_tol=5e-4)
    deviation = [t - ti for t, ti in zip(ticks, ideal.pulse_times(), strict=True)]
    worst = max(range(len(deviation)), key=lambda k: abs(deviation[k]))
    dev_ticks, dev_c0, pulse, c0_ticks = number(report, "largest deviation")
    assert (dev_ticks, pulse) == (round(abs(deviation[worst]), 2), worst)
    assert math.isclose(dev_c0, abs(deviation[worst]) / c0_ticks, abs_tol=1e-4)
    alpha = 2 * math.pi / inputs["spr"]
    assert math.isclose(c0_ticks, f_tick * math.sqrt(2 * alpha / inputs["accel"]), abs_tol=0.5)
    assert "RTL edges == model    True" in report
