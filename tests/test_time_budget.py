"""The per-file time budgets: every test file has one, and a file over its budget is named."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

from time_budget import BUDGETS, MARGIN, SLOW_S, TimeBudget

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
        budget.pytest_runtest_logreport(SimpleNamespace(nodeid=nodeid, duration=duration, keywords={}))  # type: ignore[arg-type]
    assert budget.over_budget() == {"tests/test_a.py": (11.0, 10.0)}


def test_a_test_over_the_slow_rule_and_not_marked_slow_is_named() -> None:
    budget = TimeBudget(SimpleNamespace())  # type: ignore[arg-type]
    over = MARGIN * SLOW_S + 1
    for nodeid, duration, keywords in [
        ("tests/test_a.py::unmarked", over - 2, {}),  # setup, then call: they add up
        ("tests/test_a.py::unmarked", 2.0, {}),
        ("tests/test_a.py::marked", over, {"slow": 1}),
        ("tests/test_a.py::quick", 1.0, {}),
    ]:
        report = SimpleNamespace(nodeid=nodeid, duration=duration, keywords=keywords)
        budget.pytest_runtest_logreport(report)  # type: ignore[arg-type]
    assert budget.unmarked_slow() == {"tests/test_a.py::unmarked": over}


def test_the_files_with_the_largest_budgets_run_first_each_in_its_order() -> None:
    budget = TimeBudget(SimpleNamespace())  # type: ignore[arg-type]
    budget.budgets = {"tests/test_a.py": 10.0, "tests/test_b.py": 100.0}
    ids = ["tests/test_a.py::one", "tests/test_c.py::x", "tests/test_b.py::two", "tests/test_a.py::two",
           "tests/test_b.py::one"]  # fmt: skip
    items = [SimpleNamespace(nodeid=nodeid) for nodeid in ids]
    budget.pytest_collection_modifyitems(items)  # type: ignore[arg-type]
    assert [item.nodeid for item in items] == [
        "tests/test_b.py::two",
        "tests/test_b.py::one",
        "tests/test_c.py::x",  # no budget: the default, 30 s
        "tests/test_a.py::one",
        "tests/test_a.py::two",
    ]
