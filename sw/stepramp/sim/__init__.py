# SPDX-License-Identifier: MIT
"""Simulation: the cocotb runner, the engine bench, the RTL session, monitors, bus masters, waveform layouts,
profiles."""
