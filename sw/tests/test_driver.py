# SPDX-License-Identifier: MIT
"""The Python driver over a fake register bank (no simulator): what it writes, how it decodes, how it fails."""

from __future__ import annotations

import asyncio
import mmap
from pathlib import Path

import pytest

from stepramp.board import regmap
from stepramp.board.driver import (
    NO_SEGMENT,
    MmapAccess,
    Outputs,
    Status,
    StepRamp,
    StepRampError,
    plan_writes,
    segment_writes,
)
from stepramp.board.plan import plan_move
from stepramp.board.regmap import ERROR_CODES, ID_VALUE, REGISTERS_BY_NAME, offset


class FakeBank:
    """Registers as a dict; STATUS answers from a script; writes are logged with their strobes."""

    def __init__(self, status_script: list[int] | None = None) -> None:
        self.regs: dict[int, int] = {offset("ID"): ID_VALUE}
        self.log: list[tuple[int, int, int]] = []
        self.status_script = list(status_script or [])

    async def read(self, addr: int) -> int:
        if addr == offset("STATUS") and self.status_script:
            return self.status_script.pop(0)
        return self.regs.get(addr, 0)

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None:
        self.log.append((addr, value, strobe))
        self.regs[addr] = value


def run(coro):
    return asyncio.run(coro)


def test_move_writes_every_motion_register_then_start() -> None:
    bank = FakeBank()
    drv = StepRamp(bank, fclk=1e6, spr=200.0)
    plan = run(drv.move(-150, 1000.0, 800.0, 50.0))
    assert plan == plan_move(-150, 1000.0, 800.0, 50.0, 200.0, 1e6)
    # A new driver does not know what SEGMENT .. HEAD_PROD hold: its first move writes them, 0 (a move from rest).
    zeros = [(a, v, 0xF) for a, v in segment_writes(NO_SEGMENT)]
    assert bank.log[:-1] == [(a, v, 0xF) for a, v in plan_writes(plan)] + zeros
    assert all(v == 0 for _, v, _ in zeros) and len(zeros) == 5
    assert bank.log[-1] == (offset("CTRL"), 1, 0x1), "START is a byte-0 write"
    assert bank.regs[offset("STEPS")] == (-150) & 0xFFFF_FFFF
    assert bank.regs[offset("CRUISE_HI")] == plan.cruise >> 32
    # The next move: the motion registers only.
    bank.log.clear()
    plan = run(drv.move(150, 1000.0, 800.0, 50.0))
    assert bank.log[:-1] == [(a, v, 0xF) for a, v in plan_writes(plan)]


def test_a_jog_then_a_move_clears_the_segment() -> None:
    bank = FakeBank()
    drv = StepRamp(bank, fclk=1e6, spr=200.0)
    run(drv.move(10, 1000.0, 800.0, 50.0))
    bank.log.clear()
    run(drv.jog(-50.0, 1000.0, 800.0))
    assert bank.regs[offset("SEGMENT")] == REGISTERS_BY_NAME["SEGMENT"].field("ENDLESS").mask
    assert bank.regs[offset("STEPS")] == 0xFFFF_FFFF, "a jog's STEPS gives its direction only: -1"
    run(drv.move(10, 1000.0, 800.0, 50.0))
    assert all(bank.regs[a] == 0 for a, _ in segment_writes(NO_SEGMENT)), "the move after a jog clears the segment"


def test_invalid_move_writes_nothing() -> None:
    bank = FakeBank()
    drv = StepRamp(bank, fclk=1e6, spr=200.0)
    with pytest.raises(ValueError, match="accel must be finite"):
        run(drv.move(100, -1.0, 800.0, 50.0))
    assert bank.log == []


def test_step_width_must_fit_the_shortest_interval() -> None:
    bank = FakeBank()
    drv = StepRamp(bank, fclk=1e6, spr=200.0)
    run(drv.configure_outputs(Outputs(mode="half", step_width=99)))
    # 100 ticks at the cruise speed: a width of 99 fits, 100 does not.
    speed = 2 * 3.141592653589793 / 200.0 * 1e6 / 100.5
    drv.plan(500, 1e6, 1e6, speed)
    run(drv.configure_outputs(Outputs(mode="half", step_width=100)))
    with pytest.raises(ValueError, match=r"STEP width 100 \+ STEP space 1 clocks does not fit"):
        drv.plan(500, 1e6, 1e6, speed)
    # the core refuses pulses closer than STEP_WIDTH + STEP_SPACE: the plan checks the sum
    run(drv.configure_outputs(Outputs(mode="half", step_width=90, step_space=10)))
    drv.plan(500, 1e6, 1e6, speed)
    run(drv.configure_outputs(Outputs(mode="half", step_width=90, step_space=11)))
    with pytest.raises(ValueError, match=r"STEP width 90 \+ STEP space 11 clocks does not fit"):
        drv.plan(500, 1e6, 1e6, speed)


def test_configure_outputs_words_and_checks() -> None:
    bank = FakeBank()
    drv = StepRamp(bank, fclk=1e6, spr=200.0)
    outputs = Outputs(mode="pwm", ustep_log2=4, step_width=7, dir_setup=20, dir_hold=9, pwm_period=40, step_space=3)
    run(drv.configure_outputs(outputs))
    assert bank.regs[offset("STEP_SPACE")] == 3
    assert bank.regs[offset("DRIVE")] == 4 | 4 << 4
    assert bank.regs[offset("STEP_WIDTH")] == 7
    assert bank.regs[offset("DIR_TIMING")] == 20 | 9 << 16
    assert bank.regs[offset("PWM_PERIOD")] == 40
    for bad, msg in (
        (Outputs(mode="quarter"), "mode must be one of"),
        (Outputs(ustep_log2=8), "ustep_log2"),
        (Outputs(step_width=70000), "step_width"),
        (Outputs(dir_hold=-1), "dir_hold"),
        (Outputs(step_space=65536), "step_space"),
    ):
        with pytest.raises(ValueError, match=msg):
            run(drv.configure_outputs(bad))
    run(drv.set_enable(True))
    assert bank.log[-1] == (offset("CTRL"), 1 << 16, 0x4)


def test_status_decode() -> None:
    raw = 2 | 1 << 2 | 1 << 3 | 1 << 4 | 1 << 5 | ERROR_CODES["LATE"][0] << 8
    st = Status.decode(raw)
    assert (st.state, st.busy, st.direction, st.done, st.error, st.err_name) == ("RUN", True, 1, True, True, "LATE")


def test_wait_done_clears_flags_and_reports_errors() -> None:
    bank = FakeBank(status_script=[1 << 2, 1 << 2, 1 << 4])
    drv = StepRamp(bank, fclk=1e6, spr=200.0)
    assert run(drv.wait_done()).done
    assert bank.log[-1] == (offset("STATUS"), 0x30, 0x1), "DONE and ERROR cleared by writing 1"
    bank.status_script = [1 << 4 | 1 << 5 | ERROR_CODES["BOUNDS"][0] << 8]
    with pytest.raises(StepRampError, match="BOUNDS"):
        run(drv.wait_done())
    bank.status_script = [1 << 2] * 5
    with pytest.raises(StepRampError, match="no DONE after 3 polls"):
        run(drv.wait_done(polls=3))


def test_id_and_position() -> None:
    bank = FakeBank()
    drv = StepRamp(bank, fclk=1e6, spr=200.0)
    assert run(drv.check_id()) == ID_VALUE & 0xFFFF
    bank.regs[offset("ID")] = 0xDEADBEEF
    with pytest.raises(StepRampError, match="not a stepramp core"):
        run(drv.check_id())
    run(drv.set_position(-5))
    assert bank.regs[offset("POSITION")] == 0xFFFF_FFFB
    assert run(drv.position()) == -5
    with pytest.raises(ValueError, match="does not fit"):
        run(drv.set_position(1 << 31))


def test_a_core_without_windings_refuses_the_winding_modes() -> None:
    """ID bit 14 set (NO_WINDINGS: the core was built with G_WINDINGS false): check_id learns it, the version is bits
    13:0 without it, and configure_outputs refuses every winding mode (nothing written) but takes STEP/DIR."""
    assert regmap.ID_WINDINGS_BIT == 14
    bank = FakeBank()
    drv = StepRamp(bank, fclk=1e6, spr=200.0)
    assert drv.windings, "a driver assumes windings until the ID says otherwise"
    bank.regs[offset("ID")] = 0x5352 << 16 | 1 << 14 | 0x3A << 8 | 0x5C
    assert run(drv.check_id()) == 0x3A5C, "the version is ID bits 13:0, bit 14 is not part of it"
    assert drv.windings is False
    for mode in ("wave", "full", "half", "pwm"):
        with pytest.raises(ValueError, match=r"without winding outputs.*ID bit 14.*G_WINDINGS"):
            run(drv.configure_outputs(Outputs(mode=mode)))
    assert bank.log == [], "a refused configuration writes nothing"
    bank.regs[offset("DRIVE")] = 0x33
    run(drv.configure_outputs(Outputs(mode="stepdir", ustep_log2=2, step_width=5)))
    assert bank.regs[offset("DRIVE")] == 2 << 4, "DRIVE.MODE 0"
    assert bank.regs[offset("STEP_WIDTH")] == 5
    # Bit 14 clear: a core with windings, every mode as before.
    bank.regs[offset("ID")] = 0x5352 << 16 | 0x3F << 8 | 0xFF
    assert run(drv.check_id()) == 0x3FFF
    assert drv.windings is True
    run(drv.configure_outputs(Outputs(mode="half")))
    assert bank.regs[offset("DRIVE")] == 3


def test_mmap_access_on_a_file(tmp_path: Path) -> None:
    """MmapAccess on a plain file: the same code path as /dev/mem or /dev/uioN, byte strobes included."""
    f = tmp_path / "regs.bin"
    f.write_bytes(bytes(mmap.PAGESIZE))
    acc = MmapAccess(str(f), 0, mmap.PAGESIZE)
    run(acc.write(0x10, 0x11223344))
    run(acc.write(0x10, 0xAABBCCDD, strobe=0b0101))
    assert run(acc.read(0x10)) == 0x11BB33DD
    acc.close()
    assert f.read_bytes()[0x10:0x14] == bytes.fromhex("dd33bb11")


class LaneBank(FakeBank):
    """FakeBank with byte lanes as docs/registers.md gives them: a write changes only the bytes its strobe names, and
    CTRL reads back its RW fields only (the WS command bits read 0)."""

    async def read(self, addr: int) -> int:
        value = await super().read(addr)
        if addr == offset("CTRL"):
            value &= sum(f.mask for f in REGISTERS_BY_NAME["CTRL"].fields if f.access == "RW")
        return value

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None:
        self.log.append((addr, value, strobe))
        lanes = sum(0xFF << (8 * b) for b in range(4) if strobe >> b & 1)
        self.regs[addr] = (self.regs.get(addr, 0) & ~lanes | value & lanes) & 0xFFFF_FFFF


def test_enable_irq_keeps_the_input_irq_enables() -> None:
    # CTRL bits 10 .. 14 (the input interrupt enables) share byte 1 with IRQ_DONE_EN and IRQ_ERROR_EN (bits 8, 9):
    # enable_irq sets DONE / ERROR and leaves the input enables that enable_input_irq set; nothing in byte 0 (no
    # command) or byte 2 (ENABLE) is written
    ctrl = REGISTERS_BY_NAME["CTRL"]
    bank = LaneBank()
    drv = StepRamp(bank, fclk=1e6, spr=200.0)
    run(drv.set_enable(True))
    run(drv.enable_input_irq(limit_neg=True, home=True, latch=True, done=False, error=False))
    inputs = ctrl.field("IRQ_LIMIT_NEG_EN").mask | ctrl.field("IRQ_HOME_EN").mask | ctrl.field("IRQ_LATCH_EN").mask
    enable = ctrl.field("ENABLE").mask
    assert bank.regs[offset("CTRL")] == enable | inputs
    bank.log.clear()
    run(drv.enable_irq(done=True, error=False))
    assert bank.regs[offset("CTRL")] == enable | inputs | ctrl.field("IRQ_DONE_EN").mask
    run(drv.enable_irq(done=False, error=True))
    assert bank.regs[offset("CTRL")] == enable | inputs | ctrl.field("IRQ_ERROR_EN").mask
    run(drv.enable_irq(done=False, error=False))
    assert bank.regs[offset("CTRL")] == enable | inputs
    assert [strobe for addr, _, strobe in bank.log] == [0x2] * 3 and {a for a, _, _ in bank.log} == {offset("CTRL")}
    # enable_input_irq still sets every enable of byte 1 as asked
    run(drv.enable_input_irq(done=True))
    assert bank.regs[offset("CTRL")] == enable | ctrl.field("IRQ_DONE_EN").mask | ctrl.field("IRQ_ERROR_EN").mask
