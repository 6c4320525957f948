# SPDX-License-Identifier: MIT
"""The drivers' machine-input calls and the homing (stepramp.board.homing, sw/c/src/stepramp_homing.c) without a
simulator.

- The Python driver's input calls on a fake register bank: the words of docs/registers.md, the byte lanes that keep
  the other sticky flags, the latch's pin_time, TIME read LO then HI, the E-stop clear, the reasons for bad input.
- Homing.check: the arguments and the latch-speed bound (filter + settle + LATCH_MARGIN clocks per step).
- Both drivers' homing on the C fake register bank (libstepramp.so) with a model of the core and the axis behind it
  (the bank's hook; the model's rules are those of sw/c/tests/test_stepramp_homing.c): a switch whose filtered edge
  trails the crossing by `delay` clocks, so that at T clocks per step the latch lands floor(delay / T) steps past it.
  From many starts and delays the zero is the switch's first position off it (the physics), and the Python and the C
  driver write the same words to the same registers in the same order.
"""

from __future__ import annotations

import asyncio
import ctypes
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from test_c_driver import CDev, CFakeBus
from test_driver import FakeBank

from c_abi import struct_fields
from stepramp.board.driver import Inputs, Latch, Status, StepRamp, StepRampError
from stepramp.board.homing import LATCH_MARGIN, Homing, home
from stepramp.board.regmap import ERROR_CODES, REGISTERS_BY_NAME, offset
from stepramp.tools import clib


def run(coro: Any) -> Any:
    return asyncio.run(coro)


def bit(reg: str, field: str) -> int:
    return 1 << REGISTERS_BY_NAME[reg].field(field).lsb


# ---- the Python driver's input calls ---------------------------------------------------------------------------


def test_configure_inputs_words_and_reasons() -> None:
    bank = FakeBank()
    drv = StepRamp(bank, fclk=1e6, spr=200.0)
    inputs = Inputs(150, frozenset({"home", "estop"}), True, True, "limit_pos", False, True)
    run(drv.configure_inputs(inputs))
    # docs/registers.md: POL_* bits 3:0, LIMIT_EN 4, LIMIT_HARD 5, LATCH_SRC 9:8 (3: LIMIT_POS), ON_RELEASE 11
    assert bank.log == [(0x90, 150, 0xF), (0x94, 0x4 | 0x8 | 0x10 | 0x20 | 3 << 8 | 1 << 11, 0xF)]
    assert drv.inputs == inputs and inputs.filter_clocks == 150 and Inputs().filter_clocks == 1
    assert Inputs(latch_source="none", latch_on_active=True).cfg_word() == 0x10, "no source: no edge bits"
    bank.log.clear()
    for bad, reason in (
        (Inputs(filter=1 << 20), r"filter must be an integer number of clocks in 0 \.\. 1048575"),
        (Inputs(filter=-1), "filter"),
        (Inputs(filter=True), "filter"),  # type: ignore[arg-type]
        (Inputs(active_low=frozenset({"home", "door"})), r"unknown inputs \['door'\]"),
        (Inputs(latch_source="index"), "latch_source must be one of"),
        (Inputs(latch_source="home"), "needs latch_on_active, latch_on_release or both"),
    ):
        with pytest.raises(ValueError, match=reason):
            run(drv.configure_inputs(bad))
    assert bank.log == [], "nothing written on bad input"
    assert drv.inputs == inputs


def test_latch_arm_read_and_time() -> None:
    bank = FakeBank()
    drv = StepRamp(bank, fclk=1e6, spr=200.0)
    run(drv.configure_inputs(Inputs(filter=50, active_low=frozenset({"limit_neg"}))))
    bank.log.clear()
    run(drv.arm_latch("home", on_active=True, on_release=True))
    assert bank.log == [(0x94, 0x1 | 0x10 | 1 << 8 | 1 << 10 | 1 << 11, 0xF), (0x08, 1 << 24, 0x8)]
    with pytest.raises(ValueError, match="latch_source must be one of"):
        run(drv.arm_latch("door"))
    bank.regs[offset("STATUS")] = 0
    assert run(drv.latch()) is None
    bank.regs[offset("STATUS")] = bit("STATUS", "LATCHED")
    bank.regs[offset("LATCH_POS")] = (-123) & 0xFFFF_FFFF
    bank.regs[offset("LATCH_TIME_LO")] = 0x10
    bank.regs[offset("LATCH_TIME_HI")] = 2
    assert run(drv.latch()) == Latch(-123, 0x2_0000_0010, 0x2_0000_0010 - 50 - 2)
    drv.inputs = Inputs(filter=0)  # 0 acts as 1
    assert run(drv.read_latch()).pin_time == 0x2_0000_0010 - 1 - 2

    class TimeBank(FakeBank):
        """TIME_LO's read copies the high word to TIME_HI, as the core does."""

        async def read(self, addr: int) -> int:
            if addr == offset("TIME_LO"):
                self.regs[offset("TIME_HI")] = 0x1234
            return await super().read(addr)

    tbank = TimeBank()
    tbank.regs[offset("TIME_LO")] = 0x5678_9ABC
    tbank.regs[offset("TIME_HI")] = 0xDEAD  # stale: a driver reading HI first gets it
    assert run(StepRamp(tbank, 1e6, 200.0).time()) == 0x1234_5678_9ABC


def test_events_estop_and_irq_enables() -> None:
    bank = FakeBank()
    drv = StepRamp(bank, fclk=1e6, spr=200.0)
    run(drv.clear_events(limit_neg=False, limit_pos=True, home=True))
    assert bank.log == [(0x08, 1 << 21 | 1 << 22, 0x4)], "byte 2 of STATUS only"
    bank.log.clear()
    run(drv.clear_events(False, False, False))
    assert bank.log == []
    bank.status_script = [bit("STATUS", "ESTOP_FAULT") | bit("STATUS", "ESTOP")]
    with pytest.raises(StepRampError, match="ESTOP input is still active"):
        run(drv.clear_estop())
    assert bank.log == [(0x08, 1 << 23, 0x4)], "no ENABLE while the fault stays"
    bank.log.clear()
    bank.status_script = [0]
    run(drv.clear_estop())
    assert bank.log == [(0x08, 1 << 23, 0x4), (0x04, 1 << 16, 0x4)]
    bank.log.clear()
    run(drv.enable_input_irq(home=True, estop=True, latch=True, done=False))
    assert bank.log == [(0x04, 1 << 9 | 1 << 12 | 1 << 13 | 1 << 14, 0x2)]


def test_status_decodes_the_inputs() -> None:
    st = Status.decode(0x015A_0040)
    assert (st.limit_neg, st.limit_pos, st.home, st.estop) == (False, True, False, True)
    assert (st.limit_neg_ev, st.limit_pos_ev, st.home_ev, st.estop_fault) == (True, False, True, False)
    assert st.latched and st.dir_fault and not st.done
    assert st.level("limit_pos") and not st.level("home")
    with pytest.raises(ValueError, match="pin must be one of"):
        st.level("door")
    st = Status.decode(0x00A5_0000)
    assert (st.limit_neg, st.home, st.limit_pos_ev, st.estop_fault, st.latched) == (True, True, True, True, False)


# ---- Homing.check -----------------------------------------------------------------------------------------------

FCLK, SPR = 1e6, 200.0
ALPHA = 2 * math.pi / SPR


def homing(**kw: Any) -> Homing:
    seek = ALPHA * FCLK / 100
    latch = ALPHA * FCLK / 500
    args: dict[str, Any] = {
        "seek_speed": seek,
        "seek_accel": seek**2 / (2 * 12 * ALPHA),
        "latch_speed": latch,
        "latch_accel": latch**2 / (2 * 2 * ALPHA),
        "settle_clocks": 300,
        "max_travel": 5000,
    }
    return Homing(**(args | kw))


def test_homing_check_reasons() -> None:
    homing().check(FCLK, SPR, 1, 60)
    for kw, reason in (
        ({"switch": "door"}, "switch must be one of"),
        ({"direction": 0}, "direction must be -1 or"),
        ({"switch": "limit_pos", "direction": -1}, r"limit_pos lies in direction \+1"),
        ({"seek_speed": 0.0}, "seek_speed must be a finite positive number"),
        ({"latch_accel": math.nan}, "latch_accel"),
        ({"offset": 1 << 31}, "offset must fit 32 bits"),
        ({"settle_clocks": -1}, "settle_clocks"),
        ({"max_travel": 0}, "max_travel"),
    ):
        with pytest.raises(ValueError, match=reason):
            homing(**kw).check(FCLK, SPR, 1, 60)
    # the latch speed: a step of at least 60 + 300 + LATCH_MARGIN clocks
    need = 60 + 300 + LATCH_MARGIN
    homing(latch_speed=ALPHA * FCLK / (need + 0.5)).check(FCLK, SPR, 1, 60)
    with pytest.raises(ValueError, match=rf"needs at least {need} \(filter 60 \+ settle 300 \+ 5\)"):
        homing(latch_speed=ALPHA * FCLK / (need - 1)).check(FCLK, SPR, 1, 60)
    assert homing().max_latch_speed(FCLK, SPR, 1, 60) == pytest.approx(ALPHA * FCLK / need)


def test_homing_refuses_a_moving_axis_and_the_estop() -> None:
    for raw, reason in (
        (bit("STATUS", "BUSY"), "the axis is moving"),
        (bit("STATUS", "ESTOP_FAULT"), "E-stop"),
        (bit("STATUS", "ESTOP"), "E-stop"),
    ):
        bank = FakeBank(status_script=[raw])
        with pytest.raises(StepRampError, match=reason):
            run(home(StepRamp(bank, FCLK, SPR), homing()))
        assert bank.log == [], "nothing written"
    with pytest.raises(ValueError, match="latch speed"):
        run(home(StepRamp(FakeBank(), FCLK, SPR), homing(latch_speed=ALPHA * FCLK / 64)))


# ---- both drivers on the C fake bank, with a core and axis model ------------------------------------------------

BASE = 0x44A0_0000  # STEPRAMP_FAKEBUS_BASE
W = {r.name: r.offset // 4 for r in REGISTERS_BY_NAME.values()}
PINS = {"limit_neg": 0, "limit_pos": 1, "home": 2}
LIMIT = ERROR_CODES["LIMIT"][0]
HOOK = ctypes.CFUNCTYPE(None, ctypes.c_uint32, ctypes.c_int)


class Core:
    """The core and the axis behind the fake bank (as sw/c/tests/test_stepramp_homing.c models them): one step per
    STATUS read while a motion runs; the switch's filtered edge arrives floor(delay / T) steps after the crossing at T
    clocks per step (CRUISE_HI); SOFT_STOP ends the motion 3 steps later; a limit used as home stops the motion itself
    (LIMIT_EN: ERROR LIMIT); INPUT_CFG selects what the latch takes."""

    def __init__(self, state: Any, carriage: int, at: int, side: int, pin: str, delay: int) -> None:
        self.s, self.regs = state, state.regs
        self.carriage, self.at, self.side, self.pin, self.delay = carriage, at, side, 1 << PINS[pin], delay
        self.busy = self.jog = False
        self.dir = 1
        self.remaining = self.stopping = self.steps = 0
        self.pending: tuple[int, bool] | None = None
        self.limit_stopped = False
        self.seen = (0, 0, 0)
        self.moves = 0
        self.set_bits(self.pin << 16, self.active(carriage))

    def active(self, pos: int) -> bool:
        return pos <= self.at if self.side < 0 else pos >= self.at

    def set_bits(self, mask: int, on: bool) -> None:
        st = W["STATUS"]
        self.regs[st] = self.regs[st] | mask if on else self.regs[st] & ~mask

    def end(self, err: int = 0) -> None:
        self.busy, self.stopping = False, 0
        self.set_bits(bit("STATUS", "BUSY") | 3, False)
        self.set_bits(bit("STATUS", "DONE"), True)
        if err:
            self.set_bits(bit("STATUS", "ERROR"), True)
            self.regs[W["STATUS"]] = self.regs[W["STATUS"]] & ~0x1F00 | err << 8

    def towards_limit(self, direction: int) -> int:
        return 1 << PINS["limit_neg" if direction < 0 else "limit_pos"]

    def edge(self, active: bool) -> None:
        cfg = self.regs[W["INPUT_CFG"]]
        src = cfg >> 8 & 3
        src_pin = {1: 1 << PINS["home"], 2: 1 << PINS["limit_neg"], 3: 1 << PINS["limit_pos"]}.get(src, 0)
        on = cfg >> (10 if active else 11) & 1
        self.set_bits(self.pin << 16, active)
        if active:
            self.set_bits(self.pin << 20, True)
        if src_pin == self.pin and on and not self.regs[W["STATUS"]] & bit("STATUS", "LATCHED"):
            self.regs[W["LATCH_POS"]] = self.regs[W["POSITION"]]
            self.set_bits(bit("STATUS", "LATCHED"), True)
        if active and self.busy and self.pin == self.towards_limit(self.dir) and cfg & 0x10 and not self.limit_stopped:
            self.limit_stopped = True
            self.set_bits(bit("STATUS", "ERROR"), True)
            self.regs[W["STATUS"]] = self.regs[W["STATUS"]] & ~0x1F00 | LIMIT << 8
            self.stopping = self.stopping or 3

    def step(self) -> None:
        ticks = self.regs[W["CRUISE_HI"]]
        was = self.active(self.carriage)
        self.carriage += self.dir
        self.regs[W["POSITION"]] = (self.regs[W["POSITION"]] + self.dir) & 0xFFFF_FFFF
        self.steps += 1
        if self.pending is not None:
            left, act = self.pending
            self.pending = None if left == 0 else (left - 1, act)
            if left == 0:
                self.edge(act)
        if self.active(self.carriage) != was:
            left = self.delay // ticks if ticks else 0
            if left == 0:
                self.edge(not was)
            else:
                self.pending = (left - 1, not was)

    def command(self) -> None:
        starts, softs, hards = self.s.starts, self.s.soft_stops, self.s.hard_stops
        seen_starts, seen_softs, seen_hards = self.seen
        self.seen = (starts, softs, hards)
        if hards != seen_hards and self.busy:
            self.end()
        if softs != seen_softs and self.busy and not self.stopping:
            self.stopping = 3
        if starts != seen_starts and not self.busy:
            steps = self.regs[W["STEPS"]]
            direction = -1 if steps >> 31 else 1
            levels = self.regs[W["STATUS"]] >> 16 & 0xF
            if self.regs[W["INPUT_CFG"]] & 0x10 and levels & self.towards_limit(direction):
                self.end(LIMIT)
                return
            self.busy, self.dir, self.steps, self.limit_stopped = True, direction, 0, False
            self.jog = bool(self.regs[W["SEGMENT"]] & 2)
            self.remaining = (-steps if direction < 0 else steps) & 0xFFFF_FFFF
            self.moves += 1
            self.set_bits(bit("STATUS", "BUSY"), True)
            self.set_bits(bit("STATUS", "DIR"), direction < 0)

    def hook(self, off: int, write: int) -> None:
        if write:
            if off == offset("CTRL"):
                self.command()
            return
        if off != offset("STATUS") or not self.busy:
            return
        self.step()
        if self.stopping:
            self.stopping -= 1
            if not self.stopping:
                self.end()
        elif not self.jog:
            self.remaining -= 1
            if not self.remaining:
                self.end()


class BankAccess:
    """The Python driver's register access on the C fake bank (the C driver's own path to it)."""

    def __init__(self, so: ctypes.CDLL) -> None:
        self.so = so

    async def read(self, addr: int) -> int:
        return int(self.so.stepramp_hostbus_read32(BASE + addr))

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None:
        if strobe == 0xF:
            self.so.stepramp_hostbus_write32(BASE + addr, value & 0xFFFF_FFFF)
            return
        for b in range(4):
            if strobe >> b & 1:
                self.so.stepramp_hostbus_write8(BASE + addr + b, value >> (8 * b) & 0xFF)


HEADER = clib.SRC_DIR / "stepramp_homing.h"


class CLatch(ctypes.Structure):
    _fields_ = struct_fields(clib.SRC_DIR / "stepramp.h", "stepramp_latch_t")


class CHoming(ctypes.Structure):
    _fields_ = struct_fields(HEADER, "stepramp_homing_t")


class CResult(ctypes.Structure):
    _fields_ = struct_fields(HEADER, "stepramp_homing_result_t", {"stepramp_latch_t": CLatch})


class CInputs(ctypes.Structure):
    _fields_ = struct_fields(clib.SRC_DIR / "stepramp.h", "stepramp_inputs_t")


@pytest.fixture(scope="module")
def so(build: Path) -> ctypes.CDLL:
    lib = ctypes.CDLL(str(build / "libstepramp.so"))
    lib.stepramp_hostbus_read32.argtypes = [ctypes.c_size_t]
    lib.stepramp_hostbus_read32.restype = ctypes.c_uint32
    lib.stepramp_hostbus_write32.argtypes = [ctypes.c_size_t, ctypes.c_uint32]
    lib.stepramp_hostbus_write8.argtypes = [ctypes.c_size_t, ctypes.c_uint8]
    lib.stepramp_fakebus_reset.argtypes = [ctypes.c_size_t, ctypes.c_uint32]
    lib.stepramp_fakebus_state.restype = ctypes.POINTER(CFakeBus)
    lib.stepramp_fakebus_set_hook.argtypes = [HOOK]
    dev = ctypes.POINTER(CDev)
    lib.stepramp_init.argtypes = [dev, ctypes.c_size_t, ctypes.c_double, ctypes.c_double, ctypes.c_uint32]
    lib.stepramp_configure_inputs.argtypes = [dev, ctypes.POINTER(CInputs)]
    lib.stepramp_home.argtypes = [dev, ctypes.POINTER(CHoming), ctypes.POINTER(CResult)]
    lib.stepramp_strresult.argtypes = [ctypes.c_int]
    lib.stepramp_strresult.restype = ctypes.c_char_p
    return lib


@dataclass
class Outcome:
    """One driver's homing on the model: its result (or error), the writes it made, where POSITION reads `offset`
    in carriage steps, and the model."""

    error: str | None
    writes: list[tuple[int, int]]
    zero: int
    core: Core


def effective(writes: list[Any]) -> list[tuple[int, int]]:
    """(offset, byte lane << 8 | byte) of each written byte: a write of 0 to a STATUS lane (W1C) does nothing, so the
    drivers' DONE / ERROR clear (a byte-0 write in Python, a whole word in C) compares equal."""
    out = []
    for w in writes:
        for b in range(4):
            byte = w.value >> (8 * b) & 0xFF
            if w.be >> b & 1 and not (w.offset == offset("STATUS") and byte == 0):
                out.append((w.offset, b << 8 | byte))
    return out


FILTER = 55


def outcome(so: ctypes.CDLL, c: bool, cfg: Homing, carriage: int, at: int, side: int, pin: str, delay: int) -> Outcome:
    so.stepramp_fakebus_reset(BASE, REGISTERS_BY_NAME["ID"].reset)
    state = so.stepramp_fakebus_state().contents
    core = Core(state, carriage, at, side, pin, delay)
    state.regs[W["POSITION"]] = 4242
    hook = HOOK(core.hook)
    error = None
    if c:
        dev = CDev()
        assert so.stepramp_init(ctypes.byref(dev), BASE, FCLK, SPR, 1) == 0
        assert (
            so.stepramp_configure_inputs(ctypes.byref(dev), ctypes.byref(CInputs(filter=FILTER, limit_enable=1))) == 0
        )
        so.stepramp_fakebus_clear_log()
        so.stepramp_fakebus_set_hook(hook)
        sw = {"home": 1, "limit_neg": 2, "limit_pos": 3}[cfg.switch]
        args = {f: getattr(cfg, f) for f, _ in CHoming._fields_ if f not in ("sw", "max_polls")}
        rc = so.stepramp_home(ctypes.byref(dev), ctypes.byref(CHoming(sw=sw, max_polls=100_000, **args)), None)
        error = None if rc == 0 else so.stepramp_strresult(rc).decode()
    else:
        drv = StepRamp(BankAccess(so), FCLK, SPR)
        run(drv.configure_inputs(Inputs(filter=FILTER)))
        so.stepramp_fakebus_clear_log()
        so.stepramp_fakebus_set_hook(hook)
        try:
            run(home(drv, cfg, polls=100_000))
        except (StepRampError, ValueError) as exc:
            error = str(exc)
    so.stepramp_fakebus_set_hook(HOOK())
    assert state.bus_errors == 0 and state.writes <= len(state.log)
    position = state.regs[W["POSITION"]]
    position -= (position >> 31) << 32
    return Outcome(error, effective(state.log[: state.writes]), core.carriage - (position - cfg.offset), core)


@pytest.mark.parametrize("start", [100, 1, -39, -40, -75])
@pytest.mark.parametrize("delay", [62, 150, 299, 355])
def test_both_drivers_home_to_the_switch_edge(so: ctypes.CDLL, start: int, delay: int) -> None:
    """HOME active for carriage <= -40: POSITION 1000 lands on carriage step -39 (the first off the switch) from
    every start and edge delay, with the same writes from both drivers."""
    cfg = homing(offset=1000)
    py, c = (outcome(so, lang, cfg, start, -40, -1, "home", delay) for lang in (False, True))
    assert py.error is None and c.error is None, (py.error, c.error)
    assert py.zero == c.zero == -39
    assert py.core.moves == c.core.moves == (4 if start <= -40 else 3)
    assert py.writes == c.writes
    assert len(py.writes) > 300, len(py.writes)  # bytes: 320 from off the switch, 424 from on it


def test_both_drivers_home_on_a_limit_and_fail_alike(so: ctypes.CDLL) -> None:
    """LIMIT_NEG used as home (the core stops the seek itself, error LIMIT expected); a switch out of reach (the
    travel bound: hard stop); the same writes and the same zero or failure from both drivers."""
    cfg = homing(switch="limit_neg", offset=0)
    py, c = (outcome(so, lang, cfg, 60, 0, -1, "limit_neg", 200) for lang in (False, True))
    assert py.error is None and c.error is None, (py.error, c.error)
    assert py.zero == c.zero == 1 and py.writes == c.writes
    cfg = homing(max_travel=200)
    py, c = (outcome(so, lang, cfg, 60, -4000, -1, "home", 100) for lang in (False, True))
    assert py.error is not None and "no switch edge within 200 steps" in py.error
    assert c.error is not None and "max_travel" in c.error
    assert py.writes == c.writes and py.writes[-1][0] == offset("INPUT_CFG"), "the inputs restored after a failure"
