# SPDX-License-Identifier: MIT
"""Write the Vitis (classic / SDK standalone BSP) driver folder of the stepramp IP:

    <out>/data/stepramp.mdd   driver definition (drivers/stepramp_v1_0/data, kept in git)
    <out>/data/stepramp.tcl   its xparameters.h hook (drivers/stepramp_v1_0/data, kept in git)
    <out>/src/Makefile        the BSP's library build (drivers/stepramp_v1_0/src/Makefile, kept in git)
    <out>/src/*.c, *.h        the driver: a copy of sw/c/src, made here (no second copy in git)

python -m stepramp.tools.vitis_driver [--out DIR]   (default build/vitis/drivers/stepramp_v1_0)

scripts/package_vivado.tcl assembles the same folder inside the packaged IP (drivers/stepramp_v1_0 beside
component.xml). sw/tests/test_vitis_driver.py reads the folder as the tools do and builds src/ against an
xparameters.h.
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[3]
TEMPLATE = REPO / "drivers" / "stepramp_v1_0"
DRIVER_SOURCES = REPO / "sw" / "c" / "src"
DEFAULT_OUT = REPO / "build" / "vitis" / "drivers" / TEMPLATE.name


def driver_files() -> list[Path]:
    """The driver's sources as they go into src/: every .c and .h of sw/c/src."""
    return sorted(p for p in DRIVER_SOURCES.iterdir() if p.suffix in (".c", ".h"))


def write(out: Path = DEFAULT_OUT) -> Path:
    """Write the driver folder to `out` (replacing it) and return it."""
    if out.exists():
        shutil.rmtree(out)
    shutil.copytree(TEMPLATE, out)
    for src in driver_files():
        shutil.copy2(src, out / "src" / src.name)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="the driver folder to write")
    args = parser.parse_args(argv)
    print(f"stepramp: Vitis driver folder in {write(args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
