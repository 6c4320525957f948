# SPDX-License-Identifier: MIT
"""Tools: the stepramp command, the shell, the demo, plots, synthesis, RTL checks, generators."""
