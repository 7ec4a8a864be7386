"""Per-file time budgets for the test suite: a run in which a test file took longer than its budget fails.

The budgets live in ``tests/time_budgets.json`` (file -> seconds, the sum of its tests' setup, call and
teardown times); a file that is not listed gets :data:`DEFAULT_BUDGET_S`. They are set at twice what the file
takes on a 2-core machine running the suite on two workers, plus :data:`SLACK_S` (a first Warp kernel compile
may land in any file), so noise passes and a test that became several times slower does not. ``pytest
--record-budgets`` writes the measured times of the files that ran that way into the file instead of checking
them. Works with pytest-xdist: the controller adds up the workers' reports.
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from pathlib import Path

import pytest

BUDGETS = Path(__file__).resolve().parent / "time_budgets.json"
DEFAULT_BUDGET_S = 30.0
MARGIN = 2.0
SLACK_S = 30.0


class TimeBudget:
    """Adds up each test file's time and compares it with its budget at the end of the session."""

    def __init__(self, config: pytest.Config) -> None:
        self.config = config
        self.spent: dict[str, float] = defaultdict(float)
        self.budgets: dict[str, float] = json.loads(BUDGETS.read_text()) if BUDGETS.exists() else {}

    @pytest.hookimpl
    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        self.spent[report.nodeid.split("::")[0]] += report.duration

    def over_budget(self) -> dict[str, tuple[float, float]]:
        """file -> (seconds spent, budget) for every file over its budget."""
        return {
            file: (spent, budget)
            for file, spent in self.spent.items()
            if spent > (budget := self.budgets.get(file, DEFAULT_BUDGET_S))
        }

    @pytest.hookimpl(trylast=True)
    def pytest_sessionfinish(self, session: pytest.Session, exitstatus: int) -> None:
        if hasattr(self.config, "workerinput"):  # an xdist worker: the controller checks
            return
        if self.config.getoption("record_budgets"):
            recorded = {**self.budgets}
            recorded.update({f: float(math.ceil(MARGIN * s + SLACK_S)) for f, s in self.spent.items()})
            BUDGETS.write_text(json.dumps(dict(sorted(recorded.items())), indent=1) + "\n")
            return
        over = self.over_budget()
        if over and session.exitstatus == 0:
            session.exitstatus = pytest.ExitCode.TESTS_FAILED
        self.over = over

    @pytest.hookimpl
    def pytest_terminal_summary(self, terminalreporter: pytest.TerminalReporter) -> None:
        for file, (spent, budget) in sorted(getattr(self, "over", {}).items()):
            terminalreporter.write_line(
                f"TIME BUDGET: {file} took {spent:.1f} s, over its budget of {budget:.0f} s "
                f"(tests/time_budgets.json): make its tests cheaper, or mark them slow and raise the budget",
                red=True,
            )
