# SPDX-License-Identifier: MIT
"""Reference models: the engine's bit-exact arithmetic, the stepping logic, the blocks, the ideal ramp."""
