# SPDX-License-Identifier: MIT
"""Where the RTL lives, in compile order, and how to run it under GHDL with cocotb's runner."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

#: The repository's hdl/ folder (override with STEPRAMP_HDL_DIR).
HDL_DIR = Path(os.environ.get("STEPRAMP_HDL_DIR", Path(__file__).resolve().parents[3] / "hdl"))

#: Every RTL file, in dependency order.
HDL_FILES: tuple[str, ...] = (
    "stepramp_pkg.vhd",
    "stepramp_regs_pkg.vhd",
    "stepramp_prio_enc.vhd",
    "stepramp_divider.vhd",
    "stepramp_timer.vhd",
    "stepramp_next_delay.vhd",
    "stepramp_isqrt.vhd",
    "stepramp_next_delay_exact.vhd",
    "stepramp_precompute.vhd",
    "stepramp_engine.vhd",
    "stepramp_stepper.vhd",
    "stepramp_regfile.vhd",
    "stepramp_inputs.vhd",
    "stepramp_core.vhd",
    "stepramp_plb.vhd",
    "stepramp_axil.vhd",
    "stepramp_multi_pkg.vhd",
    "stepramp_multi.vhd",
    "stepramp_plb_slave.vhd",
    "stepramp_axil_slave.vhd",
    "stepramp_multi_plb.vhd",
    "stepramp_multi_axil.vhd",
)

#: Entities that are synthesised and checked for latches, with the generics they are checked at.
SYNTH_TOPS: dict[str, dict[str, int]] = {
    "stepramp_prio_enc": {"G_WIDTH": 32},
    "stepramp_divider": {"G_WIDTH": 32},
    "stepramp_isqrt": {"G_WIDTH": 80},
    "stepramp_next_delay_exact": {},
    "stepramp_timer": {"G_WIDTH": 16},
    "stepramp_precompute": {},
    "stepramp_engine": {},
    "stepramp_stepper": {},
    "stepramp_regfile": {},
    "stepramp_inputs": {},
    "stepramp_plb": {},
    "stepramp_axil": {},
    # the multi-axis tops (stepramp_multi and the bus slaves under them): 3 axes, not a power of two
    "stepramp_multi_plb": {"G_AXES": 3},
    "stepramp_multi_axil": {"G_AXES": 3},
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


def _sim_stop_s(results_xml: Path) -> float | None:
    """The simulated time at which the last test of a cocotb results file stopped (None if it holds none)."""
    import xml.etree.ElementTree as ET

    try:
        stops = [
            float(p.get("value", "0"))
            for p in ET.parse(results_xml).iter("property")
            if p.get("name") == "sim_time_stop"
        ]
    except (OSError, ET.ParseError):
        return None
    return max(stops) * 1e-9 if stops else None  # cocotb reports it in ns


def run_cocotb(
    toplevel: str,
    test_module: str,
    build_dir: Path,
    parameters: Mapping[str, object] | None = None,
    waves: Path | None = None,
    extra_env: Mapping[str, str] | None = None,
    testcase: str | Sequence[str] | None = None,
    log_file: Path | None = None,
    netlist: bool = False,
) -> Path:
    """Build the RTL up to toplevel and run a cocotb test module against it with GHDL.

    One build directory per call, so that tests can run in parallel. waves: a .ghw or .fst path to write; for a
    .ghw of a top with a layout in stepramp.sim.waves, a GTKWave save file (.gtkw) is written beside it. With WAVES=1 in
    the environment every call writes build_dir/<toplevel>.ghw.
    log_file: send the build and simulation output there instead of stdout.
    netlist: simulate `ghdl synth`'s Verilog netlist of the top (its generics baked in) with Icarus Verilog instead
    (stepramp.sim.netlist; the benches see STEPRAMP_NETLIST=1 and collect no coverage).
    Returns the results file; under pytest a failing test raises SystemExit.
    """
    from cocotb_tools.runner import get_runner  # imported late: the model does not need cocotb

    build_dir = build_dir.resolve()
    if netlist:
        from stepramp.sim.netlist import write_netlist

        icarus = get_runner("icarus")
        icarus.build(
            sources=[write_netlist(toplevel, build_dir, parameters)],
            hdl_toplevel=toplevel,
            build_dir=build_dir,
            timescale=("1ns", "1ps"),
            always=True,
            log_file=log_file,
        )
        return icarus.test(
            hdl_toplevel=toplevel,
            test_module=test_module,
            build_dir=build_dir,
            test_dir=build_dir,
            extra_env={**dict(extra_env or {}), "STEPRAMP_NETLIST": "1", "STEPRAMP_COVERAGE_DIR": ""},
            testcase=testcase,
            log_file=log_file,
        )
    runner = get_runner("ghdl")
    runner.build(
        sources=hdl_sources(toplevel),
        hdl_toplevel=toplevel,
        build_args=["--std=08"],
        build_dir=build_dir,
        always=True,
        log_file=log_file,
    )
    if waves is None and os.environ.get("WAVES", "0") not in ("", "0"):
        waves = build_dir / f"{toplevel}.ghw"  # WAVES=1 pytest ...: every simulation writes its waveform
    plusargs = ["--ieee-asserts=disable-at-0"]
    if waves is not None:
        kind = "fst" if waves.suffix == ".fst" else "wave"
        plusargs.append(f"--{kind}={waves.resolve()}")
    results = runner.test(
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
    if waves is not None and waves.suffix == ".ghw":
        from stepramp.sim.waves import LAYOUTS, write_gtkw

        if toplevel in LAYOUTS:  # a GTKWave layout beside the waveform (gtkwave FILE.gtkw), zoomed to the whole run
            stop = _sim_stop_s(Path(results))
            write_gtkw(
                waves.with_suffix(".gtkw"),
                waves,
                top=toplevel,
                duration_s=stop,
                marker_s=stop / 2 if stop else None,
                title=f"{toplevel}: {test_module}",
            )
    return results
