# SPDX-License-Identifier: MIT
"""Functional coverage of the core, collected with cocotb-coverage by monitors in the benches.

The bins (docs/verification.md, "Functional coverage"):

* ``stepramp.fsm.transition``: the six transitions of the STOP/ACCEL/RUN/DECEL machine of the FPGA seed, the
  three more that stops and errors add (ACCEL -> STOP, RUN -> STOP, DECEL -> STOP early is transition 4 itself),
  and DECEL -> RUN (a segment's down head into its cruise);
* ``stepramp.stop.where``: a soft and a hard stop strobe as the engine sees it: before pulse 0, in ACCEL, RUN or
  DECEL, in the last interval of a phase (the next interval is of another phase), in the first interval of a phase
  (no pulse since the phase changed), while idle; ``stepramp.stop.held``: each kind while the stepping logic holds a
  start back for DIR setup;
* ``stepramp.error.code``: every error code STATUS.ERR_CODE can report;
* ``stepramp.bus.write``: every register written while idle and while busy;
* ``stepramp.drive.mode_dir``: every DRIVE mode in both directions (a STEP pulse seen in that mode and direction);
* ``stepramp.change.taken``: a take-over (CTRL.CHANGE) in each state of the running motion: ACCEL, RUN, DECEL;
* ``stepramp.change.queue``: a queued move started in the same and in the opposite direction, and a jog through
  zero (a queued move against the direction of an endless motion, after its stop);
* ``stepramp.input.edge``: each machine input (LIMIT_NEG, LIMIT_POS, HOME, ESTOP) becoming active (its filtered
  level) with the engine in each state: STOP, ACCEL, RUN, DECEL;
* ``stepramp.limit.stop``: each limit stopping a motion towards it, soft and hard, in ACCEL, RUN and DECEL;
* ``stepramp.estop.motion``: ESTOP during every kind of motion: idle, a start held for DIR setup, a move's ACCEL,
  RUN and DECEL, and a jog (an endless segment).

Monitors watch the entities' own ports and signals (engine, stepping logic, register file), wherever they sit: the
engine bench's top, or inside stepramp_core. They wait for value changes of slow signals (state, strobes, error
flags, mode), never for every clock. Collection is on when STEPRAMP_COVERAGE_DIR names a folder: each simulation
then writes its hits there as cocotb-coverage YAML when it exits, and ``python -m stepramp.tools.coverage`` merges
them and reports (``make coverage``; ``make test`` fails when a bin stays empty).
"""

from __future__ import annotations

import atexit
import os
from pathlib import Path
from typing import Any

from cocotb_coverage.coverage import CoverPoint, coverage_db

from stepramp.board.driver import MODES, STATE_NAMES
from stepramp.board.regmap import ERROR_CODES, REGISTERS

#: Where simulations write their coverage (unset: no collection).
COVERAGE_DIR_ENV = "STEPRAMP_COVERAGE_DIR"

STOP, ACCEL, RUN, DECEL = STATE_NAMES

#: FSM transitions (from, to): the six of the seed's figure (docs/stepramp_engine.md, "FSM"), then those of stops,
#: then a segment's down head reaching its cruise (docs/algorithm.md, "Changes while moving").
TRANSITIONS: tuple[tuple[str, str], ...] = (
    (STOP, ACCEL),
    (ACCEL, RUN),
    (RUN, DECEL),
    (DECEL, STOP),
    (STOP, RUN),
    (ACCEL, DECEL),
    (ACCEL, STOP),
    (RUN, STOP),
    (DECEL, RUN),
)

#: Where a stop strobe can meet the engine.
STOP_PLACES = ("before pulse 0", ACCEL, RUN, DECEL, "last interval of a phase", "first interval of a phase", "idle")
STOP_KINDS = ("soft", "hard")
ERROR_NAMES = tuple(name for name in ERROR_CODES if name != "NONE")
REGISTER_NAMES = tuple(r.name for r in REGISTERS)
DRIVE_MODES = tuple(MODES)
QUEUE_KINDS = ("same direction", "opposite direction", "jog through zero")
INPUT_NAMES = ("LIMIT_NEG", "LIMIT_POS", "HOME", "ESTOP")
LIMIT_NAMES = INPUT_NAMES[:2]
ESTOP_MOTIONS = ("idle", "held start", ACCEL, RUN, DECEL, "jog")

_PREFIX = "stepramp"


@CoverPoint(f"{_PREFIX}.fsm.transition", xf=lambda a, b: (a, b), bins=list(TRANSITIONS))
def sample_transition(before: str, after: str) -> None:
    """A change of the engine's state port."""


@CoverPoint(
    f"{_PREFIX}.stop.where",
    xf=lambda kind, place: (kind, place),
    bins=[(k, p) for k in STOP_KINDS for p in STOP_PLACES],
)
def sample_stop(kind: str, place: str) -> None:
    """A stop strobe at the engine's port, and where in the move it lands."""


@CoverPoint(f"{_PREFIX}.stop.held", vname="kind", bins=list(STOP_KINDS))
def sample_held_stop(kind: str) -> None:
    """A stop strobe at the stepping logic while it holds a start back (DIR setup)."""


@CoverPoint(f"{_PREFIX}.error.code", vname="name", bins=list(ERROR_NAMES))
def sample_error(name: str) -> None:
    """An error flag raised with this code."""


@CoverPoint(
    f"{_PREFIX}.bus.write",
    xf=lambda name, busy: (name, "busy" if busy else "idle"),
    bins=[(n, b) for n in REGISTER_NAMES for b in ("idle", "busy")],
)
def sample_write(name: str, busy: bool) -> None:
    """A bus write to a register, with the core idle or busy."""


@CoverPoint(
    f"{_PREFIX}.drive.mode_dir",
    xf=lambda mode, direction: (mode, direction),
    bins=[(m, d) for m in DRIVE_MODES for d in (0, 1)],
)
def sample_drive(mode: str, direction: int) -> None:
    """A STEP pulse in this DRIVE mode and direction."""


_export_registered = False


@CoverPoint(f"{_PREFIX}.change.taken", vname="state", bins=[ACCEL, RUN, DECEL])
def sample_change(state: str) -> None:
    """A take-over, and the state of the interval it lands in (interval P)."""


@CoverPoint(f"{_PREFIX}.change.queue", vname="kind", bins=list(QUEUE_KINDS))
def sample_queue(kind: str) -> None:
    """A queued move started."""


@CoverPoint(
    f"{_PREFIX}.input.edge",
    xf=lambda name, state: (name, state),
    bins=[(n, s) for n in INPUT_NAMES for s in STATE_NAMES],
)
def sample_input(name: str, state: str) -> None:
    """A machine input's filtered level became active, with the engine in this state."""


@CoverPoint(
    f"{_PREFIX}.limit.stop",
    xf=lambda name, kind, state: (name, kind, state),
    bins=[(n, k, s) for n in LIMIT_NAMES for k in STOP_KINDS for s in (ACCEL, RUN, DECEL)],
)
def sample_limit(name: str, kind: str, state: str) -> None:
    """A limit stopped the motion towards it (soft or hard) in this state."""


@CoverPoint(f"{_PREFIX}.estop.motion", vname="motion", bins=list(ESTOP_MOTIONS))
def sample_estop(motion: str) -> None:
    """ESTOP's filtered level became active during this kind of motion."""


def enabled() -> bool:
    """Is coverage collected in this process (STEPRAMP_COVERAGE_DIR set)?"""
    return bool(os.environ.get(COVERAGE_DIR_ENV))


def _export() -> None:
    folder = Path(os.environ[COVERAGE_DIR_ENV])
    folder.mkdir(parents=True, exist_ok=True)
    coverage_db.export_to_yaml(str(folder / f"cov_{os.getpid()}_{os.urandom(4).hex()}.yml"))


def _register_export() -> None:
    global _export_registered
    if not _export_registered:
        atexit.register(_export)
        _export_registered = True


def _int(handle: Any) -> int | None:
    """A signal's value as an integer (None while it holds X/U/Z)."""
    value = handle.value
    return int(value) if value.is_resolvable else None


def _find(parent: Any, name: str) -> Any | None:
    """A child handle by name, or None (a netlist or another top may not have it)."""
    try:
        return getattr(parent, name)
    except AttributeError:
        return None


async def _watch_engine(engine: Any) -> None:
    """State transitions of the engine."""
    state = engine.state
    before = _int(state)
    while True:
        await state.value_change
        after = _int(state)
        if before is not None and after is not None:
            sample_transition(STATE_NAMES[before], STATE_NAMES[after])
        before = after


class _PhaseTracker:
    """How many pulses since the engine's state last changed, and from which state (for the stop bins)."""

    def __init__(self, engine: Any) -> None:
        self.engine = engine
        self.entered_from: int | None = None
        self.count_at_change: int | None = None

    async def run(self) -> None:
        state = self.engine.state
        before = _int(state)
        while True:
            await state.value_change
            self.entered_from = before
            self.count_at_change = _int(self.engine.step_count)
            before = _int(state)

    def place(self) -> str:
        """Where a stop strobe meets the engine now."""
        eng = self.engine
        if _int(eng.busy) != 1:
            return "idle"
        state = _int(eng.state)
        if state is None or state == 0:
            return "before pulse 0"
        nxt_ok, nxt_state = _find(eng, "nxt_ok"), _find(eng, "nxt_state")
        if state in (1, 2) and nxt_ok is not None and nxt_state is not None and _int(nxt_ok) == 1:
            nxt = _int(nxt_state)
            if nxt is not None and nxt not in (0, state):
                return "last interval of a phase"
        if (
            state in (2, 3)
            and self.entered_from in (1, 2)
            and self.count_at_change is not None
            and _int(eng.step_count) == self.count_at_change
        ):
            return "first interval of a phase"
        return STATE_NAMES[state]


async def _watch_stop(strobe: Any, kind: str, tracker: _PhaseTracker) -> None:
    from cocotb.triggers import RisingEdge

    while True:
        await RisingEdge(strobe)
        sample_stop(kind, tracker.place())


async def _watch_error(flag: Any, code: Any) -> None:
    """An error flag rising, or its code changing while the flag is up: sample the code."""
    from cocotb.triggers import First

    names = {c: name for name, (c, _) in ERROR_CODES.items() if c != 0}
    while True:
        await First(flag.value_change, code.value_change)
        value = _int(code)
        if _int(flag) == 1 and value in names:
            sample_error(names[value])


async def _watch_drive(stepper: Any) -> None:
    """(mode, direction) of STEP pulses: after a bin is hit, wait for mode or DIR to change instead of every pulse."""
    from cocotb.triggers import First, RisingEdge

    modes = {code: name for name, code in MODES.items()}
    while True:
        await RisingEdge(stepper.step)
        mode, direction = _int(stepper.mode), _int(stepper.dir)
        if mode in modes and direction is not None:
            sample_drive(modes[mode], direction)
        await First(stepper.mode.value_change, stepper.dir.value_change)


async def _watch_held(stepper: Any, kind: str) -> None:
    from cocotb.triggers import RisingEdge

    strobe = getattr(stepper, f"{kind}_stop")
    while True:
        await RisingEdge(strobe)
        if _int(stepper.gate_busy) == 1 and _int(stepper.eng_busy) == 0:
            sample_held_stop(kind)


def _has(handle: Any, *names: str) -> bool:
    """Does the handle have all these signals (a netlist or another top may lack some)?"""
    return all(_find(handle, name) is not None for name in names)


def watch_engine(engine: Any) -> None:
    """Start the engine's monitors (state transitions, stops, errors) on a stepramp_engine handle."""
    if not enabled() or not _has(engine, "state", "busy", "step_count", "soft_stop", "hard_stop", "error", "err_code"):
        return
    import cocotb

    _register_export()
    tracker = _PhaseTracker(engine)
    cocotb.start_soon(_watch_engine(engine))
    cocotb.start_soon(tracker.run())
    for kind in STOP_KINDS:
        cocotb.start_soon(_watch_stop(getattr(engine, f"{kind}_stop"), kind, tracker))
    cocotb.start_soon(_watch_error(engine.error, engine.err_code))


def watch_stepper(stepper: Any) -> None:
    """Start the stepping logic's monitors (mode x direction, stops while a start is held) on a stepramp_stepper."""
    if not enabled() or not _has(stepper, "step", "dir", "mode", "soft_stop", "hard_stop", "gate_busy", "eng_busy"):
        return
    import cocotb

    _register_export()
    cocotb.start_soon(_watch_drive(stepper))
    for kind in STOP_KINDS:
        cocotb.start_soon(_watch_held(stepper, kind))


async def _watch_change(engine: Any) -> None:
    from cocotb.triggers import RisingEdge

    while True:
        await RisingEdge(engine.tk)
        state = _int(engine.state)
        if state in (1, 2, 3):
            sample_change(STATE_NAMES[state])


async def _watch_queue(regfile: Any, engine: Any) -> None:
    """A queued move starts at the engine's done: its direction (STEPS' sign) against the motion that ended."""
    from cocotb.triggers import ReadOnly, RisingEdge

    while True:
        await RisingEdge(regfile.eng_done)
        await ReadOnly()
        if _int(regfile.q_pend) != 1 or _int(regfile.eng_error) != 0:
            continue
        new_dir, old_dir = _int(regfile.direction), _int(regfile.eng_dir)
        if new_dir == old_dir:
            sample_queue("same direction")
        elif _int(engine.p_endless) == 1:
            sample_queue("jog through zero")
        else:
            sample_queue("opposite direction")


async def _watch_inputs(inputs: Any, regfile: Any, engine: Any, stepper: Any) -> None:
    """The machine inputs' activation strobes (stepramp_inputs.rise_r), and the limit stops (the register file's
    lim_hit rising): what the engine was doing."""
    from cocotb.triggers import First, ReadOnly, RisingEdge

    rise, hit = inputs.rise_r, regfile.lim_hit
    while True:
        await First(rise.value_change, RisingEdge(hit))
        await ReadOnly()
        state, busy = _int(engine.state), _int(engine.busy)
        if state is None:
            continue
        name = STATE_NAMES[state]
        strobes = _int(rise) or 0
        for bit, input_name in enumerate(INPUT_NAMES):
            if strobes >> bit & 1:
                sample_input(input_name, name)
        if strobes >> 3 & 1:
            if busy != 1:
                sample_estop("held start" if _int(stepper.gate_busy) == 1 else "idle")
            elif _int(engine.p_endless) == 1:
                sample_estop("jog")
            elif state:
                sample_estop(name)
        if _int(hit) == 1 and state:
            hard = _int(regfile.hard_stop_r) == 1  # (raised with lim_hit, at the same edge)
            sample_limit(LIMIT_NAMES[_int(regfile.mv_dir) == 0], "hard" if hard else "soft", name)
        await RisingEdge(inputs.clk)


def watch_core(core: Any) -> None:
    """All monitors on a stepramp_core handle: its engine, stepping logic and register file (the error codes only
    the register file raises: STEPS, POS_BUSY, CFG_BUSY)."""
    if not enabled():
        return
    import cocotb

    engine, stepper, regfile = (_find(core, n) for n in ("engine_inst", "stepper_inst", "regfile_inst"))
    inputs = _find(core, "inputs_inst")
    if engine is not None:
        watch_engine(engine)
    if stepper is not None:
        watch_stepper(stepper)
    if regfile is not None and _has(regfile, "error_flag", "err_code_r"):
        _register_export()
        cocotb.start_soon(_watch_error(regfile.error_flag, regfile.err_code_r))
    if engine is not None and _has(engine, "tk", "state"):
        cocotb.start_soon(_watch_change(engine))
    if (
        engine is not None
        and regfile is not None
        and _has(regfile, "eng_done", "q_pend", "eng_error", "direction", "eng_dir")
        and _has(engine, "p_endless")
    ):
        cocotb.start_soon(_watch_queue(regfile, engine))
    if (
        inputs is not None
        and regfile is not None
        and engine is not None
        and stepper is not None
        and _has(inputs, "rise_r", "clk")
        and _has(regfile, "lim_hit", "mv_dir", "hard_stop_r")
        and _has(engine, "state", "busy", "p_endless")
    ):
        cocotb.start_soon(_watch_inputs(inputs, regfile, engine, stepper))


class CoveredBus:
    """A register access (read / write coroutines) that samples every write with the core's busy."""

    def __init__(self, bus: Any, busy: Any) -> None:
        self.bus = bus
        self.busy = busy
        self.names = {r.offset: r.name for r in REGISTERS}

    async def read(self, addr: int) -> int:
        return int(await self.bus.read(addr))

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None:
        busy = _int(self.busy) == 1
        await self.bus.write(addr, value, strobe)
        name = self.names.get(addr & ~3)
        if name is not None:
            sample_write(name, busy)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.bus, name)


def watch_coverage(core: Any, bus: Any) -> Any:
    """watch_core(core), and the bench's register access wrapped so that its writes are sampled (the bus itself when
    coverage is off)."""
    if not enabled():
        return bus
    watch_core(core)
    busy = _find(core, "busy")
    return bus if busy is None else CoveredBus(bus, busy)
