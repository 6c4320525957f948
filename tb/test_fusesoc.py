# SPDX-License-Identifier: MIT
"""FuseSoC runs stepramp.core: the sim target (the self-checking VHDL testbench tb/vhdl/stepramp_plb_tb.vhd on
GHDL) passes, and the lint target (analysis and elaboration of the tops) is clean.

Each run uses a build root of its own under pytest's tmp_path. A missing fusesoc is a failure, not a skip: it is
a pinned development dependency.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
CORE_NAME = "stepramp:ip:stepramp"
PASS_LINE = "stepramp_plb_tb: PASS"


def fusesoc() -> str:
    """The fusesoc of this Python environment (else the one on PATH)."""
    local = Path(sys.executable).with_name("fusesoc")
    found = str(local) if local.exists() else shutil.which("fusesoc")
    if found is None:
        pytest.fail("fusesoc is not installed (it is pinned in the dev extra: pip install -e '.[dev]')")
    return found


def run_target(target: str, build_root: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [fusesoc(), f"--cores-root={REPO}", "run", f"--build-root={build_root}", f"--target={target}", CORE_NAME],
        cwd=build_root,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


def test_fusesoc_sim(tmp_path: Path) -> None:
    res = run_target("sim", tmp_path)
    log = res.stdout + res.stderr
    assert res.returncode == 0, log
    assert PASS_LINE in log, log


def test_fusesoc_lint(tmp_path: Path) -> None:
    res = run_target("lint", tmp_path)
    log = res.stdout + res.stderr
    assert res.returncode == 0, log
    for top in ("stepramp_plb", "stepramp_axil", "stepramp_stepper"):
        assert re.search(rf"^ghdl -r .* {top} --stop-time=0ns", log, re.MULTILINE), f"{top} not elaborated\n{log}"
