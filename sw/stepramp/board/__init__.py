# SPDX-License-Identifier: MIT
"""Board side: what the soft CPU runs (move planning, the register driver, the register map)."""
