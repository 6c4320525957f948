# SPDX-License-Identifier: MIT
"""Profile plots: step rate against time (RTL or model, the bit-exact model, the ideal trapezoid) and each
pulse's deviation from the ideal, in ticks."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

from stepramp.models.engine import FIRST_PULSE_LATENCY
from stepramp.models.ideal import ideal_move


def _rates(times_s: list[float]) -> tuple[list[float], list[float]]:
    """Step rate (steps/s) of each interval, placed at the interval's midpoint."""
    mids = [(a + b) / 2 for a, b in itertools.pairwise(times_s)]
    rates = [1.0 / (b - a) for a, b in itertools.pairwise(times_s)]
    return mids, rates


def plot_move(
    move: dict[str, Any],
    png: Path,
    model_edges: list[int] | None = None,
    compare: dict[str, list[int]] | None = None,
) -> None:
    """Draw a `stepramp sim`/`model` JSON object's move to a PNG (needs matplotlib). compare: more models of the same
    move by label, as pulse ticks (stepramp.models.engine.tick_times), drawn in the deviation panel (the other ramp
    arithmetic, say)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    inputs = move["inputs"]
    prescale = inputs.get("prescale", 1)
    f_tick = inputs["fclk"] / prescale
    ideal = ideal_move(**inputs)
    ideal_ticks = ideal.pulse_times()
    to_s = [((e - FIRST_PULSE_LATENCY) / prescale) / f_tick for e in move["edges"]]
    fig, (ax_rate, ax_dev) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True, height_ratios=(3, 2))
    t_ideal = [t / f_tick for t in ideal_ticks]
    ax_rate.plot(*_rates(t_ideal), "-", color="0.6", lw=3, label="ideal trapezoid")
    if model_edges is not None:
        t_model = [((e - FIRST_PULSE_LATENCY) / prescale) / f_tick for e in model_edges]
        ax_rate.plot(*_rates(t_model), "--", color="tab:orange", lw=1.5, label="bit-exact model")
    ax_rate.plot(*_rates(to_s), ".", color="tab:blue", ms=3, label=f"{move['tool']} ({len(to_s)} steps)")
    marks = [(ideal.t_a, "ACCEL -> RUN"), (ideal.t_d, "RUN -> DECEL")]
    if ideal.triangle:
        marks = [(ideal.t_a, "ACCEL -> DECEL")]
    for t, label in marks:
        ax_rate.axvline(t, color="0.8", ls=":")
        ax_rate.text(t, 0, f" {label}", rotation=90, va="bottom", fontsize=8, color="0.4")
    ax_rate.set_ylabel("step rate (steps/s)")
    ax_rate.legend(loc="upper right", fontsize=8)
    ax_rate.set_title(
        f"{inputs['steps']} steps, accel {inputs['accel']} decel {inputs['decel']} rad/s², "
        f"speed {inputs['speed']} rad/s, {inputs['spr']:g} steps/rev, f_tick {f_tick:g} Hz"
    )
    deviation = [(e - FIRST_PULSE_LATENCY) / prescale - ti for e, ti in zip(move["edges"], ideal_ticks, strict=False)]
    ramp = move.get("ramp", "avr446")
    ax_dev.plot(to_s, deviation, ".-", color="tab:blue", ms=2, lw=0.6, label=f"{move['tool']} ({ramp})")
    for (label, ticks), color in zip((compare or {}).items(), ("tab:green", "tab:red", "tab:purple"), strict=False):
        ax_dev.plot(
            [t / f_tick for t in ticks],
            [t - ti for t, ti in zip(ticks, ideal_ticks, strict=False)],
            ".-",
            color=color,
            ms=2,
            lw=0.6,
            label=label,
        )
    if compare:
        ax_dev.legend(loc="lower right", fontsize=8)
    ax_dev.axhline(0, color="0.6", lw=0.8)
    ax_dev.set_ylabel("pulse time - ideal (ticks)")
    ax_dev.set_xlabel("time (s)")
    fig.tight_layout()
    png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png, dpi=110)
    plt.close(fig)
