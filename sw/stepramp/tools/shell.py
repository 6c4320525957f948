# SPDX-License-Identifier: MIT
"""`stepramp shell`: the command language of the AVR446 demo application, on the simulated RTL.

The commands, units, ranges and info line of AVR446 section 3.1 (accel/decel in 0.01 rad/s^2, speed in 0.01 rad/s,
steps signed), read line by line from stdin, so a session can be typed or piped:

    printf 'a 4000\\nm 400\\n\\n' | stepramp shell

Each move runs on stepramp_plb, programmed over its bus by the Python driver, and the whole session is one
simulation (`stepramp.sim.session.RtlSession`); POSITION is read back from the core after each move. `--model` runs the
bit-exact model instead (no simulator, instant). Bad commands print the reason and the help text; the session goes
on. `q` (or end of input) ends it.

Beyond AVR446, motion on the fly (docs/algorithm.md, "The take-over, the queue and the script contract"): `j` jogs
for a time and stops, `c` changes the speed of a move while it runs; each runs as a command script
(stepramp.board.script) on the back end. `home` homes the axis on the simulated machine's HOME switch
(stepramp.board.homing, docs/homing.md): the session's core drives a carriage with a bouncing switch
(stepramp.sim.session.MECHANICS); not with --model.
"""

from __future__ import annotations

import io
import math
import re
import shutil
import sys
import tempfile
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, TextIO

from stepramp.board.driver import StepRampError
from stepramp.board.plan import RAMP_AVR446, RAMP_EXACT, Plan, min_interval_clks, plan_move
from stepramp.models.engine import edges as model_edges

if TYPE_CHECKING:
    from stepramp.sim.session import RtlSession

#: The shell's motor and clock (stepramp.sim.session's defaults): a 200-step motor half-stepped (400 steps/rev), the
#: core at 250 kHz with PRESCALE 1 (4 us ticks). An FPGA clocked at f with PRESCALE f / 250 kHz emits the same pulses;
#: the low simulated clock keeps each move to a few seconds of simulation.
SHELL_CONFIG: dict[str, Any] = {"fclk": 250e3, "spr": 400.0, "prescale": 1}

#: The shell's session: its clock and motor, and the machine `home` works on (stepramp.sim.session.MECHANICS).
SHELL_SESSION_CONFIG: dict[str, Any] = {**SHELL_CONFIG, "mechanics": {}}
#: --ramp exact: the same 250 kHz tick from a 1 MHz clock (PRESCALE 4), so that the demo's 20 rad/s keeps the exact
#: mode's MIN_INTERVAL_CLKS_EXACT (256 clocks per step).
SHELL_EXACT_CONFIG: dict[str, Any] = {"fclk": 1e6, "spr": 400.0, "prescale": 4}

#: AVR446's ranges (the speed's upper bound is this core's limit at the shell's clock, see speed_limit).
ACCEL_RANGE = (71, 32000)
STEPS_RANGE = (-64000, 64000)
SPEED_MIN = 12
#: The longest time a `j` or `c` command waits before its stop or change (ms).
MS_MAX = 60_000


def speed_limit(fclk: float, spr: float, prescale: int, ramp: int = RAMP_AVR446) -> int:
    """The highest speed (0.01 rad/s) the engine sustains: one step per MIN_INTERVAL_CLKS clocks (_EXACT in exact
    mode)."""
    alpha = 2 * math.pi / spr
    shortest_ticks = math.ceil(min_interval_clks(ramp) / prescale)
    return math.floor(100 * alpha * fclk / prescale / shortest_ticks)


@dataclass(frozen=True)
class Outcome:
    """One move as a back end ran it: the plan, its STEP edges (model convention) and the position after it."""

    plan: Plan
    edges: list[int]
    position: int


@dataclass(frozen=True)
class Homed:
    """A homing as a back end ran it: POSITION after it, and the machine's own view: the carriage's step and the
    switch edge (the first step off the switch), both in the machine's coordinate."""

    position: int
    carriage: int
    switch_edge: int


class Backend(Protocol):
    def move(self, steps: int, accel: float, decel: float, speed: float) -> Outcome: ...

    def script(self, script: dict[str, Any]) -> int: ...

    def home(self, offset: int, speed: float, accel: float) -> Homed: ...


class ModelBackend:
    """The bit-exact model in place of the RTL (no simulator)."""

    def __init__(self, fclk: float, spr: float, prescale: int = 1, ramp: int = RAMP_AVR446) -> None:
        self.fclk, self.spr, self.prescale, self.ramp = fclk, spr, prescale, ramp
        self.position = 0

    def move(self, steps: int, accel: float, decel: float, speed: float) -> Outcome:
        plan = plan_move(steps, accel, decel, speed, self.spr, self.fclk, self.prescale, self.ramp)
        self.position += steps
        return Outcome(plan, model_edges(plan), self.position)

    def script(self, script: dict[str, Any]) -> int:
        """A command script from the current position: POSITION at its end."""
        from stepramp.board.script import load_script, plan_script

        planned = plan_script(load_script(script))
        self.position += planned.positions[-1] if planned.positions else 0
        return self.position

    def home(self, offset: int, speed: float, accel: float) -> Homed:
        """The model has no machine (no switch, no latch): homing needs the simulated core."""
        raise CommandError("home needs the simulated machine (its switch and the core's latch): not with --model")


class RtlBackend:
    """Moves on the RTL, all in one simulation (a stepramp.sim.session.RtlSession, started by the caller)."""

    def __init__(self, session: RtlSession) -> None:
        self.session = session
        self.outcomes: list[Outcome] = []

    def move(self, steps: int, accel: float, decel: float, speed: float) -> Outcome:
        res = self.session.move(steps, accel, decel, speed)
        outcome = Outcome(res.plan, res.edges, res.position)
        self.outcomes.append(outcome)
        return outcome

    def script(self, script: dict[str, Any]) -> int:
        return self.session.script(script)[1]

    def home(self, offset: int, speed: float, accel: float) -> Homed:
        res = self.session.home(offset, speed, accel)
        return Homed(res.position, res.carriage, res.switch_edge)


_INTEGER = re.compile(r"[+-]?[0-9]{1,12}")


class CommandError(ValueError):
    """A command the shell does not understand, or a value out of its range."""


class Shell:
    """The AVR446 demo's menu and command interface over a back end; output goes to `out`."""

    def __init__(
        self, backend: Backend, out: TextIO, fclk: float, spr: float, prescale: int = 1, ramp: int = RAMP_AVR446
    ) -> None:
        self.backend = backend
        self.out = out
        self.accel, self.decel, self.speed, self.steps = 4000, 4000, 2000, 400
        self.position = 0
        self.config = {"spr": spr, "fclk": fclk, "prescale": prescale}
        self.ramp = ramp
        self.speed_max = speed_limit(fclk, spr, prescale, ramp)

    def help_text(self) -> str:
        return "\n".join(
            [
                "-----",
                "stepramp shell - the AVR446 demo application, on the simulated stepramp core",
                "",
                "?        - Show help",
                f"a [data] - Set acceleration (range: {ACCEL_RANGE[0]} - {ACCEL_RANGE[1]})",
                f"d [data] - Set deceleration (range: {ACCEL_RANGE[0]} - {ACCEL_RANGE[1]})",
                f"s [data] - Set speed (range: {SPEED_MIN} - {self.speed_max}, the motor limit)",
                f"m [data] - Move [data] steps (range: {STEPS_RANGE[0]} - {STEPS_RANGE[1]})",
                "move [steps] [accel] [decel] [speed]",
                "         - Move with all parameters given",
                "<enter>  - Repeat last move",
                "j [speed] [ms]",
                "         - Jog at [speed] (signed) for [ms] milliseconds, then a soft stop",
                "c [steps] [ms] [speed]",
                "         - Move [steps]; [ms] milliseconds after its start, change the speed to [speed]",
                "home [pos]",
                "         - Home on the machine's HOME switch at the current speed and acceleration: its edge",
                "           becomes position [pos] (0 if not given)",
                "q        - Quit (or end of input)",
                "",
                "         acc/dec data given in 0.01*rad/sec^2 (100 = 1 rad/sec^2)",
                "         speed data given in 0.01*rad/sec (100 = 1 rad/sec)",
                "-----",
            ]
        )

    def info_line(self) -> str:
        return f"Motor pos: {self.position}   a:{self.accel} d:{self.decel} s:{self.speed} m:{self.steps}"

    def say(self, text: str) -> None:
        print(text, file=self.out, flush=True)

    def start(self) -> None:
        self.say(self.help_text())
        self.say(self.info_line())

    @staticmethod
    def _int(token: str, name: str, lo: int, hi: int) -> int:
        if not _INTEGER.fullmatch(token):  # ASCII digits only, as AVR446's atoi
            shown = token if len(token) <= 20 else token[:20] + "..."
            raise CommandError(f"{name} must be an integer, got {shown!r}")
        value = int(token)
        if not lo <= value <= hi:
            raise CommandError(f"{name} {value} is out of range {lo} - {hi}")
        return value

    def _args(self, tokens: list[str], count: int) -> list[str]:
        if len(tokens) - 1 != count:
            raise CommandError(f"{tokens[0]!r} takes {count} value{'s' if count > 1 else ''}, got {len(tokens) - 1}")
        return tokens[1:]

    def execute(self, line: str) -> bool:
        """Run one command line; False when the session should end."""
        tokens = line.split()
        try:
            if not tokens:
                self._move(self.steps, self.accel, self.decel, self.speed)
            elif tokens[0] == "?":
                self.say(self.help_text())
            elif tokens[0] == "q":
                return False
            elif tokens[0] in ("a", "d"):
                (value,) = self._args(tokens, 1)
                number = self._int(value, "acceleration" if tokens[0] == "a" else "deceleration", *ACCEL_RANGE)
                if tokens[0] == "a":
                    self.accel = number
                else:
                    self.decel = number
            elif tokens[0] == "s":
                (value,) = self._args(tokens, 1)
                self.speed = self._int(value, "speed", SPEED_MIN, self.speed_max)
            elif tokens[0] == "m":
                (value,) = self._args(tokens, 1)
                self._move(self._int(value, "steps", *STEPS_RANGE), self.accel, self.decel, self.speed)
            elif tokens[0] == "j":
                speed, ms = self._args(tokens, 2)
                jog = self._int(speed, "speed", -self.speed_max, self.speed_max)
                if abs(jog) < SPEED_MIN:
                    raise CommandError(f"speed {jog} is out of range {SPEED_MIN} - {self.speed_max} (either sign)")
                after = self._int(ms, "time", 1, MS_MAX)
                self._script(
                    {"at": 0, "op": "jog", "speed": jog / 100, "accel": self.accel / 100, "decel": self.decel / 100},
                    {"at": self._clocks(after), "op": "soft_stop"},
                )
            elif tokens[0] == "c":
                steps, ms, speed = self._args(tokens, 3)
                move = {"at": 0, "op": "move", "steps": self._int(steps, "steps", *STEPS_RANGE)}
                move |= {"accel": self.accel / 100, "decel": self.decel / 100, "speed": self.speed / 100}
                after = self._int(ms, "time", 1, MS_MAX)
                new = self._int(speed, "speed", SPEED_MIN, self.speed_max)
                self._script(move, {"at": self._clocks(after), "op": "set", "speed": new / 100})
            elif tokens[0] == "home":
                if len(tokens) > 2:
                    raise CommandError(f"'home' takes at most 1 value, got {len(tokens) - 1}")
                offset = self._int(tokens[1], "position", *STEPS_RANGE) if len(tokens) == 2 else 0
                self._home(offset)
            elif tokens[0] == "move":
                steps, accel, decel, speed = self._args(tokens, 4)
                self._move(
                    self._int(steps, "steps", *STEPS_RANGE),
                    self._int(accel, "acceleration", *ACCEL_RANGE),
                    self._int(decel, "deceleration", *ACCEL_RANGE),
                    self._int(speed, "speed", SPEED_MIN, self.speed_max),
                )
            else:
                shown = tokens[0] if len(tokens[0]) <= 20 else tokens[0][:20] + "..."
                raise CommandError(f"unknown command {shown!r}")
        except CommandError as exc:
            self.say(f"error: {exc}")
            self.say(self.help_text())
        self.say(self.info_line())
        return True

    def _move(self, steps: int, accel: int, decel: int, speed: int) -> None:
        """Check the move with the driver's rules, take the settings, run it (nothing to run for 0 steps)."""
        args = (steps, accel / 100, decel / 100, speed / 100)
        if steps != 0:
            try:
                plan_move(*args, **self.config, ramp=self.ramp)  # the driver's checks, before anything changes
            except ValueError as exc:
                raise CommandError(str(exc)) from None
        self.steps, self.accel, self.decel, self.speed = steps, accel, decel, speed
        if steps == 0:
            return  # as AVR446: nothing to move
        self.out.write("Running... ")
        self.out.flush()
        try:
            outcome = self.backend.move(*args)
        except StepRampError as exc:  # the core flagged an error or never said DONE: report it and go on
            self.say(f"failed: {exc}")
            position = getattr(exc, "position", None)  # POSITION read back after the failure, when known
            if isinstance(position, int):
                self.position = position
            return
        self.position = outcome.position
        self.say("OK")

    def _home(self, offset: int) -> None:
        """Home at the current speed and acceleration (the back end's machine); the position is POSITION after it."""
        self.out.write("Homing... ")
        self.out.flush()
        try:
            homed = self.backend.home(offset, self.speed / 100, self.accel / 100)
        except ValueError as exc:  # the driver's reason (CommandError for the model back end)
            self.say("")
            raise CommandError(str(exc)) from None
        except StepRampError as exc:
            self.say(f"failed: {exc}")
            position = getattr(exc, "position", None)
            if isinstance(position, int):
                self.position = position
            return
        self.position = homed.position
        self.say(f"OK: the switch edge (machine step {homed.switch_edge}) is position {offset}")

    def _clocks(self, ms: int) -> int:
        return round(ms * 1e-3 * self.config["fclk"])

    def _script(self, *commands: dict[str, Any]) -> None:
        """Run commands as a script on the back end (the driver's refusals are reported, the session goes on)."""
        from stepramp.board.script import load_script, plan_script

        script = {**self.config, "ramp": "exact" if self.ramp == RAMP_EXACT else "avr446", "commands": list(commands)}
        try:
            planned = plan_script(load_script(script))
        except ValueError as exc:
            raise CommandError(str(exc)) from None
        if planned.rejected:
            raise CommandError("; ".join(f"{r['op']} at {r['at']}: {r['reason']}" for r in planned.rejected))
        self.out.write("Running... ")
        self.out.flush()
        try:
            self.position = self.backend.script(script)
        except StepRampError as exc:
            self.say(f"failed: {exc}")
            return
        self.say("OK")

    def run(self, lines: Iterable[str], prompt: bool = False) -> None:
        """The help and info line, then every line until 'q' or the end of input."""
        self.start()
        if prompt:
            self.out.write("> ")
            self.out.flush()
        for line in lines:
            if not self.execute(line.rstrip("\r\n")):
                break
            if prompt:
                self.out.write("> ")
                self.out.flush()


def main(
    model: bool = False,
    waves: Path | None = None,
    build: Path | None = None,
    stdin: TextIO | None = None,
    ramp: int = RAMP_AVR446,
) -> int:
    """`stepramp shell`: one simulation (or the model) for the whole session, commands from stdin."""
    if stdin is None:
        stdin = sys.stdin
        if isinstance(stdin, io.TextIOWrapper):
            stdin.reconfigure(errors="replace")  # bytes that are not text become a bad command, not a crash
    interactive = stdin.isatty()
    cfg = {**(SHELL_EXACT_CONFIG if ramp == RAMP_EXACT else SHELL_CONFIG), "ramp": ramp}
    if model:
        Shell(ModelBackend(**cfg), sys.stdout, **cfg).run(stdin, prompt=interactive)
        return 0

    from stepramp.sim.session import RtlSession, SessionError

    build_dir = build if build is not None else Path(tempfile.mkdtemp(prefix="stepramp-shell-"))
    log = build_dir.resolve() / "sim.log"
    print(f"stepramp shell: starting one simulation of stepramp_plb for the session (log: {log})", file=sys.stderr)
    try:
        session_cfg = {**SHELL_SESSION_CONFIG, **cfg}
        with RtlSession(build_dir, config=session_cfg, waves=waves, log_file=log) as session:
            Shell(RtlBackend(session), sys.stdout, **cfg).run(stdin, prompt=interactive)
    except SessionError as exc:
        cause = f" ({exc.__cause__!r})" if exc.__cause__ is not None else ""
        print(f"\nstepramp shell: {exc}{cause}; the build and the log are kept in {build_dir}", file=sys.stderr)
        return 1
    if build is None:
        shutil.rmtree(build_dir, ignore_errors=True)
    if waves is not None and waves.suffix == ".ghw":  # the layout is written for GHW's facility names
        from stepramp.sim.waves import write_gtkw

        gtkw = write_gtkw(waves.with_suffix(".gtkw"), waves, duration_s=session.end_s * 1.02 or None)
        print(f"stepramp shell: the session's waveform is {waves}; open it with  gtkwave {gtkw}", file=sys.stderr)
    elif waves is not None:
        print(f"stepramp shell: the session's waveform is {waves}", file=sys.stderr)
    return 0
