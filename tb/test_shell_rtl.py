# SPDX-License-Identifier: MIT
"""`stepramp shell` on the RTL: a scripted session through the command line (the issue's example), and a session
in-process whose every move is checked pulse for pulse against the bit-exact model, all in one simulation."""

from __future__ import annotations

import io
import os
import re
import subprocess
import sys
from pathlib import Path

from stepramp.board.plan import plan_move
from stepramp.models.engine import edges as model_edges
from stepramp.sim.session import RtlSession
from stepramp.tools.shell import SHELL_CONFIG, RtlBackend, Shell
from tbutil import build_dir

BIN = Path(sys.executable).parent / "stepramp"
INFO = re.compile(r"^Motor pos: (-?\d+)   a:(\d+) d:(\d+) s:(\d+) m:(-?\d+)$")


def positions(text: str) -> list[int]:
    return [int(m.group(1)) for m in map(INFO.match, text.splitlines()) if m]


def test_cli_session_from_stdin(tmp_path: Path) -> None:
    """printf 'a 4000\\nm 400\\n\\n' | stepramp shell: two moves of 400 steps, positions read back from the core."""
    waves = tmp_path / "session.ghw"
    run = subprocess.run(
        [BIN, "shell", "--waves", str(waves), "--build", str(build_dir("shell_cli"))],
        input="a 4000\nm 400\n\n",
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    assert positions(run.stdout) == [0, 0, 400, 800]
    assert run.stdout.count("Running... OK") == 2
    assert "Motor pos: 800   a:4000 d:4000 s:2000 m:400" in run.stdout.splitlines()
    assert waves.stat().st_size > 0
    assert waves.with_suffix(".gtkw").read_text().count("top.stepramp_plb.") > 20


def test_session_moves_equal_the_model() -> None:
    script = "m -60\nmove 150 3000 1200 3500\nbogus\ns 99999\n\nd 71\nm 3\n"
    out = io.StringIO()
    with RtlSession(build_dir("shell_session")) as session:
        backend = RtlBackend(session)
        Shell(backend, out, **SHELL_CONFIG).run(io.StringIO(script))
    lines = out.getvalue().splitlines()
    assert session.simulations == 1
    # -60, +150, bad command, bad speed, repeat (+150), d 71, +3
    assert positions(out.getvalue()) == [0, -60, 90, 90, 90, 240, 240, 243]
    assert [line for line in lines if line.startswith("error:")] == [
        "error: unknown command 'bogus'",
        "error: speed 99999 is out of range 12 - 6135",
    ]
    expected = [(-60, 40.0, 40.0, 20.0), (150, 30.0, 12.0, 35.0), (150, 30.0, 12.0, 35.0), (3, 30.0, 0.71, 35.0)]
    assert len(backend.outcomes) == len(expected)
    for outcome, args in zip(backend.outcomes, expected, strict=True):
        plan = plan_move(*args, **SHELL_CONFIG)
        assert outcome.plan == plan
        assert outcome.edges == model_edges(plan), args
        assert len(outcome.edges) == abs(args[0])


FAULT_SCRIPT = """
import sys
from pathlib import Path
from stepramp.sim.session import RtlSession, SessionError
session = RtlSession(Path(sys.argv[1]))
session.start()
try:
    session.request({"op": "move", "steps": 1})  # no accel: the cocotb test raises
except SessionError as exc:
    print("request:", exc)
try:
    session.close()
except SessionError as exc:
    print("close:", exc)
"""


def test_a_failing_simulation_is_reported_outside_pytest() -> None:
    """A fault inside the simulation reaches the front end as SessionError, and the failed cocotb test is reported by
    close() even where the runner does not exit (outside pytest)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_CURRENT_TEST"}
    run = subprocess.run(
        [sys.executable, "-c", FAULT_SCRIPT, str(build_dir("shell_fault"))],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
        check=False,
    )
    assert "request: the simulation failed: KeyError('accel')" in run.stdout, run.stdout + run.stderr[-2000:]
    assert "close: the simulation failed" in run.stdout, run.stdout + run.stderr[-2000:]


def test_jog_and_change_while_running_equal_the_model() -> None:
    """`j` (jog, then a soft stop after a time) and `c` (a move whose speed changes while it runs) on the RTL, in
    one session: every position read back from the core equals the bit-exact model's (the same shell on ModelBackend),
    and each command moved (a jog each way through the current position, a change to a faster speed)."""
    from stepramp.tools.shell import ModelBackend

    script = "a 4000\nj 2000 500\nj -3000 300\nc 800 400 3000\n"
    out = io.StringIO()
    with RtlSession(build_dir("shell_jog")) as session:
        Shell(RtlBackend(session), out, **SHELL_CONFIG).run(io.StringIO(script))
    model = io.StringIO()
    Shell(ModelBackend(**SHELL_CONFIG), model, **SHELL_CONFIG).run(io.StringIO(script))
    got, want = positions(out.getvalue()), positions(model.getvalue())
    assert out.getvalue().count("Running... OK") == 3, out.getvalue()[-2000:]
    assert got == want, (got, want)
    assert got[2] > 0 and got[3] < got[2] and got[4] == got[3] + 800


def test_home_on_the_machine() -> None:
    """`home` on the session's machine (stepramp.sim.session.MECHANICS: HOME active for carriage steps <= -100,
    bouncing): from the start (off the switch) and from a place on the switch (the homing leaves it first), each
    homing makes the switch edge, carriage step -99 (the physics), the position asked for; the carriage's step and
    POSITION printed in the info line agree with that after each."""
    from stepramp.sim.session import MECHANICS
    from stepramp.tools.shell import SHELL_SESSION_CONFIG, Homed

    class Recording(RtlBackend):
        def __init__(self, session: RtlSession) -> None:
            super().__init__(session)
            self.homed: list[tuple[int, Homed]] = []

        def home(self, offset: int, speed: float, accel: float) -> Homed:
            homed = super().home(offset, speed, accel)
            self.homed.append((offset, homed))
            return homed

    script = "a 32000\nhome 7\nm -10\nhome -20\nm 20\n"
    out = io.StringIO()
    with RtlSession(build_dir("shell_home"), config=SHELL_SESSION_CONFIG) as session:
        backend = Recording(session)
        Shell(backend, out, **SHELL_CONFIG).run(io.StringIO(script))
    text = out.getvalue()
    edge = MECHANICS["home_at"] + 1
    assert text.count(f"Homing... OK: the switch edge (machine step {edge}) is position") == 2, text[-2000:]
    assert [offset for offset, _ in backend.homed] == [7, -20]
    for offset, homed in backend.homed:
        assert homed.switch_edge == edge
        # POSITION counts the carriage's steps: `offset` is where the carriage is at the switch edge
        assert homed.position - offset == homed.carriage - edge, (offset, homed)
    got = positions(text)
    # start, a, home 7, m -10 (onto the switch), home -20, m 20
    assert got[:2] == [0, 0]
    assert got[2] == backend.homed[0][1].position and got[3] == got[2] - 10
    assert got[3] - 7 + edge < edge, "m -10 did not put the carriage on the switch"
    assert got[4] == backend.homed[1][1].position and got[5] == got[4] + 20
