#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Write (or check) the model's golden checksums, sw/tests/golden/checksums.json (stepramp.tools.golden).

    .venv/bin/python scripts/golden.py            # write them (only when a change of the edges is meant)
    .venv/bin/python scripts/golden.py --check    # recompute all of them and compare: exit status 1 on a difference

The random moves and scripts come from the fixed seed stepramp.tools.golden.SEED. sw/tests/test_golden.py checks the
profiles, stops and named scripts and a seeded subset of the random ones on every run; --check checks them all.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from stepramp.tools.golden import compute, differences

GOLDEN = Path(__file__).resolve().parent.parent / "sw" / "tests" / "golden" / "checksums.json"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="compare with the file instead of writing it")
    parser.add_argument("--out", type=Path, default=GOLDEN, help="the checksum file")
    args = parser.parse_args(argv)
    start = time.monotonic()
    got = compute(progress=lambda msg: print(f"{time.monotonic() - start:7.1f} s  {msg}", file=sys.stderr))
    if args.check:
        diff = differences(json.loads(args.out.read_text()), got)
        for line in diff:
            print(line)
        print(f"{len(diff)} differences ({time.monotonic() - start:.1f} s)", file=sys.stderr)
        return 1 if diff else 0
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(got, indent=1) + "\n")
    print(f"wrote {args.out} ({time.monotonic() - start:.1f} s)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
