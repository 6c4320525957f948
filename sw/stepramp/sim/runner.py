# SPDX-License-Identifier: MIT
"""Where the RTL lives, in compile order, and how to run it under GHDL with cocotb's runner."""

from __future__ import annotations

import contextlib
import fcntl
import functools
import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Iterator, Mapping, Sequence
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
    "stepramp_sched.vhd",
    "stepramp_next_delay.vhd",
    "stepramp_isqrt.vhd",
    "stepramp_next_delay_exact.vhd",
    "stepramp_precompute.vhd",
    "stepramp_engine.vhd",
    "stepramp_stepper.vhd",
    "stepramp_regfile.vhd",
    "stepramp_inputs.vhd",
    "stepramp_core.vhd",
    "stepramp_plb_slave.vhd",
    "stepramp_axil_slave.vhd",
    "stepramp_plb.vhd",
    "stepramp_axil.vhd",
    "stepramp_multi_pkg.vhd",
    "stepramp_multi.vhd",
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
    "stepramp_sched": {"G_AXES": 3},
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


#: Format of the shared builds' folders: bump it when what a build folder holds changes.
_BUILD_FORMAT = 1
#: Where build_once keeps the shared builds (one folder per content hash), unless STEPRAMP_SIM_LIB says elsewhere.
_REPO = Path(__file__).resolve().parents[3]


def ghdl_backend() -> str:
    """The GHDL back end a `ghdl` command runs, as Debian's /usr/bin/ghdl wrapper picks it: $GHDL_BACKEND when
    ghdl-$GHDL_BACKEND is installed beside it, else mcode, gcc, llvm (the first installed); "" for another ghdl."""
    ghdl = shutil.which("ghdl")
    if ghdl is None:
        return ""
    here = Path(ghdl).resolve().parent
    wanted = os.environ.get("GHDL_BACKEND", "")
    for name in (wanted, "mcode", "gcc", "llvm"):
        if name and (here / f"ghdl-{name}").exists():
            return name
    return ""


@functools.lru_cache(maxsize=8)
def _ghdl_version(backend: str) -> str:
    """`ghdl --version` of a back end (once per process and back end)."""
    env = {**os.environ, "GHDL_BACKEND": backend} if backend else None
    try:
        out = subprocess.run(["ghdl", "--version"], capture_output=True, text=True, check=False, env=env).stdout
    except OSError:
        return ""
    return out


def lib_root() -> Path:
    """The folder of the shared builds: $STEPRAMP_SIM_LIB; else _lib under $STEPRAMP_SIM_BUILD (make mutate: each
    mutant's suite has its own); else build/sim_lib in the repository (a temporary folder if that is read-only)."""
    if os.environ.get("STEPRAMP_SIM_LIB"):
        return Path(os.environ["STEPRAMP_SIM_LIB"])
    if os.environ.get("STEPRAMP_SIM_BUILD"):
        return Path(os.environ["STEPRAMP_SIM_BUILD"]) / "_lib"
    root = _REPO / "build" / "sim_lib"
    try:
        root.mkdir(parents=True, exist_ok=True)
    except OSError:
        root = Path(tempfile.gettempdir()) / "stepramp-sim-lib"
    return root


def build_key(toplevel: str, sources: Sequence[Path], build_args: Sequence[str], backend: str) -> str:
    """The content hash a build is kept under: the sources' names and contents in order, the toplevel, the build
    arguments, the GHDL back end and its version. Generics are not in it: they are given at run time (-g)."""
    h = hashlib.sha256()
    for part in (f"format {_BUILD_FORMAT}", toplevel, *build_args, backend, _ghdl_version(backend)):
        h.update(part.encode() + b"\0")
    for src in sources:
        h.update(src.name.encode() + b"\0")
        h.update(hashlib.sha256(src.read_bytes()).digest())
    return h.hexdigest()[:20]


@contextlib.contextmanager
def _locked(lock_file: Path) -> Iterator[None]:
    """An exclusive flock on lock_file (created if need be) for the body: one builder at a time, across processes."""
    lock_file.parent.mkdir(parents=True, exist_ok=True)
    with lock_file.open("a") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


#: GHDL's analysis options for every simulation build: VHDL-2008, and -O2, which the LLVM back end passes to its code
#: generator (the plain-VHDL bench runs 1.7 times as fast; the analysis takes no longer) and mcode ignores.
BUILD_ARGS = ("--std=08", "-O2")


def build_once(
    toplevel: str,
    sources: Sequence[Path] | None = None,
    build_args: Sequence[str] = BUILD_ARGS,
    log_file: Path | None = None,
) -> Path:
    """Analyse and elaborate toplevel from sources (default: hdl_sources(toplevel)) with GHDL once, and return the
    folder that holds the build (its work library and, with the LLVM or GCC back end, the executable).

    The folder is lib_root()/<toplevel>-<build_key>: every simulation of the same top, sources, build arguments and
    back end shares it, whatever its generics; a changed source gives another key, so another build. Safe under
    pytest -n: the build runs under an flock of <folder>.lock, and a folder counts as built only once its `.done`
    marker is written (a build that died half-way is redone)."""
    from cocotb_tools.runner import get_runner  # imported late: the model does not need cocotb

    srcs = [Path(s).resolve() for s in (sources if sources is not None else hdl_sources(toplevel))]
    backend = ghdl_backend()
    key = build_key(toplevel, srcs, build_args, backend)
    lib = lib_root().resolve() / f"{toplevel}-{key}"
    done = lib / ".done"
    if done.exists():
        return lib
    with _locked(lib.with_name(lib.name + ".lock")):
        if done.exists():  # another process built it while this one waited for the lock
            return lib
        shutil.rmtree(lib, ignore_errors=True)
        runner = get_runner("ghdl")
        runner.build(
            sources=srcs,
            hdl_toplevel=toplevel,
            build_args=list(build_args),
            build_dir=lib,
            always=True,
            log_file=log_file,
        )
        done.write_text(f"{toplevel}\n{backend}\n" + "".join(f"{s}\n" for s in srcs))
    _prune(lib.parent, toplevel)
    return lib


#: Builds of one top kept in a lib_root() (the newest), and the age below which none is removed.
KEEP_BUILDS, KEEP_BUILDS_S = 4, 3600.0


def _prune(root: Path, toplevel: str) -> None:
    """Remove the older builds of toplevel in root (each edit of the RTL makes a new one): all but the KEEP_BUILDS
    newest, and none less than KEEP_BUILDS_S old (a simulation started before the edit may still be using it)."""
    import time

    builds = sorted(
        (d for d in root.glob(f"{toplevel}-*") if d.is_dir() and (d / ".done").exists()),
        key=lambda d: (d / ".done").stat().st_mtime,
        reverse=True,
    )
    now = time.time()
    for old in builds[KEEP_BUILDS:]:
        with contextlib.suppress(OSError):
            if now - (old / ".done").stat().st_mtime > KEEP_BUILDS_S:
                shutil.rmtree(old, ignore_errors=True)
                old.with_name(old.name + ".lock").unlink(missing_ok=True)


def _link_executable(lib: Path, toplevel: str, test_dir: Path) -> None:
    """Where the back end elaborates to an executable (LLVM, GCC), `ghdl -r` runs ./<toplevel> of the folder it runs
    in: point test_dir/<toplevel> at the shared build's (replacing whatever an older run left there)."""
    exe = lib / toplevel
    if not exe.exists():  # mcode: ghdl -r elaborates from the work library (--workdir) in memory
        return
    link = test_dir / toplevel
    tmp = test_dir / f".{toplevel}.link-{os.getpid()}"
    with contextlib.suppress(FileNotFoundError):
        tmp.unlink()
    tmp.symlink_to(exe)
    os.replace(tmp, link)


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


#: The modules whose assert statements cocotb has pytest rewrite (for the values in a failing assert's message): the
#: benches' test modules and helpers. cocotb's default, every module imported after it starts, re-parsed the whole
#: package and its libraries in every simulation (no byte-code cache with PYTHONDONTWRITEBYTECODE): about 1 s each.
REWRITE_ASSERTIONS = "test_*.py *_bench.py *_tb.py tbutil.py session.py"


def _sim_env(extra_env: Mapping[str, str] | None) -> dict[str, str]:
    """The simulation's extra environment: the assertion rewriting's modules (unless the caller's environment sets
    COCOTB_REWRITE_ASSERTION_FILES), then extra_env."""
    key = "COCOTB_REWRITE_ASSERTION_FILES"
    env = {} if key in os.environ else {key: REWRITE_ASSERTIONS}
    return {**env, **dict(extra_env or {})}


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
    """Run a cocotb test module against the RTL up to toplevel with GHDL (built once: build_once).

    build_dir is this call's own folder (results, waveforms, logs), so that tests can run in parallel; the analysed
    and elaborated RTL is shared with every call for the same top and sources (build_once), generics given at run
    time. waves: a .ghw or .fst path to write; for a
    .ghw of a top with a layout in stepramp.sim.waves, a GTKWave save file (.gtkw) is written beside it. With WAVES=1 in
    the environment every call writes build_dir/<toplevel>.ghw.
    log_file: send the build and simulation output there instead of stdout.
    STEPRAMP_GHDL_EXTRA in the environment: more GHDL run options, space-separated (e.g. --backtrace-severity=warning).
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
            extra_env={**_sim_env(extra_env), "STEPRAMP_NETLIST": "1", "STEPRAMP_COVERAGE_DIR": ""},
            testcase=testcase,
            log_file=log_file,
        )
    # One build per (top, sources, back end) for the whole regression, shared; this call's results in build_dir.
    build_dir.mkdir(parents=True, exist_ok=True)
    lib = build_once(toplevel, log_file=log_file)
    _link_executable(lib, toplevel, build_dir)
    runner = get_runner("ghdl")
    if waves is None and os.environ.get("WAVES", "0") not in ("", "0"):
        waves = build_dir / f"{toplevel}.ghw"  # WAVES=1 pytest ...: every simulation writes its waveform
    plusargs = ["--ieee-asserts=disable-at-0", *os.environ.get("STEPRAMP_GHDL_EXTRA", "").split()]
    if waves is not None:
        kind = "fst" if waves.suffix == ".fst" else "wave"
        plusargs.append(f"--{kind}={waves.resolve()}")
    results = runner.test(
        hdl_toplevel=toplevel,
        hdl_toplevel_lang="vhdl",  # (this runner did not build: it cannot tell from its sources)
        test_module=test_module,
        test_args=["--std=08", f"--workdir={lib}"],
        plusargs=plusargs,
        parameters=dict(parameters or {}),
        build_dir=lib,
        test_dir=build_dir,
        extra_env=_sim_env(extra_env),
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
