"""Tests that share a worker-scoped fixture by an ``xdist_group`` do run in one pytest-xdist worker."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def test_a_group_runs_in_one_worker(tmp_path: Path) -> None:
    """Six grouped tests, two workers, with this suite's conftest: every one runs in the same worker (without the
    conftest's hook, pytest 9.2 with pytest-xdist 3.8 spread them over both)."""
    for name in ("conftest.py", "time_budget.py"):
        (tmp_path / name).write_text((TESTS / name).read_text())
    (tmp_path / "test_grouped.py").write_text(
        "import time, pytest\n"
        "pytestmark = pytest.mark.xdist_group('together')\n"
        "@pytest.mark.parametrize('k', range(6))\n"
        "def test_k(k):\n"
        "    time.sleep(0.2)\n"
    )
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-n", "2", "--dist", "loadgroup", "-p", "no:cacheprovider", "-v"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    workers = re.findall(r"^\[(gw\d+)\] .* PASSED test_grouped\.py::test_k\[\d\]@together", done.stdout, re.MULTILINE)
    assert len(workers) == 6 and len(set(workers)) == 1, done.stdout
