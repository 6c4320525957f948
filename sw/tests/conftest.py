# SPDX-License-Identifier: MIT
"""Fixtures of the sw/tests modules."""

from __future__ import annotations

from pathlib import Path

import pytest

from stepramp.tools import clib


@pytest.fixture(scope="module")
def build() -> Path:
    """Build the C library and run its host tests (make -C sw/c); a missing toolchain fails, it is not skipped."""
    return clib.build()
