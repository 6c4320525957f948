# SPDX-License-Identifier: MIT
"""stepramp: driver, bit-exact reference model and tools for the stepramp IP core."""

__version__ = "0.1.0"
