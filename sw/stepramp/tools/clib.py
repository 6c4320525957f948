# SPDX-License-Identifier: MIT
"""Build the C driver library (sw/c) for the host, for the tests that load it with ctypes."""

from __future__ import annotations

import fcntl
import shutil
import subprocess
from pathlib import Path

C_DIR = Path(__file__).resolve().parents[3] / "sw" / "c"
#: the driver a MicroBlaze runs (its headers declare the structs the tests read)
SRC_DIR = C_DIR / "src"
#: the host-only code: the fake register bank, the ctypes entry points, the callback bus
HOST_DIR = C_DIR / "host"
BUILD_DIR = C_DIR / "build"
SHARED_LIB = BUILD_DIR / "libstepramp.so"


def build(target: str | None = None) -> Path:
    """`make -C sw/c [target]` (all: the libraries and the host tests). One make at a time across pytest workers,
    which share sw/c/build (the later ones find everything up to date). Raises RuntimeError with the reason when
    the toolchain is missing or the build or a host test fails. Returns the build directory."""
    for tool in ("make", "gcc"):
        if shutil.which(tool) is None:
            raise RuntimeError(f"'{tool}' is not on PATH: the C driver (sw/c) cannot be built; install {tool}")
    cmd = ["make", "-C", str(C_DIR), *([target] if target else [])]
    with (C_DIR / "Makefile").open() as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            result = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=300)
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{result.stdout}\n{result.stderr}")
    return BUILD_DIR
