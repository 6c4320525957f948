# SPDX-License-Identifier: MIT
"""What the ctypes tests of the C library (test_c_plan.py, test_c_driver.py) share: stepramp_plan_t as its header
declares it, running a host test program, and the log-uniform draw of their random moves."""

from __future__ import annotations

import ctypes
import math
import random
import re
import subprocess
from typing import Any

from stepramp.tools import clib

PLAN_HEADER = clib.C_DIR / "stepramp_plan.h"

_C_TYPES = {
    "uint32_t": ctypes.c_uint32,
    "uint64_t": ctypes.c_uint64,
    "int32_t": ctypes.c_int32,
    "int64_t": ctypes.c_int64,
}


def plan_struct_fields() -> list[tuple[str, Any]]:
    """stepramp_plan_t's fields, read from stepramp_plan.h (so that a field added there is followed here)."""
    text = PLAN_HEADER.read_text()
    match = re.search(r"typedef struct \{(.*?)\} stepramp_plan_t;", text, re.S)
    assert match, f"no stepramp_plan_t in {PLAN_HEADER}"
    body = re.sub(r"/\*.*?\*/", "", match.group(1), flags=re.S)
    fields = re.findall(r"(\w+)\s+(\w+)\s*;", body)
    assert fields, "stepramp_plan_t has no fields"
    return [(name, _C_TYPES[ctype]) for ctype, name in fields]


class CPlan(ctypes.Structure):
    """stepramp_plan_t."""

    _fields_ = plan_struct_fields()


def run(cmd: list[str]) -> subprocess.CompletedProcess[str]:
    """Run a host program (a C test binary), its output captured."""
    return subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=120)


def log_uniform(rng: random.Random, lo: float, hi: float) -> float:
    """A draw whose logarithm is uniform between log(lo) and log(hi)."""
    return math.exp(rng.uniform(math.log(lo), math.log(hi)))
