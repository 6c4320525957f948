# SPDX-License-Identifier: MIT
"""What the ctypes tests of the C library (test_c_plan.py, test_c_driver.py, test_c_change.py) share: the structs as
their headers declare them (stepramp_plan_t), running a host test program, and the log-uniform draw of their random
moves."""

from __future__ import annotations

import ctypes
import math
import random
import re
import subprocess
from pathlib import Path
from typing import Any

from stepramp.sim.cdriver import C_TYPES
from stepramp.tools import clib

PLAN_HEADER = clib.SRC_DIR / "stepramp_plan.h"


def struct_fields(header: Path, struct: str, types: dict[str, Any] | None = None) -> list[tuple[str, Any]]:
    """The fields of `typedef struct { ... } <struct>;` in a header, as ctypes types (so that a field added there is
    followed here); types names further C types, such as a struct the struct holds."""
    text = re.sub(r"/\*.*?\*/", "", header.read_text(), flags=re.S)
    match = re.search(r"typedef struct \{([^{}]*)\} " + struct + ";", text)
    assert match, f"no {struct} in {header}"
    fields = re.findall(r"(\w+)\s+(\w+)\s*;", match.group(1))
    assert fields, f"{struct} has no fields"
    known = C_TYPES | (types or {})
    return [(name, known[ctype]) for ctype, name in fields]


def plan_struct_fields() -> list[tuple[str, Any]]:
    """stepramp_plan_t's fields, read from stepramp_plan.h."""
    return struct_fields(PLAN_HEADER, "stepramp_plan_t")


class CPlan(ctypes.Structure):
    """stepramp_plan_t."""

    _fields_ = plan_struct_fields()


def run(cmd: list[str]) -> subprocess.CompletedProcess[str]:
    """Run a host program (a C test binary), its output captured."""
    return subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=120)


def log_uniform(rng: random.Random, lo: float, hi: float) -> float:
    """A draw whose logarithm is uniform between log(lo) and log(hi)."""
    return math.exp(rng.uniform(math.log(lo), math.log(hi)))
