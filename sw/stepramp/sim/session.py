# SPDX-License-Identifier: MIT
"""One simulation of the whole peripheral for a session of moves: the RTL as a MicroBlaze program would see it.

`RtlSession` (front end, any Python process) builds stepramp_plb with GHDL, starts one simulation through cocotb's
runner in a thread, and talks to the cocotb test in this module (`session`, running inside the simulator) over a
Unix socket: one JSON request per line, one JSON answer per line. The test plays the soft CPU: it programs the core
through the PLB-like IPIF with the Python driver (`stepramp.board.driver.StepRamp`), starts each move, waits for DONE on
the interrupt and reads POSITION back, while coroutines timestamp every STEP edge. `make demo` and
`stepramp shell` both use it, so a whole shell session is one simulation (and one waveform).

Requests: {"op": "move", "steps", "accel", "decel", "speed"} (rad/s^2, rad/s), {"op": "script", "script": {...}} (a
command script, stepramp.board.script: the driver's planned writes and commits played at their clocks from now on;
POSITION read back at its end), {"op": "home", "offset", "speed", "accel"} (stepramp.board.homing on the session's
machine: needs "mechanics" in the configuration), {"op": "signals", "paths": [[path, width], ...]} (which of these
design signals are missing) and {"op": "quit"}.

With "mechanics" in the configuration (a dict over MECHANICS, {} for its defaults: a home switch and its bounce, the
input filter, the homing's latch speed) the session's core drives a machine: a carriage
(stepramp.sim.mechanics.Carriage) follows STEP/DIR from carriage step 0 (POSITION 0 after reset) and closes the HOME
input at its switch, bouncing.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import socket
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stepramp.board.driver import Inputs, Outputs, StepRamp, StepRampError
from stepramp.board.plan import Plan
from stepramp.board.regmap import offset
from stepramp.models.engine import last_edge
from stepramp.sim.runner import run_cocotb
from stepramp.sim.waves import missing_in

#: Default setting: the AVR446 demo's motor (200 steps/rev, half-stepped: 400 steps/rev) with the windings driven in
#: half steps, on a 250 kHz core clock (the clock's period sets the waveform's time axis).
#: Clocks between two STATUS polls at most (the driver sleeps on irq in between).
_POLL_CYCLES = 20_000

DEFAULT_CONFIG: dict[str, Any] = {"fclk": 250e3, "spr": 400.0, "prescale": 1, "mode": "half", "dir_setup": 2}

#: The shell's machine (config key "mechanics"): the HOME switch active for carriage steps <= home_at (a quarter
#: turn below the start), bouncing up to max_bounces times at intervals below the filter (filter clocks, 200 us at
#: 250 kHz); the homing's release at latch_speed rad/s (one step per 785 clocks; exact up to 11.3 rad/s with this
#: filter and bounce), poll_clocks between the homing's STATUS polls, seed for the bounce.
MECHANICS: dict[str, Any] = {
    "home_at": -100,
    "filter": 50,
    "max_bounces": 3,
    "latch_speed": 5.0,
    "poll_clocks": 100,
    "max_travel": 100_000,
    "seed": 1,
}


@dataclass(frozen=True)
class MoveResult:
    """What the RTL did for one move: STEP edges in the model's convention (clock edges from the engine's start
    edge, less the stepping logic's register stage), POSITION read back, the plan, and the move's time span."""

    plan: Plan
    edges: list[int]
    position: int
    start_s: float
    end_s: float


@dataclass(frozen=True)
class HomeResult:
    """A homing on the session's machine: POSITION after it, the carriage's step (the machine's own coordinate), the
    switch edge (the first carriage step off the switch), and the latched positions (the frame before the homing)."""

    position: int
    carriage: int
    switch_edge: int
    seek_latch: int
    release_latch: int


class SessionError(RuntimeError):
    """The simulation failed, hung or went away."""


class MoveError(StepRampError):
    """The core flagged an error during a move, or never said DONE within the move's budget; `position` is POSITION
    read back afterwards."""

    def __init__(self, message: str, position: int) -> None:
        super().__init__(message)
        self.position = position


class RtlSession:
    """Front end of one simulation of stepramp_plb (use as a context manager)."""

    def __init__(
        self,
        build_dir: Path,
        config: dict[str, Any] | None = None,
        waves: Path | None = None,
        log_file: Path | None = None,
    ) -> None:
        self.build_dir = build_dir.resolve()
        self.config = {**DEFAULT_CONFIG, **(config or {})}
        self.waves = waves
        self.log_file = log_file if log_file is not None else self.build_dir / "sim.log"
        self.failure: BaseException | None = None
        self.simulations = 0  # how many simulator runs this session started (one)
        self.end_s = 0.0  # simulated time at the end of the last move
        self._thread: threading.Thread | None = None
        self._conn: socket.socket | None = None
        self._buffer = b""
        self._tmp: tempfile.TemporaryDirectory[str] | None = None

    def __enter__(self) -> RtlSession:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def start(self) -> None:
        self.build_dir.mkdir(parents=True, exist_ok=True)
        # A short path: Unix socket names are limited to about 100 bytes.
        short = "/tmp" if len(tempfile.gettempdir()) > 60 and os.path.isdir("/tmp") else None
        self._tmp = tempfile.TemporaryDirectory(prefix="stepramp-", dir=short)
        path = os.path.join(self._tmp.name, "s")
        server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        server.bind(path)
        server.listen(1)
        server.settimeout(0.2)
        env = {"STEPRAMP_SESSION_SOCKET": path, "STEPRAMP_SESSION_CONFIG": json.dumps(self.config)}
        self._thread = threading.Thread(target=self._run, args=(env,), daemon=True)
        self._thread.start()
        self.simulations += 1
        try:
            while True:
                try:
                    conn, _ = server.accept()
                    break
                except TimeoutError:
                    if not self._thread.is_alive():
                        raise SessionError(f"the simulation did not start; see {self.log_file}") from self.failure
        finally:
            server.close()
        conn.settimeout(0.2)
        self._conn = conn

    def _run(self, env: dict[str, str]) -> None:
        try:
            ramp = self.config.get("ramp", 0)
            results = run_cocotb(
                "stepramp_plb",
                "stepramp.sim.session",
                self.build_dir,
                parameters={"G_RAMP": ramp} if ramp else None,
                waves=self.waves,
                extra_env=env,
                log_file=self.log_file,
            )
            # Outside pytest the runner returns even when the test failed: read its verdict.
            from cocotb_tools.check_results import get_results

            tests, failed = get_results(results)
            if tests != 1 or failed:
                self.failure = SessionError(f"the cocotb session test failed ({failed} of {tests})")
        except BaseException as exc:  # the runner raises SystemExit under pytest: report it later
            self.failure = exc

    def request(self, req: dict[str, Any]) -> dict[str, Any]:
        """Send one request and wait for its answer (SessionError if the simulation ends first). A move that never
        ends is bounded inside the simulation (its budget comes from the model), not here: a long valid move may
        take hours of simulation."""
        if self._conn is None or self._thread is None:
            raise SessionError("the session is not started")
        try:
            self._conn.sendall(json.dumps(req).encode() + b"\n")
        except OSError as exc:
            raise SessionError(f"the simulation went away ({exc}); see {self.log_file}") from self.failure
        while b"\n" not in self._buffer:
            try:
                chunk = self._conn.recv(1 << 16)
            except TimeoutError:
                if not self._thread.is_alive():
                    raise SessionError(f"no answer from the simulation; see {self.log_file}") from self.failure
                continue
            except OSError as exc:
                raise SessionError(f"the simulation went away ({exc}); see {self.log_file}") from self.failure
            if not chunk:
                raise SessionError(f"the simulation ended; see {self.log_file}") from self.failure
            self._buffer += chunk
        line, self._buffer = self._buffer.split(b"\n", 1)
        answer: dict[str, Any] = json.loads(line)
        if "fault" in answer:
            raise SessionError(f"the simulation failed: {answer['fault']}")
        return answer

    def move(self, steps: int, accel: float, decel: float, speed: float) -> MoveResult:
        """One move on the RTL. ValueError (the driver's reason) if it is not a valid move; StepRampError if the
        core flags an error."""
        answer = self.request({"op": "move", "steps": steps, "accel": accel, "decel": decel, "speed": speed})
        if "value_error" in answer:
            raise ValueError(answer["value_error"])
        if "core_error" in answer:
            raise MoveError(answer["core_error"], answer["position"])
        self.end_s = answer["end_s"]
        return MoveResult(
            Plan(**answer["plan"]), answer["edges"], answer["position"], answer["start_s"], answer["end_s"]
        )

    def script(self, script: dict[str, Any]) -> tuple[list[int], int]:
        """A command script on the RTL (stepramp.board.script; ValueError if it is not valid): its STEP edges (clocks
        from its clock 0) and POSITION read back at its end. Played by stepramp.sim.player: every commit lands on its
        clock, or the session fails."""
        answer = self.request({"op": "script", "script": script})
        if "value_error" in answer:
            raise ValueError(answer["value_error"])
        return answer["edges"], answer["position"]

    def home(self, offset: int, speed: float, accel: float) -> HomeResult:
        """Home on the session's machine (stepramp.board.homing: seek at speed rad/s and accel rad/s^2, release at the
        machine's latch speed) so that the switch edge becomes POSITION offset. ValueError (the driver's reason, or no
        machine in this session) if it cannot run; MoveError if the core flags an error or the switch is not found."""
        answer = self.request({"op": "home", "offset": offset, "speed": speed, "accel": accel})
        if "value_error" in answer:
            raise ValueError(answer["value_error"])
        if "core_error" in answer:
            raise MoveError(answer["core_error"], answer["position"])
        self.end_s = answer.pop("end_s")
        return HomeResult(**answer)

    def missing_signals(self, paths: list[tuple[str, int]]) -> list[str]:
        """Which of these (dotted path below the top, width) design signals the simulator does not have."""
        missing: list[str] = self.request({"op": "signals", "paths": paths})["missing"]
        return missing

    def close(self) -> None:
        """End the simulation (it writes the waveform) and wait for it; SessionError if it failed."""
        if self._conn is not None:
            with contextlib.suppress(OSError):
                self._conn.sendall(b'{"op": "quit"}\n')
            self._conn.close()
            self._conn = None
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self._tmp is not None:
            self._tmp.cleanup()
            self._tmp = None
        if self.failure is not None and not (isinstance(self.failure, SystemExit) and not self.failure.code):
            raise SessionError(f"the simulation failed; see {self.log_file}") from self.failure


# ---- inside the simulator -------------------------------------------------------------------------------------

try:
    import cocotb
    from cocotb.triggers import ClockCycles, First, RisingEdge, SimTimeoutError, Timer, with_timeout
    from cocotb.utils import get_sim_time

    from stepramp.sim import player
    from stepramp.sim.clocking import apply_reset, now_cycles, quiet_inputs, start_clock
except ImportError:  # the front end does not need cocotb
    cocotb = None  # type: ignore[assignment]


if cocotb is not None:
    # The session serves a whole interactive shell; each step carries its own limit (below).
    # The decorator's backstop: an hour of simulated time (about 4,500 demo moves at 250 kHz).
    @cocotb.test(timeout_time=3_600_000, timeout_unit="ms")
    async def session(dut: Any) -> None:
        """Serve the front end's requests until it quits or goes away."""
        from stepramp.sim.ipif import IpifMaster  # needs cocotb-bus
        from stepramp.sim.stepwatch import StepWatch

        cfg: dict[str, Any] = json.loads(os.environ["STEPRAMP_SESSION_CONFIG"])
        period_ps = round(1e12 / cfg["fclk"])
        start_clock(dut.clk, period_ps)
        quiet_inputs(dut)

        async def limited(work: Any, clocks: int, what: str) -> Any:
            """Await work within a simulated-time limit of `clocks` clock periods; fail clearly if it hangs."""
            try:
                return await with_timeout(work, clocks * period_ps, "ps")
            except SimTimeoutError:
                raise SessionError(f"{what}: no end within its limit of {clocks} clocks of simulated time") from None

        bus = IpifMaster(dut, dut.clk, period_ps // 1000 or 1)
        drv = StepRamp(bus, fclk=cfg["fclk"], spr=cfg["spr"], prescale=cfg["prescale"], ramp=cfg.get("ramp", 0))

        # the machine: MECHANICS with what the configuration's "mechanics" sets ({} for the defaults), or none
        mech: dict[str, Any] | None = None if cfg.get("mechanics") is None else {**MECHANICS, **cfg["mechanics"]}
        carriage: Any = None

        # the register file's write strobes: where each of a script's commits landed (stepramp.sim.player)
        regfile = dut.core_inst.regfile_inst
        writes = player.WriteLog(regfile.wr, regfile.waddr, period_ps)
        latency = 0

        async def setup() -> StepWatch:
            nonlocal carriage
            await apply_reset(dut.clk, dut.rst, settle=2)
            pins = StepWatch(dut.step, dut.core_inst.busy, period_ps)
            # the bus's write latency for the scripts' commits (a CTRL byte-1 write of 0 while CTRL is 0 after reset)
            nonlocal latency
            latency = await player.calibrate(bus, dut.clk, writes, offset("CTRL"))
            await drv.check_id()
            await drv.configure_outputs(
                Outputs(mode=cfg["mode"], dir_setup=cfg["dir_setup"], dir_hold=cfg["dir_setup"])
            )
            await drv.set_enable(True)
            await drv.enable_irq()
            if mech is not None:
                from stepramp.sim.mechanics import Bounce, Carriage, Switch

                await drv.configure_inputs(Inputs(filter=mech["filter"]))
                bounce = Bounce(filter_clocks=mech["filter"], max_bounces=mech["max_bounces"])
                switch = Switch("home", at=mech["home_at"], side=-1)
                carriage = Carriage(dut.step, dut.dir, {"home": dut.home}, [switch], 0, bounce, mech["seed"], period_ps)
                carriage.start()
            return pins

        # Limit: the reset and the configuration writes, measured at 20 clocks (24 with the machine), 5x over.
        pins: StepWatch = await limited(setup(), 150, "reset and configuration")

        async def idle() -> None:
            if not int(dut.irq.value):  # irq may have risen during the status read
                await First(RisingEdge(dut.irq), Timer(_POLL_CYCLES * period_ps, unit="ps"))

        async def do_move(req: dict[str, Any]) -> dict[str, Any]:
            try:
                plan = drv.plan(req["steps"], req["accel"], req["decel"], req["speed"])
            except ValueError as exc:
                return {"value_error": str(exc)}
            # A hang fails the move instead of the session waiting for ever: the model's last edge, plus DIR
            # setup/hold and slack, in polls of at most _POLL_CYCLES.
            budget = (last_edge(plan) or 0) + 2 * cfg["dir_setup"] + _POLL_CYCLES
            polls = budget // _POLL_CYCLES + 10

            async def run() -> dict[str, Any]:
                mark = pins.mark()
                start_s = get_sim_time("ps") * 1e-12
                await drv.program(plan)
                await drv.start()
                try:
                    await drv.wait_done(idle=idle, polls=polls)
                except StepRampError as exc:
                    return {"core_error": str(exc), "position": await drv.position()}
                end_s = get_sim_time("ps") * 1e-12
                position = await drv.position()
                return {
                    "plan": dataclasses.asdict(plan),
                    "edges": pins.since(*mark),
                    "position": position,
                    "start_s": start_s,
                    "end_s": end_s,
                }

            # Limit: twice wait_done's own bound (polls of _POLL_CYCLES idle clocks and a <= 100-clock STATUS read).
            result: dict[str, Any] = await limited(run(), 2 * polls * (_POLL_CYCLES + 100), f"move {req}")
            return result

        async def do_script(req: dict[str, Any]) -> dict[str, Any]:
            from stepramp.board.script import PREP_CLOCKS, load_script, plan_script

            try:
                planned = plan_script(load_script(req["script"]))
            except ValueError as exc:
                return {"value_error": str(exc)}
            origin = now_cycles(period_ps) + PREP_CLOCKS + 10
            first = len(pins.step_edges)
            ctrl = offset("CTRL")
            commits = [player.Commit(a.at, a.writes, ctrl, a.ctrl, PREP_CLOCKS) for a in planned.actions]

            async def run() -> dict[str, Any]:
                await player.play(bus, dut.clk, writes, commits, origin, latency)
                await player.at_edge(dut.clk, origin + planned.until, late_ok=True, period_ps=period_ps)
                await drv.clear_flags()
                edges = [e - origin for e in pins.step_edges[first:]]
                return {"edges": edges, "position": await drv.position()}

            result: dict[str, Any] = await limited(run(), planned.until + 2 * PREP_CLOCKS + 1000, "script")
            return result

        async def do_home(req: dict[str, Any]) -> dict[str, Any]:
            from stepramp.board.homing import Homing, home

            if mech is None or carriage is None:
                return {"value_error": "this session has no machine to home (no 'mechanics' in its configuration)"}
            switch = carriage.switches[0]
            cfg_h = Homing(
                seek_speed=req["speed"],
                seek_accel=req["accel"],
                latch_speed=mech["latch_speed"],
                latch_accel=req["accel"],
                offset=req["offset"],
                settle_clocks=carriage.bounce.settle_clocks,
                max_travel=mech["max_travel"],
            )
            try:
                cfg_h.check(drv.fclk, drv.spr, drv.prescale, drv.inputs.filter_clocks)
            except ValueError as exc:
                return {"value_error": str(exc)}
            # A hang fails the homing, not the session: the seek and the way back (to the switch plus 1000 steps of
            # stop distance) and a 1000-step release, each as cruise time plus ramps (2 v / a, or a triangle's
            # 2 sqrt(d / a)), 4x over.
            start = await drv.position()
            alpha = 2 * math.pi / drv.spr

            def trip(steps: int, speed: float) -> float:
                rad = steps * alpha
                return rad / speed + 2 * speed / req["accel"] + 2 * math.sqrt(rad / req["accel"])

            seconds = 2 * trip(abs(carriage.position - switch.at) + 1000, req["speed"])
            seconds += trip(1000, mech["latch_speed"])
            budget = math.ceil(4 * seconds * drv.fclk) + 100_000

            async def run() -> dict[str, Any]:
                try:
                    result = await home(drv, cfg_h, idle=lambda: ClockCycles(dut.clk, mech["poll_clocks"]))
                except ValueError as exc:  # a jog or move the driver refuses (a speed above the engine's limit)
                    return {"value_error": str(exc)}
                except StepRampError as exc:
                    await drv.clear_flags()
                    return {"core_error": f"homing failed: {exc}", "position": await drv.position()}
                return {
                    "position": result.position,
                    "carriage": carriage.position,
                    "switch_edge": switch.first_off,
                    "seek_latch": result.seek.position,
                    "release_latch": result.release.position,
                    "end_s": get_sim_time("ps") * 1e-12,
                }

            dut._log.info("home from POSITION %d, carriage step %d", start, carriage.position)
            answer: dict[str, Any] = await limited(run(), budget, "home")
            return answer

        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        sock.connect(os.environ["STEPRAMP_SESSION_SOCKET"])
        stream = sock.makefile("rwb")
        while True:
            line = stream.readline()  # blocks the simulator: no simulated time passes while the user thinks
            if not line:
                break
            req = json.loads(line)
            if req["op"] == "quit":
                break
            try:
                if req["op"] == "move":
                    answer = await do_move(req)
                elif req["op"] == "script":
                    answer = await do_script(req)
                elif req["op"] == "home":
                    answer = await do_home(req)
                elif req["op"] == "signals":
                    answer = {"missing": missing_in(dut, req["paths"])}
                else:
                    answer = {"fault": f"unknown request {req['op']!r}"}
            except Exception as exc:  # tell the front end, then fail the test
                stream.write(json.dumps({"fault": repr(exc)}).encode() + b"\n")
                stream.flush()
                raise
            stream.write(json.dumps(answer).encode() + b"\n")
            stream.flush()
        await ClockCycles(dut.clk, 10)
        sock.close()
