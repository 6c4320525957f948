# SPDX-License-Identifier: MIT
"""`stepramp shell` without a simulator (the bit-exact model as back end): the AVR446 command language, its units,
ranges and info line, bad commands, and the GTKWave layout writer the shell and the demo share."""

from __future__ import annotations

import io
import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

from stepramp.board.driver import StepRampError
from stepramp.board.plan import MIN_INTERVAL_CLKS, MIN_INTERVAL_CLKS_EXACT, RAMP_EXACT, plan_move
from stepramp.models.engine import edges as model_edges
from stepramp.sim.runner import _sim_stop_s
from stepramp.sim.waves import LAYOUT, LAYOUTS, missing_in, signal_paths, write_gtkw, zoom_for
from stepramp.tools.shell import SHELL_CONFIG, SHELL_EXACT_CONFIG, ModelBackend, Shell, speed_limit

BIN = Path(sys.executable).parent / "stepramp"
INFO = re.compile(r"^Motor pos: (-?\d+)   a:(\d+) d:(\d+) s:(\d+) m:(-?\d+)$")


def session(script: str) -> tuple[list[str], ModelBackend]:
    backend = ModelBackend(**SHELL_CONFIG)
    out = io.StringIO()
    Shell(backend, out, **SHELL_CONFIG).run(io.StringIO(script))
    return out.getvalue().splitlines(), backend


def infos(lines: list[str]) -> list[tuple[int, ...]]:
    return [tuple(int(g) for g in m.groups()) for m in map(INFO.match, lines) if m]


def test_avr446_info_line_and_defaults() -> None:
    lines, _ = session("")
    # The info line exactly as AVR446 section 3.1 prints it after the help screen.
    assert "Motor pos: 0   a:4000 d:4000 s:2000 m:400" in lines
    assert lines[0] == "-----" and any(
        line.startswith("a [data] - Set acceleration (range: 71 - 32000)") for line in lines
    )


def test_scripted_session_positions() -> None:
    lines, backend = session("a 4000\nm 400\n\nm -150\nd 2500\ns 1500\n\nmove 30 900 800 700\n?\n")
    got = infos(lines)
    # start, a, m 400, repeat, m -150, d, s, repeat (-150 with the new d and s), move, ?
    assert [g[0] for g in got] == [0, 0, 400, 800, 650, 650, 650, 500, 530, 530]
    assert got[-1] == (530, 900, 800, 700, 30)
    assert got[6] == (650, 4000, 2500, 1500, -150)
    assert lines.count("Running... OK") == 5
    assert backend.position == 530


def test_units_are_hundredths() -> None:
    """m 400 at a 4000, s 2000 is the move of 40 rad/s^2 and 20 rad/s: its STEP edges are the model's for that plan."""
    backend = ModelBackend(**SHELL_CONFIG)
    shell = Shell(backend, io.StringIO(), **SHELL_CONFIG)
    seen = []
    real_move = backend.move

    def spy(steps: int, accel: float, decel: float, speed: float):  # type: ignore[no-untyped-def]
        seen.append((steps, accel, decel, speed))
        return real_move(steps, accel, decel, speed)

    backend.move = spy  # type: ignore[method-assign]
    shell.execute("move -400 4000 3000 2000")
    assert seen == [(-400, 40.0, 30.0, 20.0)]
    plan = plan_move(-400, 40.0, 30.0, 20.0, **SHELL_CONFIG)
    assert len(model_edges(plan)) == 400


@pytest.mark.parametrize(
    ("command", "reason"),
    [
        ("x", "unknown command 'x'"),
        ("a", "'a' takes 1 value, got 0"),
        ("a 70", "acceleration 70 is out of range 71 - 32000"),
        ("d 32001", "deceleration 32001 is out of range 71 - 32000"),
        ("s 11", "speed 11 is out of range 12 - "),
        ("s 1e3", "speed must be an integer, got '1e3'"),
        ("m 64001", "steps 64001 is out of range -64000 - 64000"),
        ("move 1 2 3", "'move' takes 4 values, got 3"),
        ("m 10 20", "'m' takes 1 value, got 2"),
        ("m \uff14\uff10", "steps must be an integer"),  # full-width digits: not for atoi
        ("m 1_0", "steps must be an integer, got '1_0'"),
        ("a " + "9" * 30, "acceleration must be an integer, got '99999999999999999999...'"),
    ],
)
def test_bad_commands_get_the_reason_and_the_help(command: str, reason: str) -> None:
    lines, backend = session(command + "\nm 10\n")
    err = [line for line in lines if line.startswith("error:")]
    assert len(err) == 1 and reason in err[0]
    after = lines[lines.index(err[0]) :]
    assert after[1] == "-----"  # the help text follows
    assert "Running... OK" in lines  # and the session goes on
    assert backend.position == 10
    assert infos(lines)[-1][1:] == (4000, 4000, 2000, 10)  # the bad command changed no setting


def test_speed_limit_is_the_engine_limit() -> None:
    """The help's motor limit is the fastest speed the driver accepts: one step per MIN_INTERVAL_CLKS clocks."""
    limit = speed_limit(**SHELL_CONFIG)
    alpha = 2 * math.pi / SHELL_CONFIG["spr"]
    assert limit == math.floor(100 * alpha * SHELL_CONFIG["fclk"] / MIN_INTERVAL_CLKS)
    plan_move(2000, 320.0, 320.0, limit / 100, **SHELL_CONFIG)  # accepted
    with pytest.raises(ValueError, match="clocks"):
        plan_move(2000, 320.0, 320.0, (limit + 1) / 100, **SHELL_CONFIG)
    lines, _ = session(f"s {limit}\nm 2000\n")
    assert infos(lines)[-1][0] == 2000


def test_zero_steps_moves_nothing_and_q_ends() -> None:
    lines, backend = session("m 0\n\nq\nm 5\n")
    assert "Running... OK" not in lines
    assert backend.position == 0
    assert infos(lines)[-1] == (0, 4000, 4000, 2000, 0)


def test_cli_model_shell_from_stdin() -> None:
    run = subprocess.run(
        [BIN, "shell", "--model"], input="a 4000\nm 400\n\n", capture_output=True, text=True, check=True, timeout=60
    )
    got = infos(run.stdout.splitlines())
    assert [g[0] for g in got] == [0, 0, 400, 800]


def test_gtkw_layout(tmp_path: Path) -> None:
    gtkw = write_gtkw(tmp_path / "w.gtkw", tmp_path / "w.ghw", duration_s=0.8, marker_s=0.4)
    text = gtkw.read_text().splitlines()
    assert f'[dumpfile] "{(tmp_path / "w.ghw").resolve()}"' in text
    # Groups open and close in order, one per LAYOUT entry.
    opens = [text[i + 1][1:] for i, line in enumerate(text) if line == "@800200"]
    closes = [text[i + 1][1:] for i, line in enumerate(text) if line == "@1000200"]
    assert opens == closes == [group for group, _ in LAYOUT]
    # Every vector is a concatenation of its GHW bit facilities, msb first; scalars are one facility.
    for path, width in signal_paths():
        name = f"top.stepramp_plb.{path}"
        if width == 1:
            assert name in text or any(line.startswith("+{") and line.endswith("} " + name) for line in text), path
        else:
            bits = " ".join(f"{name}[{i}]" for i in range(width - 1, -1, -1))
            assert any(line.startswith("#{") and line.endswith("} " + bits) for line in text), path
    zoom_line = next(line for line in text if line.startswith("*"))
    assert zoom_line.split()[1] == str(round(0.4e15))
    # The zoom doubles the visible span for each step of -1.
    assert zoom_for(1.6) == pytest.approx(zoom_for(0.8) - 1)
    assert any("state_name" in p for p, _ in signal_paths())


def test_a_failed_move_is_reported_and_the_session_goes_on() -> None:
    """A core error (or a move that never ends) from the back end: 'failed: reason', position kept, session goes on."""

    class Flaky(ModelBackend):
        def move(self, steps: int, accel: float, decel: float, speed: float):  # type: ignore[no-untyped-def]
            if steps == 7:
                raise StepRampError("the core flagged error 3 (C_FIRST)")
            return super().move(steps, accel, decel, speed)

    out = io.StringIO()
    Shell(Flaky(**SHELL_CONFIG), out, **SHELL_CONFIG).run(io.StringIO("m 5\nm 7\nm 2\n"))
    lines = out.getvalue().splitlines()
    assert "Running... failed: the core flagged error 3 (C_FIRST)" in lines
    assert [g[0] for g in infos(lines)] == [0, 5, 5, 7]


def test_cli_survives_bytes_that_are_not_text() -> None:
    run = subprocess.run(
        [BIN, "shell", "--model"], input=b"m \xff\xfe\n\xc3\nm 3\n", capture_output=True, check=True, timeout=60
    )
    out = run.stdout.decode("utf-8", errors="replace").splitlines()
    assert sum(line.startswith("error:") for line in out) == 2
    assert infos(out)[-1][0] == 3


def test_missing_in_reports_absent_signals_and_wrong_widths() -> None:
    """The check every simulation makes of its layout, on a stand-in for cocotb handles."""

    class Vec:
        def __init__(self, width: int) -> None:
            self.width = width

        def __len__(self) -> int:
            return self.width

    class Scope:
        pass

    dut = Scope()
    dut.clk = Vec(1)  # type: ignore[attr-defined]
    dut.core_inst = Scope()  # type: ignore[attr-defined]
    dut.core_inst.cur_delay = Vec(31)  # type: ignore[attr-defined]
    got = missing_in(dut, [("clk", 1), ("core_inst.cur_delay", 32), ("core_inst.nope", 1), ("nope.x", 4)])
    assert got == ["core_inst.cur_delay (width 31, not 32)", "core_inst.nope", "nope.x"]
    # every top's layout shows the engine's state by name, its delay and counters, and STEP/DIR
    for top, layout in LAYOUTS.items():
        names = {p.rsplit(".", 1)[-1] for p, _ in signal_paths(layout)}
        assert {"state_name", "cur_delay", "step_count", "position", "step", "dir"} <= names, top


def test_sim_stop_from_cocotb_results(tmp_path: Path) -> None:
    xml = tmp_path / "r.xml"
    xml.write_text(
        '<testsuites><testsuite><testcase><properties><property name="sim_time_stop" value="1500.0" />'
        '</properties></testcase><testcase><properties><property name="sim_time_stop" value="97360.0" />'
        "</properties></testcase></testsuite></testsuites>"
    )
    assert _sim_stop_s(xml) == pytest.approx(97360e-9)
    assert _sim_stop_s(tmp_path / "absent.xml") is None


def test_jog_and_change_commands_on_the_model() -> None:
    """`j` jogs for a time then stops (the stop distance past the jog), `c` ends exactly on its steps with the
    speed changed while running; bad values get the reason."""
    out = io.StringIO()
    Shell(ModelBackend(**SHELL_CONFIG), out, **SHELL_CONFIG).run(io.StringIO("j 2000 500\nc 800 400 3000\nj 5 10\n"))
    pos = [int(m.group(1)) for m in map(INFO.match, out.getvalue().splitlines()) if m]
    assert pos[0] == 0 and pos[1] > 0 and pos[2] == pos[1] + 800 and pos[3] == pos[2]
    assert "error: speed 5 is out of range 12 - 6135 (either sign)" in out.getvalue()


def test_home_command_needs_the_machine() -> None:
    """`home [pos]`: the model has no machine (the reason, the session goes on, the position unchanged); bad values."""
    lines, backend = session("m 50\nhome\nhome 7 8\nhome x\nhome 99999\n")
    errors = [line for line in lines if line.startswith("error:")]
    assert errors == [
        "error: home needs the simulated machine (its switch and the core's latch): not with --model",
        "error: 'home' takes at most 1 value, got 2",
        "error: position must be an integer, got 'x'",
        "error: position 99999 is out of range -64000 - 64000",
    ]
    assert [g[0] for g in infos(lines)][-1] == 50 and backend.position == 50
    assert any(line.startswith("home [pos]") for line in lines)


def test_exact_mode_shell() -> None:
    """`stepramp shell --model --ramp exact`: the same session in exact mode (1 MHz, PRESCALE 4: the same 4 us tick),
    each move planned for the exact ramp; the speed limit is one step per MIN_INTERVAL_CLKS_EXACT clocks."""
    cfg = {**SHELL_EXACT_CONFIG, "ramp": RAMP_EXACT}
    backend = ModelBackend(**cfg)
    out = io.StringIO()
    Shell(backend, out, **cfg).run(io.StringIO("a 4000\nm 400\n\nj 1500 200\n"))
    assert [g[0] for g in infos(out.getvalue().splitlines())][:4] == [0, 0, 400, 800]
    limit = speed_limit(**cfg)
    alpha = 2 * math.pi / cfg["spr"]
    assert limit == math.floor(100 * alpha * cfg["fclk"] / cfg["prescale"] / (MIN_INTERVAL_CLKS_EXACT / 4))
    cmd = [BIN, "shell", "--model", "--ramp", "exact"]
    run = subprocess.run(cmd, input="a 4000\nm 400\n", capture_output=True, text=True, timeout=60)
    assert run.returncode == 0 and [g[0] for g in infos(run.stdout.splitlines())][-1] == 400
