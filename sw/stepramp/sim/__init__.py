# SPDX-License-Identifier: MIT
"""Simulation: the cocotb runner, the benches' clock and reset, the engine bench, the RTL session, the script
player, the step watch, the motor-pin monitors (STEP width, DIR timing, shoot-through, ESTOP, windings), the bus
master, waveform layouts, profiles."""
