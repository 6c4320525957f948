# SPDX-License-Identifier: MIT
"""The multi-axis driver (stepramp.board.multi) over a fake multi-axis top (no simulator), and the address map's four
copies (hdl/stepramp_multi_pkg.vhd, multi.py, sw/c/src/stepramp_multi.h, docs/stepramp_multi.md) against each other."""

from __future__ import annotations

import asyncio
import re
from pathlib import Path

import pytest

from stepramp.board import coord, multi
from stepramp.board.coord import plan_coordinated
from stepramp.board.driver import NO_SEGMENT, Outputs, plan_writes, segment_writes
from stepramp.board.multi import (
    AXIS_WINDOW,
    REG_AXES_STATUS,
    REG_ID,
    REG_IRQ_MASK,
    REG_SYNC_SOFT_STOP,
    REG_SYNC_START,
    AxesStatus,
    MultiAxis,
    MultiAxisError,
    OffsetAccess,
    axis_base,
    mask_of,
)
from stepramp.board.regmap import ERROR_CODES, ID_VALUE, REGISTERS_BY_NAME, offset

REPO = Path(__file__).resolve().parents[2]
DONE = 1 << REGISTERS_BY_NAME["STATUS"].field("DONE").lsb
ERROR = 1 << REGISTERS_BY_NAME["STATUS"].field("ERROR").lsb
ERR_CODE = REGISTERS_BY_NAME["STATUS"].field("ERR_CODE").lsb

#: A path whose lead moves 48 steps (spr 200, 1 MHz, prescale 2).
PATH = {"accel": 2200.0, "decel": 1800.0, "speed": 52.0}
FCLK, SPR, PRESCALE = 1e6, 200.0, 2


class FakeTop:
    """A multi-axis top as registers in a dict: ID / AXES, IRQ_MASK (a bit per axis), SYNC_START (logged, reads 0),
    AXES_STATUS from a script, each axis's ID and STATUS (DONE / ERROR cleared by writing 1). Every access is logged."""

    def __init__(self, axes: int, status_script: list[int] | None = None) -> None:
        self.axes = axes
        self.regs: dict[int, int] = {REG_ID: multi.ID_MAGIC << 16 | multi.ID_VERSION << 8 | axes}
        self.regs[REG_IRQ_MASK] = (1 << axes) - 1
        for i in range(axes):
            self.regs[axis_base(i) + offset("ID")] = ID_VALUE
        self.status_script = list(status_script or [])
        self.log: list[tuple[int, int, int]] = []
        self.reads: list[int] = []

    async def read(self, addr: int) -> int:
        self.reads.append(addr)
        if addr == REG_AXES_STATUS and self.status_script:
            raw = self.status_script.pop(0)
            self.regs[REG_AXES_STATUS] = raw
            for i in range(self.axes):  # DONE in the word: the axis's STATUS.DONE is set too
                if raw >> (8 + i) & 1:
                    self.regs[axis_base(i) + offset("STATUS")] = (
                        self.regs.get(axis_base(i) + offset("STATUS"), 0) | DONE
                    )
        return self.regs.get(addr, 0)

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None:
        self.log.append((addr, value, strobe))
        if addr == REG_IRQ_MASK:
            self.regs[addr] = value & ((1 << self.axes) - 1)
        elif addr >= AXIS_WINDOW and addr % AXIS_WINDOW == offset("STATUS"):
            self.regs[addr] = self.regs.get(addr, 0) & ~(value & (DONE | ERROR))
        elif addr not in (REG_ID, REG_SYNC_START, REG_SYNC_SOFT_STOP, REG_AXES_STATUS):
            self.regs[addr] = value


def run(coro):
    return asyncio.run(coro)


def test_offset_access_shifts_every_access() -> None:
    top = FakeTop(2)
    window = OffsetAccess(top, axis_base(1))
    run(window.write(offset("STEPS"), 7, strobe=0x3))
    assert top.log == [(0x200 + offset("STEPS"), 7, 0x3)]
    assert run(window.read(offset("ID"))) == ID_VALUE
    assert top.reads == [0x200]


def test_axis_base_and_masks() -> None:
    assert [axis_base(i) for i in range(8)] == [0x100 * (i + 1) for i in range(8)]
    assert mask_of([0, 2, 2, 7]) == 0x85
    assert mask_of([]) == 0
    for bad in (-1, 8, True, 1.0):
        with pytest.raises(ValueError, match="axis must be"):
            axis_base(bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"0 \.\. 2"):
        mask_of([3], count=3)
    assert AxesStatus.decode(0x00_05_06_03) == AxesStatus(busy=0x03, done=0x06, irq=0x05)


def test_probe_and_check_id() -> None:
    top = FakeTop(3)
    m = run(MultiAxis.probe(top, FCLK, SPR, PRESCALE))
    assert m.axes == 3 and len(m.drivers) == 3
    assert run(m.check_id()) == multi.ID_VERSION
    assert [d.access.base for d in m.drivers] == [0x100, 0x200, 0x300]  # type: ignore[attr-defined]
    assert run(m.axis(2).check_id()) == ID_VALUE & 0xFFFF  # the axis driver reads its own window's ID
    with pytest.raises(MultiAxisError, match="made for 2"):
        run(MultiAxis(top, 2, FCLK, SPR).check_id())
    top.regs[REG_ID] = ID_VALUE  # a single core at this address
    with pytest.raises(MultiAxisError, match="not a multi-axis"):
        run(MultiAxis.probe(top, FCLK, SPR))
    with pytest.raises(MultiAxisError, match="not a multi-axis"):
        run(m.check_id())
    top.regs[REG_ID] = multi.ID_MAGIC << 16 | 9
    with pytest.raises(MultiAxisError, match="not a multi-axis"):
        run(MultiAxis.probe(top, FCLK, SPR))
    for bad in (0, 9, True):
        with pytest.raises(ValueError, match="axes must be"):
            MultiAxis(top, bad, FCLK, SPR)
    with pytest.raises(ValueError, match=r"0 \.\. 2"):
        m.axis(3)


def test_probe_reads_each_axis_windings_from_its_own_window() -> None:
    """Each axis's driver learns from its own window's ID whether its core has windings (bit 14 set: built with
    G_WINDINGS false, STEP/DIR only), as stepramp_multi_init does through stepramp_init; an axis window that is no
    stepramp core fails the probe."""
    top = FakeTop(3)
    top.regs[axis_base(1) + offset("ID")] = ID_VALUE | 1 << 14
    m = run(MultiAxis.probe(top, FCLK, SPR, PRESCALE))
    assert [m.axis(i).windings for i in range(3)] == [True, False, True]
    assert [a for a in top.reads if a != REG_ID] == [axis_base(i) + offset("ID") for i in range(3)]
    with pytest.raises(ValueError, match="without winding outputs"):
        run(m.configure_outputs(Outputs(mode="full"), axes=[1]))
    run(m.configure_outputs(Outputs(mode="full"), axes=[0, 2]))
    assert top.regs[axis_base(0) + offset("DRIVE")] == top.regs[axis_base(2) + offset("DRIVE")] == 2
    run(m.configure_outputs(Outputs()))  # STEP/DIR on every axis
    top.regs[axis_base(2) + offset("ID")] = 0xDEADBEEF
    with pytest.raises(MultiAxisError, match="axis 2") as err:
        run(MultiAxis.probe(top, FCLK, SPR))
    assert err.value.axes == (2,)


def test_global_registers() -> None:
    top = FakeTop(3)
    m = MultiAxis(top, 3, FCLK, SPR)
    run(m.sync_start([2, 0]))
    run(m.set_irq_mask([1]))
    assert top.log == [(REG_SYNC_START, 0b101, 0xF), (REG_IRQ_MASK, 0b010, 0xF)]
    assert run(m.irq_mask()) == 0b010
    with pytest.raises(ValueError, match="axis must be"):
        run(m.sync_start([3]))
    assert len(top.log) == 2, "a bad mask wrote something"
    top.status_script = [0x00_01_01_06]
    assert run(m.status()) == AxesStatus(busy=0b110, done=0b001, irq=0b001)
    run(m.sync_soft_stop([1, 2]))
    assert top.log[-1] == (REG_SYNC_SOFT_STOP, 0b110, 0xF)
    with pytest.raises(ValueError, match="axis must be"):
        run(m.sync_soft_stop([0, 3]))
    assert len(top.log) == 3, "a bad mask wrote something"


def test_move_coordinated_programs_each_window_then_one_sync_start() -> None:
    top = FakeTop(4)
    m = MultiAxis(top, 4, FCLK, SPR, PRESCALE)
    steps = [48, 0, -29, 17]
    plans = run(m.move_coordinated(steps, **PATH))
    assert plans == plan_coordinated(steps, PATH["accel"], PATH["decel"], PATH["speed"], SPR, FCLK, PRESCALE)
    assert MultiAxis.started(plans) == [0, 2, 3]
    want: list[tuple[int, int, int]] = []
    for i in (0, 2, 3):  # each axis's move (and, the first time, its segment registers) in its window
        writes = plan_writes(plans[i]) + segment_writes(NO_SEGMENT)
        want += [(axis_base(i) + a, v, 0xF) for a, v in writes]
    want.append((REG_SYNC_START, 0b1101, 0xF))
    assert top.log == want
    # A second move: the started axes' segment registers are known to hold 0 now; axis 1's (0 steps before) not.
    top.log.clear()
    plans = run(m.move_coordinated([-10, 20, 5], **PATH))
    assert [a for a, _, _ in top.log if a % AXIS_WINDOW == offset("SEGMENT")] == [axis_base(1) + offset("SEGMENT")]
    assert top.log[-1] == (REG_SYNC_START, 0b0111, 0xF)
    assert top.regs[axis_base(0) + offset("STEPS")] == (-10) & 0xFFFF_FFFF


def test_plan_coordinated_checks() -> None:
    m = MultiAxis(FakeTop(2), 2, FCLK, SPR, PRESCALE)
    with pytest.raises(ValueError, match="3 step counts for a top of 2 axes"):
        m.plan_coordinated([10, 20, 30], **PATH)
    with pytest.raises(ValueError, match="sequence"):
        m.plan_coordinated("12", **PATH)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="accel"):
        m.plan_coordinated([48, 17], -1.0, PATH["decel"], PATH["speed"])
    with pytest.raises(ValueError, match="3 plans"):
        run(m.program_sync(plan_coordinated([48, 17, 5], PATH["accel"], PATH["decel"], PATH["speed"], SPR, FCLK, 2)))
    # STEP width + space per axis: 1000 clocks fit axis 1's shortest interval (17 steps: about 1,770 clocks), not the
    # lead's (about 600).
    m.drivers[1].outputs = Outputs(step_width=500, step_space=500)
    assert len(m.plan_coordinated([48, 17], **PATH)) == 2
    m.drivers[0].outputs = Outputs(step_width=500, step_space=500)
    with pytest.raises(ValueError, match="axis 0: STEP width"):
        m.plan_coordinated([48, 17], **PATH)


def test_wait_done_clears_and_names_the_failed_axes() -> None:
    top = FakeTop(3, status_script=[0x0000_0005, 0x0000_0104, 0x0005_0500])
    m = MultiAxis(top, 3, FCLK, SPR)
    idles: list[int] = []

    async def idle() -> None:
        idles.append(1)

    status = run(m.wait_done([0, 2], idle=idle))
    assert status.done == 0b101 and len(idles) == 2
    for i in (0, 2):
        assert top.regs[axis_base(i) + offset("STATUS")] & (DONE | ERROR) == 0, f"axis {i}: flags not cleared"
    # An error on axis 1: every waited axis is cleared, the exception names axis 1.
    top.status_script = [0x0007_0700]
    code = ERROR_CODES["ESTOP"][0]
    top.regs[axis_base(1) + offset("STATUS")] = ERROR | code << ERR_CODE
    with pytest.raises(MultiAxisError, match="axis 1") as raised:
        run(m.wait_done(range(3)))
    assert raised.value.axes == (1,)
    assert all(top.regs[axis_base(i) + offset("STATUS")] & (DONE | ERROR) == 0 for i in range(3))
    top.status_script = [0] * 3
    with pytest.raises(MultiAxisError, match="no DONE"):
        run(m.wait_done([0], polls=3))


def _vhdl_constants() -> dict[str, int]:
    text = (REPO / "hdl" / "stepramp_multi_pkg.vhd").read_text()
    found: dict[str, int] = {}
    for name, value in re.findall(r"constant\s+(C_\w+)\s*:\s*[\w() ]+:=\s*([^;]+);", text):
        value = value.strip()
        if (m := re.fullmatch(r'x"([0-9A-Fa-f]+)"', value)) or (m := re.fullmatch(r"16#([0-9A-Fa-f]+)#", value)):
            found[name] = int(m.group(1), 16)
        else:
            found[name] = int(value)
    return found


def _c_defines() -> dict[str, int]:
    text = (REPO / "sw" / "c" / "src" / "stepramp_multi.h").read_text()
    return {n: int(v, 0) for n, v in re.findall(r"#define (STEPRAMP_MULTI_\w+) (0x[0-9A-Fa-f]+|\d+)u", text)}


#: (VHDL constant, Python name, C define) of every value of the map.
MAP = [
    ("C_MULTI_ADDR_BITS", "MULTI_ADDR_BITS", "STEPRAMP_MULTI_ADDR_BITS"),
    ("C_MULTI_MAX_AXES", "MAX_AXES", "STEPRAMP_MULTI_MAX_AXES"),
    ("C_MULTI_ID_MAGIC", "ID_MAGIC", "STEPRAMP_MULTI_ID_MAGIC"),
    ("C_MULTI_ID_VERSION", "ID_VERSION", "STEPRAMP_MULTI_ID_VERSION"),
    ("C_MREG_ID", "REG_ID", "STEPRAMP_MULTI_REG_ID"),
    ("C_MREG_SYNC_START", "REG_SYNC_START", "STEPRAMP_MULTI_REG_SYNC_START"),
    ("C_MREG_AXES_STATUS", "REG_AXES_STATUS", "STEPRAMP_MULTI_REG_AXES_STATUS"),
    ("C_MREG_IRQ_MASK", "REG_IRQ_MASK", "STEPRAMP_MULTI_REG_IRQ_MASK"),
    ("C_MREG_SYNC_SOFT_STOP", "REG_SYNC_SOFT_STOP", "STEPRAMP_MULTI_REG_SYNC_SOFT_STOP"),
    ("C_AXES_STATUS_BUSY_LSB", "AXES_STATUS_BUSY_LSB", "STEPRAMP_MULTI_AXES_STATUS_BUSY_SHIFT"),
    ("C_AXES_STATUS_DONE_LSB", "AXES_STATUS_DONE_LSB", "STEPRAMP_MULTI_AXES_STATUS_DONE_SHIFT"),
    ("C_AXES_STATUS_IRQ_LSB", "AXES_STATUS_IRQ_LSB", "STEPRAMP_MULTI_AXES_STATUS_IRQ_SHIFT"),
]


def test_the_map_is_the_same_in_vhdl_python_c_and_docs() -> None:
    vhdl, c = _vhdl_constants(), _c_defines()
    problems = []
    for v_name, py_name, c_name in MAP:
        values = {"vhdl": vhdl.get(v_name), "python": getattr(multi, py_name), "c": c.get(c_name)}
        if len(set(values.values())) != 1:
            problems.append(f"{v_name} / {py_name} / {c_name}: {values}")
    assert not problems, "\n".join(problems)
    assert c["STEPRAMP_MULTI_AXIS_WINDOW"] == AXIS_WINDOW == 1 << (vhdl["C_MULTI_ADDR_BITS"] - 4)
    assert multi.MAX_AXES == coord.MAX_AXES, "the planner and the top disagree on the most axes"
    # docs: the global window's register table, | `0x000` | ID | ...
    page = (REPO / "docs" / "stepramp_multi.md").read_text()
    rows = {name: int(addr, 16) for addr, name in re.findall(r"^\| `(0x[0-9A-F]{3})` \| (\w+) \|", page, re.M)}
    assert rows == {
        "ID": REG_ID,
        "SYNC_START": REG_SYNC_START,
        "AXES_STATUS": REG_AXES_STATUS,
        "IRQ_MASK": REG_IRQ_MASK,
        "SYNC_SOFT_STOP": REG_SYNC_SOFT_STOP,
    }
