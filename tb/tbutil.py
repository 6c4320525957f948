# SPDX-License-Identifier: MIT
"""Shared helpers for the cocotb testbenches: build directories, clock and reset, edge timestamps."""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, FallingEdge
from cocotb.utils import get_sim_time

REPO = Path(__file__).resolve().parents[1]
CLK_PERIOD_NS = 10


def build_dir(name: str) -> Path:
    """A build directory of its own for one test (pytest -n needs one per test)."""
    safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", name)
    path = REPO / "build" / "sim" / safe
    path.mkdir(parents=True, exist_ok=True)
    return path


def env_int(name: str, default: int) -> int:
    """An integer handed to the simulation through the environment."""
    return int(os.environ.get(name, default))


async def start_clock_and_reset(dut: Any, cycles: int = 3) -> None:
    """Start clk (cocotb GPI clock) and hold rst high for a few cycles; the caller drives the inputs."""
    Clock(dut.clk, CLK_PERIOD_NS, unit="ns").start()
    dut.rst.value = 1
    await ClockCycles(dut.clk, cycles)
    await FallingEdge(dut.clk)
    dut.rst.value = 0


def now_cycles() -> int:
    """Simulation time in clock periods, rounded: the index of the most recent rising edge."""
    return round(get_sim_time("ns") / CLK_PERIOD_NS)


__all__ = ["CLK_PERIOD_NS", "build_dir", "cocotb", "env_int", "now_cycles", "start_clock_and_reset"]
