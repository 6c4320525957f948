# SPDX-License-Identifier: MIT
"""Merge the functional coverage the simulations wrote (stepramp.sim.coverage) and report it.

    python -m stepramp.tools.coverage build/coverage [--check]

Merges every cov_*.yml of the folder with cocotb-coverage's merge_coverage into merged.yml, writes report.md (one
table per cover point: every bin and its hits, the empty ones marked) and prints a summary. With --check, exits 1
when a bin stays empty or when no simulation wrote coverage.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import yaml
from cocotb_coverage.coverage import merge_coverage


def merge(folder: Path) -> dict[str, Any]:
    """The merged coverage database of the folder's cov_*.yml (written to merged.yml)."""
    files = sorted(str(f) for f in folder.glob("cov_*.yml"))
    if not files:
        raise FileNotFoundError(f"no coverage in {folder}: run the simulations with STEPRAMP_COVERAGE_DIR={folder}")
    merged = folder / "merged.yml"
    merge_coverage(lambda _msg: None, str(merged), *files)
    return dict(yaml.safe_load(merged.read_text()))


def points(db: dict[str, Any]) -> dict[str, dict[str, int]]:
    """Cover point name -> {bin: hits}, for every point with bins."""
    return {name: dict(item["bins:_hits"]) for name, item in sorted(db.items()) if "bins:_hits" in item}


def report(bins: dict[str, dict[str, int]], n_files: int) -> str:
    """The Markdown report."""
    total = sum(len(b) for b in bins.values())
    hit = sum(1 for b in bins.values() for h in b.values() if h > 0)
    lines = [
        "# Functional coverage",
        "",
        f"{hit} of {total} bins hit, merged from {n_files} simulations (stepramp.sim.coverage; docs/verification.md).",
        "",
    ]
    for name, hits in bins.items():
        covered = sum(1 for h in hits.values() if h > 0)
        lines += [f"## {name}: {covered} / {len(hits)}", "", "| bin | hits |", "|---|---|"]
        lines += [f"| {b} | {h if h else '**0 (empty)**'} |" for b, h in hits.items()]
        lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder", type=Path, help="where the simulations wrote cov_*.yml")
    ap.add_argument("--check", action="store_true", help="exit 1 when a bin stays empty")
    args = ap.parse_args(argv)
    try:
        db = merge(args.folder)
    except FileNotFoundError as exc:
        print(f"coverage: {exc}", file=sys.stderr)
        return 1
    bins = points(db)
    n_files = len(list(args.folder.glob("cov_*.yml")))
    text = report(bins, n_files)
    (args.folder / "report.md").write_text(text + "\n")
    empty = [f"{name}: {b}" for name, hits in bins.items() for b, h in hits.items() if h == 0]
    total = sum(len(b) for b in bins.values())
    for name, hits in bins.items():
        print(f"coverage {name}: {sum(1 for h in hits.values() if h)} / {len(hits)} bins")
    print(f"coverage: {total - len(empty)} / {total} bins hit -> {args.folder / 'report.md'}")
    if empty:
        print("coverage: empty bins:\n  " + "\n  ".join(empty), file=sys.stderr)
        return 1 if args.check else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
