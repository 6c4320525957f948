# SPDX-License-Identifier: MIT
"""The peripheral programmed with register values computed by the C driver library (sw/c), loaded with ctypes.

For a few profiles, stepramp_plan_move of build/libstepramp.so plans the move; its stepramp_plan_t becomes a
stepramp.board.plan.Plan, which the Python driver writes over the bus (StepRamp.program / start / wait_done through
peripheral_tb.PeripheralTb): the PLB-like top stepramp_plb with stepramp.sim.ipif's master, and the AXI4-Lite top too.
The STEP edges must be those of the bit-exact model for that plan, and the position must follow. Then the C driver
itself: the bus writes stepramp_move makes into the fake register bank (sw/c/host/stepramp_fakebus.c) are replayed on
the bus, byte enables included. The C library is built by the pytest function below (``make -C sw/c lib``).
"""

from __future__ import annotations

import ctypes
import json
import os
from pathlib import Path
from typing import Any

import pytest

from peripheral_tb import TOPS, PeripheralTb, profiles_limit_us
from stepramp.board.plan import Plan, plan_move
from stepramp.board.regmap import offset
from stepramp.models.engine import edges as model_edges
from stepramp.sim.cdriver import c_struct
from stepramp.sim.profiles import PROFILES_BY_NAME, Profile
from stepramp.sim.runner import run_cocotb
from stepramp.tools import clib
from tbutil import REPO, build_dir, cocotb, edges_differ

C_DIR = REPO / "sw" / "c"
C_LIB = C_DIR / "build" / "libstepramp.so"

#: A trapezoid, a triangle with negative steps, a move starting in RUN, and one with PRESCALE > 1.
PROFILE_NAMES = ("trap_basic", "triangle_negative", "run_start", "trap_prescale_4")


def c_plan_move(so: ctypes.CDLL, prof: Profile) -> Plan:
    """The C library's plan of a profile, as a Python Plan."""
    c_plan_t = c_struct(C_DIR / "src" / "stepramp_plan.h", "stepramp_plan_t")
    so.stepramp_plan_move.argtypes = [
        ctypes.POINTER(c_plan_t),
        ctypes.c_int64,
        *(ctypes.c_double,) * 5,
        ctypes.c_uint32,
    ]
    so.stepramp_plan_move.restype = ctypes.c_int
    so.stepramp_fakebus_sizeof_plan.restype = ctypes.c_size_t
    assert ctypes.sizeof(c_plan_t) == so.stepramp_fakebus_sizeof_plan(), "stepramp_plan_t layout"
    out = c_plan_t()
    rc = so.stepramp_plan_move(
        ctypes.byref(out), prof.steps, prof.accel, prof.decel, prof.speed, prof.spr, prof.fclk, prof.prescale
    )
    assert rc == 0, f"{prof.name}: stepramp_plan_move returned {rc}"
    c_values = {name: getattr(out, name) for name, _ in c_plan_t._fields_}
    py_plan = plan_move(**prof.args())
    plan = Plan(**c_values)
    assert plan == py_plan, f"{prof.name}: C plan {plan} differs from Python's {py_plan}"
    return plan


# Limit: from the profiles this run is given (PROFILE_NAMES), as the model says they last: 3.5 ms, measured 1.6 ms.
PROFILES_LIMIT_US = profiles_limit_us(json.loads(os.environ.get("PROFILE_NAMES", "[]")))


@cocotb.test(timeout_time=PROFILES_LIMIT_US, timeout_unit="us")
async def c_plans_through_the_bus(dut) -> None:
    """Each profile planned by the C library and programmed over the bus matches the model edge for edge."""
    so = ctypes.CDLL(os.environ["STEPRAMP_C_LIB"])
    tb = await PeripheralTb.started(dut)
    await tb.driver().enable_irq(done=True, error=True)
    problems: list[str] = []
    position = 0
    for name in json.loads(os.environ["PROFILE_NAMES"]):
        prof = PROFILES_BY_NAME[name]
        plan = c_plan_move(so, prof)
        drv = tb.driver(prof.args())
        edges, status = await tb.run_plan(drv, plan)
        want = model_edges(plan)
        position += prof.steps
        dut._log.info("%s: %d steps, %d edges from the C plan", name, prof.steps, len(edges))
        if edges != want:
            problems.append(f"{name}: {edges_differ(edges, want)}")
        if len(edges) != abs(prof.steps):
            problems.append(f"{name}: {len(edges)} pulses for {prof.steps} steps")
        if status.error or await drv.position() != position:
            problems.append(f"{name}: error={status.error} position {await drv.position()} expected {position}")
    assert not problems, "\n".join(problems)


Write = tuple[int, int, int]
"""(offset, data, byte enables) of one bus write."""


def c_driver_writes(so: ctypes.CDLL, prof: Profile) -> list[Write]:
    """The C driver's bus writes (offset, data, byte enables) for stepramp_move of a profile, from the fake bank."""
    so.stepramp_fakebus_move.argtypes = [ctypes.c_int64, *(ctypes.c_double,) * 5, ctypes.c_uint32]
    so.stepramp_fakebus_move.restype = ctypes.c_int
    so.stepramp_fakebus_log_count.restype = ctypes.c_uint32
    so.stepramp_fakebus_log_entry.argtypes = [ctypes.c_uint32, *(ctypes.POINTER(ctypes.c_uint32),) * 3]
    rc = so.stepramp_fakebus_move(prof.steps, prof.accel, prof.decel, prof.speed, prof.spr, prof.fclk, prof.prescale)
    assert rc == 0, f"{prof.name}: stepramp_move returned {rc}"
    writes: list[Write] = []
    for i in range(so.stepramp_fakebus_log_count()):
        off, value, be = ctypes.c_uint32(), ctypes.c_uint32(), ctypes.c_uint32()
        assert so.stepramp_fakebus_log_entry(i, ctypes.byref(off), ctypes.byref(value), ctypes.byref(be)) == 0
        writes.append((off.value, value.value, be.value))
    return writes


@cocotb.test(timeout_time=PROFILES_LIMIT_US, timeout_unit="us")  # the same profiles, the same limit
async def c_driver_writes_replayed(dut) -> None:
    """The C driver's own bus writes for each move, replayed on the bus: the motion registers (and, from a fresh
    driver, the segment registers cleared to 0), then START as a byte write. The move matches the model, and the
    interrupt enables in CTRL byte 1 survive the START."""
    so = ctypes.CDLL(os.environ["STEPRAMP_C_LIB"])
    tb = await PeripheralTb.started(dut)
    drv = tb.driver()
    await drv.enable_irq(done=True, error=True)
    enables = await tb.bus.read(offset("CTRL"))
    assert enables == 0x300, f"CTRL reads {enables:#x} after enabling both interrupts"
    problems: list[str] = []
    position = 0
    for name in json.loads(os.environ["PROFILE_NAMES"]):
        prof = PROFILES_BY_NAME[name]
        writes = c_driver_writes(so, prof)
        assert writes[-1] == (offset("CTRL"), 0x1, 0x1), f"{name}: the C driver's last write is {writes[-1]}"
        n_steps, n_starts = len(tb.step_edges), len(tb.start_edges)
        for addr, value, strobe in writes:
            await tb.bus.write(addr, value, strobe=strobe)
        status = await drv.wait_done(idle=lambda: tb.irq_or(20_000))
        edges = tb.edges_since(n_steps, n_starts)
        # The plan_move plan: the C plan is the same (c_plan_move checks it).
        want = model_edges(plan_move(**prof.args()))
        position += prof.steps
        dut._log.info("%s: %d writes replayed, %d edges", name, len(writes), len(edges))
        if edges != want:
            problems.append(f"{name}: {edges_differ(edges, want)}")
        if status.error or await drv.position() != position:
            problems.append(f"{name}: error={status.error} position {await drv.position()} expected {position}")
        if (ctrl := await tb.bus.read(offset("CTRL"))) != enables:
            problems.append(f"{name}: CTRL reads {ctrl:#x} after START, expected the enables {enables:#x}")
    assert not problems, "\n".join(problems)


TESTCASES = ["c_plans_through_the_bus", "c_driver_writes_replayed"]


def _build_c_library() -> Path:
    """make -C sw/c lib (a missing toolchain is a failure, not a skip)."""
    clib.build("lib")
    return C_LIB


@pytest.mark.parametrize("top", TOPS)
def test_c_plans_through_the_bus(top: str) -> None:
    """The C library's plans, programmed through the peripheral, move the motor like the model."""
    lib = _build_c_library()
    extra: dict[str, Any] = {"STEPRAMP_C_LIB": str(lib), "PROFILE_NAMES": json.dumps(PROFILE_NAMES)}
    run_cocotb(top, "test_plb_c", build_dir(f"{top}_c_plans"), testcase=TESTCASES, extra_env=extra)
