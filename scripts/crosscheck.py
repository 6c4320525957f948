#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Fresh random moves (a new seed each run unless given): the model against the ideal bound, and the RTL against
the model, edge for edge, through the `stepramp sim` / `stepramp model` command line.

    .venv/bin/python scripts/crosscheck.py [--seed N] [--moves 200] [--sims 4]
"""

from __future__ import annotations

import argparse
import json
import math
import random
import subprocess
import sys
import time
from pathlib import Path

from stepramp.board.plan import plan_move
from stepramp.models.engine import tick_times
from stepramp.models.ideal import pulse_times
from stepramp.sim.profiles import design_args

BIN = Path(sys.executable).parent / "stepramp"


def random_move(rng: random.Random, max_cycles: float) -> dict[str, float | int]:
    """A valid move lasting at most max_cycles clocks."""
    while True:
        prescale = rng.choice((1, 1, 2, 3, 7))
        fclk = rng.choice((1e6, 2e6, 4e6))
        spr = rng.choice((200.0, 400.0, 1600.0))
        period = math.ceil(64 / prescale) + rng.uniform(0.5, 200.0)
        n_a = math.exp(rng.uniform(math.log(0.3), math.log(300)))
        n_d = n_a * math.exp(rng.uniform(-math.log(50), math.log(50)))
        move = design_args(rng.randint(1, 800) * rng.choice((1, -1)), period, n_a, n_d, spr, fclk, prescale)
        try:
            plan = plan_move(**move)
        except ValueError:
            continue
        ticks = tick_times(plan)
        if not ticks or ticks[-1] * prescale < max_cycles:
            return move


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seed", type=int, default=int(time.time()))
    parser.add_argument("--moves", type=int, default=200, help="moves checked against the ideal bound")
    parser.add_argument("--sims", type=int, default=4, help="moves simulated on the RTL with `stepramp sim`")
    args = parser.parse_args()
    rng = random.Random(args.seed)
    worst_c0, worst_ticks, worst_use = 0.0, 0.0, 0.0
    for _ in range(args.moves):
        move = random_move(rng, 5e6)
        ticks = tick_times(plan_move(**move))
        ideal = pulse_times(**move)
        alpha = 2 * math.pi / move["spr"]
        c0_slow = move["fclk"] / move["prescale"] * math.sqrt(2 * alpha / min(move["accel"], move["decel"]))
        err = max((abs(t - i) for t, i in zip(ticks, ideal, strict=True)), default=0.0)
        assert err <= 0.008 * c0_slow + 2, f"bound exceeded: {move}"
        worst_use = max(worst_use, err / (0.008 * c0_slow + 2))
        worst_ticks = max(worst_ticks, err)
        if c0_slow >= 1000:  # where the 2-tick allowance does not dominate
            worst_c0 = max(worst_c0, err / c0_slow)
    print(
        f"seed {args.seed}: {args.moves} fresh moves within the bound (worst use {worst_use:.1%}); worst "
        f"{worst_ticks:.1f} ticks; worst {worst_c0:.4f} c0_slow where c0_slow >= 1000 ticks"
    )
    for _ in range(args.sims):
        move = random_move(rng, 150_000)
        cli = [f"--{k}={v}" for k, v in move.items()]
        model = json.loads(subprocess.run([BIN, "model", *cli], capture_output=True, text=True, check=True).stdout)
        sim = json.loads(subprocess.run([BIN, "sim", *cli], capture_output=True, text=True, check=True).stdout)
        same = sim["edges"] == model["edges"] and sim["final_position"] == model["final_position"]
        print(f"  sim == model: {same}  ({len(sim['edges'])} edges, position {sim['final_position']}, {move})")
        if not same:
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
