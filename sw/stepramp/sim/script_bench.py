# SPDX-License-Identifier: MIT
"""The cocotb side of `stepramp sim --script`: the driver's actions of command scripts played through a bus top.

Runs inside the simulator (stepramp.sim.script_sim starts it). The request (STEPRAMP_SCRIPT_REQUEST) holds scripts,
each as the actions the driver's planner made (stepramp.board.script.plan_script): register writes that prepare a
commit, and the CTRL write that commits it, which the register file must sample at exactly the clock edge `at` of the
script's clock axis. Every script starts from a reset of the top. The bench issues the preparing writes in the
PREP_CLOCKS before the commit, then the committing write so that it lands on its edge (the bus master's latency is
measured once, on a harmless write, and every commit is checked against the register file's own write strobe), and
records every STEP rising edge with POSITION after it, and every error the core flags. Results go to
STEPRAMP_SCRIPT_RESULT: per script {"edges", "positions", "core_errors": [[edge, code], ...], "commits": [...]}.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import cocotb
from cocotb.triggers import FallingEdge, First, ReadOnly, RisingEdge, Timer, ValueChange
from cocotb.utils import get_sim_time

from stepramp.board.multi import axis_base
from stepramp.board.regmap import REGISTERS_BY_NAME, offset
from stepramp.sim import player
from stepramp.sim.clocking import (
    CLK_PERIOD_NS,
    CLK_PERIOD_PS,
    apply_reset,
    now_cycles,
    quiet_inputs,
    start_clock,
)
from stepramp.sim.coverage import watch_core
from stepramp.sim.ipif import IpifMaster
from stepramp.sim.monitors import EstopMonitor

CTRL = offset("CTRL")
INPUT_CFG = REGISTERS_BY_NAME["INPUT_CFG"]
#: Clocks between the reset of a script and its clock 0 (its first commit's preparing writes fit in them).
LEAD_CLOCKS = 400


class _AxilWriter:
    """A minimal AXI4-Lite write master (the scripts only write): AW and W valid together from a falling edge, each
    dropped once its handshake is sampled, BREADY high until BVALID. No coroutine runs between writes, so an idle bus
    costs the simulation nothing (cocotbext-axi's channels wake every clock)."""

    def __init__(self, dut: Any) -> None:
        self.dut, self.clk = dut, dut.aclk
        for name in (
            "awvalid",
            "wvalid",
            "bready",
            "arvalid",
            "rready",
            "awaddr",
            "wdata",
            "wstrb",
            "awprot",
            "araddr",
        ):
            getattr(dut, f"s_axil_{name}").value = 0
        for name in ("arprot",):
            getattr(dut, f"s_axil_{name}").value = 0

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None:
        dut = self.dut
        await FallingEdge(self.clk)
        dut.s_axil_awaddr.value = addr
        dut.s_axil_wdata.value = value & 0xFFFF_FFFF
        dut.s_axil_wstrb.value = strobe
        dut.s_axil_awvalid.value = 1
        dut.s_axil_wvalid.value = 1
        dut.s_axil_bready.value = 1
        aw = w = False
        for _ in range(100):
            await RisingEdge(self.clk)
            await ReadOnly()
            aw = aw or bool(int(dut.s_axil_awready.value))
            w = w or bool(int(dut.s_axil_wready.value))
            done = bool(int(dut.s_axil_bvalid.value))
            await FallingEdge(self.clk)
            dut.s_axil_awvalid.value = int(not aw)
            dut.s_axil_wvalid.value = int(not w)
            if done:
                if int(dut.s_axil_bresp.value) != 0:
                    raise RuntimeError(f"write {addr:#x}: BRESP {int(dut.s_axil_bresp.value)}")
                dut.s_axil_bready.value = 0
                return
        raise TimeoutError(f"write {addr:#x}: no BVALID within 100 clocks")

    async def read(self, addr: int) -> int:
        dut = self.dut
        await FallingEdge(self.clk)
        dut.s_axil_araddr.value = addr
        dut.s_axil_arvalid.value = 1
        dut.s_axil_rready.value = 1
        ar = False
        for _ in range(100):
            await RisingEdge(self.clk)
            await ReadOnly()
            ar = ar or bool(int(dut.s_axil_arready.value))
            done = bool(int(dut.s_axil_rvalid.value))
            data = int(dut.s_axil_rdata.value) if done else 0
            await FallingEdge(self.clk)
            dut.s_axil_arvalid.value = int(not ar)
            if done:
                dut.s_axil_rready.value = 0
                return data
        raise TimeoutError(f"read {addr:#x}: no RVALID within 100 clocks")


def _is_axil(top: str) -> bool:
    """Whether the top is an AXI4-Lite one (aclk, aresetn), not a PLB-like one (clk, rst)."""
    return top.endswith("axil")


def _clock(dut: Any, top: str) -> Any:
    return dut.aclk if _is_axil(top) else dut.clk


def _input_cfg(script: Mapping[str, Any]) -> int:
    """INPUT_CFG for a script: the limit inputs on, LIMIT_HARD as the script's "limit_hard"."""
    cfg = 1 << INPUT_CFG.field("LIMIT_EN").lsb
    return cfg | (int(bool(script.get("limit_hard"))) << INPUT_CFG.field("LIMIT_HARD").lsb)


async def _reset(dut: Any, top: str) -> Any:
    """Reset the top and return its register access."""
    if _is_axil(top):
        bus = _AxilWriter(dut)
        await apply_reset(dut.aclk, dut.aresetn, active=0)
        return bus
    bus = IpifMaster(dut, dut.clk, CLK_PERIOD_NS)
    await apply_reset(dut.clk, dut.rst)
    return bus


class _Recorder:
    """STEP rising edges with POSITION after them and the core's errors, as absolute clock edges, from now on."""

    def __init__(self, dut: Any, clk: Any) -> None:
        self.dut, self.clk = dut, clk
        self.edges: list[int] = []
        self.positions: list[int] = []
        self.errors: list[tuple[int, int]] = []
        self.running = True
        for coro in (self._steps(), self._errors()):
            cocotb.start_soon(coro)

    async def _steps(self) -> None:
        core = self.dut.core_inst
        while self.running:
            await RisingEdge(self.dut.step)
            self.edges.append(now_cycles(CLK_PERIOD_PS))
            self.positions.append(core.position.value.to_signed())

    async def _errors(self) -> None:
        # ERROR is sticky (a script never clears it): a new error shows as a new ERR_CODE, or as ERROR rising.
        regfile = self.dut.core_inst.regfile_inst
        while self.running:
            await First(RisingEdge(regfile.error_flag), ValueChange(regfile.err_code_r))
            await ReadOnly()
            if int(regfile.error_flag.value):
                self.errors.append((now_cycles(CLK_PERIOD_PS), int(regfile.err_code_r.value)))


async def _after_edge(origin: int, a: Any) -> None:
    """Wait until half a clock after edge origin + a, where a script's pin change falls (it must not be past)."""
    now = get_sim_time("ps")
    half = (origin + int(a)) * CLK_PERIOD_PS + CLK_PERIOD_PS // 2
    assert now <= half, f"the pin change after edge {a} is late"
    if half > now:
        await Timer(half - now, unit="ps")


async def _drive_pins(dut: Any, clk: Any, origin: int, pins: list[list[Any]]) -> None:
    """Each (a, pin, level) of the script: the pin (active high) takes the level after edge origin + a."""
    for a, name, level in pins:
        await _after_edge(origin, a)
        getattr(dut, str(name)).value = int(level)


async def _play(dut: Any, top: str, script: dict[str, Any]) -> dict[str, Any]:
    clk = _clock(dut, top)
    quiet_inputs(dut)
    bus = await _reset(dut, top)
    if script.get("pins") or script.get("input_filter") or script.get("limit_hard"):
        await bus.write(offset("INPUT_FILTER"), int(script.get("input_filter", 0)))
        await bus.write(offset("INPUT_CFG"), _input_cfg(script))
    rec = _Recorder(dut, clk)
    regfile = dut.core_inst.regfile_inst
    log = player.WriteLog(regfile.wr, regfile.waddr)
    latency = await player.calibrate(bus, clk, log, CTRL)
    origin = now_cycles(CLK_PERIOD_PS) + LEAD_CLOCKS
    # docs/algorithm.md, "Machine inputs": no STEP rising edge more than 2 clocks after the filtered ESTOP edge
    estop = EstopMonitor(dut.core_inst.estop_stop, [dut.step]).start()
    watchers = [cocotb.start_soon(_drive_pins(dut, clk, origin, script.get("pins", [])))]
    commits = player.commits_of(script["actions"], int(script["prep_clocks"]), lambda _: CTRL)
    landed = await player.play(bus, clk, log, commits, origin, latency)
    await player.at_edge(clk, origin + int(script["until"]) + 2)
    rec.running = False
    log.stop()
    for task in watchers:
        task.cancel()
    estop.stop()
    keep = [i for i, e in enumerate(rec.edges) if e - origin <= int(script["until"])]
    return {
        "edges": [rec.edges[i] - origin for i in keep],
        "positions": [rec.positions[i] for i in keep],
        "core_errors": [[e - origin, code] for e, code in rec.errors],
        "commits": landed,
        "estop_violations": [f"{t:.0f} ns: {message}" for t, message in estop.violations],
    }


def _backstop_ns() -> int:
    path = os.environ.get("STEPRAMP_SCRIPT_REQUEST")
    if not path or not Path(path).exists():
        return 1_000_000_000
    request = json.loads(Path(path).read_text())
    clocks = sum(int(s["until"]) + 4 * LEAD_CLOCKS for s in request["scripts"])
    return (clocks + 10_000) * CLK_PERIOD_NS


def _request_scripts() -> list[dict[str, Any]]:
    """The request's scripts (STEPRAMP_SCRIPT_REQUEST, written by stepramp.sim.script_sim)."""
    scripts: list[dict[str, Any]] = json.loads(Path(os.environ["STEPRAMP_SCRIPT_REQUEST"]).read_text())["scripts"]
    return scripts


def _write_results(results: list[dict[str, Any]]) -> None:
    """Per script what the RTL did, to STEPRAMP_SCRIPT_RESULT (stepramp.sim.script_sim reads it)."""
    Path(os.environ["STEPRAMP_SCRIPT_RESULT"]).write_text(json.dumps({"results": results}))


@cocotb.test(timeout_time=_backstop_ns(), timeout_unit="ns")
async def play_scripts(dut: Any) -> None:
    """Play every script of the request, each from a reset, and write what the RTL did."""
    top = dut._name
    start_clock(_clock(dut, top))
    quiet_inputs(dut)
    watch_core(dut.core_inst)
    results = []
    for script in _request_scripts():
        results.append(await _play(dut, top, script))
    _write_results(results)


# ---------------------------------------------------------------------------------------------------------------
# The multi-axis top (stepramp.board.multi_script): each axis's actions in its own register window
# ---------------------------------------------------------------------------------------------------------------


class _MultiRecorder:
    """Per axis, the STEP rising edges (from the step vector) and the position counted from DIR at each."""

    def __init__(self, dut: Any, axes: int) -> None:
        self.dut, self.axes = dut, axes
        self.edges: list[list[int]] = [[] for _ in range(axes)]
        self.positions: list[list[int]] = [[] for _ in range(axes)]
        self.running = True
        self._pos = [0] * axes
        cocotb.start_soon(self._steps())

    async def _steps(self) -> None:
        step, direction = self.dut.step, self.dut.dir
        before = 0
        while self.running:
            await ValueChange(step)
            value = step.value
            now = int(value) if value.is_resolvable else 0
            rising = now & ~before
            before = now
            if rising:
                edge, dirs = now_cycles(CLK_PERIOD_PS), int(direction.value)
                for axis in range(self.axes):
                    if rising >> axis & 1:
                        self._pos[axis] += -1 if dirs >> axis & 1 else 1
                        self.edges[axis].append(edge)
                        self.positions[axis].append(self._pos[axis])


async def _drive_multi_pins(dut: Any, origin: int, pins: list[list[Any]]) -> None:
    """(a, pin, axis, level): axis's bit of the pin (ESTOP: the one pin) takes the level after edge origin + a."""
    shadow = {"limit_neg": 0, "limit_pos": 0, "home": 0}
    for a, name, axis, level in pins:
        await _after_edge(origin, a)
        if name == "estop":
            dut.estop.value = int(level)
        else:
            bit = 1 << int(axis)
            shadow[name] = (shadow[name] | bit) if level else (shadow[name] & ~bit)
            getattr(dut, name).value = shadow[name]


async def _play_multi(dut: Any, top: str, script: dict[str, Any]) -> dict[str, Any]:
    clk = _clock(dut, top)
    axes = int(script["axes"])
    quiet_inputs(dut)
    bus = await _reset(dut, top)
    for axis in range(axes):
        base = axis_base(axis)
        await bus.write(base + offset("INPUT_FILTER"), int(script.get("input_filter", 0)))
        await bus.write(base + offset("INPUT_CFG"), _input_cfg(script))
    rec = _MultiRecorder(dut, axes)
    # the top's write strobes (stepramp_multi's wr and waddr: an axis takes a write at the edge the top samples it)
    log = player.WriteLog(dut.multi_inst.wr, dut.multi_inst.waddr)
    latency = await player.calibrate(bus, clk, log, axis_base(0) + CTRL)  # (axis 0's interrupt enables: all off)
    origin = now_cycles(CLK_PERIOD_PS) + LEAD_CLOCKS
    driver = cocotb.start_soon(_drive_multi_pins(dut, origin, script.get("pins", [])))

    def commit_address(action: Mapping[str, Any]) -> int:
        # the axis's CTRL, or the global window's SYNC_SOFT_STOP or SYNC_START (a group of axes); a SYNC_START's
        # "prep" is the clocks its axes' writes take
        return int(action["commit"]) if "commit" in action else axis_base(int(action["axis"])) + CTRL

    commits = player.commits_of(script["actions"], int(script["prep_clocks"]), commit_address)
    landed = await player.play(bus, clk, log, commits, origin, latency)
    await player.at_edge(clk, origin + int(script["until"]) + 2)
    rec.running = False
    log.stop()
    driver.cancel()
    status = []
    for axis in range(axes):
        status.append(await bus.read(axis_base(axis) + offset("STATUS")))
    until = int(script["until"])
    return {
        "edges": [[e - origin for e in edges if e - origin <= until] for edges in rec.edges],
        "positions": [
            [p for e, p in zip(edges, positions, strict=True) if e - origin <= until]
            for edges, positions in zip(rec.edges, rec.positions, strict=True)
        ],
        "status": status,
        "commits": landed,
    }


@cocotb.test(timeout_time=_backstop_ns(), timeout_unit="ns")
async def play_multi_scripts(dut: Any) -> None:
    """Play every multi-axis script of the request on stepramp_multi_plb / _axil, each from a reset."""
    top = dut._name
    start_clock(_clock(dut, top))
    quiet_inputs(dut)
    results = [await _play_multi(dut, top, script) for script in _request_scripts()]
    _write_results(results)
