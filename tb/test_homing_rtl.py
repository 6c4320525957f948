# SPDX-License-Identifier: MIT
"""Homing on the RTL, both tops, against a mechanical model with bouncing switches (stepramp.sim.mechanics).

The carriage follows STEP/DIR; the home switch is active for carriage positions <= HOME_AT, so the first position
off it is HOME_AT + 1 (the physics). Each run puts the carriage at a random place (by hand, the motor off: off the
switch, or on it now and then), sets POSITION to a random value, and homes with offset OFFSET
(stepramp.board.homing); every switch crossing bounces with a pattern from the run's seed (intervals shorter than
the input filter, some close to it). After the run POSITION must read OFFSET exactly where the carriage is at
HOME_AT + 1: the zero found, in carriage steps, is the same on every run (spread 0) and equals the physics. Checked
besides, per run: the seek's latch lies inside the switch by no more than the filter and the bounce allow at the seek
speed; every latch's pin_time (LATCH_TIME - N - 2) is the clock edge after which the carriage's pin last changed,
within one clock, on TIME's axis as a TIME read through the driver (TIME_LO, then TIME_HI) shows it.

- python_homing: HOMING_RUNS runs (12 per top; 24 over both) with the Python driver.
- c_homing: C_HOMING_RUNS runs (4 per top) with the C driver's stepramp_home (sw/c/src/stepramp_homing.c) on the same
  core, through cocotb's bridge (stepramp.sim.cdriver).
- limit_homing (PLB-like top): LIMIT_NEG used as home, 3 runs: the core's own limit stop (hard, then soft) ends the
  seek; from off the limit and from on it.

Seeds: run k uses seed HOMING_SEED * 1000 + k in python_homing and HOMING_SEED * 1000 + 500 + k in c_homing
(HOMING_SEED 16 unless set), printed with its start, bounce counts and zero. Every run starts from the same state at
the same clock phase, so `HOMING_SEED=S HOMING_ONLY=k pytest tb/test_homing_rtl.py` replays run k of each test alone,
edge for edge.
"""

from __future__ import annotations

import ctypes
import dataclasses
import os
import random
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from cocotb.triggers import ClockCycles

from peripheral_tb import TOPS, PeripheralTb
from stepramp.board.driver import Inputs, Latch, StepRamp
from stepramp.board.homing import LATCH_MARGIN, Homing, home
from stepramp.sim.cdriver import CDriver, c_struct
from stepramp.sim.clocking import CLK_PERIOD_PS, Cycles
from stepramp.sim.mechanics import Bounce, Carriage, Crossing, Switch
from tbutil import REPO, build_dir, cocotb, env_int, now_cycles, run_with_c_lib

#: The driver's view of the clock and motor (the bench's clock runs at 100 MHz; only clock counts matter).
FCLK, SPR, PRESCALE = 1e6, 200.0, 1
#: The input filter, clocks, and the switches' bounce (intervals below the filter, some near it).
FILTER = 60
BOUNCE = Bounce(filter_clocks=FILTER, max_bounces=3)
#: The home switch: active for carriage positions <= HOME_AT.
HOME_AT = -40
SWITCH = Switch("home", at=HOME_AT, side=-1)
OFFSET = 1000
#: Seek at one step per 100 clocks, ramps of about 8 steps; release at one step per 500 clocks (the exact bound is
#: FILTER + settle + LATCH_MARGIN = 60 + 352 + 5 = 417), ramps of about 2 steps.
ALPHA = 2 * 3.141592653589793 / SPR
SEEK_SPEED = ALPHA * FCLK / 100
LATCH_SPEED = ALPHA * FCLK / 500
CFG = Homing(
    seek_speed=SEEK_SPEED,
    seek_accel=SEEK_SPEED**2 / (2 * 8 * ALPHA),
    latch_speed=LATCH_SPEED,
    latch_accel=LATCH_SPEED**2 / (2 * 2 * ALPHA),
    switch="home",
    direction=-1,
    offset=OFFSET,
    settle_clocks=BOUNCE.settle_clocks,
    max_travel=2000,
)
#: Where runs start: carriage positions off the switch, and on it.
START_OFF = (HOME_AT + 1, HOME_AT + 50)
START_ON = (HOME_AT - 30, HOME_AT)
#: Clocks the driver waits between two STATUS polls.
POLL_IDLE = 200
#: Runs start on a multiple of this many clocks.
ALIGN = 1000

SEED = env_int("HOMING_SEED", 16)
RUNS = env_int("HOMING_RUNS", 12)
C_RUNS = env_int("C_HOMING_RUNS", 4)
ONLY = os.environ.get("HOMING_ONLY")


@dataclass
class Run:
    """One homing run's inputs and what it found, in carriage steps."""

    seed: int
    start: int
    position0: int
    zero: int = 0
    clocks: int = 0  # the run's length, clocks (a fingerprint of its timing, for replays)
    seek_depth: int = 0
    on_switch: bool = False
    bounces: int = 0


async def bench(dut: Any) -> tuple[PeripheralTb, StepRamp, Carriage]:
    """The top, reset, with the inputs configured (filter) and a carriage on the home pin."""
    tb = await PeripheralTb.started(dut)
    drv = tb.driver({"fclk": FCLK, "spr": SPR, "prescale": PRESCALE})
    await drv.check_id()
    await drv.configure_inputs(Inputs(filter=FILTER))
    carriage = Carriage(dut.step, dut.dir, {"home": dut.home}, [SWITCH], 0, BOUNCE, seed=SEED, period_ps=CLK_PERIOD_PS)
    carriage.start()
    return tb, drv, carriage


def runs(count: int, salt: int) -> list[Run]:
    """The runs of a test: seeds, start positions (every fourth run on the switch, the others off it) and POSITION
    before homing."""
    out = []
    for k in range(count):
        seed = SEED * 1000 + salt + k
        rng = random.Random(seed)
        start = rng.randint(START_ON[0], START_ON[1]) if k % 4 == 3 else rng.randint(*START_OFF)
        out.append(Run(seed, start, rng.randint(-100_000, 100_000)))
    if ONLY is not None:
        out = [r for r in out if r.seed % 1000 - salt == int(ONLY)]
    return out


def last_crossing(carriage: Carriage, first: int, active: bool, pin: str = "home") -> Crossing:
    """The last crossing of a switch's edge (by its pin) into `active` since crossing index `first`."""
    found = [c for c in carriage.crossings[first:] if c.pin == pin and c.active == active]
    assert found, f"the carriage never crossed the switch edge to {'active' if active else 'released'}"
    return found[-1]


def time_origin(latch: Latch, crossing: Crossing) -> int:
    """The clock edge r that TIME counts from, as this latch implies it: pin_time + r is the clock edge after which
    the pin last changed (docs/algorithm.md, "TIME and the latch")."""
    return crossing.last_change_ps // CLK_PERIOD_PS - latch.pin_time


async def time_origin_bounds(read_time: Any) -> tuple[int, int]:
    """The clock edge r TIME counts from (TIME = k - r after edge k), bracketed by one read of TIME through a
    driver: the register was sampled at an edge between the edges before and after the read (within one)."""
    before = now_cycles()
    value = await read_time()
    after = now_cycles()
    return before - value - 1, after - value


def check_origins(origins: set[int], bounds: tuple[int, int], problems: list[str]) -> None:
    """Every latch implies the same TIME origin (within one clock: the pin is asynchronous), and it is the one a TIME
    read gives: pin_time = LATCH_TIME - N - 2 is the pin's own edge on TIME's axis."""
    if not origins:
        return
    if max(origins) - min(origins) > 1:
        problems.append(f"the latches imply different TIME origins {sorted(origins)} (pin_time off the pin's edge)")
    if not (bounds[0] <= min(origins) and max(origins) <= bounds[1]):
        problems.append(
            f"the latches imply TIME origins {sorted(origins)}, a TIME read gives {bounds[0]} .. {bounds[1]}"
        )


def report(dut: Any, top: str, who: str, done: list[Run]) -> None:
    """The runs' summary: the zeros found and their spread, the seek latch's depths."""
    if not done:
        return
    zeros = [r.zero for r in done]
    depths = [r.seek_depth for r in done]
    dut._log.info(
        "%s %s homing: %d runs, zero (carriage step at POSITION %d) %s, spread %d step(s); switch edge at %d; "
        "seek latch depth into the switch %d .. %d steps",
        top,
        who,
        len(done),
        OFFSET,
        sorted(set(zeros)),
        max(zeros) - min(zeros),
        SWITCH.first_off,
        min(depths),
        max(depths),
    )


def check_all_runs(
    dut: Any, top: str, who: str, done: list[Run], origins: set[int], bounds: tuple[int, int], problems: list[str]
) -> None:
    """After one driver's runs: their summary (report), the TIME origins their latches imply (check_origins against
    the bounds of a TIME read), a run done unless HOMING_ONLY selected none, and no problem."""
    report(dut, top, who, done)
    dut._log.info("TIME origin: %s from the latches, %d .. %d from a TIME read", sorted(origins), *bounds)
    check_origins(origins, bounds, problems)
    assert done or ONLY is not None, "no run selected"
    assert not problems, "\n".join(problems)


async def place(tb: PeripheralTb, carriage: Carriage, run: Run) -> None:
    """Put the carriage at the run's start (the motor off), seed its bounce, let the filter settle, and go on at the
    next multiple of ALIGN clocks: every run starts in the same state and phase, so a seed replays alone."""
    carriage.rng.seed(run.seed)
    carriage.place(run.start)
    await ClockCycles(tb.clk, 2 * FILTER + 10)
    await ClockCycles(tb.clk, ALIGN - now_cycles() % ALIGN)


def check_run(run: Run, carriage: Carriage, position: int, problems: list[str], switch: Switch = SWITCH) -> None:
    """The zero in carriage steps: where POSITION reads OFFSET. It must be the switch's first position off it."""
    run.zero = carriage.position - (position - OFFSET)
    if run.zero != switch.first_off:
        problems.append(
            f"seed {run.seed} (start {run.start}): POSITION {OFFSET} is at carriage step {run.zero}, "
            f"the switch edge is at {switch.first_off}"
        )


def run_checks(
    dut: Any,
    run: Run,
    carriage: Carriage,
    first: int,
    shift0: int,
    left: Latch | None,
    seek: Latch,
    release: Latch,
    position: int,
    origins: set[int],
    problems: list[str],
    switch: Switch = SWITCH,
) -> None:
    """One run against the physics: the zero, where the seek latched, whether the homing left the switch first (it
    must exactly when the run started on it), and the TIME origin each latch's pin_time implies (from the carriage's
    crossings since index `first`); logs the run."""
    run.clocks = now_cycles() - run.clocks
    run.seek_depth = switch.side * (seek.position + shift0 - switch.at)
    if not 0 <= run.seek_depth <= seek_depth_bound():
        problems.append(f"seed {run.seed}: the seek latched {run.seek_depth} steps inside the switch")
    origins.add(time_origin(seek, last_crossing(carriage, first, True, switch.pin)))
    origins.add(time_origin(release, last_crossing(carriage, first, False, switch.pin)))
    run.on_switch = left is not None
    if run.on_switch != switch.active(run.start):
        problems.append(f"seed {run.seed}: started at {run.start}, the homing left the switch: {run.on_switch}")
    if release.position + shift0 != switch.first_off:
        problems.append(f"seed {run.seed}: the release latched carriage step {release.position + shift0}")
    run.bounces = sum(len(c.intervals) // 2 for c in carriage.crossings[first:])
    check_run(run, carriage, position, problems, switch)
    dut._log.info(
        "seed %d: start %d, POSITION %d -> %d, seek latch %d steps in%s, %d crossings (%d bounces), %d clocks, zero %d",
        run.seed,
        run.start,
        run.position0,
        position,
        run.seek_depth,
        " (started on the switch)" if run.on_switch else "",
        len(carriage.crossings) - first,
        run.bounces,
        run.clocks,
        run.zero,
    )


def seek_depth_bound() -> int:
    """How far inside the switch the seek's latch may lie at the seek speed: the pulses within filter + settle +
    margin clocks of the crossing, at one pulse per 100 clocks or slower."""
    return -(-(FILTER + BOUNCE.settle_clocks + LATCH_MARGIN) // 100)


# Limit: measured 1.73 / 1.78 ms of simulated time for 12 runs (PLB / AXI), about 0.15 ms a run; 0.5 ms a run.
@cocotb.test(timeout_time=500 * max(RUNS, 1), timeout_unit="us")
async def python_homing(dut) -> None:
    """HOMING_RUNS runs of stepramp.board.homing.home: every one finds the switch edge at POSITION OFFSET."""
    tb, drv, carriage = await bench(dut)
    bounds = await time_origin_bounds(drv.time)
    problems: list[str] = []
    origins: set[int] = set()
    done: list[Run] = []
    for run in runs(RUNS, 0):
        await place(tb, carriage, run)
        await drv.set_position(run.position0)
        first, run.clocks = len(carriage.crossings), now_cycles()
        shift0 = carriage.position - run.position0  # carriage step = POSITION + shift0 before homing
        result = await home(drv, CFG, idle=lambda: Cycles(tb.clk, POLL_IDLE))
        position = await drv.position()
        run_checks(
            dut, run, carriage, first, shift0, result.left, result.seek, result.release, position, origins, problems
        )
        done.append(run)
    check_all_runs(dut, tb.top, "Python", done, origins, bounds, problems)
    assert any(r.on_switch for r in done) or ONLY is not None or RUNS < 4, "no run started on the switch"
    assert any(r.bounces for r in done) or len(done) < 4, "no switch bounced"
    # the seek's fast latch moves with the bounce: the same check on it would fail, the release's exactness is no gift
    assert len({r.seek_depth for r in done}) > 1 or len(done) < 4, "the seek latched at the same depth on every run"
    tb.finish()


#: LIMIT_NEG used as home: active for carriage steps <= LIMIT_AT (a travel end), the limit stopping the seek itself.
LIMIT_AT = -30
LIMIT = Switch("limit_neg", at=LIMIT_AT, side=-1)


# Limit: measured 0.40 ms of simulated time for 3 runs; 0.5 ms a run.
@cocotb.test(timeout_time=1500, timeout_unit="us")
async def limit_homing(dut) -> None:
    """LIMIT_NEG used as home (Homing(switch="limit_neg")): the core's own limit stop ends the seek (error LIMIT,
    expected) -- a hard stop with LIMIT_HARD (no overshoot to come back from) or a soft stop -- and the zero is the
    limit's first position off it, from off the limit and from on it."""
    tb = await PeripheralTb.started(dut)
    drv = tb.driver({"fclk": FCLK, "spr": SPR, "prescale": PRESCALE})
    await drv.check_id()
    carriage = Carriage(
        dut.step, dut.dir, {"limit_neg": dut.limit_neg}, [LIMIT], 0, BOUNCE, seed=SEED, period_ps=CLK_PERIOD_PS
    )
    carriage.start()
    cfg = dataclasses.replace(CFG, switch="limit_neg")
    problems: list[str] = []
    cases = [(True, LIMIT_AT + 40), (False, LIMIT_AT + 25), (False, LIMIT_AT - 6)]  # (LIMIT_HARD, start)
    for k, (hard, start) in enumerate(cases):
        run = Run(SEED * 1000 + 800 + k, start, -7 * k)
        await drv.configure_inputs(Inputs(filter=FILTER, limit_hard=hard))
        await place(tb, carriage, run)
        await drv.set_position(run.position0)
        first, run.clocks = len(carriage.crossings), now_cycles()
        result = await home(drv, cfg, idle=lambda: Cycles(tb.clk, POLL_IDLE))
        run_checks(
            dut,
            run,
            carriage,
            first,
            start - run.position0,
            result.left,
            result.seek,
            result.release,
            await drv.position(),
            set(),
            problems,
            LIMIT,
        )
        status = await drv.status()
        if status.error or status.done or status.busy:
            problems.append(f"seed {run.seed}: STATUS after the homing {status}")
    assert not problems, "\n".join(problems)
    tb.finish()


def c_types(cdrv: CDriver) -> tuple[Any, Any, Any]:
    """stepramp_inputs_t, stepramp_homing_t and stepramp_homing_result_t as ctypes structures, and the signatures of
    the C calls this test makes beyond CDriver's."""
    c_dir = REPO / "sw" / "c" / "src"
    inputs_t = c_struct(c_dir / "stepramp.h", "stepramp_inputs_t")
    latch_t = c_struct(c_dir / "stepramp.h", "stepramp_latch_t")
    homing_t = c_struct(c_dir / "stepramp_homing.h", "stepramp_homing_t")
    result_t = c_struct(c_dir / "stepramp_homing.h", "stepramp_homing_result_t", {"stepramp_latch_t": latch_t})
    dev = ctypes.POINTER(cdrv.dev_t)
    cdrv.so.stepramp_configure_inputs.argtypes = [dev, ctypes.POINTER(inputs_t)]
    cdrv.so.stepramp_configure_inputs.restype = ctypes.c_int
    cdrv.so.stepramp_home.argtypes = [dev, ctypes.POINTER(homing_t), ctypes.POINTER(result_t)]
    cdrv.so.stepramp_home.restype = ctypes.c_int
    cdrv.so.stepramp_time.argtypes = [dev]
    cdrv.so.stepramp_time.restype = ctypes.c_uint64
    return inputs_t, homing_t, result_t


def c_latch(latch: Any) -> Latch:
    return Latch(latch.position, latch.time, latch.pin_time)


# Limit: measured 0.54 / 0.56 ms of simulated time for 4 runs (PLB / AXI), about 0.14 ms a run; 0.5 ms a run.
@cocotb.test(timeout_time=500 * max(C_RUNS, 1), timeout_unit="us")
async def c_homing(dut) -> None:
    """C_HOMING_RUNS runs of the C driver's stepramp_home (sw/c/src/stepramp_homing.c) on the same core and mechanics:
    the same physics as python_homing."""
    tb = await PeripheralTb.started(dut)
    cdrv = CDriver(Path(os.environ["STEPRAMP_C_CB_LIB"]), tb.bus, idle=lambda: Cycles(tb.clk, POLL_IDLE))
    inputs_t, homing_t, result_t = c_types(cdrv)
    assert await cdrv.dev_call("stepramp_init", cdrv.base, FCLK, SPR, PRESCALE) == 0
    rc = await cdrv.dev_call("stepramp_configure_inputs", ctypes.byref(inputs_t(filter=FILTER, limit_enable=1)))
    assert rc == 0, await cdrv.call("stepramp_strresult", rc)
    bounds = await time_origin_bounds(lambda: cdrv.dev_call("stepramp_time"))
    args = {name: getattr(CFG, name) for name, _ in homing_t._fields_ if name not in ("sw", "max_polls")}
    cfg = homing_t(sw=1, max_polls=1_000_000, **args)  # STEPRAMP_LATCH_HOME
    carriage = Carriage(dut.step, dut.dir, {"home": dut.home}, [SWITCH], 0, BOUNCE, seed=SEED, period_ps=CLK_PERIOD_PS)
    carriage.start()
    problems: list[str] = []
    origins: set[int] = set()
    done: list[Run] = []
    for run in runs(C_RUNS, 500):
        await place(tb, carriage, run)
        await cdrv.dev_call("stepramp_set_position", run.position0)
        first, run.clocks = len(carriage.crossings), now_cycles()
        shift0 = carriage.position - run.position0
        res = result_t()
        rc = await cdrv.dev_call("stepramp_home", ctypes.byref(cfg), ctypes.byref(res))
        assert rc == 0, f"seed {run.seed}: stepramp_home: {await cdrv.call('stepramp_strresult', rc)}"
        position = await cdrv.dev_call("stepramp_position")
        assert res.position == position
        left = c_latch(res.left) if res.left_valid else None
        run_checks(
            dut,
            run,
            carriage,
            first,
            shift0,
            left,
            c_latch(res.seek),
            c_latch(res.release),
            position,
            origins,
            problems,
        )
        done.append(run)
    check_all_runs(dut, tb.top, "C", done, origins, bounds, problems)
    tb.finish()


@pytest.mark.parametrize("top", TOPS)
def test_homing(top: str) -> None:
    """The Python and the C driver's homing through each top (the C library is built here: make -C sw/c lib); a limit
    used as home on the PLB-like top (the inputs' logic is the same core behind either bus)."""
    tests = ["python_homing", "c_homing"] + (["limit_homing"] if top == "stepramp_plb" else [])
    run_with_c_lib(top, "test_homing_rtl", build_dir(f"{top}_homing"), testcase=tests)
