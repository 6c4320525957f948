# SPDX-License-Identifier: MIT
"""`make demo`: simulate the core on the RTL and write waveforms and a report under build/demo/.

Until the ramp engine lands this simulates the divider on a few numbers (and says so).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from stepramp.hdl import run_cocotb

TB_DIR = Path(__file__).resolve().parents[2] / "tb"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("build/demo"))
    args = parser.parse_args(argv)
    out: Path = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    sys.path.insert(0, str(TB_DIR))
    waves = out / "divider.ghw"
    print("stepramp demo: the ramp engine has not landed yet; simulating the divider on a few numbers.")
    run_cocotb(
        "stepramp_divider",
        "test_divider",
        out / "sim",
        parameters={"G_WIDTH": 32},
        waves=waves,
        extra_env={"N_PAIRS": "40", "PAIR_SEED": "1"},
        testcase="divider_against_model",
    )
    print(f"waveform: {waves}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
