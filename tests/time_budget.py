"""Per-file time budgets for the test suite: a run in which a test file took longer than its budget fails.

The budgets live in ``tests/time_budgets.json`` (file -> seconds, the sum of its tests' setup, call and
teardown times); a file that is not listed gets :data:`DEFAULT_BUDGET_S`. They are set at twice what the file
takes on a 2-core machine running the suite on two workers, plus :data:`SLACK_S` (a first compile of our own small
Warp kernels may land in any file), so noise passes and a test that became several times slower does not. The
simulator's Warp kernels (mujoco_warp's) compile in the first file of the Warp group, ``tests/sim/test_backend_warp.py``
(the group's largest budget, so its first), on a machine that has not compiled them yet, as CI's has not: about a
minute there, so its budget was measured with an empty kernel cache. ``pytest
--record-budgets`` writes the measured times of the files that ran that way into the file instead of checking
them. Works with pytest-xdist: the controller adds up the workers' reports.

The ``slow`` marker has a rule (pyproject.toml): a test that takes over :data:`SLOW_S` seconds on that machine
is marked slow, so that ``pytest -m "not slow"`` stays a quick check. A run in which a test not marked slow took
over :data:`MARGIN` times the rule fails, naming it, unless the machine was busier than its cores (the load
average over its last minute above their number, as when other jobs share it) or budgets are being recorded: then
the tests are only named.
And the files run longest first (by their budgets, each file's tests together and in their order), so that no
long file starts last while the other worker sits idle.
"""

from __future__ import annotations

import json
import math
import os
from collections import defaultdict
from pathlib import Path

import pytest

BUDGETS = Path(__file__).resolve().parent / "time_budgets.json"
DEFAULT_BUDGET_S = 30.0
MARGIN = 2.0
SLACK_S = 30.0
SLOW_S = 5.0


class TimeBudget:
    """Adds up each test file's time and compares it with its budget at the end of the session."""

    def __init__(self, config: pytest.Config) -> None:
        self.config = config
        self.spent: dict[str, float] = defaultdict(float)
        self.tests: dict[str, float] = defaultdict(float)  # unmarked test -> seconds (setup, call and teardown)
        self.budgets: dict[str, float] = json.loads(BUDGETS.read_text()) if BUDGETS.exists() else {}

    def budget(self, file: str) -> float:
        return self.budgets.get(file, DEFAULT_BUDGET_S)

    @pytest.hookimpl(trylast=True)
    def pytest_collection_modifyitems(self, items: list[pytest.Item]) -> None:
        """The files with the largest budgets first, each file's tests together and in their order."""
        order = {id(item): n for n, item in enumerate(items)}
        file = {id(item): item.nodeid.split("::")[0] for item in items}
        items.sort(key=lambda item: (-self.budget(file[id(item)]), file[id(item)], order[id(item)]))

    @pytest.hookimpl
    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        self.spent[report.nodeid.split("::")[0]] += report.duration
        if "slow" not in report.keywords:
            self.tests[report.nodeid] += report.duration

    def unmarked_slow(self) -> dict[str, float]:
        """test -> seconds, for each test not marked slow that took over :data:`MARGIN` times the rule."""
        return {test: spent for test, spent in self.tests.items() if spent > MARGIN * SLOW_S}

    def over_budget(self) -> dict[str, tuple[float, float]]:
        """file -> (seconds spent, budget) for every file over its budget."""
        return {file: (spent, budget) for file, spent in self.spent.items() if spent > (budget := self.budget(file))}

    @pytest.hookimpl(trylast=True)
    def pytest_sessionfinish(self, session: pytest.Session, exitstatus: int) -> None:
        if hasattr(self.config, "workerinput"):  # an xdist worker: the controller checks
            return
        self.unmarked = self.unmarked_slow()
        if self.config.getoption("record_budgets"):
            recorded = {**self.budgets}
            recorded.update({f: float(math.ceil(MARGIN * s + SLACK_S)) for f, s in self.spent.items()})
            BUDGETS.write_text(json.dumps(dict(sorted(recorded.items())), indent=1) + "\n")
            self.lenient = "budgets recorded"
            return
        self.over = self.over_budget()
        self.lenient = "the machine was busier than its cores" if os.getloadavg()[0] > (os.cpu_count() or 1) else ""
        if (self.over or (self.unmarked and not self.lenient)) and session.exitstatus == 0:
            session.exitstatus = pytest.ExitCode.TESTS_FAILED

    @pytest.hookimpl
    def pytest_terminal_summary(self, terminalreporter: pytest.TerminalReporter) -> None:
        for file, (spent, budget) in sorted(getattr(self, "over", {}).items()):
            terminalreporter.write_line(
                f"TIME BUDGET: {file} took {spent:.1f} s, over its budget of {budget:.0f} s "
                f"(tests/time_budgets.json): make its tests cheaper, or mark them slow and raise the budget",
                red=True,
            )
        lenient = getattr(self, "lenient", "")
        for test, spent in sorted(getattr(self, "unmarked", {}).items()):
            terminalreporter.write_line(
                f"SLOW TEST: {test} took {spent:.1f} s and is not marked slow (the rule in pyproject.toml: over "
                f"{SLOW_S:.0f} s): make it cheaper, or mark it @pytest.mark.slow"
                + (f" (not failed: {lenient})" if lenient else ""),
                red=not lenient,
                yellow=bool(lenient),
            )
