"""CI runs what the README's quick start tells people to run, and the dev extra installs every tool it needs."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _readme_test_commands() -> list[str]:
    """The commands of the quick start's second line (the first installs and runs the evaluator)."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"## Quick start\s+```bash\n(.*?)```", readme, re.DOTALL)
    assert block is not None, "README has no quick start block"
    lines = block.group(1).strip().splitlines()
    return [command.strip() for command in lines[1].split("&&")]


def _ci_commands_after_install() -> list[str]:
    lines = [line.strip() for line in (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()]
    install = next(k for k, line in enumerate(lines) if line.startswith("pip install") and ".[dev]" in line)
    return [line for line in lines[install + 1 :] if line and not line.startswith("#")]


def test_ci_runs_the_readme_test_command_lint_first() -> None:
    assert _ci_commands_after_install() == _readme_test_commands()
    assert _readme_test_commands()[0].startswith("ruff check")


def test_the_dev_extra_installs_the_tools_ci_runs() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    dev = project["optional-dependencies"]["dev"]
    installed = {re.split(r"[<>=!~\[ ]", requirement, maxsplit=1)[0] for requirement in dev}
    assert {command.split()[0] for command in _ci_commands_after_install()} <= installed


def test_slow_tests_are_marked_but_the_default_run_keeps_them() -> None:
    tool = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]
    pytest_options = tool["pytest"]["ini_options"]
    assert any(marker.startswith("slow:") for marker in pytest_options["markers"])
    assert "--strict-markers" in pytest_options["addopts"].split()
    assert not {"-m", "-k"} & set(pytest_options["addopts"].split()), "the default run must run everything"
