# SPDX-License-Identifier: MIT
"""Driver of the multi-axis top (stepramp_multi_plb, stepramp_multi_axil; docs/stepramp_multi.md).

The top holds G_AXES stepramp cores behind one slave with a 12-bit address: a global window at byte offset 0x000
(ID / AXES, SYNC_START, AXES_STATUS, IRQ_MASK, SYNC_SOFT_STOP) and axis i's register window at 0x100 * (i + 1). Each
axis is an ordinary stepramp core, driven by stepramp.board.driver.StepRamp through an OffsetAccess (the register
access shifted to its window); MultiAxis adds what needs the global window: the axis count, SYNC_START (the selected
axes' pulse 0 on one clock edge), SYNC_SOFT_STOP (a soft stop of the selected axes on one clock edge), the status
word, the interrupt mask, and coordinated linear moves planned by stepramp.board.coord.plan_coordinated and started
together. The global registers are written as whole words, as the
C driver (sw/c/src/stepramp_multi.c) writes them.

    multi = await MultiAxis.probe(access, fclk=50e6, spr=400 * 16)
    plans = await multi.move_coordinated([3200, -1600, 800], accel=40.0, decel=40.0, speed=20.0)
    await multi.wait_done(multi.started(plans))
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Iterable, Sequence
from dataclasses import dataclass

from stepramp.board.coord import CoordStop, plan_coordinated_info
from stepramp.board.driver import Outputs, RegisterAccess, StepRamp, StepRampError
from stepramp.board.plan import Plan

#: Decoded address bits of the multi-axis top, and its most axes (stepramp_multi_pkg: C_MULTI_ADDR_BITS,
#: C_MULTI_MAX_AXES).
MULTI_ADDR_BITS = 12
MAX_AXES = 8
#: Bytes of each window; axis i's window starts at AXIS_WINDOW * (i + 1).
AXIS_WINDOW = 0x100

#: ID bits 31:16 ('SM') and 15:8; bits 7:0 hold G_AXES.
ID_MAGIC = 0x534D
ID_VERSION = 0x01

#: Byte offsets of the global window.
REG_ID = 0x000
REG_SYNC_START = 0x004
REG_AXES_STATUS = 0x008
REG_IRQ_MASK = 0x00C
REG_SYNC_SOFT_STOP = 0x010
#: Bits 7:0 of AXES_STATUS: BUSY of each axis; 15:8 DONE; 23:16 the axis's irq line (before IRQ_MASK).
AXES_STATUS_BUSY_LSB = 0
AXES_STATUS_DONE_LSB = 8
AXES_STATUS_IRQ_LSB = 16


def soft_stop_line_bound(lead: Plan, p: int | None) -> float:
    """How far (steps) an axis of a coordinated move may rest from the line after a SYNC_SOFT_STOP: from L_i / L_lead
    times the lead's rest position (docs/algorithm.md, "Coordinated moves": the coordinated soft stop). `lead` is the
    lead axis's plan and `p` the pulse at which its stop is decided (stepramp.models.engine.soft_stop_pulse).

    Every axis decides its stop one pulse after its own first pulse after the request (docs/algorithm.md, "Soft
    stop"), so it accelerates up to two of its own intervals longer than the request, the lead too: p_i - r_i p_lead
    lies in (1 - 2 r_i, 2 - r_i). Its ACCEL stop, floor(p_i * STOP_RATIO / 2^16) steps, carries that on scaled by
    the ratio s = accel / decel: less than 2 + 2 s steps when the lead and the axis decide in ACCEL; in RUN (stop =
    its own decel ramp, ceil(r_i n_d) against r_i ceil(n_d), one step of rounding more) less than 3. Where their
    phases differ (an axis's sa rounded off its share of the lead's, one pulse either side) the axis's stop and the
    lead's are of different rules: an axis in RUN while the lead accelerates adds up to s (3 - r_i) more, an axis in
    ACCEL while the lead cruises up to s + 1. Hence 3 + 3 s when the lead decides in ACCEL and 3 + s in RUN
    (measured over 100 seeds of 500 moves: at most 0.93 of the first, and 2.96 steps in RUN); 0 when the lead's
    stop is ignored (DECEL, or p + m >= L: every axis ends on its own target, on the line)."""
    s = lead.stop_ratio / 65536.0
    if p is None or p >= lead.steps - 1 or p >= lead.sd:
        return 0.0 if p is None or p >= lead.steps - 1 else 3.0 + s
    if p >= lead.sa:
        return 3.0 + s
    return 3.0 + 3.0 * s


def axis_base(axis: int) -> int:
    """Byte offset of axis `axis`'s register window in the multi-axis top."""
    if isinstance(axis, bool) or not isinstance(axis, int) or not 0 <= axis < MAX_AXES:
        raise ValueError(f"axis must be in 0 .. {MAX_AXES - 1}, got {axis!r}")
    return AXIS_WINDOW * (axis + 1)


class MultiAxisError(RuntimeError):
    """The top does not answer as a multi-axis stepramp, or axes flagged errors (their indices in .axes)."""

    def __init__(self, message: str, axes: Sequence[int] = ()) -> None:
        super().__init__(message)
        self.axes = tuple(axes)


class OffsetAccess:
    """A RegisterAccess whose offset 0 is `base` of another: an axis's window seen as a single core."""

    def __init__(self, access: RegisterAccess, base: int) -> None:
        self.access = access
        self.base = base

    async def read(self, addr: int) -> int:
        return await self.access.read(self.base + addr)

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None:
        await self.access.write(self.base + addr, value, strobe)


@dataclass(frozen=True)
class AxesStatus:
    """AXES_STATUS decoded: bit i of each mask is axis i."""

    busy: int
    done: int
    irq: int

    @classmethod
    def decode(cls, raw: int) -> AxesStatus:
        return cls(
            raw >> AXES_STATUS_BUSY_LSB & 0xFF,
            raw >> AXES_STATUS_DONE_LSB & 0xFF,
            raw >> AXES_STATUS_IRQ_LSB & 0xFF,
        )


def mask_of(axes: Iterable[int], count: int = MAX_AXES) -> int:
    """The bit mask of a set of axis indices (each in 0 .. count - 1)."""
    mask = 0
    for axis in axes:
        if isinstance(axis, bool) or not isinstance(axis, int) or not 0 <= axis < count:
            raise ValueError(f"axis must be in 0 .. {count - 1}, got {axis!r}")
        mask |= 1 << axis
    return mask


class MultiAxis:
    """Driver of one multi-axis top: the global window, and a StepRamp per axis (`axis(i)`).

    fclk, spr and prescale are those of every axis's moves (a coordinated move needs them shared); the drivers of
    `axis(i)` plan single-axis moves with them too.
    """

    def __init__(self, access: RegisterAccess, axes: int, fclk: float, spr: float, prescale: int = 1) -> None:
        if isinstance(axes, bool) or not isinstance(axes, int) or not 1 <= axes <= MAX_AXES:
            raise ValueError(f"axes must be in 1 .. {MAX_AXES}, got {axes!r}")
        self.access = access
        self.axes = axes
        self.fclk = fclk
        self.spr = spr
        self.prescale = prescale
        self.drivers = [
            StepRamp(OffsetAccess(access, axis_base(i)), fclk=fclk, spr=spr, prescale=prescale) for i in range(axes)
        ]

    @classmethod
    async def probe(cls, access: RegisterAccess, fclk: float, spr: float, prescale: int = 1) -> MultiAxis:
        """The driver of the top at `access`, its axis count read from ID (MultiAxisError if it is none), then each
        axis's ID read in its own window (StepRamp.check_id, as stepramp_multi_init's stepramp_init), so each axis's
        driver knows whether its core has windings (ID bit 14); MultiAxisError naming the axes whose window is no
        stepramp core for this driver (all axes are read first)."""
        raw = await access.read(REG_ID)
        axes = raw & 0xFF
        if raw >> 16 != ID_MAGIC or not 1 <= axes <= MAX_AXES:
            raise MultiAxisError(f"ID reads {raw:#010x}: not a multi-axis stepramp top at this address")
        top = cls(access, axes, fclk, spr, prescale)
        failed: list[tuple[int, str]] = []
        for i, drv in enumerate(top.drivers):
            try:
                await drv.check_id()
            except StepRampError as exc:
                failed.append((i, str(exc)))
        if failed:
            reasons = "; ".join(f"axis {i}: {why}" for i, why in failed)
            raise MultiAxisError(reasons, [i for i, _ in failed])
        return top

    async def check_id(self) -> int:
        """Read ID; raise MultiAxisError unless it is a multi-axis top with this driver's axis count. Returns the
        version (ID bits 15:8)."""
        raw = await self.access.read(REG_ID)
        if raw >> 16 != ID_MAGIC:
            raise MultiAxisError(f"ID reads {raw:#010x}: not a multi-axis stepramp top at this address")
        if raw & 0xFF != self.axes:
            raise MultiAxisError(f"the top has {raw & 0xFF} axes, the driver was made for {self.axes}")
        return raw >> 8 & 0xFF

    def axis(self, axis: int) -> StepRamp:
        """The StepRamp driver of axis `axis` (its window; everything a single core does)."""
        if isinstance(axis, bool) or not isinstance(axis, int) or not 0 <= axis < self.axes:
            raise ValueError(f"axis must be in 0 .. {self.axes - 1}, got {axis!r}")
        return self.drivers[axis]

    def mask(self, axes: Iterable[int]) -> int:
        return mask_of(axes, self.axes)

    async def sync_start(self, axes: Iterable[int]) -> None:
        """START the selected axes on one clock edge (one write of their mask to SYNC_START): each as if
        CTRL.START were written to it at that edge, with the same refusals (busy: ignored; bad STEPS, ESTOP, a limit:
        DONE and ERROR)."""
        await self.access.write(REG_SYNC_START, self.mask(axes))

    async def sync_soft_stop(self, axes: Iterable[int]) -> None:
        """SOFT_STOP the selected axes on one clock edge (one write of their mask to SYNC_SOFT_STOP): each as if
        CTRL.SOFT_STOP were written to it at that edge (each decides its stop one pulse after its own next pulse, with
        its plan's decel; a queued move is dropped). On a coordinated move every axis comes to rest near the line
        (docs/algorithm.md, "Coordinated moves": the coordinated soft stop)."""
        await self.access.write(REG_SYNC_SOFT_STOP, self.mask(axes))

    async def stop_coordinated(self, stop: CoordStop, plans: Sequence[Plan]) -> list[int]:
        """Commit a coordinated stop on the line (stepramp.board.coord.plan_coordinated_stop of the running
        coordinated move `plans`): each axis's CHANGE in axis order (its segment and CHANGE_AT staged, then
        CTRL.CHANGE), each commit no later than the edge its take-over pulse was named for. When the stop fell back
        (stop.fallback), one SYNC_SOFT_STOP of the moving axes instead (within soft_stop_line_bound of the line, not
        on it). Returns the axes written to."""
        if stop.fallback is not None:
            axes = [i for i, plan in enumerate(plans) if plan.steps >= 2]
            await self.sync_soft_stop(axes)
            return axes
        for i in stop.changes:
            axis = stop.axes[i]
            assert axis.change is not None
            await self.drivers[i].change(axis.change.segment, plans[i].direction, axis.pulse)
        return stop.changes

    async def status(self) -> AxesStatus:
        return AxesStatus.decode(await self.access.read(REG_AXES_STATUS))

    async def set_irq_mask(self, axes: Iterable[int]) -> None:
        """Let only the selected axes' irq reach the top's irq output (all of them after reset)."""
        await self.access.write(REG_IRQ_MASK, self.mask(axes))

    async def irq_mask(self) -> int:
        return await self.access.read(REG_IRQ_MASK) & 0xFF

    async def configure_outputs(self, outputs: Outputs, axes: Iterable[int] | None = None) -> None:
        """The same stepping outputs on the selected axes (all when None); only while they are stopped."""
        for i in range(self.axes) if axes is None else axes:
            await self.axis(i).configure_outputs(outputs)

    def plan_coordinated(self, steps: Sequence[int], accel: float, decel: float, speed: float) -> list[Plan]:
        """Plans of a coordinated linear move, one per axis from axis 0 (stepramp.board.coord.plan_coordinated with
        this driver's spr, fclk and prescale): accel, decel (rad/s^2) and speed (rad/s) are the lead axis's.

        Raises ValueError with the reason: more step counts than axes, plan_coordinated's reasons, or an axis whose
        STEP width + STEP space (its configure_outputs) does not fit its shortest interval.
        """
        if isinstance(steps, (str, bytes)) or not isinstance(steps, Sequence):
            raise ValueError(f"steps must be a sequence of step counts, one per axis, got {steps!r}")
        if len(steps) > self.axes:
            raise ValueError(f"{len(steps)} step counts for a top of {self.axes} axes")
        plans, info = plan_coordinated_info(steps, accel, decel, speed, self.spr, self.fclk, self.prescale)
        for i, (plan, move) in enumerate(zip(plans, info.infos, strict=True)):
            gap = self.drivers[i].outputs.min_gap
            if plan.steps > 1 and gap > int(move.min_interval) * self.prescale:
                raise ValueError(
                    f"axis {i}: STEP width + STEP space ({gap} clocks) does not fit its shortest interval "
                    f"({int(move.min_interval) * self.prescale} clocks): lower the speed, the STEP width or the space"
                )
        return plans

    @staticmethod
    def started(plans: Sequence[Plan]) -> list[int]:
        """The axes a coordinated move starts: those with at least one step (an axis of 0 steps is left alone)."""
        return [i for i, plan in enumerate(plans) if plan.steps > 0]

    async def program_sync(self, plans: Sequence[Plan]) -> list[int]:
        """Program plan i into axis i (the axes latch their moves at START, so this is safe while they move) and
        SYNC_START every axis with steps; returns those axes."""
        if len(plans) > self.axes:
            raise ValueError(f"{len(plans)} plans for a top of {self.axes} axes")
        axes = self.started(plans)
        for i in axes:
            await self.drivers[i].program(plans[i])
        await self.sync_start(axes)
        return axes

    async def move_coordinated(self, steps: Sequence[int], accel: float, decel: float, speed: float) -> list[Plan]:
        """Plan a coordinated linear move (plan_coordinated), program each axis and start them with one SYNC_START.
        Returns the plans (wait for the axes of `started(plans)`)."""
        plans = self.plan_coordinated(steps, accel, decel, speed)
        await self.program_sync(plans)
        return plans

    async def wait_done(
        self,
        axes: Iterable[int],
        idle: Callable[[], Awaitable[None]] | None = None,
        polls: int = 1_000_000,
    ) -> AxesStatus:
        """Poll AXES_STATUS until every selected axis has DONE, then clear each one's flags (its StepRamp.wait_done)
        and return the last AXES_STATUS; raise MultiAxisError naming the axes that flagged an error (every axis's
        flags are cleared first) or when DONE does not come within `polls` reads."""
        want = self.mask(axes)
        for _ in range(polls):
            status = await self.status()
            if status.done & want == want:
                failed: list[int] = []
                reasons: list[str] = []
                for i in range(self.axes):
                    if want >> i & 1:
                        try:
                            await self.drivers[i].wait_done(polls=1)
                        except StepRampError as exc:
                            failed.append(i)
                            reasons.append(f"axis {i}: {exc}")
                if failed:
                    raise MultiAxisError("; ".join(reasons), failed)
                return status
            if idle is not None:
                await idle()
        raise MultiAxisError(f"no DONE on axes {want:#04x} after {polls} polls", [i for i in range(8) if want >> i & 1])


__all__ = [
    "AXES_STATUS_BUSY_LSB",
    "AXES_STATUS_DONE_LSB",
    "AXES_STATUS_IRQ_LSB",
    "AXIS_WINDOW",
    "ID_MAGIC",
    "ID_VERSION",
    "MAX_AXES",
    "MULTI_ADDR_BITS",
    "REG_AXES_STATUS",
    "REG_ID",
    "REG_IRQ_MASK",
    "REG_SYNC_SOFT_STOP",
    "REG_SYNC_START",
    "AxesStatus",
    "MultiAxis",
    "MultiAxisError",
    "OffsetAccess",
    "axis_base",
    "mask_of",
    "soft_stop_line_bound",
]
