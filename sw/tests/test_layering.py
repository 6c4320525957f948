# SPDX-License-Identifier: MIT
"""The package's import graph against its documented layering (the numbered list of layers in the docstring of
sw/stepramp/__init__.py): a module imports from its own layer and the layers below it, never from one above,
wherever the import is (a late import inside a function or under TYPE_CHECKING counts the same), so no two
sub-packages import each other.

* test_layers_documented: the docstring lists every sub-package and top-level module of stepramp, once;
* test_no_import_above_its_layer: every import of a stepramp module in sw/stepramp respects the order;
* test_violations_are_found: the check finds a late import from a layer above (a hand-made module);
* test_no_module_over_700_lines: no module of sw/stepramp is longer than 700 lines (issue 34).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import stepramp

ROOT = Path(stepramp.__file__).resolve().parent
MAX_LINES = 700


def documented_layers() -> list[str]:
    """The layers in the package docstring's numbered list ("1. ``stepramp.spec``: ..."), lowest first."""
    return re.findall(r"^\d+\. ``stepramp\.(\w+)``", stepramp.__doc__ or "", flags=re.M)


def layer_of(module: str) -> str | None:
    """The layer of a dotted stepramp module name (None for the package itself)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def imported_modules(tree: ast.AST, module: str) -> list[tuple[int, str]]:
    """(line, module) of every stepramp import anywhere in a module's tree (relative imports resolved)."""
    out: list[tuple[int, str]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names if a.name.split(".")[0] == "stepramp"]
        elif isinstance(node, ast.ImportFrom):
            name = node.module or ""
            if node.level:
                base = module.split(".")[: -node.level]
                name = ".".join([*base, *([name] if name else [])])
            if name.split(".")[0] == "stepramp":
                out.append((node.lineno, name))
    return out


def module_name(root: Path, path: Path) -> str:
    parts = path.relative_to(root.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def violations(root: Path, layers: list[str]) -> list[str]:
    """Every import in the package at `root` of a module from a layer above the importing module's (or from a
    sub-package no layer names). The package's own __init__ (the public API) may import any layer."""
    rank = {name: n for n, name in enumerate(layers)}
    out = []
    for path in sorted(root.rglob("*.py")):
        module = module_name(root, path)
        mine = layer_of(module)
        if mine is None:
            continue
        for line, target in imported_modules(ast.parse(path.read_text(encoding="utf-8")), module):
            theirs = layer_of(target)
            if theirs is None or theirs == mine:
                continue
            if theirs not in rank or mine not in rank or rank[theirs] > rank[mine]:
                out.append(f"{path.relative_to(root.parent)}:{line}: {module} ({mine}) imports {target} ({theirs})")
    return out


def test_layers_documented() -> None:
    layers = documented_layers()
    assert layers[:1] == ["spec"], layers
    assert len(layers) == len(set(layers))
    present = {p.stem if p.is_file() else p.name for p in ROOT.iterdir() if p.suffix == ".py" or p.is_dir()}
    present -= {"__init__", "__pycache__"}
    assert present == set(layers), f"the docstring's layers {layers} are not the package's parts {sorted(present)}"


def test_no_import_above_its_layer() -> None:
    found = violations(ROOT, documented_layers())
    assert found == [], "\n".join(found)


def test_violations_are_found(tmp_path: Path) -> None:
    pkg = tmp_path / "stepramp"
    for sub in ("models", "board"):
        (pkg / sub).mkdir(parents=True)
    (pkg / "__init__.py").write_text("from stepramp.board.x import y\n")
    (pkg / "spec.py").write_text("X = 1\n")
    (pkg / "models" / "__init__.py").write_text("")
    (pkg / "models" / "engine.py").write_text(
        "from stepramp.spec import X\n\n\ndef f():\n    from stepramp.board.change import Segment\n"
    )
    (pkg / "board" / "__init__.py").write_text("")
    (pkg / "board" / "change.py").write_text("from ..models import engine\nfrom stepramp.spec import X\n")
    found = violations(pkg, ["spec", "models", "board"])
    late = "stepramp/models/engine.py:5: stepramp.models.engine (models) imports stepramp.board.change (board)"
    assert found == [late]
    assert violations(pkg, ["spec", "board", "models"]) == [
        "stepramp/board/change.py:1: stepramp.board.change (board) imports stepramp.models (models)"
    ]


def test_no_module_over_700_lines() -> None:
    long = {
        str(p.relative_to(ROOT.parent)): n
        for p in sorted(ROOT.rglob("*.py"))
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert long == {}, f"modules over {MAX_LINES} lines: {long}"
