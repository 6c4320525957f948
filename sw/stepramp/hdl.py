# SPDX-License-Identifier: MIT
"""Where the RTL lives, in compile order, and how to run it under GHDL with cocotb's runner."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

#: The repository's hdl/ folder (override with STEPRAMP_HDL_DIR).
HDL_DIR = Path(os.environ.get("STEPRAMP_HDL_DIR", Path(__file__).resolve().parents[2] / "hdl"))

#: Every RTL file, in dependency order.
HDL_FILES: tuple[str, ...] = (
    "stepramp_pkg.vhd",
    "stepramp_regs_pkg.vhd",
    "stepramp_prio_enc.vhd",
    "stepramp_divider.vhd",
    "stepramp_timer.vhd",
    "stepramp_next_delay.vhd",
    "stepramp_engine.vhd",
    "stepramp_stepper.vhd",
    "stepramp_regfile.vhd",
    "stepramp_core.vhd",
    "stepramp_plb.vhd",
    "stepramp_axil.vhd",
)

#: Entities that are synthesised and checked for latches, with the generics they are checked at.
SYNTH_TOPS: dict[str, dict[str, int]] = {
    "stepramp_prio_enc": {"G_WIDTH": 32},
    "stepramp_divider": {"G_WIDTH": 32},
    "stepramp_timer": {"G_WIDTH": 16},
    "stepramp_engine": {},
    "stepramp_stepper": {},
    "stepramp_regfile": {},
    "stepramp_plb": {},
    "stepramp_axil": {},
}


def hdl_sources(upto: str | None = None) -> list[Path]:
    """Existing RTL files in compile order, optionally only up to (and including) one entity's file."""
    files: list[Path] = []
    for name in HDL_FILES:
        path = HDL_DIR / name
        if path.exists():
            files.append(path)
        if upto is not None and name == f"{upto}.vhd":
            break
    return files


def run_cocotb(
    toplevel: str,
    test_module: str,
    build_dir: Path,
    parameters: Mapping[str, object] | None = None,
    waves: Path | None = None,
    extra_env: Mapping[str, str] | None = None,
    testcase: str | Sequence[str] | None = None,
    log_file: Path | None = None,
) -> Path:
    """Build the RTL up to toplevel and run a cocotb test module against it with GHDL.

    One build directory per call, so that tests can run in parallel. waves: a .ghw or .fst path to write.
    log_file: send the build and simulation output there instead of stdout.
    Returns the results file; under pytest a failing test raises SystemExit.
    """
    from cocotb_tools.runner import get_runner  # imported late: the model does not need cocotb

    runner = get_runner("ghdl")
    build_dir = build_dir.resolve()
    runner.build(
        sources=hdl_sources(toplevel),
        hdl_toplevel=toplevel,
        build_args=["--std=08"],
        build_dir=build_dir,
        always=True,
        log_file=log_file,
    )
    plusargs = ["--ieee-asserts=disable-at-0"]
    if waves is not None:
        kind = "fst" if waves.suffix == ".fst" else "wave"
        plusargs.append(f"--{kind}={waves.resolve()}")
    return runner.test(
        hdl_toplevel=toplevel,
        test_module=test_module,
        test_args=["--std=08"],
        plusargs=plusargs,
        parameters=dict(parameters or {}),
        build_dir=build_dir,
        test_dir=build_dir,
        extra_env=dict(extra_env or {}),
        testcase=testcase,
        log_file=log_file,
    )
