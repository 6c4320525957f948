# SPDX-License-Identifier: MIT
"""Homing: find a switch with the position latch and make its edge a known POSITION (docs/homing.md).

The procedure (one axis, the driver's StepRamp; every step polls STATUS, awaiting `idle` between polls):

1. If the switch is already active, jog away from it at the seek speed until the latch sees its release, and stop.
2. Seek: arm the latch on the switch's activation edge, jog towards it at the seek speed; at STATUS.LATCHED soft-stop
   (a limit used as home stops the motion itself, error LIMIT, which is expected here). The latch holds POSITION at
   the filtered edge, p_seek, a few steps inside the switch (how many depends on the bounce and the speed).
3. Back: a positioning move at the seek speed back to p_seek (still inside the switch).
4. Release: arm the latch on the release edge and jog away from the switch at the slow latch speed; at
   STATUS.LATCHED soft-stop. The latch holds POSITION after the first step off the switch, p_release, exactly: at
   the latch speed one step lasts longer than the switch's delay and bounce plus the filter's N + 2 clocks, so no
   further pulse comes before the filtered edge (check() refuses a latch speed for which that fails).
5. POSITION += offset - p_release: the first position off the switch is now `offset`.

Since p_release counts pulses and the step that leaves the switch is fixed by the mechanics, the zero is the same
step on every run, whatever the bounce (shorter than the filter) or the speed of the seek. Board side: imports nothing
from simulation.
"""

from __future__ import annotations

import math
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

from stepramp.board.driver import ERROR_NAMES, Latch, Status, StepRamp, StepRampError

#: The inputs that can serve as the homing switch, and the direction a limit lies in.
SWITCHES = {"home": None, "limit_neg": -1, "limit_pos": 1}

#: Clocks from the STEP edge that puts the carriage over the switch edge to the last pulse the latch may count, beyond
#: the switch's own delay and bounce (settle) and the filter N: the pin is sampled by the next clock edge (1), the
#: filtered level follows N + 2 edges later (docs/algorithm.md, "Filter"), and LATCH_POS counts the pulses whose STEP
#: edge is at or before F + 1 (1), plus one clock of margin.
LATCH_MARGIN = 5

#: Error codes a stop on a limit used as the homing switch is allowed to end with.
_LIMIT = next(code for code, name in ERROR_NAMES.items() if name == "LIMIT")

Idle = Callable[[], Awaitable[object]]


@dataclass(frozen=True)
class Homing:
    """A homing run.

    switch: the input used, "home", or a limit ("limit_neg", "limit_pos") used as home.
    direction: where the switch is, -1 (the way POSITION counts down) or +1; a limit's own direction.
    seek_speed, seek_accel: the fast search (rad/s, rad/s^2; the decel is seek_accel too).
    latch_speed, latch_accel: the slow move off the switch whose edge becomes the zero (rad/s, rad/s^2).
    offset: the POSITION given to the first position off the switch.
    settle_clocks: the longest time from the STEP edge that crosses the switch edge to the pin's last change (delay
        and contact bounce), clocks: with the filter it sets the highest exact latch speed.
    max_travel: the farthest each jog may go, steps, before the homing gives up (hard stop, StepRampError).
    """

    seek_speed: float
    seek_accel: float
    latch_speed: float
    latch_accel: float
    switch: str = "home"
    direction: int = -1
    offset: int = 0
    settle_clocks: int = 0
    max_travel: int = (1 << 31) - 1

    def latch_clocks(self, fclk: float, spr: float, prescale: int) -> int:
        """Clocks per step at the latch speed (the shortest interval of the release jog)."""
        return int(fclk / prescale / (self.latch_speed * spr / (2 * math.pi))) * prescale

    def max_latch_speed(self, fclk: float, spr: float, prescale: int, filter_clocks: int) -> float:
        """The highest latch speed (rad/s) at which the release latch is exact for this filter and settle time."""
        need = filter_clocks + self.settle_clocks + LATCH_MARGIN
        return 2 * math.pi / spr * fclk / need

    def check(self, fclk: float, spr: float, prescale: int, filter_clocks: int) -> None:
        """ValueError with the reason if the run cannot give an exact zero, or an argument is out of range."""
        if self.switch not in SWITCHES:
            raise ValueError(f"switch must be one of {list(SWITCHES)}, got {self.switch!r}")
        if self.direction not in (-1, 1):
            raise ValueError(f"direction must be -1 or +1, got {self.direction!r}")
        side = SWITCHES[self.switch]
        if side is not None and side != self.direction:
            raise ValueError(f"{self.switch} lies in direction {side:+d}: the homing must seek that way")
        for name in ("seek_speed", "seek_accel", "latch_speed", "latch_accel"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise ValueError(f"{name} must be a finite positive number, got {value!r}")
        if isinstance(self.offset, bool) or not isinstance(self.offset, int) or not -(1 << 31) <= self.offset < 1 << 31:
            raise ValueError(f"offset must fit 32 bits signed, got {self.offset!r}")
        if isinstance(self.settle_clocks, bool) or not isinstance(self.settle_clocks, int) or self.settle_clocks < 0:
            raise ValueError(f"settle_clocks must be a non-negative integer, got {self.settle_clocks!r}")
        if isinstance(self.max_travel, bool) or not isinstance(self.max_travel, int) or self.max_travel < 1:
            raise ValueError(f"max_travel must be a positive integer number of steps, got {self.max_travel!r}")
        need = filter_clocks + self.settle_clocks + LATCH_MARGIN
        have = self.latch_clocks(fclk, spr, prescale)
        if have < need:
            raise ValueError(
                f"latch speed {self.latch_speed} rad/s gives a step every {have} clocks, but an exact zero needs at "
                f"least {need} (filter {filter_clocks} + settle {self.settle_clocks} + {LATCH_MARGIN}): use at most "
                f"{self.max_latch_speed(fclk, spr, prescale, filter_clocks):.6g} rad/s"
            )


@dataclass(frozen=True)
class HomingResult:
    """What a homing run found, positions in the frame before the homing: the latch of the release edge when the
    switch was active at the start and the axis left it first (else None), the seek's latch (activation edge at the
    seek speed), the release latch (the zero); the shift added to POSITION, and POSITION at the end."""

    left: Latch | None
    seek: Latch
    release: Latch
    shift: int
    position: int


async def _poll(
    drv: StepRamp, idle: Idle | None, polls: int, start: int, max_travel: int, what: str
) -> tuple[Status, bool]:
    """Poll STATUS until LATCHED (True) or DONE (False); hard-stop and raise past max_travel steps from start or
    after `polls` polls."""
    for _ in range(polls):
        status = await drv.status()
        if status.latched:
            return status, True
        if status.done:
            return status, False
        if abs(await drv.position() - start) > max_travel:
            await drv.hard_stop()
            await _finish(drv, idle, polls)
            raise StepRampError(f"{what}: no switch edge within {max_travel} steps")
        if idle is not None:
            await idle()
    await drv.hard_stop()
    raise StepRampError(f"{what}: no switch edge after {polls} polls")


async def _finish(drv: StepRamp, idle: Idle | None, polls: int, allowed: tuple[int, ...] = ()) -> None:
    """Wait for DONE and clear the flags; StepRampError for an error other than `allowed`."""
    for _ in range(polls):
        status = await drv.status()
        if status.done:
            await drv.clear_flags()
            if status.error and status.err_code not in allowed:
                raise StepRampError(f"the core flagged error {status.err_code} ({status.err_name})")
            return
        if idle is not None:
            await idle()
    raise StepRampError(f"no DONE after {polls} polls")


async def _jog_to_latch(
    drv: StepRamp, speed: float, accel: float, idle: Idle | None, polls: int, cfg: Homing, what: str
) -> Latch:
    """Jog at `speed` (signed) until the armed latch holds, soft-stop, wait for DONE; the latch."""
    start = await drv.position()
    await drv.jog(speed, accel, accel)
    status, latched = await _poll(drv, idle, polls, start, cfg.max_travel, what)
    allowed = (_LIMIT,) if cfg.switch != "home" else ()
    if not latched:  # the motion ended before the latch: a stop of its own
        await _finish(drv, idle, polls, allowed)
        raise StepRampError(f"{what}: the motion ended before the switch edge ({status.err_name})")
    await drv.soft_stop()
    await _finish(drv, idle, polls, allowed)
    return await drv.read_latch()


async def home(drv: StepRamp, cfg: Homing, idle: Idle | None = None, polls: int = 10_000_000) -> HomingResult:
    """Run the homing procedure on a stopped axis (module docstring); returns what it found. ValueError (nothing
    moves) for arguments that cannot give an exact zero; StepRampError when the core flags an error, the switch is not
    found within max_travel, or the axis is not ready (moving, E-stop fault). The input configuration (drv.inputs) is
    restored at the end, the latch off as it was."""
    inputs = drv.inputs
    cfg.check(drv.fclk, drv.spr, drv.prescale, inputs.filter_clocks)
    status = await drv.status()
    if status.busy:
        raise StepRampError("homing: the axis is moving")
    if status.estop_fault or status.estop:
        raise StepRampError("homing: the E-stop is active or its fault is set (clear_estop first)")
    await drv.clear_flags()  # a DONE left from an earlier motion would end the first poll at once
    away = -cfg.direction
    try:
        left = None
        if status.level(cfg.switch):
            await drv.arm_latch(cfg.switch, on_active=False, on_release=True)
            left = await _jog_to_latch(drv, away * cfg.seek_speed, cfg.seek_accel, idle, polls, cfg, "leaving")
        await drv.arm_latch(cfg.switch, on_active=True, on_release=False)
        seek = await _jog_to_latch(drv, cfg.direction * cfg.seek_speed, cfg.seek_accel, idle, polls, cfg, "seek")
        back = seek.position - await drv.position()
        if back:
            await drv.move(back, cfg.seek_accel, cfg.seek_accel, cfg.seek_speed)
            await _finish(drv, idle, polls)
        if not (await drv.status()).level(cfg.switch):
            raise StepRampError(f"homing: {cfg.switch} is not active at the position where the seek latched it")
        await drv.arm_latch(cfg.switch, on_active=False, on_release=True)
        release = await _jog_to_latch(drv, away * cfg.latch_speed, cfg.latch_accel, idle, polls, cfg, "release")
        shift = cfg.offset - release.position
        position = await drv.position() + shift
        await drv.set_position(position)
        if await drv.position() != position:
            raise StepRampError(f"homing: POSITION did not take {position}")
    finally:
        await drv.configure_inputs(inputs)
    if cfg.switch == "home":
        await drv.clear_events(limit_neg=False, limit_pos=False, home=True)
    return HomingResult(left, seek, release, shift, position)


__all__ = ["LATCH_MARGIN", "SWITCHES", "Homing", "HomingResult", "home"]
