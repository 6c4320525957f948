# SPDX-License-Identifier: MIT
"""stepramp: driver, bit-exact reference model and tools for the stepramp IP core.

The package is grouped in layers, lowest first. A module imports from its own layer and the layers below it, never
from one above, anywhere in the module (a late import inside a function counts the same; sw/tests/test_layering.py
checks it):

1. ``stepramp.spec``: the engine's inputs as docs/algorithm.md specifies them: ``Plan`` (a move), ``Segment`` (a
   continuation), the register widths, the fixed-point formats, the ramp kinds. Imports nothing of stepramp.
2. ``stepramp.models``: the reference models, pure Python: the engine's bit-exact arithmetic (``engine``) with one
   implementation per ramp kind (``ramp``: AVR446 through ``blocks``, exact through ``exact``), the stepping logic
   (``stepping``), the machine inputs (``inputs``), the arithmetic blocks (``blocks``), the shared ramp computer's
   scheduler (``scheduler``) and the ideal trapezoid that judges them (``ideal``).
3. ``stepramp.board``: what the soft CPU (or a host) runs: move planning (``plan``, ``change``, ``coord``), the
   register driver (``driver``, ``multi``, ``homing``), the register map (``regmap``), the script planner
   (``script_schema`` to load a script, ``script`` to plan it, ``multi_script`` for the multi-axis top). Nothing of
   the simulator.
4. ``stepramp.sim``: simulation: the cocotb runner (``runner``), the benches, the RTL session, the step watch, the
   bus masters, the waveform layouts, and the test material: profiles (``profiles``), random and named scripts
   (``scripts``, ``multi_scripts``).
5. ``stepramp.tools``: the ``stepramp`` command and what it drives: shell, demo, plot, synthesis, RTL checks, the
   register-map generator, the golden checksums.

The package itself re-exports the driver's public API from ``stepramp.board``: ``from stepramp import StepRamp,
plan_move``.
"""

from stepramp.board.driver import MmapAccess, Outputs, Status, StepRamp, StepRampError
from stepramp.board.plan import Plan, plan_move

__version__ = "0.1.0"

__all__ = ["MmapAccess", "Outputs", "Plan", "Status", "StepRamp", "StepRampError", "plan_move"]
