# SPDX-License-Identifier: MIT
"""The regression's order on the workers (`make test`: pytest -n 2 --dist loadgroup --no-loadscope-reorder).

Longest first: the tests run in the order of their measured durations, longest first, so that the two workers end
together (a 5-minute simulation started last would leave one worker idle for 5 minutes). The durations are the
committed tb/durations.json, updated with build/durations.json (which every run here updates with its
own); a test in neither is taken as 60 s (a new test is most likely a simulation: run it early). Each sw/tests
module stays one unit on one worker (its module fixtures are set up once, and ~1,000 quick tests do not cost a
scheduling round each); so does each tb module with a module-scoped fixture (test_synth_size's yosys run). The units
are given to xdist by UnitScheduling, a loadgroup scheduler that reads the unit from the test's path: xdist 3.8's own
loadgroup marks a group by rewriting `item._nodeid`, which pytest 9 no longer reads, so its groups were split.
No test is left out or changed: this only orders and groups. To refresh the committed table after a full run:
cp build/durations.json tb/durations.json.
"""

from __future__ import annotations

import contextlib
import json
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[1]
#: The durations measured here (every passing run), and the committed ones (a fresh clone).
MEASURED = REPO / "build" / "durations.json"
COMMITTED = Path(__file__).with_name("durations.json")
#: A test with no measured duration: a new simulation, run early.
UNKNOWN_S = 60.0
#: tb modules whose tests share a module-scoped fixture: one worker runs them all.
GROUPED_TB_MODULES = ("test_synth_size.py",)


def _read(path: Path) -> dict[str, float]:
    with contextlib.suppress(OSError, ValueError, AttributeError):
        return {str(k): float(v) for k, v in json.loads(path.read_text()).items()}
    return {}


def _durations() -> dict[str, float]:
    """The committed durations, updated with those measured here."""
    return {**_read(COMMITTED), **_read(MEASURED)}


def _unit_of_path(path: str) -> str | None:
    """The unit of a test file ("sw/tests/x.py" or "tb/test_synth_size.py"), or None: each test its own unit."""
    parts = Path(path).parts
    if len(parts) >= 3 and parts[-3:-1] == ("sw", "tests"):
        return f"sw/tests/{parts[-1]}"
    if parts and parts[-1] in GROUPED_TB_MODULES:
        return f"tb/{parts[-1]}"
    return None


def _group(item: pytest.Item) -> str | None:
    return _unit_of_path(str(item.path))


def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """With `--dist loadgroup`: one work unit per sw/tests module and per grouped tb module, each other test its own
    (the units of pytest_collection_modifyitems, in its order: `--no-loadscope-reorder`)."""
    if config.getvalue("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class UnitScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return _unit_of_path(nodeid.split("::")[0]) or nodeid

    return UnitScheduling(config, log)


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(session: pytest.Session, config: pytest.Config, items: list[pytest.Item]) -> None:
    """Order the items longest unit first, each unit's tests together."""
    durations = _durations()
    units: dict[str, list[pytest.Item]] = {}
    for item in items:
        units.setdefault(_group(item) or item.nodeid, []).append(item)
    cost = {
        key: sum(durations.get(i.nodeid, UNKNOWN_S if _group(i) is None else 0.1) for i in unit)
        for key, unit in units.items()
    }
    order = sorted(units, key=lambda key: -cost[key])  # (stable: ties keep the collection order)
    items[:] = [item for key in order for item in units[key]]


_reports: dict[str, float] = {}


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    _reports[report.nodeid] = _reports.get(report.nodeid, 0.0) + report.duration


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """Merge this run's durations into build/durations.json (on the xdist controller, or in a run without
    xdist; not after an interrupted run or a usage error)."""
    config: Any = session.config
    if hasattr(config, "workerinput") or exitstatus not in (0, 1) or not _reports:
        return
    table = _read(MEASURED)
    table.update({k: round(v, 2) for k, v in _reports.items()})
    MEASURED.parent.mkdir(parents=True, exist_ok=True)
    MEASURED.write_text(json.dumps(dict(sorted(table.items())), indent=0) + "\n")
