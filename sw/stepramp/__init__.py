# SPDX-License-Identifier: MIT
"""stepramp: driver, bit-exact reference model and tools for the stepramp IP core.

The package is grouped by layer, and no layer imports one above it:

* ``stepramp.board``: what the soft CPU runs: move planning (``plan``), the register driver (``driver``), the
  register map (``regmap``).
* ``stepramp.models``: the reference models: the engine's bit-exact arithmetic (``engine``), the stepping logic
  (``stepping``), the arithmetic blocks (``blocks``) and the ideal trapezoid that judges them (``ideal``).
* ``stepramp.sim``: simulation: the cocotb runner (``runner``), the engine bench, the RTL session, the step watch,
  the bus masters, the waveform layouts and the test profiles.
* ``stepramp.tools``: the ``stepramp`` command and what it drives: shell, demo, plot, synthesis, RTL checks, the
  register-map generator.

The driver's public API is also here, at the top: ``from stepramp import StepRamp, plan_move``.
"""

from stepramp.board.driver import MmapAccess, Outputs, Status, StepRamp, StepRampError
from stepramp.board.plan import Plan, plan_move

__version__ = "0.1.0"

__all__ = ["MmapAccess", "Outputs", "Plan", "Status", "StepRamp", "StepRampError", "plan_move"]
