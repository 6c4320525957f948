# SPDX-License-Identifier: MIT
"""stepramp_regfile alone, clock by clock against a Python model of the register file (issue 12, point 2).

The model (RegfileModel below) is written from stepramp.board.regmap, the one source of the register layout: the
offsets, fields, access kinds (RO, RW, W1C, WS), reset values and masks come from there, and the behaviour from
docs/registers.md, docs/stepramp_plb.md ("Register behaviour") and docs/algorithm.md ("The take-over, the queue and
the script contract"), not from the VHDL. The bench drives the register file's bus port (one-cycle wr / rd strobes
with addr, wdata and be; ack, err and rdata one clock later) and plays the engine's side (eng_busy, eng_done,
eng_error, eng_err_code, eng_state, eng_dir, eng_position, eng_step_count, eng_cur_delay, eng_chg_pend,
eng_chg_refused, dir_fault). Every input is driven at a falling edge, the model takes the same inputs at the rising
edge that samples them, and at the next falling edge every output of the register file is compared with the model:
ack, err, rdata (on a read acknowledge without err), irq, the start / soft_stop / hard_stop / change / pos_load
strobes and pos_value (with pos_load), and every move and configuration output (steps / direction, prescale,
c_first .. cruise, sa, sd, stop_ratio, the segment's outputs, change_at, enable, mode, ustep_log2, step_width,
dir_setup, dir_hold, pwm_period, step_space). So every test below is checked in every cycle; the directed tests add
explicit assertions of the documented rules.

Rules the model holds (docs/registers.md, docs/stepramp_plb.md, docs/algorithm.md):

* word addresses: address bits 1:0 are ignored; a word offset with no register answers err (and a write there
  changes nothing); byte enables select the byte lanes of every writable register; bits not listed read 0;
* RW fields keep what was written (byte-merged, masked to the field); RO registers and fields ignore writes; WS
  fields (CTRL.START / SOFT_STOP / HARD_STOP / CHANGE / QUEUE) act when written 1 (byte 0 enabled) and read 0;
  START, SOFT_STOP and HARD_STOP pulse their output for one clock (high in the cycle after the write edge); W1C flags
  (STATUS.DONE / ERROR) are cleared by writing 1 and set by the engine's strobes, and a set in the same cycle as the
  clear wins;
* START with STEPS = 0x80000000 while eng_busy = '0': no start strobe, DONE and ERROR with ERR_CODE STEPS;
* a POSITION write while eng_busy = '0' pulses pos_load with the written bytes merged into eng_position; while
  busy it is ignored and sets ERROR with POS_BUSY; a write to DRIVE .. STEP_SPACE while busy is ignored and sets
  ERROR with CFG_BUSY (CTRL can be written at any time);
* locked = the change strobe (the registered change output) or eng_chg_pend or a queued move (q_pend); STATUS.PENDING
  reads it. A write to a staging word (regmap.STAGING: STEPS .. STOP_RATIO, SEGMENT .. CHANGE_AT) while locked is
  ignored (the word, its output and its read-back keep their value) and sets ERROR with STAGED (acknowledged, no
  err); otherwise the staging words are written at any time. The configuration words keep their CFG_BUSY rule only;
* a CTRL write with CHANGE or QUEUE is refused (ERROR with CHANGE; no change strobe, no queue) when eng_busy = '0',
  or locked, or both are set, or (CHANGE) STEPS bit 31 differs from eng_dir, or (QUEUE) STEPS = 0x80000000; else
  CHANGE pulses change for one clock and QUEUE sets q_pend. A CTRL write with SOFT_STOP or HARD_STOP and without
  QUEUE clears q_pend (its stop strobes still pulse);
* at an edge with eng_done = '1' and q_pend = '1' (q_pend as it was before the edge): q_pend clears and, if
  eng_error = '0', the start strobe pulses, as if START had been written at that edge;
* eng_chg_refused sets ERROR with ERR_CODE CHANGE (a set in the cycle of a W1C clear wins, as the engine's);
* irq = (DONE and IRQ_DONE_EN) or (ERROR and IRQ_ERROR_EN), registered (one clock after the flags);
* STATUS.STATE / BUSY / DIR / DIR_FAULT, POSITION, CUR_DELAY and STEP_COUNT read the engine's inputs.

Choices the documents leave open are pinned here as the RTL has them:

* ERR_CODE when several causes meet at one edge: eng_chg_refused's CHANGE over the engine's eng_err_code over the
  register file's own (STEPS, POS_BUSY, CFG_BUSY, STAGED, CHANGE); of the two own causes one CTRL write can raise
  (START refused for STEPS, CHANGE / QUEUE refused), STEPS;
* a START written at the edge where a queued move is dropped by eng_error is dropped too (no start strobe);
* a stop written at the edge of the engine's done still lets the queued move start (q_pend was set before the edge):
  the start strobe pulses with the stop's.

Tests: reset values, field read/write with every byte-enable pattern, read-only and unmapped offsets, the outputs
to the engine, the CTRL strobes and the STEPS check, STATUS and irq, POSITION and configuration while busy, CHANGE
accepted and refused (change_commit), the queued move (queue_commit), the staging lock (staging_locked), and a
seeded random sequence (REGFILE_SEED, printed; REGFILE_CYCLES cycles, 4,000 by default) of reads, writes, engine
events and resets. Replay a failing sequence with REGFILE_SEED=<seed> .venv/bin/pytest tb/test_regfile.py.
"""

from __future__ import annotations

import functools
import os
import random
from collections import Counter, deque
from typing import Any

from cocotb.triggers import FallingEdge

from stepramp.board.regmap import (
    ADDR_BITS,
    ERROR_CODES,
    REGISTERS,
    REGISTERS_BY_NAME,
    RO,
    RW,
    STAGING,
    W1C,
    WS,
    Register,
)
from stepramp.sim.clocking import start_clock
from stepramp.sim.runner import run_cocotb
from tbutil import build_dir, cocotb, env_int

# ---------------------------------------------------------------------------------------------------------------
# The register map as the model sees it (all from stepramp.board.regmap).

WORD = 0xFFFF_FFFF
WINDOW = 1 << ADDR_BITS
BY_OFFSET: dict[int, Register] = {r.offset: r for r in REGISTERS}
UNMAPPED = [o for o in range(0, WINDOW, 4) if o not in BY_OFFSET]


def access_mask(reg: Register, *kinds: str) -> int:
    """Bits of a register's fields of the given access kinds."""
    return sum(f.mask for f in reg.fields if f.access in kinds)


def _span(first: str, last: str) -> tuple[str, ...]:
    lo, hi = REGISTERS_BY_NAME[first].offset, REGISTERS_BY_NAME[last].offset
    return tuple(r.name for r in REGISTERS if lo <= r.offset <= hi)


MOTION = STAGING  # written at any time unless locked (STAGED); latched at START or at a take-over
CONFIG = _span("DRIVE", "STEP_SPACE")  # written only while stopped (CFG_BUSY)
STORAGE = MOTION + CONFIG  # plain read/write storage
CTRL = REGISTERS_BY_NAME["CTRL"]
STATUS = REGISTERS_BY_NAME["STATUS"]
STEPS_REJECTED = 0x8000_0000  # -2^31: no 31-bit magnitude
ERR = {name: code for name, (code, _) in ERROR_CODES.items()}

#: Read-only values that come from the engine's side: (register, field) -> input port.
ENGINE_SOURCES = {
    ("STATUS", "STATE"): "eng_state",
    ("STATUS", "BUSY"): "eng_busy",
    ("STATUS", "DIR"): "eng_dir",
    ("STATUS", "DIR_FAULT"): "dir_fault",
    ("POSITION", "VALUE"): "eng_position",
    ("CUR_DELAY", "VALUE"): "eng_cur_delay",
    ("STEP_COUNT", "VALUE"): "eng_step_count",
}

#: Wide values assembled from NAME_LO (bits 31:0) and NAME_HI: port name -> (LO, HI) register names.
WIDE_PORTS = {
    r.name[:-3].lower(): (r.name, r.name[:-3] + "_HI")
    for r in REGISTERS
    if r.name.endswith("_LO") and r.name[:-3] + "_HI" in REGISTERS_BY_NAME
}


def _field_ports() -> dict[str, tuple[str, str]]:
    """Outputs that carry one field, port -> (register, field): every field of the storage registers but STEPS (the
    steps and direction outputs) and the wide values' words, in map order, then CTRL.ENABLE. The port of a VALUE
    field is named after its register, any other after the field (DIR_TIMING's with dir_ in front)."""
    wide = {name for pair in WIDE_PORTS.values() for name in pair}
    ports: dict[str, tuple[str, str]] = {}
    for rname in STORAGE:
        if rname == "STEPS" or rname in wide:
            continue
        for f in REGISTERS_BY_NAME[rname].fields:
            port = rname if f.name == "VALUE" else f"DIR_{f.name}" if rname == "DIR_TIMING" else f.name
            ports[port.lower()] = (rname, f.name)
    return {**ports, "enable": ("CTRL", "ENABLE")}


#: Outputs that carry one field: port -> (register, field).
FIELD_PORTS = _field_ports()
#: WS fields of CTRL that pulse the output of their name whenever written 1 (CHANGE only when accepted, QUEUE has no
#: output of its own).
STROBES = {f.name: f.name.lower() for f in CTRL.fields if f.access == WS and f.name not in ("CHANGE", "QUEUE")}
#: Every one-clock strobe output.
STROBE_PORTS = (*STROBES.values(), "change", "pos_load")
#: W1C flags of STATUS and the CTRL enable that routes each to irq (DONE -> IRQ_DONE_EN).
IRQ_ENABLES = {f.name: CTRL.field(f"IRQ_{f.name}_EN") for f in STATUS.fields if f.access == W1C}

ENGINE_INPUTS = (
    "eng_busy",
    "eng_done",
    "eng_error",
    "eng_err_code",
    "eng_state",
    "eng_dir",
    "eng_position",
    "eng_step_count",
    "eng_cur_delay",
    "eng_chg_pend",
    "eng_chg_refused",
    "dir_fault",
)
BUS_INPUTS = ("wr", "rd", "addr", "wdata", "be")
#: Back to 0 after one cycle unless driven again.
PULSE_INPUTS = ("rst", "wr", "rd", "eng_done", "eng_error", "eng_chg_refused")


def byte_mask(be: int) -> int:
    """The data bits selected by byte enables."""
    return sum(0xFF << (8 * i) for i in range(4) if (be >> i) & 1)


def steps_split(value: int) -> tuple[int, int]:
    """STEPS (two's complement) as the engine gets it: (31-bit magnitude, sign)."""
    sign = value >> 31
    return ((-value if sign else value) & 0x7FFF_FFFF), sign


# ---------------------------------------------------------------------------------------------------------------
# The model.


class RegfileModel:
    """The register file as docs/registers.md, docs/stepramp_plb.md and docs/algorithm.md describe it, one clock edge
    at a time."""

    def __init__(self) -> None:
        self.events: Counter[str] = Counter()
        self.pos_value: int | None = None  # pos_value is defined only with pos_load
        self.own_error = False  # the register file flagged an error of its own at this edge
        self.reset()

    def reset(self) -> None:
        self.store = {
            name: REGISTERS_BY_NAME[name].reset & access_mask(REGISTERS_BY_NAME[name], RW) for name in STORAGE
        }
        self.ctrl = CTRL.reset & access_mask(CTRL, RW)
        self.flags = STATUS.reset & access_mask(STATUS, W1C)
        self.err_code = STATUS.field("ERR_CODE").reset
        self.ack = self.err = self.irq = 0
        self.read_ack = False
        self.rdata = 0
        self.strobes = dict.fromkeys(STROBE_PORTS, 0)
        self.q_pend = False  # a queued move, started at the engine's next done

    def locked(self, ins: dict[str, int]) -> bool:
        """STATUS.PENDING at the edge that samples ins: the change strobe out, the engine's pending change, or a
        queued move."""
        return bool(self.strobes["change"] or ins["eng_chg_pend"] or self.q_pend)

    # What a read returns, from the state before the edge and the inputs at the edge.
    def read_value(self, reg: Register, ins: dict[str, int]) -> int:
        value = 0
        for f in reg.fields:
            src = ENGINE_SOURCES.get((reg.name, f.name))
            if src is not None:
                v = ins[src]
            elif reg.name == "STATUS" and f.name == "ERR_CODE":
                v = self.err_code
            elif reg.name == "STATUS" and f.name == "PENDING":
                v = int(self.locked(ins))
            elif f.access == RO:
                v = f.reset  # constant (ID)
            elif f.access == WS:
                v = 0
            elif f.access == W1C:
                v = self.flags >> f.lsb
            elif reg.name == "CTRL":
                v = self.ctrl >> f.lsb
            else:
                v = self.store[reg.name] >> f.lsb
            value |= (v << f.lsb) & f.mask
        return value

    def _flag(self, name: str) -> int:
        return (self.flags >> STATUS.field(name).lsb) & 1

    def _set_flag(self, name: str) -> None:
        self.flags |= STATUS.field(name).mask

    def _error(self, code: str) -> None:
        self.own_error = True
        self._set_flag("ERROR")
        self.err_code = ERR[code]
        self.events[f"error {code}"] += 1

    def _refusal(self, cmd: dict[str, int], ins: dict[str, int], locked: bool) -> str | None:
        """Why a CTRL write with CHANGE or QUEUE is refused (None: accepted)."""
        if not ins["eng_busy"]:
            return "idle"
        if locked:
            return "locked"
        if cmd["CHANGE"] and cmd["QUEUE"]:
            return "both"
        if cmd["CHANGE"] and self.store["STEPS"] >> 31 != ins["eng_dir"]:
            return "direction"
        if cmd["QUEUE"] and self.store["STEPS"] == STEPS_REJECTED:
            return "steps"
        return None

    def _ctrl_write(self, data: int, m: int, ins: dict[str, int], locked: bool) -> bool:
        """A CTRL write (data already masked to the enabled lanes); returns the queued-move flag after it."""
        self.ctrl = ((self.ctrl & ~m) | data) & access_mask(CTRL, RW)
        cmd = {f.name: (data >> f.lsb) & 1 for f in CTRL.fields if f.access == WS}
        for fname, port in STROBES.items():
            self.strobes[port] = cmd[fname]
        q_pend = self.q_pend
        if (cmd["SOFT_STOP"] or cmd["HARD_STOP"]) and not cmd["QUEUE"]:
            self.events["queue dropped by a stop"] += q_pend
            q_pend = False
        if cmd["CHANGE"] or cmd["QUEUE"]:
            reason = self._refusal(cmd, ins, locked)
            if reason is not None:
                self._error("CHANGE")
                self.events[f"refused: {reason}"] += 1
            elif cmd["CHANGE"]:
                self.strobes["change"] = 1
            else:
                q_pend = True
                self.events["queue"] += 1
        if self.strobes["start"] and not ins["eng_busy"] and self.store["STEPS"] == STEPS_REJECTED:
            self.strobes["start"] = 0
            self._set_flag("DONE")
            self._error("STEPS")  # after a CHANGE / QUEUE refusal of the same write: its code wins
        return q_pend

    def clock(self, ins: dict[str, int]) -> None:
        """One rising edge with these inputs."""
        if ins["rst"]:
            self.reset()
            self.events["reset"] += 1
            return
        busy = ins["eng_busy"]
        locked = self.locked(ins)
        self.events["locked"] += locked
        irq = 0
        for flag, enable in IRQ_ENABLES.items():
            irq |= self._flag(flag) & (self.ctrl >> enable.lsb) & 1
        reg = BY_OFFSET.get(ins["addr"] & (WINDOW - 4))
        access = ins["wr"] or ins["rd"]
        self.ack, self.err = int(access), int(access and reg is None)
        self.read_ack = bool(ins["rd"] and reg is not None)
        if access and reg is None:
            self.events["unmapped"] += 1
        if self.read_ack:
            self.rdata = self.read_value(reg, ins)
            self.events[f"read {reg.name}"] += 1
        self.strobes = dict.fromkeys(self.strobes, 0)

        clear = 0
        q_pend = self.q_pend
        self.own_error = False
        if ins["wr"] and reg is not None:
            self.events[f"write {reg.name}"] += 1
            m = byte_mask(ins["be"])
            data = ins["wdata"] & m
            if reg.name in CONFIG and busy:
                self._error("CFG_BUSY")
            elif reg.name in MOTION and locked:
                self._error("STAGED")
            elif reg.name in STORAGE:
                self.store[reg.name] = ((self.store[reg.name] & ~m) | data) & access_mask(reg, RW)
                self.events["config written while locked, idle"] += reg.name in CONFIG and locked
            elif reg is CTRL:
                q_pend = self._ctrl_write(data, m, ins, locked)
            elif reg is STATUS:
                clear = data & access_mask(STATUS, W1C)
            elif reg.name == "POSITION":
                if busy:
                    self._error("POS_BUSY")
                else:
                    self.strobes["pos_load"] = 1
                    self.pos_value = (ins["eng_position"] & ~m & WORD) | data
            # RO registers (ID, CUR_DELAY, STEP_COUNT): acknowledged, nothing changes.

        # The queued move at the engine's done (q_pend as before the edge): started unless the engine failed; then a
        # START written at this edge is dropped with it (the RTL's choice).
        if ins["eng_done"] and self.q_pend:
            q_pend = False
            self.events["queued start" if not ins["eng_error"] else "queue dropped by an error"] += 1
            self.events["start written, dropped with the queue"] += self.strobes["start"] and ins["eng_error"]
            self.strobes["start"] = int(not ins["eng_error"])
        self.q_pend = q_pend

        # Sticky flags: the clear, then this cycle's sets (a set in the same cycle as the clear wins).
        done_m, error_m = STATUS.field("DONE").mask, STATUS.field("ERROR").mask
        sets_error = ins["eng_error"] or ins["eng_chg_refused"]
        if (ins["eng_done"] and clear & done_m) or (sets_error and clear & error_m):
            self.events["set wins over clear"] += 1
        self.flags &= ~clear
        if ins["eng_done"]:
            self._set_flag("DONE")
        if ins["eng_error"]:
            self._set_flag("ERROR")
            self.err_code = ins["eng_err_code"]  # the engine's cause; it wins over the register file's own
            self.events["engine code over own"] += self.own_error
        if ins["eng_chg_refused"]:
            self._set_flag("ERROR")
            self.err_code = ERR["CHANGE"]  # wins over the engine's eng_err_code and the register file's own
            self.events["chg_refused"] += 1
            self.events["chg_refused code over engine's"] += ins["eng_error"]
        for port, value in self.strobes.items():
            self.events[port] += value
        self.events["irq rises"] += irq and not self.irq
        self.irq = irq

    def expected(self) -> dict[str, int | None]:
        """Every output of the register file after the last edge (None: not defined, not compared)."""
        out: dict[str, int | None] = {"ack": self.ack, "err": self.err, "irq": self.irq, **self.strobes}
        out["rdata"] = self.rdata if self.read_ack else None
        out["pos_value"] = self.pos_value if self.strobes["pos_load"] else None
        out["steps"], out["direction"] = steps_split(self.store["STEPS"])
        for port, (rname, fname) in FIELD_PORTS.items():
            f = REGISTERS_BY_NAME[rname].field(fname)
            word = self.ctrl if rname == "CTRL" else self.store[rname]
            out[port] = (word & f.mask) >> f.lsb
        for port, (lo, hi) in WIDE_PORTS.items():
            out[port] = (self.store[hi] << 32) | self.store[lo]
        return out


# ---------------------------------------------------------------------------------------------------------------
# The bench: drives one cycle at a time and compares every output with the model after each edge.


def _value(handle: Any) -> int | None:
    try:
        return int(handle.value)
    except ValueError:
        return None  # X, U, Z ...


class Bench:
    """The register file's inputs, driven one clock at a time, and the model beside it."""

    def __init__(self, dut: Any) -> None:
        self.dut = dut
        self.model = RegfileModel()
        self.ins: dict[str, int] = dict.fromkeys(("rst", *BUS_INPUTS, *ENGINE_INPUTS), 0)
        self.ins["be"] = 0xF
        self.driven: dict[str, int] = {}
        self.handles = {name: getattr(dut, name) for name in self.ins}
        self.outputs = {name: getattr(dut, name) for name in self.model.expected()}
        self.cycles = 0
        self.history: deque[str] = deque(maxlen=6)
        self.widths_checked = False

    async def start(self) -> None:
        """Start the clock and reset; every output is checked from the first reset edge on."""
        start_clock(self.dut.clk)
        self._drive()
        await FallingEdge(self.dut.clk)
        await self.reset()

    async def reset(self, cycles: int = 2) -> None:
        for _ in range(cycles):
            await self.cycle(rst=1)

    def set_engine(self, **values: int) -> None:
        """Engine inputs that stay until changed (eng_done / eng_error are pulses: give them to cycle())."""
        for name, v in values.items():
            assert name in ENGINE_INPUTS, name
            self.ins[name] = v

    def _drive(self) -> None:
        for name, v in self.ins.items():
            if self.driven.get(name) != v:
                self.handles[name].value = v
                self.driven[name] = v
                if name == "addr":  # one address for reads and writes, as on the PLB-like top
                    self.dut.waddr.value = v

    async def cycle(self, **drive: int) -> dict[str, int | None]:
        """Drive inputs for one clock (from a falling edge), let the rising edge sample them, compare after it."""
        for name in PULSE_INPUTS:
            self.ins[name] = 0
        self.ins.update(drive)
        self._drive()
        self.model.clock(self.ins)
        self.history.append(" ".join(f"{k}={v:#x}" for k, v in self.ins.items() if v))
        await FallingEdge(self.dut.clk)
        self.cycles += 1
        got = {name: _value(h) for name, h in self.outputs.items()}
        want = self.model.expected()
        bad = {k: (got[k], w) for k, w in want.items() if w is not None and got[k] != w}
        if bad:
            lines = [f"  {k}: got {g if g is None else hex(g)}, model {w:#x}" for k, (g, w) in bad.items()]
            raise AssertionError(
                f"cycle {self.cycles}: the register file differs from the model\n"
                + "\n".join(lines)
                + "\nlast inputs (oldest first):\n  "
                + "\n  ".join(self.history)
            )
        return got

    async def idle(self, n: int = 1) -> dict[str, int | None]:
        got: dict[str, int | None] = {}
        for _ in range(n):
            got = await self.cycle()
        return got

    async def write(self, offset: int, data: int, be: int = 0xF, **engine: int) -> dict[str, int | None]:
        """One write strobe; returns the outputs one clock later (ack, err, strobes)."""
        got = await self.cycle(wr=1, addr=offset % WINDOW, wdata=data & WORD, be=be, **engine)
        assert got["ack"] == 1, f"no ack for a write at {offset:#x}"
        return got

    async def read(self, offset: int, **engine: int) -> int:
        """One read strobe; returns rdata one clock later (checked against the model there)."""
        got = await self.cycle(rd=1, addr=offset % WINDOW, **engine)
        assert got["ack"] == 1, f"no ack for a read at {offset:#x}"
        assert got["err"] == int(offset % WINDOW & ~3 not in BY_OFFSET)
        return got["rdata"] if got["rdata"] is not None else -1

    async def reg(self, name: str) -> int:
        return await self.read(REGISTERS_BY_NAME[name].offset)

    async def snapshot(self) -> dict[str, int]:
        """Every register as read."""
        return {r.name: await self.read(r.offset) for r in REGISTERS}

    def check_widths(self) -> None:
        """The ports are as wide as the register map's fields."""
        for port, (rname, fname) in FIELD_PORTS.items():
            assert len(self.outputs[port]) == REGISTERS_BY_NAME[rname].field(fname).width, port
        for port, (lo, hi) in WIDE_PORTS.items():
            want = REGISTERS_BY_NAME[lo].field("VALUE").width + REGISTERS_BY_NAME[hi].field("VALUE").width
            assert len(self.outputs[port]) == want, port
        assert len(self.dut.eng_err_code) == STATUS.field("ERR_CODE").width
        assert len(self.dut.addr) == ADDR_BITS


async def new_bench(dut: Any) -> Bench:
    tb = Bench(dut)
    tb.check_widths()
    await tb.start()
    return tb


def off(name: str) -> int:
    return REGISTERS_BY_NAME[name].offset


def field_bits(reg: str, field: str, value: int) -> int:
    f = REGISTERS_BY_NAME[reg].field(field)
    return (value << f.lsb) & f.mask


def field_of(reg: str, field: str, word: int) -> int:
    f = REGISTERS_BY_NAME[reg].field(field)
    return (word & f.mask) >> f.lsb


def cmd(*names: str) -> int:
    """CTRL with these fields set."""
    return sum(CTRL.field(name).mask for name in names)


async def status(tb: Bench) -> dict[str, int]:
    """STATUS as read, field by field."""
    word = await tb.reg("STATUS")
    return {f.name: field_of("STATUS", f.name, word) for f in STATUS.fields}


async def fresh_error(tb: Bench) -> None:
    """ERROR cleared with ERR_CODE LATE (an engine error, then the W1C clear), so that a later flag shows both as
    ERROR = 1 and as a new ERR_CODE."""
    await tb.cycle(eng_error=1, eng_err_code=ERR["LATE"])
    await tb.write(off("STATUS"), STATUS.field("ERROR").mask)
    s = await status(tb)
    assert s["ERROR"] == 0 and s["ERR_CODE"] == ERR["LATE"]


async def refused_command(tb: Bench, data: int, what: str, pending: int = 0) -> None:
    """A CTRL write with CHANGE or QUEUE that the register file refuses: no strobe, ERROR with CHANGE, PENDING as
    given."""
    await fresh_error(tb)
    got = await tb.write(off("CTRL"), data)
    assert got["start"] == 0 and got["change"] == 0, what
    s = await flagged(tb, "CHANGE", what)
    assert s["PENDING"] == pending, what
    await fresh_error(tb)


async def flagged(tb: Bench, code: str | None, what: str) -> dict[str, int]:
    """STATUS after fresh_error(): ERROR with ERR_CODE code, or (None) no new error."""
    s = await status(tb)
    if code is None:
        assert s["ERROR"] == 0 and s["ERR_CODE"] == ERR["LATE"], f"{what}: flagged {s}"
    else:
        assert s["ERROR"] == 1 and s["ERR_CODE"] == ERR[code], f"{what}: {s}, expected ERROR with {code}"
    return s


# ---------------------------------------------------------------------------------------------------------------
# Directed tests.


@cocotb.test(timeout_time=200, timeout_unit="us")
async def reset_values(dut) -> None:
    """Every register reads its reset value after reset, at every address of its word; the outputs to the engine
    are the reset values; and a reset after everything was written brings them all back."""
    tb = await new_bench(dut)
    for reg in REGISTERS:
        for low in range(4):
            assert await tb.read(reg.offset + low) == reg.reset, f"{reg.name}+{low}"
    got = await tb.idle()
    assert got["prescale"] == REGISTERS_BY_NAME["PRESCALE"].reset == 1
    assert got["step_width"] == 1 and got["step_space"] == 1
    assert got["steps"] == 0 and got["direction"] == 0 and got["enable"] == 0 and got["irq"] == 0

    # Write everything, raise the flags and enables, then reset: back to the reset values, irq low.
    rng = random.Random(7)
    for name in STORAGE:
        await tb.write(off(name), rng.getrandbits(32) | 1)
    await tb.write(off("CTRL"), 0xFFFF_FF00)
    await tb.cycle(eng_done=1, eng_error=1, eng_err_code=ERR["LATE"])
    got = await tb.idle(2)
    assert got["irq"] == 1 and got["enable"] == 1
    await tb.reset(1)
    got = await tb.idle()
    assert got["irq"] == 0
    for reg in REGISTERS:
        assert await tb.read(reg.offset) == reg.reset, reg.name


@cocotb.test(timeout_time=500, timeout_unit="us")
async def read_write_fields(dut) -> None:
    """RW fields with their masks under every byte-enable pattern and every low address; RO registers ignore writes;
    unmapped word offsets answer err, and a write there changes nothing."""
    tb = await new_bench(dut)
    rng = random.Random(12)
    for name in (*STORAGE, "CTRL"):
        reg = REGISTERS_BY_NAME[name]
        rw = access_mask(reg, RW)
        await tb.write(reg.offset, WORD)
        assert await tb.reg(name) == rw, name
        await tb.write(reg.offset, 0)
        assert await tb.reg(name) == 0, name
        shadow = 0
        for be in range(16):
            data = rng.getrandbits(32)
            low = rng.randrange(4)
            got = await tb.write(reg.offset + low, data, be)
            assert got["err"] == 0
            m = byte_mask(be)
            shadow = ((shadow & ~m) | (data & m)) & rw
            assert await tb.read(reg.offset + rng.randrange(4)) == shadow, f"{name} be={be:#x}"
    # Read-only: ID, CUR_DELAY, STEP_COUNT and STATUS (its W1C flags are 0, its other fields read the engine).
    tb.set_engine(eng_cur_delay=0x1234_5678, eng_step_count=0x0ABC_DEF0)
    await tb.write(
        off("STATUS"), WORD
    )  # the ERROR of the CHANGE + QUEUE in CTRL = 0xFFFFFFFF: a STATUS write clears it
    before = await tb.snapshot()
    for name in ("ID", "CUR_DELAY", "STEP_COUNT", "STATUS"):
        for data in (WORD, 0, 0x5A5A_5A5A):
            got = await tb.write(off(name), data)
            assert got["err"] == 0
            assert not any(got[s] for s in STROBE_PORTS)
    assert await tb.snapshot() == before
    # Unmapped offsets: err on read and write, at every low address; a write there changes nothing.
    assert UNMAPPED, "the register map fills the window"
    for offset in UNMAPPED:
        for low in range(4):
            got = await tb.write(offset + low, WORD)
            assert got["err"] == 1 and got["ack"] == 1
            assert not any(got[s] for s in STROBE_PORTS)
            await tb.read(offset + low)  # err checked by read()
    assert await tb.snapshot() == before
    # A mapped offset never answers err.
    for reg in REGISTERS:
        got = await tb.cycle(rd=1, addr=reg.offset + 3)
        assert got["err"] == 0 and got["ack"] == 1


@cocotb.test(timeout_time=500, timeout_unit="us")
async def engine_outputs(dut) -> None:
    """The move and configuration outputs: STEPS as magnitude and sign, the wide values from their LO / HI words
    (also written byte by byte), the other fields, and enable."""
    tb = await new_bench(dut)
    rng = random.Random(3)
    for value in (0, 1, 5, 0x7FFF_FFFF, WORD, 0x8000_0001, 0xFFFF_FF9C, 0x8000_0000, *rng.sample(range(1 << 32), 8)):
        await tb.write(off("STEPS"), value, 0xF)
        got = await tb.idle()
        signed = value - (1 << 32) if value >> 31 else value
        assert got["direction"] == int(signed < 0), hex(value)
        assert got["steps"] == abs(signed) % (1 << 31), hex(value)
    for port, (lo, hi) in WIDE_PORTS.items():
        width = len(tb.outputs[port])
        for _ in range(4):
            value = rng.getrandbits(width)
            # LO then HI, byte by byte, in a random order of lanes.
            for word_name, word in ((lo, value & WORD), (hi, value >> 32)):
                for lane in rng.sample(range(4), 4):
                    await tb.write(off(word_name) + rng.randrange(4), word, 1 << lane)
            got = await tb.idle()
            assert got[port] == value, f"{port}: {got[port]:#x} != {value:#x}"
    for port, (rname, fname) in FIELD_PORTS.items():
        f = REGISTERS_BY_NAME[rname].field(fname)
        for value in (0, (1 << f.width) - 1, rng.getrandbits(f.width)):
            if rname == "CTRL":
                await tb.write(off(rname), value << f.lsb, 0b0100)  # ENABLE is in byte 2
            else:
                await tb.write(off(rname), (rng.getrandbits(32) & ~f.mask) | (value << f.lsb))
            got = await tb.idle()
            assert got[port] == value, f"{port}: {got[port]} != {value}"


@cocotb.test(timeout_time=500, timeout_unit="us")
async def ctrl_strobes(dut) -> None:
    """START / SOFT_STOP / HARD_STOP: one-clock pulses only when written 1 with byte 0 enabled; the irq enables in
    byte 1, ENABLE in byte 2; CTRL reads its RW bits only. STEPS = 0x80000000 at START while idle: no start, DONE +
    ERROR with ERR_CODE STEPS; while busy the start strobe passes (the engine ignores it) and nothing is flagged.
    (CHANGE and QUEUE: change_commit, queue_commit.)"""
    tb = await new_bench(dut)
    bits = {port: CTRL.field(name).mask for name, port in STROBES.items()}
    for be in range(16):
        for data in (WORD & ~cmd("CHANGE", "QUEUE"), bits["start"], bits["soft_stop"] | bits["hard_stop"], 0x0001_0300):
            got = await tb.write(off("CTRL") + (be & 3), data, be)
            for port, mask in bits.items():
                assert got[port] == int(bool(be & 1 and data & mask)), f"{port} be={be:#x} data={data:#x}"
            assert got["change"] == 0
            got = await tb.idle()
            assert not any(got[p] for p in bits), "a strobe longer than one clock"
            ctrl = await tb.reg("CTRL")
            assert ctrl & access_mask(CTRL, WS) == 0
    # Byte lanes of the RW bits.
    await tb.write(off("CTRL"), 0, 0xF)
    await tb.write(off("CTRL"), WORD & ~cmd("CHANGE", "QUEUE"), 0b0001)
    assert await tb.reg("CTRL") == 0
    await tb.write(off("CTRL"), WORD, 0b0010)
    assert await tb.reg("CTRL") == field_bits("CTRL", "IRQ_DONE_EN", 1) | field_bits("CTRL", "IRQ_ERROR_EN", 1)
    await tb.write(off("CTRL"), 0, 0b0001)
    await tb.write(off("CTRL"), WORD, 0b1100)
    assert await tb.reg("CTRL") == access_mask(CTRL, RW)
    await tb.write(off("CTRL"), 0, 0b0010)
    assert await tb.reg("CTRL") == field_bits("CTRL", "ENABLE", 1)

    # The STEPS check, written byte by byte (the check sees the whole word).
    for lane, byte in enumerate((0x00, 0x00, 0x00, 0x80)):
        await tb.write(off("STEPS"), byte << (8 * lane), 1 << lane)
    assert await tb.reg("STEPS") == STEPS_REJECTED
    got = await tb.write(off("CTRL"), bits["start"], 0b0010)  # START bit but byte 0 not enabled: nothing
    assert got["start"] == 0 and await tb.reg("STATUS") == 0
    got = await tb.write(off("CTRL"), bits["start"] | bits["hard_stop"], 0b0001)
    assert got["start"] == 0 and got["hard_stop"] == 1
    status = await tb.reg("STATUS")
    assert field_of("STATUS", "DONE", status) == 1 and field_of("STATUS", "ERROR", status) == 1
    assert field_of("STATUS", "ERR_CODE", status) == ERR["STEPS"]
    await tb.write(off("STATUS"), WORD)
    assert await tb.reg("STATUS") == field_bits("STATUS", "ERR_CODE", ERR["STEPS"])  # ERR_CODE stays
    tb.set_engine(eng_busy=1)
    got = await tb.write(off("CTRL"), bits["start"], 0b0001)
    assert got["start"] == 1
    status = await tb.reg("STATUS")
    assert field_of("STATUS", "DONE", status) == 0 and field_of("STATUS", "ERROR", status) == 0
    tb.set_engine(eng_busy=0)
    # One below and one above: no rejection.
    for value in (0x7FFF_FFFF, 0x8000_0001):
        await tb.write(off("STEPS"), value)
        got = await tb.write(off("CTRL"), bits["start"])
        assert got["start"] == 1
        assert field_of("STATUS", "ERROR", await tb.reg("STATUS")) == 0


@cocotb.test(timeout_time=500, timeout_unit="us")
async def status_and_irq(dut) -> None:
    """STATUS follows the engine's inputs; DONE and ERROR are sticky and W1C (byte 0 enabled), a set in the same
    cycle as the clear wins, ERR_CODE keeps the last cause; irq is registered, one clock after the flags."""
    tb = await new_bench(dut)
    rng = random.Random(5)
    for _ in range(40):
        state, busy, d, fault = rng.randrange(4), rng.randrange(2), rng.randrange(2), rng.randrange(2)
        tb.set_engine(eng_state=state, eng_busy=busy, eng_dir=d, dir_fault=fault, eng_err_code=rng.randrange(32))
        status = await tb.reg("STATUS")
        assert field_of("STATUS", "STATE", status) == state
        assert field_of("STATUS", "BUSY", status) == busy
        assert field_of("STATUS", "DIR", status) == d
        assert field_of("STATUS", "DIR_FAULT", status) == fault
        assert field_of("STATUS", "DONE", status) == 0 and field_of("STATUS", "ERROR", status) == 0
        assert field_of("STATUS", "ERR_CODE", status) == 0, "eng_err_code counts only with eng_error"
        for name, port in (("POSITION", "eng_position"), ("CUR_DELAY", "eng_cur_delay")):
            tb.set_engine(**{port: rng.getrandbits(32)})
            assert await tb.reg(name) == tb.ins[port]
        tb.set_engine(eng_step_count=rng.getrandbits(31))
        assert await tb.reg("STEP_COUNT") == tb.ins["eng_step_count"]
    tb.set_engine(eng_state=0, eng_busy=0, eng_dir=0, dir_fault=0)

    done, error = STATUS.field("DONE").mask, STATUS.field("ERROR").mask
    await tb.cycle(eng_done=1)
    for _ in range(3):
        assert await tb.reg("STATUS") == done
    await tb.write(off("STATUS"), done, 0b1110)  # byte 0 not enabled: no clear
    assert await tb.reg("STATUS") == done
    await tb.write(off("STATUS"), error)  # clears only ERROR (which is 0)
    assert await tb.reg("STATUS") == done
    await tb.write(off("STATUS"), done)
    assert await tb.reg("STATUS") == 0
    for code in (ERR["LATE"], ERR["STEP_SPACE"], 31, ERR["PRESCALE"]):
        await tb.cycle(eng_error=1, eng_err_code=code)
        tb.set_engine(eng_err_code=0)
        assert await tb.reg("STATUS") == error | field_bits("STATUS", "ERR_CODE", code)
    await tb.write(off("STATUS"), error)
    assert await tb.reg("STATUS") == field_bits("STATUS", "ERR_CODE", ERR["PRESCALE"]), "ERR_CODE keeps its cause"
    # A set in the same cycle as the clear wins, for each flag.
    await tb.cycle(eng_done=1, eng_error=1, eng_err_code=ERR["RANGE"])
    await tb.write(off("STATUS"), done | error, eng_done=1)
    assert await tb.reg("STATUS") & (done | error) == done
    await tb.write(off("STATUS"), done | error, eng_error=1, eng_err_code=ERR["ZERO_TICKS"])
    status = await tb.reg("STATUS")
    assert status & (done | error) == error and field_of("STATUS", "ERR_CODE", status) == ERR["ZERO_TICKS"]
    await tb.write(off("STATUS"), done | error)
    assert await tb.reg("STATUS") & (done | error) == 0

    # irq: each flag through its enable, one clock after the flag; and low again one clock after the clear.
    for flag, enable in IRQ_ENABLES.items():
        mask = STATUS.field(flag).mask
        pulse = {"eng_done": 1} if flag == "DONE" else {"eng_error": 1, "eng_err_code": ERR["LATE"]}
        for other in IRQ_ENABLES.values():  # the other enable alone does not route this flag
            if other is not enable:
                await tb.write(off("CTRL"), other.mask, 0b0010)
                await tb.cycle(**pulse)
                assert (await tb.idle(3))["irq"] == 0
                await tb.write(off("STATUS"), mask)
        await tb.write(off("CTRL"), enable.mask, 0b0010)
        got = await tb.cycle(**pulse)  # the flag is set at this edge ...
        assert got["irq"] == 0
        got = await tb.idle()  # ... and irq one edge later
        assert got["irq"] == 1
        await tb.write(off("CTRL"), 0, 0b0001)  # a byte-0 write keeps the enables
        assert (await tb.idle())["irq"] == 1
        got = await tb.write(off("STATUS"), mask)
        assert got["irq"] == 1
        assert (await tb.idle())["irq"] == 0
        await tb.cycle(**pulse)  # the enable off: the flag stays, irq falls
        assert (await tb.idle())["irq"] == 1
        await tb.write(off("CTRL"), 0, 0b0010)
        assert (await tb.idle())["irq"] == 0
        await tb.write(off("STATUS"), mask)


@cocotb.test(timeout_time=500, timeout_unit="us")
async def position_and_config_while_busy(dut) -> None:
    """POSITION: pos_load with the written bytes merged into eng_position while idle; ignored with ERROR POS_BUSY
    while busy. DRIVE .. STEP_SPACE: ignored with ERROR CFG_BUSY while busy; the motion registers and CTRL.ENABLE
    are written at any time."""
    tb = await new_bench(dut)
    rng = random.Random(9)
    for be in range(16):
        tb.set_engine(eng_position=rng.getrandbits(32))
        data = rng.getrandbits(32)
        got = await tb.write(off("POSITION") + rng.randrange(4), data, be)
        m = byte_mask(be)
        assert got["pos_load"] == 1
        assert got["pos_value"] == (tb.ins["eng_position"] & ~m & WORD) | (data & m)
        assert (await tb.idle())["pos_load"] == 0
    assert await tb.reg("STATUS") == 0

    tb.set_engine(eng_busy=1)
    got = await tb.write(off("POSITION"), 0x1234_5678)
    assert got["pos_load"] == 0
    status = await tb.reg("STATUS")
    assert field_of("STATUS", "ERROR", status) == 1 and field_of("STATUS", "DONE", status) == 0
    assert field_of("STATUS", "ERR_CODE", status) == ERR["POS_BUSY"]
    await tb.write(off("STATUS"), WORD)

    before = {name: await tb.reg(name) for name in STORAGE}
    for name in CONFIG:
        got = await tb.write(off(name), ~before[name] & WORD, rng.randrange(1, 16))
        status = await tb.reg("STATUS")
        assert field_of("STATUS", "ERROR", status) == 1 and field_of("STATUS", "ERR_CODE", status) == ERR["CFG_BUSY"]
        await tb.write(off("STATUS"), WORD)
        assert await tb.reg(name) == before[name], f"{name} written while busy"
    for name in MOTION:
        value = rng.getrandbits(32) & access_mask(REGISTERS_BY_NAME[name], RW)
        await tb.write(off(name), value)
        assert await tb.reg(name) == value
    assert field_of("STATUS", "ERROR", await tb.reg("STATUS")) == 0
    await tb.write(off("CTRL"), WORD, 0b0100)
    assert (await tb.idle())["enable"] == 1
    # A write that enables no byte is still a write while busy (rejected, flagged).
    await tb.write(off("DRIVE"), WORD, 0)
    assert field_of("STATUS", "ERR_CODE", await tb.reg("STATUS")) == ERR["CFG_BUSY"]
    # The engine's own error in the same cycle: its code is kept.
    await tb.write(off("PWM_PERIOD"), 7, eng_error=1, eng_err_code=ERR["LATE"])
    assert field_of("STATUS", "ERR_CODE", await tb.reg("STATUS")) == ERR["LATE"]
    tb.set_engine(eng_busy=0)
    for name in CONFIG:
        await tb.write(off(name), ~before[name] & WORD)
        assert await tb.reg(name) == ~before[name] & access_mask(REGISTERS_BY_NAME[name], RW)


#: The outputs that carry staging words (locked while PENDING).
STAGED_PORTS = ("steps", "direction", *(p for p, (r, _) in FIELD_PORTS.items() if r in MOTION), *WIDE_PORTS)


@cocotb.test(timeout_time=500, timeout_unit="us")
async def change_commit(dut) -> None:
    """CTRL.CHANGE (byte 0 enabled) while busy, with nothing pending and STEPS' sign equal to eng_dir: change pulses
    for one clock (with a stop in the same write too: the engine checks that), no error, PENDING while the pulse is
    out and while eng_chg_pend holds it. Refused (no pulse, ERROR with ERR_CODE CHANGE) while idle, with STEPS' sign
    against eng_dir (either way), with QUEUE in the same write, and while locked by the pulse itself, eng_chg_pend or
    a queued move. eng_chg_refused flags CHANGE, over an engine error and over a clear in the same cycle. change_at
    follows CHANGE_AT."""
    tb = await new_bench(dut)
    for value in (0x7FFF_FFFF, 0xDEAD_BEEF, 0x8000_0000, 1234):
        await tb.write(off("CHANGE_AT"), value)
        assert (await tb.idle())["change_at"] == value & 0x7FFF_FFFF
    await tb.write(off("STEPS"), 100)  # forwards
    tb.set_engine(eng_busy=1, eng_state=2, eng_dir=0)
    await fresh_error(tb)

    async def accepted(data: int, what: str) -> None:
        got = await tb.write(off("CTRL"), data)
        assert got["change"] == 1 and got["change_at"] == 1234, what
        s = await status(tb)  # sampled while the pulse is out
        assert s["PENDING"] == 1, what
        assert (await tb.idle())["change"] == 0, f"{what}: a pulse longer than one clock"
        s = await flagged(tb, None, what)
        assert s["PENDING"] == 0, what

    refused = functools.partial(refused_command, tb)

    got = await tb.write(off("CTRL"), cmd("CHANGE"), 0b1110)  # byte 0 not enabled: no command
    assert got["change"] == 0
    await flagged(tb, None, "CHANGE without byte 0")
    await accepted(cmd("CHANGE"), "CHANGE forwards")
    got = await tb.write(off("CTRL"), cmd("CHANGE", "SOFT_STOP"))
    assert got["change"] == 1 and got["soft_stop"] == 1
    await tb.idle()
    await flagged(tb, None, "CHANGE with SOFT_STOP")

    tb.set_engine(eng_busy=0, eng_state=0)
    await refused(cmd("CHANGE"), "CHANGE while idle")
    tb.set_engine(eng_busy=1, eng_state=1)
    tb.set_engine(eng_dir=1)
    await refused(cmd("CHANGE"), "CHANGE forwards while running backwards")
    await tb.write(off("STEPS"), -100 & WORD)
    await accepted(cmd("CHANGE"), "CHANGE backwards")
    tb.set_engine(eng_dir=0)
    await refused(cmd("CHANGE"), "CHANGE backwards while running forwards")
    await tb.write(off("STEPS"), 100)
    await refused(cmd("CHANGE", "QUEUE"), "CHANGE with QUEUE")
    await accepted(cmd("CHANGE"), "CHANGE after the refusals")

    # Locked by the pulse: a second CHANGE in the next cycle is refused.
    await fresh_error(tb)
    got = await tb.write(off("CTRL"), cmd("CHANGE"))
    assert got["change"] == 1
    got = await tb.write(off("CTRL"), cmd("CHANGE"))
    assert got["change"] == 0
    await flagged(tb, "CHANGE", "CHANGE during the pulse")
    # Locked by the engine's pending change (the engine takes it over from the pulse on).
    await fresh_error(tb)
    got = await tb.write(off("CTRL"), cmd("CHANGE"))
    assert got["change"] == 1
    tb.set_engine(eng_chg_pend=1)
    for _ in range(3):
        assert (await status(tb))["PENDING"] == 1
    await refused(cmd("CHANGE"), "CHANGE while the engine holds one", pending=1)
    tb.set_engine(eng_chg_pend=0)
    assert (await status(tb))["PENDING"] == 0
    # Locked by a queued move.
    got = await tb.write(off("CTRL"), cmd("QUEUE"))
    await flagged(tb, None, "QUEUE")
    await refused(cmd("CHANGE"), "CHANGE while a move is queued", pending=1)
    await tb.write(off("CTRL"), cmd("HARD_STOP"))  # drops the queue
    await accepted(cmd("CHANGE"), "CHANGE once the queue is dropped")

    # The engine's refusal: ERROR with CHANGE, over an engine error and over a clear in the same cycle.
    got = await tb.cycle(eng_chg_refused=1)
    assert got["change"] == 0
    s = await flagged(tb, "CHANGE", "eng_chg_refused")
    assert s["PENDING"] == 0
    await fresh_error(tb)
    await tb.cycle(eng_chg_refused=1, eng_error=1, eng_err_code=ERR["STEP_SPACE"])
    await flagged(tb, "CHANGE", "eng_chg_refused with an engine error")
    await fresh_error(tb)
    await tb.write(off("STATUS"), WORD, eng_chg_refused=1)
    await flagged(tb, "CHANGE", "eng_chg_refused with a clear")
    # The register file's own refusal with an engine error in the same cycle: the engine's code.
    await fresh_error(tb)
    tb.set_engine(eng_busy=0)
    await tb.write(off("CTRL"), cmd("CHANGE"), eng_error=1, eng_err_code=ERR["STEP_SPACE"])
    await flagged(tb, "STEP_SPACE", "CHANGE refused with an engine error")
    # START refused for STEPS and CHANGE refused (idle) in one write: STEPS (the RTL's order).
    await tb.write(off("STEPS"), STEPS_REJECTED)
    await fresh_error(tb)
    got = await tb.write(off("CTRL"), cmd("START", "CHANGE"))
    assert got["start"] == 0 and got["change"] == 0
    await flagged(tb, "STEPS", "START and CHANGE refused together")


@cocotb.test(timeout_time=500, timeout_unit="us")
async def queue_commit(dut) -> None:
    """CTRL.QUEUE (byte 0 enabled) while busy, with nothing pending and STEPS != 0x80000000 (its sign is free): no
    strobe, PENDING until the engine's done, which pulses start at that edge (once), or without a start when the done
    comes with an error. A SOFT_STOP or HARD_STOP written without QUEUE drops the queued move (its strobe pulses),
    SOFT_STOP + QUEUE stops and queues, and a reset drops it. Refused (ERROR with CHANGE, nothing queued) while idle,
    with STEPS = 0x80000000, and while locked (eng_chg_pend, a queued move)."""
    tb = await new_bench(dut)
    await tb.write(off("STEPS"), -50 & WORD)  # against eng_dir: QUEUE does not check the direction
    tb.set_engine(eng_busy=1, eng_state=1, eng_dir=0)
    await fresh_error(tb)

    async def queue(data: int = cmd("QUEUE"), what: str = "QUEUE") -> dict[str, int | None]:
        got = await tb.write(off("CTRL"), data)
        assert got["start"] == 0 and got["change"] == 0, what
        s = await flagged(tb, None, what)
        assert s["PENDING"] == 1, f"{what}: not queued"
        return got

    async def done(start: int, what: str, **engine: int) -> None:
        """The engine's done (busy already low at that edge, as in the core), then the queue is gone."""
        tb.set_engine(eng_busy=0, eng_state=0)
        got = await tb.cycle(eng_done=1, **engine)
        assert got["start"] == start, f"{what}: start {got['start']}"
        assert (await tb.idle())["start"] == 0, f"{what}: a start longer than one clock"
        s = await status(tb)
        assert s["PENDING"] == 0 and s["DONE"] == 1, what
        got = await tb.cycle(eng_done=1)  # a second done starts nothing
        assert got["start"] == 0, what
        await tb.write(off("STATUS"), STATUS.field("DONE").mask)
        tb.set_engine(eng_busy=1, eng_state=1)

    refused = functools.partial(refused_command, tb)

    got = await tb.write(off("CTRL"), cmd("QUEUE"), 0b1110)  # byte 0 not enabled: no command
    assert (await status(tb))["PENDING"] == 0
    await queue()
    await tb.idle(5)
    assert (await status(tb))["PENDING"] == 1
    await refused(cmd("QUEUE"), "QUEUE while one is queued", pending=1)
    await done(1, "queued move at done")

    # Dropped: by an error at the done, by a stop written without QUEUE, by a reset.
    await queue()
    await done(0, "queued move at a done with error", eng_error=1, eng_err_code=ERR["STEP_SPACE"])
    await flagged(tb, "STEP_SPACE", "queued move at a done with error")
    await fresh_error(tb)
    for stop in ("SOFT_STOP", "HARD_STOP"):
        await queue()
        got = await tb.write(off("CTRL"), cmd(stop))
        assert got[stop.lower()] == 1 and got["start"] == 0
        assert (await status(tb))["PENDING"] == 0, f"{stop} kept the queued move"
        await done(0, f"queued move after {stop}")
    await queue()
    await tb.reset(1)
    tb.set_engine(eng_busy=1, eng_state=1)
    await tb.write(off("STEPS"), 50)
    assert (await status(tb))["PENDING"] == 0
    await done(0, "queued move after a reset")
    await fresh_error(tb)

    # SOFT_STOP + QUEUE: the stop and the queue (how the driver reverses); with a move already queued the QUEUE is
    # refused and the stop, which comes with QUEUE, does not drop the queued move.
    got = await queue(cmd("SOFT_STOP", "QUEUE"), "SOFT_STOP + QUEUE")
    assert got["soft_stop"] == 1
    await fresh_error(tb)
    got = await tb.write(off("CTRL"), cmd("HARD_STOP", "QUEUE"))
    assert got["hard_stop"] == 1
    s = await flagged(tb, "CHANGE", "HARD_STOP + QUEUE while queued")
    assert s["PENDING"] == 1
    await fresh_error(tb)
    await done(1, "queued move after SOFT_STOP + QUEUE")

    # Refusals.
    tb.set_engine(eng_busy=0, eng_state=0)
    await refused(cmd("QUEUE"), "QUEUE while idle")
    tb.set_engine(eng_busy=1, eng_state=1)
    await tb.write(off("STEPS"), STEPS_REJECTED)
    await refused(cmd("QUEUE"), "QUEUE with STEPS = 0x80000000")
    await tb.write(off("STEPS"), STEPS_REJECTED + 1)
    tb.set_engine(eng_chg_pend=1)
    await refused(cmd("QUEUE"), "QUEUE while the engine holds a change", pending=1)
    tb.set_engine(eng_chg_pend=0)
    await queue(what="QUEUE with STEPS = 0x80000001")

    # Pinned as the RTL has them: a stop written at the done's edge lets the queued move start (it was queued before
    # that edge) ...
    tb.set_engine(eng_busy=0, eng_state=0)
    got = await tb.write(off("CTRL"), cmd("SOFT_STOP"), eng_done=1)
    assert got["start"] == 1 and got["soft_stop"] == 1
    assert (await status(tb))["PENDING"] == 0
    # ... and a START written at the edge where an error drops the queued move is dropped too.
    tb.set_engine(eng_busy=1, eng_state=1)
    await queue()
    tb.set_engine(eng_busy=0, eng_state=0)
    got = await tb.write(off("CTRL"), cmd("START"), eng_done=1, eng_error=1, eng_err_code=ERR["LATE"])
    assert got["start"] == 0
    assert (await status(tb))["PENDING"] == 0
    got = await tb.write(off("CTRL"), cmd("START"))  # without the error: the START passes
    assert got["start"] == 1


@cocotb.test(timeout_time=1, timeout_unit="ms")
async def staging_locked(dut) -> None:
    """While locked (the change pulse, eng_chg_pend, a queued move) a write to a staging word (STEPS .. STOP_RATIO,
    SEGMENT .. CHANGE_AT), with any byte enables, is acknowledged without err, ignored (read-back and outputs keep
    their value) and sets ERROR with STAGED; once unlocked the words are written again. The lock leaves the other
    registers alone: a configuration word keeps its CFG_BUSY rule only (written while locked and idle), CTRL, STATUS
    and POSITION work as ever."""
    tb = await new_bench(dut)
    rng = random.Random(21)
    values = {name: rng.getrandbits(32) & access_mask(REGISTERS_BY_NAME[name], RW) for name in MOTION}
    values["STEPS"] = rng.getrandbits(31) | 1  # forwards, not 0x80000000: CHANGE and QUEUE are accepted
    for name, value in values.items():
        await tb.write(off(name), value)
    tb.set_engine(eng_busy=1, eng_state=2, eng_dir=0)
    before = await tb.idle()

    for source in ("change", "eng_chg_pend", "queue"):
        for name in MOTION:
            await fresh_error(tb)
            if source == "eng_chg_pend":
                tb.set_engine(eng_chg_pend=1)
            elif source == "queue":
                await tb.write(off("CTRL"), cmd("QUEUE"))
            else:  # the staging write in the cycle right after the CHANGE
                assert (await tb.write(off("CTRL"), cmd("CHANGE")))["change"] == 1
            got = await tb.write(off(name) + rng.randrange(4), ~values[name] & WORD, rng.randrange(16))
            assert got["err"] == 0
            got = await tb.idle()
            changed = [p for p in STAGED_PORTS if got[p] != before[p]]
            assert not changed, f"{name} written while locked by {source}: {changed} changed"
            assert await tb.read(off(name)) == values[name], f"{name} written while locked by {source}"
            await flagged(tb, "STAGED", f"{name} while locked by {source}")
            if source == "eng_chg_pend":
                tb.set_engine(eng_chg_pend=0)
            elif source == "queue":
                await tb.write(off("CTRL"), cmd("HARD_STOP"))
            assert (await status(tb))["PENDING"] == 0

    # The other registers while locked.
    tb.set_engine(eng_chg_pend=1)
    await fresh_error(tb)
    await tb.write(off("CTRL"), field_bits("CTRL", "IRQ_DONE_EN", 1), 0b0010)
    assert await tb.reg("CTRL") == field_bits("CTRL", "IRQ_DONE_EN", 1)
    await tb.cycle(eng_done=1)
    await tb.write(off("STATUS"), STATUS.field("DONE").mask)
    s = await flagged(tb, None, "CTRL and STATUS while locked")
    assert s["DONE"] == 0 and s["PENDING"] == 1
    await tb.write(off("DRIVE"), WORD)  # busy: CFG_BUSY, checked first
    await flagged(tb, "CFG_BUSY", "DRIVE while locked and busy")
    await fresh_error(tb)
    await tb.write(off("POSITION"), 77)
    await flagged(tb, "POS_BUSY", "POSITION while locked and busy")
    tb.set_engine(eng_busy=0, eng_state=0)  # locked while idle (the engine's pending change, in this bench)
    await fresh_error(tb)
    assert (await tb.write(off("POSITION"), 77))["pos_load"] == 1
    for name in CONFIG:
        value = rng.getrandbits(32) & access_mask(REGISTERS_BY_NAME[name], RW)
        await tb.write(off(name), value)
        assert await tb.reg(name) == value, f"{name} (configuration) not written while locked and idle"
    await flagged(tb, None, "configuration while locked and idle")
    await tb.write(off("STEPS"), 5)
    await flagged(tb, "STAGED", "STEPS while locked and idle")
    tb.set_engine(eng_chg_pend=0)

    # Unlocked: the staging words are written again.
    await fresh_error(tb)
    for name in MOTION:
        value = rng.getrandbits(32) & access_mask(REGISTERS_BY_NAME[name], RW)
        await tb.write(off(name), value)
        assert await tb.reg(name) == value, f"{name} not written once unlocked"
    await flagged(tb, None, "staging words once unlocked")


# ---------------------------------------------------------------------------------------------------------------
# The random sequence.

#: Relative weights of the registers a random access picks (the ones with behaviour weigh more).
WEIGHTS = {"CTRL": 9, "STATUS": 4, "STEPS": 4, "POSITION": 3, **dict.fromkeys(CONFIG, 2)}


#: CTRL command bits a random CTRL write picks from.
COMMAND_MIXES = tuple(
    sum(CTRL.field(name).mask for name in names)
    for names in (
        ("CHANGE",),
        ("CHANGE",),
        ("QUEUE",),
        ("QUEUE",),
        ("SOFT_STOP",),
        ("HARD_STOP",),
        ("SOFT_STOP", "QUEUE"),
        ("HARD_STOP", "CHANGE"),
        ("CHANGE", "QUEUE"),
        ("START", "CHANGE"),
    )
)


def random_inputs(rng: random.Random, tb: Bench) -> dict[str, int]:
    """The inputs of one random cycle (engine inputs are changed in tb directly)."""
    eng = tb.ins
    if rng.random() < 0.05:
        eng["eng_busy"] ^= 1
        eng["eng_state"] = rng.randrange(1, 4) if eng["eng_busy"] else 0
    if rng.random() < 0.05:
        eng["eng_dir"] ^= 1
    if rng.random() < 0.01:
        eng["dir_fault"] ^= 1
    for name, bits in (("eng_position", 32), ("eng_cur_delay", 32), ("eng_step_count", 31)):
        if rng.random() < 0.1:
            eng[name] = rng.getrandbits(bits)
    if rng.random() < (0.1 if eng["eng_chg_pend"] else 0.01):  # held for about 10 cycles, off about 100
        eng["eng_chg_pend"] ^= 1
    eng["eng_err_code"] = rng.randrange(1, 17) if rng.random() < 0.9 else rng.randrange(32)
    # A queued move (the model's state, so the sequence stays replayable) meets the engine's done sooner and more
    # often with an error.
    queued = tb.model.q_pend
    done = int(rng.random() < (0.12 if queued else 0.04))
    drive: dict[str, int] = {
        "eng_done": done,
        "eng_error": int(rng.random() < (0.3 if done and queued else 0.03)),
        "eng_chg_refused": int(rng.random() < 0.01),
        # Garbage on the bus when there is no strobe.
        "addr": rng.randrange(WINDOW),
        "wdata": rng.getrandbits(32),
        "be": rng.randrange(16),
    }
    if rng.random() < 0.002:
        drive["rst"] = 1
    kind = rng.random()
    if kind < 0.2:
        return drive
    if rng.random() < 0.08:
        offset = rng.choice(UNMAPPED)
    else:
        names = [r.name for r in REGISTERS]
        offset = off(rng.choices(names, weights=[WEIGHTS.get(n, 1) for n in names])[0])
    drive["addr"] = offset + rng.randrange(4)
    if rng.random() < 0.5:
        drive["be"] = 0xF
    if kind < 0.55:
        drive["rd"] = 1
        return drive
    drive["wr"] = 1
    if offset == off("STEPS") and rng.random() < 0.5:
        drive["wdata"] = STEPS_REJECTED
    elif offset == off("CTRL"):
        kind = rng.random()
        if kind < (0.3 if eng["eng_busy"] else 0.5):  # START mostly while idle, the commands mostly while busy
            drive["wdata"] |= CTRL.field("START").mask
        elif kind < 0.9:  # one command mix (QUEUE and CHANGE mostly), the other command bits 0
            drive["wdata"] = (drive["wdata"] & ~access_mask(CTRL, WS)) | rng.choice(COMMAND_MIXES)
    elif offset == off("STATUS"):
        drive["wdata"] = rng.choice((WORD, 0, drive["wdata"]))
        if rng.random() < 0.3:  # an engine event in the cycle of the clear
            drive[rng.choice(("eng_done", "eng_error", "eng_chg_refused"))] = 1
    return drive


@cocotb.test(timeout_time=20, timeout_unit="ms")  # room for REGFILE_CYCLES up to 1,000,000
async def random_sequence(dut) -> None:
    """A seeded random sequence of reads, writes, engine events and resets, compared cycle by cycle with the model
    (REGFILE_SEED, REGFILE_CYCLES): CTRL writes with CHANGE / QUEUE mixes, eng_chg_pend held now and then, rare
    eng_chg_refused strobes."""
    seed = env_int("REGFILE_SEED", 1)
    n = env_int("REGFILE_CYCLES", 4000)
    dut._log.info(f"REGFILE_SEED={seed} REGFILE_CYCLES={n}")
    rng = random.Random(seed)
    tb = await new_bench(dut)
    try:
        for _ in range(n):
            await tb.cycle(**random_inputs(rng, tb))
    except AssertionError as e:
        raise AssertionError(f"REGFILE_SEED={seed}: {e}") from None
    ev = tb.model.events
    dut._log.info(
        f"{tb.cycles} cycles: " + ", ".join(f"{k} {v}" for k, v in sorted(ev.items()) if not k.startswith("read "))
    )
    if n >= 4000:  # the sequence reached every rule
        for key in (
            "start",
            "soft_stop",
            "hard_stop",
            "pos_load",
            "error STEPS",
            "error POS_BUSY",
            "error CFG_BUSY",
            "set wins over clear",
            "unmapped",
            "irq rises",
            "reset",
            "change",
            "queue",
            "error CHANGE",
            "error STAGED",
            "chg_refused",
        ):
            assert ev[key] >= 2, f"REGFILE_SEED={seed}: the sequence hit '{key}' {ev[key]} times"
        assert ev["queued start"] >= 1, f"REGFILE_SEED={seed}: no queued move started"
        for reg in REGISTERS:
            assert ev[f"read {reg.name}"] >= 5 and ev[f"write {reg.name}"] >= 5, reg.name


def test_regfile() -> None:
    """stepramp_regfile alone against the model; REGFILE_SEED (printed; random unless set) seeds the random test."""
    seed = int(os.environ.get("REGFILE_SEED") or random.randrange(1 << 32))
    print(f"REGFILE_SEED={seed}")
    run_cocotb(
        "stepramp_regfile",
        "test_regfile",
        build_dir("regfile"),
        extra_env={"REGFILE_SEED": str(seed), "REGFILE_CYCLES": os.environ.get("REGFILE_CYCLES", "4000")},
    )
