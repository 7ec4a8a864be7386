"""CI runs the README's quick start as written, and the dev extra installs every tool it needs."""

from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _quick_start() -> list[str]:
    """The README's quick start as .ci/run reads it: one command line per line."""
    done = subprocess.run([sys.executable, str(ROOT / ".ci" / "quick_start.py")], capture_output=True, text=True,
                          check=True)
    return done.stdout.strip().splitlines()


def test_ci_runs_the_readme_quick_start_as_written() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"## Quick start\s+```bash\n(.*?)```", readme, re.DOTALL)
    assert block is not None
    assert _quick_start() == block.group(1).strip().splitlines()
    lines = _quick_start()
    assert len(lines) == 2 and lines[0] == 'pip install -e ".[dev]" && python -m robotool.eval'
    steps = [step.strip() for step in lines[1].split("&&")]
    assert steps[0].startswith("ruff check") and steps[-1].startswith("pytest"), "lint first, then the tests"
    assert "mypy" in steps, "the test command type-checks robotool/ (pyproject.toml's [tool.mypy])"
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "python3 .ci/quick_start.py" in ci and 'bash -o pipefail -c "${quick_start[0]}"' in ci
    assert "^Traceback" in ci and "results/*/results.json" in ci
    assert f'test_command="{lines[1]}"' in ci  # the README's test command, checked against it when CI runs
    ran = [line.strip() for line in ci.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    assert " && ".join(ran[-len(steps) :]) == lines[1]


def test_the_dev_extra_installs_the_tools_ci_runs() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    dev = project["optional-dependencies"]["dev"]
    installed = {re.split(r"[<>=!~\[ ]", requirement, maxsplit=1)[0] for requirement in dev}
    tools = {command.split()[0] for command in _quick_start()[1].split("&&")}
    assert tools <= installed


def test_the_type_checker_covers_the_whole_package_strictly_enough() -> None:
    """mypy checks every module of robotool/ with untyped function bodies included; libraries without type
    information are named one by one, and robotool's own modules may not switch errors off."""
    mypy = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["mypy"]
    assert mypy["packages"] == ["robotool"] and mypy["check_untyped_defs"] is True
    assert mypy["warn_unused_ignores"] is True and "ignore_missing_imports" not in mypy
    for override in mypy.get("overrides", []):
        modules = override["module"] if isinstance(override["module"], list) else [override["module"]]
        assert not any(m.split(".")[0] == "robotool" for m in modules), override
        assert set(override) <= {"module", "ignore_missing_imports"}, override


def test_slow_tests_are_marked_but_the_default_run_keeps_them() -> None:
    tool = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]
    pytest_options = tool["pytest"]["ini_options"]
    assert any(marker.startswith("slow:") for marker in pytest_options["markers"])
    assert "--strict-markers" in pytest_options["addopts"].split()
    assert not {"-m", "-k"} & set(pytest_options["addopts"].split()), "the default run must run everything"
