"""The per-file time budgets: every test file has one, and a file over its budget is named."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

from time_budget import BUDGETS, TimeBudget

TESTS = Path(__file__).resolve().parent


def test_every_test_file_has_a_recorded_budget() -> None:
    budgets = json.loads(BUDGETS.read_text())
    files = {p.relative_to(TESTS.parent).as_posix() for p in TESTS.rglob("test_*.py")}
    assert files <= set(budgets), f"record budgets (pytest --record-budgets) for {sorted(files - set(budgets))}"
    assert set(budgets) <= files, f"budgets of files that no longer exist: {sorted(set(budgets) - files)}"


def test_a_file_over_its_budget_is_named() -> None:
    budget = TimeBudget(SimpleNamespace())  # type: ignore[arg-type]
    budget.budgets = {"tests/test_a.py": 10.0}
    for nodeid, duration in [("tests/test_a.py::one", 6.0), ("tests/test_a.py::two", 5.0), ("tests/test_b.py::x", 1)]:
        budget.pytest_runtest_logreport(SimpleNamespace(nodeid=nodeid, duration=duration))  # type: ignore[arg-type]
    assert budget.over_budget() == {"tests/test_a.py": (11.0, 10.0)}
