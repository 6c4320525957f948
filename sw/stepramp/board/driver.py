# SPDX-License-Identifier: MIT
"""The stepramp driver: physical units in, register writes out, over any register access.

The same class drives the simulated bus (cocotb, through an IPIF or AXI4-Lite master) and, on a board, the core
mapped with /dev/mem or UIO (:class:`MmapAccess`). Register access is asynchronous so that a simulation can
advance while the driver waits; on a board the methods simply run to completion.

    drv = StepRamp(access, fclk=50e6, spr=400 * 16)
    await drv.move(steps=3200, accel=40.0, decel=40.0, speed=20.0)
    status = await drv.wait_done()
"""

from __future__ import annotations

import dataclasses
import math
import mmap
import os
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Protocol

from stepramp.board.change import Segment, plan_change
from stepramp.board.plan import RAMP_AVR446, RAMP_EXACT, Plan, check_ramp, plan_move_info
from stepramp.board.regmap import (
    ERROR_CODES,
    ID_MAGIC,
    ID_RAMP_BIT,
    ID_WINDINGS_BIT,
    REGISTERS_BY_NAME,
    offset,
    split_wide,
)

STATE_NAMES = ("STOP", "ACCEL", "RUN", "DECEL")
ERROR_NAMES = {code: name for name, (code, _) in ERROR_CODES.items()}


class RegisterAccess(Protocol):
    """32-bit register access at byte offsets from the core's base address."""

    async def read(self, addr: int) -> int: ...

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None: ...


class StepRampError(RuntimeError):
    """The core reported an error (STATUS.ERROR), or does not answer as a stepramp core."""


@dataclass(frozen=True)
class Status:
    """STATUS decoded. The machine inputs (docs/algorithm.md, "Machine inputs"): limit_neg .. estop are the filtered
    levels after polarity (True: active); the *_ev flags, estop_fault and latched are sticky (clear_events,
    clear_estop, arm_latch)."""

    state: str
    busy: bool
    direction: int
    done: bool
    error: bool
    err_code: int
    pending: bool = False  # a CHANGE or QUEUE waits (the staging registers are locked)
    dir_fault: bool = False
    limit_neg: bool = False
    limit_pos: bool = False
    home: bool = False
    estop: bool = False
    limit_neg_ev: bool = False
    limit_pos_ev: bool = False
    home_ev: bool = False
    estop_fault: bool = False
    latched: bool = False

    @property
    def err_name(self) -> str:
        return ERROR_NAMES.get(self.err_code, f"code {self.err_code}")

    def level(self, pin: str) -> bool:
        """The filtered level of an input by its name in INPUTS ("limit_neg", "limit_pos", "home", "estop")."""
        if pin not in INPUTS:
            raise ValueError(f"pin must be one of {list(INPUTS)}, got {pin!r}")
        return bool(getattr(self, pin))

    @classmethod
    def decode(cls, raw: int) -> Status:
        reg = REGISTERS_BY_NAME["STATUS"]

        def get(name: str) -> int:
            f = reg.field(name)
            return (raw >> f.lsb) & ((1 << f.width) - 1)

        return cls(
            STATE_NAMES[get("STATE")],
            bool(get("BUSY")),
            get("DIR"),
            bool(get("DONE")),
            bool(get("ERROR")),
            get("ERR_CODE"),
            bool(get("PENDING")),
            bool(get("DIR_FAULT")),
            *(bool(get(name)) for name in ("LIMIT_NEG", "LIMIT_POS", "HOME", "ESTOP")),
            *(bool(get(name)) for name in ("LIMIT_NEG_EV", "LIMIT_POS_EV", "HOME_EV", "ESTOP_FAULT", "LATCHED")),
        )


def _bit(register: str, field: str) -> int:
    return 1 << REGISTERS_BY_NAME[register].field(field).lsb


_INPUT_IRQ_ENABLES = sum(
    _bit("CTRL", f"IRQ_{name}_EN") for name in ("LIMIT_NEG", "LIMIT_POS", "HOME", "ESTOP", "LATCH")
)
"""CTRL bits 10 .. 14, the input interrupt enables (enable_input_irq), which enable_irq keeps."""


def _strobe(mask: int) -> int:
    """The byte enables that cover the set bits of a 32-bit mask."""
    return sum(1 << b for b in range(4) if mask >> (8 * b) & 0xFF)


#: The registers written for a move, from a Plan: (register, Plan field or None, word: 0 = LO/whole, 1 = HI).
_WIDE = ("c_first", "c_last", "c_sa", "c_sd", "accel_seed", "decel_seed", "cruise")


def plan_writes(plan: Plan) -> list[tuple[int, int]]:
    """(offset, value) of every motion register for a plan, in address order (STEPS signed)."""
    signed = (-plan.steps if plan.direction else plan.steps) & 0xFFFF_FFFF
    writes = [(offset("STEPS"), signed), (offset("PRESCALE"), plan.prescale)]
    for name in _WIDE:
        lo, hi = split_wide(getattr(plan, name), 64 if name in ("cruise", "accel_seed", "decel_seed") else 48)
        writes += [(offset(f"{name.upper()}_LO"), lo), (offset(f"{name.upper()}_HI"), hi)]
    writes += [(offset("SA"), plan.sa), (offset("SD"), plan.sd)]
    ratio = getattr(plan, "stop_ratio", None)
    if ratio is not None:
        writes.append((offset("STOP_RATIO"), ratio))
    return sorted(writes)


def segment_writes(segment: dict[str, int]) -> list[tuple[int, int]]:
    """(offset, value) of SEGMENT .. HEAD_PROD_HI for the segment fields of Segment.registers (all 0: a move from
    rest to rest)."""
    reg = REGISTERS_BY_NAME["SEGMENT"]
    flags = segment["head_down"] << reg.field("HEAD_DOWN").lsb | segment["endless"] << reg.field("ENDLESS").lsb
    lo, hi = split_wide(segment["head_prod"], 48)
    return [
        (offset("SEGMENT"), flags),
        (offset("HEAD_INDEX"), segment["head_index"]),
        (offset("RUN_STOP"), segment["run_stop"]),
        (offset("HEAD_PROD_LO"), lo),
        (offset("HEAD_PROD_HI"), hi),
    ]


#: The segment registers of a move from rest to rest.
NO_SEGMENT = {"head_down": 0, "endless": 0, "head_index": 0, "run_stop": 0, "head_prod": 0}


#: DRIVE.MODE values.
MODES = {"stepdir": 0, "wave": 1, "full": 2, "half": 3, "pwm": 4}

#: The machine inputs of an axis, in the order of their bits (INPUT_CFG.POL_*, STATUS levels and events).
INPUTS = ("limit_neg", "limit_pos", "home", "estop")

#: INPUT_CFG.LATCH_SRC values: which input the position latch takes its edges from.
LATCH_SOURCES = {"none": 0, "home": 1, "limit_neg": 2, "limit_pos": 3}

#: INPUT_FILTER's width: the filter holds up to 2^20 - 1 clocks.
FILTER_MAX = (1 << REGISTERS_BY_NAME["INPUT_FILTER"].field("VALUE").width) - 1


@dataclass(frozen=True)
class Inputs:
    """Configuration of the machine inputs (registers INPUT_FILTER and INPUT_CFG; docs/algorithm.md, "Machine
    inputs"): the filter in clocks (0 acts as 1), which pins are active low, whether the limits stop a motion towards
    them (limit_enable, the reset value) and how (limit_hard: a hard stop, else a soft stop at the decel in force), and
    the position latch's source and edges."""

    filter: int = 0
    active_low: frozenset[str] = frozenset()
    limit_enable: bool = True
    limit_hard: bool = False
    latch_source: str = "none"
    latch_on_active: bool = False
    latch_on_release: bool = False

    @property
    def filter_clocks(self) -> int:
        """N = max(INPUT_FILTER, 1): a level must hold N clocks; a clean pin edge after clock edge a reaches the
        filtered level at edge a + N + 2."""
        return max(self.filter, 1)

    def check(self) -> None:
        """ValueError with the reason if a field does not fit its register."""
        if isinstance(self.filter, bool) or not isinstance(self.filter, int) or not 0 <= self.filter <= FILTER_MAX:
            raise ValueError(
                f"the input filter must be an integer number of clocks in 0 .. {FILTER_MAX}, got {self.filter!r}"
            )
        unknown = sorted(set(self.active_low) - set(INPUTS))
        if unknown:
            raise ValueError(f"active_low names unknown inputs {unknown}: the inputs are {list(INPUTS)}")
        if self.latch_source not in LATCH_SOURCES:
            raise ValueError(f"latch_source must be one of {list(LATCH_SOURCES)}, got {self.latch_source!r}")
        if self.latch_source != "none" and not (self.latch_on_active or self.latch_on_release):
            raise ValueError(f"a latch on {self.latch_source} needs latch_on_active, latch_on_release or both")

    def cfg_word(self) -> int:
        """The INPUT_CFG word."""
        self.check()
        word = sum(_bit("INPUT_CFG", f"POL_{pin.upper()}") for pin in self.active_low)
        word |= _bit("INPUT_CFG", "LIMIT_EN") if self.limit_enable else 0
        word |= _bit("INPUT_CFG", "LIMIT_HARD") if self.limit_hard else 0
        word |= LATCH_SOURCES[self.latch_source] << REGISTERS_BY_NAME["INPUT_CFG"].field("LATCH_SRC").lsb
        if self.latch_source != "none":  # without a source the edge bits are not written
            word |= _bit("INPUT_CFG", "LATCH_ON_ACTIVE") if self.latch_on_active else 0
            word |= _bit("INPUT_CFG", "LATCH_ON_RELEASE") if self.latch_on_release else 0
        return word


@dataclass(frozen=True)
class Latch:
    """What the position latch took at its source's filtered edge: POSITION after edge F (LATCH_POS), TIME there
    (LATCH_TIME = F - r), and the TIME of the pin's own edge it implies, pin_time = LATCH_TIME - N - 2 with
    N = max(INPUT_FILTER, 1): the pin changed between clock edges pin_time and pin_time + 1 of TIME's count (exact
    for a pin driven from the core's clock, within one clock for an asynchronous one; for a bouncing pin, the last
    bounce)."""

    position: int
    time: int
    pin_time: int


@dataclass(frozen=True)
class Outputs:
    """Configuration of the stepping outputs (registers DRIVE, STEP_WIDTH, DIR_TIMING, PWM_PERIOD, STEP_SPACE)."""

    mode: str = "stepdir"
    ustep_log2: int = 0
    step_width: int = 1
    dir_setup: int = 0
    dir_hold: int = 0
    pwm_period: int = 0
    step_space: int = 1

    @property
    def min_gap(self) -> int:
        """Shortest distance between two STEP rising edges the core allows, clocks (docs/algorithm.md)."""
        return max(self.step_width, 1) + max(self.step_space, 1)

    def check(self) -> None:
        """ValueError with the reason if a field does not fit its register."""
        if self.mode not in MODES:
            raise ValueError(f"mode must be one of {sorted(MODES)}, got {self.mode!r}")
        if not 0 <= self.ustep_log2 <= 7:
            raise ValueError(f"ustep_log2 must be in 0 .. 7, got {self.ustep_log2}")
        for name in ("step_width", "dir_setup", "dir_hold", "pwm_period", "step_space"):
            value = getattr(self, name)
            if not isinstance(value, int) or not 0 <= value <= 0xFFFF:
                raise ValueError(f"{name} must be an integer number of clocks in 0 .. 65535, got {value!r}")


class StepRamp:
    """Driver of one stepramp core."""

    def __init__(
        self, access: RegisterAccess, fclk: float, spr: float, prescale: int = 1, ramp: int = RAMP_AVR446
    ) -> None:
        """ramp: the core's ramp arithmetic (its generic G_RAMP): RAMP_AVR446 or RAMP_EXACT."""
        self.access = access
        self.fclk = fclk
        self.spr = spr
        self.prescale = prescale
        self.ramp = check_ramp(ramp)
        self.outputs = Outputs()
        self.inputs = Inputs()  # as configure_inputs last wrote them (the reset values until then)
        # Whether the core has winding outputs (A1 .. B2): ID bit 14 (NO_WINDINGS) clear. Assumed until check_id reads
        # ID; a core built with G_WINDINGS false sets the bit and configure_outputs then takes STEP/DIR only.
        self.windings = True
        # Whether SEGMENT .. HEAD_PROD_HI are known to hold what a move from rest to rest needs (all 0), so that
        # program() need not write them. Not at first: an earlier program (a restart without a core reset) or
        # another master may have left them set, so the first program() writes them; a jog sets them again.
        self._segment_clear = False

    async def check_id(self) -> int:
        """Read ID; raise StepRampError if this is not a stepramp core, or if it was built for the other ramp
        arithmetic than this driver plans for (ID bit 15, G_RAMP). Sets `windings` from ID bit 14 (NO_WINDINGS: set
        when the core was built with G_WINDINGS false). Returns the version (major << 8 | minor, ID bits 13:0)."""
        raw = await self.access.read(offset("ID"))
        if raw >> 16 != ID_MAGIC:
            raise StepRampError(f"ID register reads {raw:#010x}: not a stepramp core at this address")
        self.windings = not raw >> ID_WINDINGS_BIT & 1
        core_ramp = raw >> ID_RAMP_BIT & 1
        if core_ramp != self.ramp:
            names = {RAMP_AVR446: "AVR446 (G_RAMP = 0)", RAMP_EXACT: "exact (G_RAMP = 1)"}
            raise StepRampError(
                f"ID register reads {raw:#010x}: the core's ramp is {names[core_ramp]}, "
                f"but this driver plans for {names[self.ramp]}"
            )
        return raw & 0x3FFF

    def plan(self, steps: int, accel: float, decel: float, speed: float) -> Plan:
        """Register values of a move in physical units (rad/s^2, rad/s); ValueError with the reason if invalid.

        Besides the plan's own limits, the STEP pulse width plus the STEP low time configured with configure_outputs
        must fit the move's shortest interval (the core stops a move with error STEP_SPACE otherwise).
        """
        plan, info = plan_move_info(steps, accel, decel, speed, self.spr, self.fclk, self.prescale, self.ramp)
        shortest = int(info.min_interval) * self.prescale if plan.steps > 1 else None
        if shortest is not None and self.outputs.min_gap > shortest:
            raise ValueError(
                f"STEP width {self.outputs.step_width} + STEP space {self.outputs.step_space} clocks does not fit "
                f"the shortest interval of the move ({shortest} clocks): lower the speed, the STEP width or the space"
            )
        return plan

    async def configure_outputs(self, outputs: Outputs) -> None:
        """Write the stepping output registers (only while stopped: the core flags CFG_BUSY otherwise). ValueError
        (nothing written) for a winding mode on a core without windings (`windings` False, from check_id)."""
        outputs.check()
        if MODES[outputs.mode] != MODES["stepdir"] and not self.windings:
            raise ValueError(
                f"mode {outputs.mode!r} needs the winding outputs, but the core was built without winding outputs "
                "(ID bit 14 set: G_WINDINGS false): only the STEP/DIR mode ('stepdir')"
            )
        drive = REGISTERS_BY_NAME["DRIVE"]
        timing = REGISTERS_BY_NAME["DIR_TIMING"]
        await self.access.write(
            offset("DRIVE"),
            MODES[outputs.mode] << drive.field("MODE").lsb | outputs.ustep_log2 << drive.field("USTEP_LOG2").lsb,
        )
        await self.access.write(offset("STEP_WIDTH"), outputs.step_width)
        await self.access.write(
            offset("DIR_TIMING"),
            outputs.dir_setup << timing.field("SETUP").lsb | outputs.dir_hold << timing.field("HOLD").lsb,
        )
        await self.access.write(offset("PWM_PERIOD"), outputs.pwm_period)
        await self.access.write(offset("STEP_SPACE"), outputs.step_space)
        self.outputs = outputs

    async def set_enable(self, on: bool) -> None:
        """The ENABLE output (byte 2 of CTRL only); off also switches the H-bridge windings off."""
        await self.access.write(offset("CTRL"), _bit("CTRL", "ENABLE") if on else 0, strobe=0x4)

    async def program(self, plan: Plan, segment: dict[str, int] | None = None) -> None:
        """Write the move registers (the core latches them at START, so this is safe during a move), and the segment
        registers when a segment is given (Segment.registers) or when an earlier one left them set."""
        for addr, value in plan_writes(plan):
            await self.access.write(addr, value)
        if segment is not None or not self._segment_clear:
            for addr, value in segment_writes(NO_SEGMENT if segment is None else segment):
                await self.access.write(addr, value)
            self._segment_clear = segment is None or segment == NO_SEGMENT

    def plan_jog(self, speed: float, accel: float, decel: float) -> tuple[Plan, dict[str, int], Segment]:
        """Register values of a jog from rest (velocity mode: the sign of speed, rad/s, gives the direction); raises
        ValueError with the reason, as plan() does."""
        if isinstance(speed, bool) or not isinstance(speed, (int, float)) or not speed or not math.isfinite(speed):
            raise ValueError(f"the jog speed must be a finite non-zero number of rad/s, got {speed!r}")
        seg = plan_change(0.0, None, accel, decel, abs(speed), self.spr, self.fclk, self.prescale, self.ramp).segment
        shortest = int(self.fclk / self.prescale / (abs(speed) * self.spr / (2 * math.pi))) * self.prescale
        if self.outputs.min_gap > shortest:
            raise ValueError(
                f"STEP width {self.outputs.step_width} + STEP space {self.outputs.step_space} clocks does not fit "
                f"the jog's shortest interval ({shortest} clocks): lower the speed, the STEP width or the space"
            )
        plan, segment = seg.registers(direction=int(speed < 0))
        return plan, segment, seg

    async def jog(self, speed: float, accel: float, decel: float) -> Segment:
        """Jog from rest: accelerate at accel to |speed| in the direction of its sign and hold it until soft_stop()
        (decelerates at decel to rest) or hard_stop(). Returns the segment (the model predicts every edge from it:
        stepramp.models.engine.segment_edges)."""
        plan, segment, seg = self.plan_jog(speed, accel, decel)
        await self.program(plan, segment)
        await self.start()
        return seg

    async def start(self) -> None:
        """START (byte 0 of CTRL only, so the interrupt enables in byte 1 are kept)."""
        await self.access.write(offset("CTRL"), _bit("CTRL", "START"), strobe=0x1)

    async def move(self, steps: int, accel: float, decel: float, speed: float) -> Plan:
        """Plan, program and start a move. Returns the plan."""
        plan = self.plan(steps, accel, decel, speed)
        await self.program(plan)
        await self.start()
        return plan

    async def change(self, segment: Segment, direction: int, pulse: int) -> None:
        """Take `segment` over at pulse `pulse` of the running motion (docs/algorithm.md, "The take-over"): stage its
        registers, CHANGE_AT, then CTRL.CHANGE (byte 0). The core refuses it (STATUS.ERROR, code CHANGE) when pulse
        - 1 has been emitted, the core is idle or something is pending; the driver picks the pulse with
        stepramp.board.change.change_pulse and the segment with stepramp.board.change.plan_change."""
        if isinstance(pulse, bool) or not isinstance(pulse, int) or not 1 <= pulse < 1 << 31:
            raise ValueError(f"the take-over pulse must be in 1 .. 2^31 - 1, got {pulse!r}")
        plan, regs = segment.registers(direction)
        await self.program(plan, regs)
        await self.access.write(offset("CHANGE_AT"), pulse)
        await self.access.write(offset("CTRL"), _bit("CTRL", "CHANGE"), strobe=0x1)

    async def queue(self, plan: Plan, segment: dict[str, int] | None = None) -> None:
        """Start `plan` (and segment) when the running motion ends, as a START at its last pulse (CTRL.QUEUE)."""
        await self.program(plan, segment)
        await self.access.write(offset("CTRL"), _bit("CTRL", "QUEUE"), strobe=0x1)

    async def soft_stop(self) -> None:
        """Decelerate at the programmed decel to zero, then done."""
        await self.access.write(offset("CTRL"), _bit("CTRL", "SOFT_STOP"), strobe=0x1)

    async def hard_stop(self) -> None:
        """No further step from the next clock on."""
        await self.access.write(offset("CTRL"), _bit("CTRL", "HARD_STOP"), strobe=0x1)

    async def enable_irq(self, done: bool = True, error: bool = True) -> None:
        """CTRL.IRQ_DONE_EN and IRQ_ERROR_EN. They share byte 1 of CTRL with the input interrupt enables (bits 10 ..
        14, enable_input_irq), so CTRL is read and byte 1 written back with those as read: they are kept, no command
        is written (byte 0) and ENABLE is left alone (byte 2)."""
        keep = await self.access.read(offset("CTRL")) & _INPUT_IRQ_ENABLES
        value = (_bit("CTRL", "IRQ_DONE_EN") if done else 0) | (_bit("CTRL", "IRQ_ERROR_EN") if error else 0)
        await self.access.write(offset("CTRL"), keep | value, strobe=0x2)

    async def status(self) -> Status:
        return Status.decode(await self.access.read(offset("STATUS")))

    async def clear_flags(self) -> None:
        """Clear the sticky DONE and ERROR flags."""
        await self.access.write(offset("STATUS"), _bit("STATUS", "DONE") | _bit("STATUS", "ERROR"), strobe=0x1)

    async def position(self) -> int:
        raw = await self.access.read(offset("POSITION"))
        return raw - (1 << 32) if raw >> 31 else raw

    async def set_position(self, value: int) -> None:
        """Set the position counter (only while stopped: the core ignores it and flags POS_BUSY otherwise)."""
        if not -(1 << 31) <= value < 1 << 31:
            raise ValueError(f"position {value} does not fit 32 bits signed")
        await self.access.write(offset("POSITION"), value & 0xFFFF_FFFF)

    # -- machine inputs: limits, home, E-stop, the position latch, TIME (docs/algorithm.md, "Machine inputs") ------
    async def configure_inputs(self, inputs: Inputs) -> None:
        """Write INPUT_FILTER and INPUT_CFG (only while stopped: the core ignores them during a motion and flags
        CFG_BUSY). ValueError with the reason, nothing written, if a field does not fit."""
        word = inputs.cfg_word()
        await self.access.write(offset("INPUT_FILTER"), inputs.filter)
        await self.access.write(offset("INPUT_CFG"), word)
        self.inputs = inputs

    async def arm_latch(self, source: str, on_active: bool = True, on_release: bool = False) -> None:
        """Select the latch's source and edges (INPUT_CFG alone, the polarity and limit settings of configure_inputs
        kept; only while stopped), then clear STATUS.LATCHED, which arms the latch: the first selected filtered edge
        from now on takes POSITION and TIME. source "none" switches the latch off. ValueError, nothing written, for an
        unknown source or a source with neither edge."""
        inputs = dataclasses.replace(
            self.inputs,
            latch_source=source,
            latch_on_active=on_active and source != "none",
            latch_on_release=on_release and source != "none",
        )
        await self.access.write(offset("INPUT_CFG"), inputs.cfg_word())
        self.inputs = inputs
        await self.rearm_latch()

    async def rearm_latch(self) -> None:
        """Clear STATUS.LATCHED (write 1): the latch takes the next selected edge (allowed during a motion)."""
        bit = _bit("STATUS", "LATCHED")
        await self.access.write(offset("STATUS"), bit, strobe=_strobe(bit))

    async def latch(self) -> Latch | None:
        """The latched position and time, or None while STATUS.LATCHED is 0 (nothing latched since it was armed)."""
        if not (await self.status()).latched:
            return None
        return await self.read_latch()

    async def read_latch(self) -> Latch:
        """LATCH_POS and LATCH_TIME (LO then HI) as they are, whether STATUS.LATCHED is set or not."""
        raw = await self.access.read(offset("LATCH_POS"))
        lo = await self.access.read(offset("LATCH_TIME_LO"))
        hi = await self.access.read(offset("LATCH_TIME_HI"))
        time = hi << 32 | lo
        position = raw - (1 << 32) if raw >> 31 else raw
        return Latch(position, time, time - self.inputs.filter_clocks - 2)

    async def time(self) -> int:
        """TIME, the 64-bit clock count since reset: TIME_LO first (that read copies bits 63:32 into TIME_HI), then
        TIME_HI, so the two words belong together."""
        lo = await self.access.read(offset("TIME_LO"))
        hi = await self.access.read(offset("TIME_HI"))
        return hi << 32 | lo

    async def clear_events(self, limit_neg: bool = True, limit_pos: bool = True, home: bool = True) -> None:
        """Clear the sticky input events STATUS.LIMIT_NEG_EV, LIMIT_POS_EV, HOME_EV (write 1; byte 2 of STATUS only,
        so DONE, ERROR, ESTOP_FAULT and LATCHED are kept)."""
        mask = 0
        for pin, on in (("LIMIT_NEG", limit_neg), ("LIMIT_POS", limit_pos), ("HOME", home)):
            mask |= _bit("STATUS", f"{pin}_EV") if on else 0
        if mask:
            await self.access.write(offset("STATUS"), mask, strobe=_strobe(mask))

    async def clear_estop(self, enable: bool = True) -> Status:
        """Clear STATUS.ESTOP_FAULT (write 1) and, with enable, set CTRL.ENABLE again (the fault cleared it). The core
        keeps the fault while ESTOP is active: StepRampError then, and ENABLE is left off. Returns STATUS after."""
        bit = _bit("STATUS", "ESTOP_FAULT")
        await self.access.write(offset("STATUS"), bit, strobe=_strobe(bit))
        status = await self.status()
        if status.estop_fault:
            why = "the ESTOP input is still active" if status.estop else "the fault is still set"
            raise StepRampError(f"STATUS.ESTOP_FAULT not cleared: {why}")
        if enable:
            await self.set_enable(True)
        return status

    async def enable_input_irq(
        self,
        limit_neg: bool = False,
        limit_pos: bool = False,
        home: bool = False,
        estop: bool = False,
        latch: bool = False,
        done: bool = True,
        error: bool = True,
    ) -> None:
        """All interrupt enables of CTRL byte 1 (irq follows DONE, ERROR, the input events, ESTOP_FAULT, LATCHED)."""
        value = 0
        for name, on in (
            ("IRQ_DONE_EN", done),
            ("IRQ_ERROR_EN", error),
            ("IRQ_LIMIT_NEG_EN", limit_neg),
            ("IRQ_LIMIT_POS_EN", limit_pos),
            ("IRQ_HOME_EN", home),
            ("IRQ_ESTOP_EN", estop),
            ("IRQ_LATCH_EN", latch),
        ):
            value |= _bit("CTRL", name) if on else 0
        await self.access.write(offset("CTRL"), value, strobe=0x2)

    async def wait_done(self, idle: Callable[[], Awaitable[None]] | None = None, polls: int = 1_000_000) -> Status:
        """Poll STATUS until DONE, clear the flags, and return the status; raise StepRampError on ERROR.

        idle: awaited between polls (a simulation timer, or a sleep on a board). polls bounds the wait.
        """
        for _ in range(polls):
            status = await self.status()
            if status.done:
                await self.clear_flags()
                if status.error:
                    raise StepRampError(f"the core flagged error {status.err_code} ({status.err_name})")
                return status
            if idle is not None:
                await idle()
        raise StepRampError(f"no DONE after {polls} polls")


class MmapAccess:
    """Register access through mmap of a device file: /dev/mem at the core's base address, or a UIO device."""

    def __init__(self, path: str = "/dev/mem", base: int = 0, size: int = 4096) -> None:
        fd = os.open(path, os.O_RDWR | os.O_SYNC)
        try:
            self._map = mmap.mmap(fd, size, mmap.MAP_SHARED, mmap.PROT_READ | mmap.PROT_WRITE, offset=base)
        finally:
            os.close(fd)

    async def read(self, addr: int) -> int:
        return int.from_bytes(self._map[addr : addr + 4], "little")

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None:
        data = value.to_bytes(4, "little")
        for b in range(4):  # byte strobes as byte writes
            if strobe >> b & 1:
                self._map[addr + b : addr + b + 1] = data[b : b + 1]

    def close(self) -> None:
        self._map.close()
