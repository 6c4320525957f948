# SPDX-License-Identifier: MIT
"""stepramp.sim.runner.build_once: each (top, sources, build arguments, GHDL back end) is analysed and elaborated once
and shared (issue 33), a changed source rebuilds, two processes asking at once build it once, old builds are pruned.

The builds here go to a folder of the test's own (STEPRAMP_SIM_LIB), from copies of the RTL files, so that a source can
be changed without touching hdl/.
"""

from __future__ import annotations

import multiprocessing
import os
import time
from pathlib import Path

import pytest

from stepramp.sim import runner

TOP = "stepramp_prio_enc"


@pytest.fixture
def sources(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> list[Path]:
    """Copies of the prio encoder's sources, and a lib folder of this test's own."""
    monkeypatch.setenv("STEPRAMP_SIM_LIB", str(tmp_path / "lib"))
    out = []
    for src in runner.hdl_sources(TOP):
        copy = tmp_path / "hdl" / src.name
        copy.parent.mkdir(exist_ok=True)
        copy.write_bytes(src.read_bytes())
        out.append(copy)
    return out


def test_the_key_follows_the_contents_not_the_generics(sources: list[Path]) -> None:
    """The key is the same for the same contents (wherever the files are), another one for any change of a source's
    contents, the toplevel, the build arguments or the back end."""
    key = runner.build_key(TOP, sources, ["--std=08"], "llvm")
    assert runner.build_key(TOP, runner.hdl_sources(TOP), ["--std=08"], "llvm") == key, "same contents, other folder"
    assert runner.build_key(TOP, sources, ["--std=93c"], "llvm") != key
    assert runner.build_key(TOP, sources, ["--std=08"], "mcode") != key
    assert runner.build_key("stepramp_timer", sources, ["--std=08"], "llvm") != key
    sources[-1].write_text(sources[-1].read_text() + "-- a comment changes the contents\n")
    assert runner.build_key(TOP, sources, ["--std=08"], "llvm") != key


def test_one_build_shared_and_a_changed_source_rebuilds(sources: list[Path]) -> None:
    lib = runner.build_once(TOP, sources)
    done = lib / ".done"
    assert done.exists() and (lib / "top-obj08.cf").exists()
    stamp = done.stat().st_mtime_ns
    time.sleep(0.05)
    assert runner.build_once(TOP, sources) == lib, "the same sources built into another folder"
    assert done.stat().st_mtime_ns == stamp, "the same sources were built again"
    sources[-1].write_text(sources[-1].read_text() + "-- changed\n")
    changed = runner.build_once(TOP, sources)
    assert changed != lib and (changed / ".done").exists(), "a changed source did not give a new build"


def _build(sources: list[str], log: str) -> str:
    return str(runner.build_once(TOP, [Path(s) for s in sources], log_file=Path(log)))


def test_two_processes_build_once(sources: list[Path], tmp_path: Path) -> None:
    """Two processes asking for the same build at the same time get the same folder, built by one of them (the other
    waits on the lock and writes no build log)."""
    logs = [tmp_path / f"build{i}.log" for i in range(2)]
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(2) as pool:
        folders = pool.starmap(_build, [([str(s) for s in sources], str(log)) for log in logs])
    assert folders[0] == folders[1]
    assert sum(log.exists() for log in logs) == 1, "both processes built"


def test_old_builds_are_pruned(tmp_path: Path) -> None:
    """Of a top's builds, the KEEP_BUILDS newest stay, and any younger than KEEP_BUILDS_S; other tops' stay."""
    root = tmp_path / "lib"
    now = time.time()
    ages = [10, 20, 30, 40, 50, 60]  # hours
    for k, age in enumerate(ages):
        for top in (TOP, "stepramp_prio_enc_other"):
            d = root / f"{top}-{k:020d}"
            d.mkdir(parents=True)
            (d / ".done").write_text("")
            os.utime(d / ".done", (now - age * 3600, now - age * 3600))
            (root / f"{d.name}.lock").write_text("")
    young = root / f"{TOP}-young"
    young.mkdir()
    (young / ".done").write_text("")
    runner._prune(root, TOP)
    left = sorted(d.name for d in root.glob(f"{TOP}-*") if d.is_dir())
    assert left == sorted([f"{TOP}-{k:020d}" for k in range(3)] + [young.name]), left
    assert len([d for d in root.glob("stepramp_prio_enc_other-*") if d.is_dir()]) == len(ages)
    assert not (root / f"{TOP}-{5:020d}.lock").exists()
