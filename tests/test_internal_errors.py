"""An unexpected exception in any entry point is reported as a bug in one line, exit 70, traceback in a file."""

from __future__ import annotations

import logging
import re
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fixtures.reference import REFERENCE, program_path

from robotool.cli.internal_error import EXIT_INTERNAL_ERROR, TRACEBACK_PREFIX
from robotool.robots.arm.arm_controller import ArmController


class InjectedFault(Exception):
    """The failure a test injects (TEST FIXTURE): stands for a bug deep inside robotool."""


def _boom(*_args: object, **_kwargs: object) -> None:
    raise InjectedFault("the injected fault\x1b[2J with a control byte")


def _entry_points(tmp_path: Path) -> dict[str, tuple[str, Callable[[], int]]]:
    from robotool.cli import main as cli_main
    from robotool.cli.eval_command import main as eval_main
    from robotool.cli.optimize_command import main as optimize_main

    return {
        "robotool tasks": ("robotool.cli.task_commands.cmd_tasks", lambda: cli_main(["tasks"])),
        "robotool eval": (
            "robotool.eval.sweep.evaluate",
            lambda: cli_main(["eval", "--tasks", "milk_reaching_near", "--out", str(tmp_path / "eval")]),
        ),
        "python -m robotool.eval": (
            "robotool.eval.sweep.evaluate",
            lambda: eval_main(["--tasks", "milk_reaching_near", "--out", str(tmp_path / "eval")]),
        ),
        "python -m robotool.optimize": (
            "robotool.cli.optimize_command.optimize",
            lambda: optimize_main(["--optimizer", "planner-demos", "--out", str(tmp_path / "p.json")]),
        ),
    }


@pytest.mark.parametrize(
    "entry", ["robotool tasks", "robotool eval", "python -m robotool.eval", "python -m robotool.optimize"]
)
def test_an_unexpected_exception_is_one_line_naming_the_traceback_file(
    entry: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))  # the temp folder gettempdir() answers
    target, call = _entry_points(tmp_path)[entry]
    monkeypatch.setattr(target, _boom)
    assert call() == EXIT_INTERNAL_ERROR
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err and "\x1b" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "a bug in robotool" in lines[0] and "InjectedFault: the injected fault" in lines[0]
    path = Path(re.search(r"written to (\S+\.txt)", lines[0]).group(1))
    assert path.name.startswith(TRACEBACK_PREFIX) and path.is_file()
    text = path.read_text()
    assert "Traceback (most recent call last)" in text and "_boom" in text
    expected = {
        "robotool eval": tmp_path / "eval",
        "python -m robotool.eval": tmp_path / "eval",
        "python -m robotool.optimize": tmp_path / "p-log",
    }.get(entry, tmp_path / "tmp")
    assert path.parent == expected.resolve()


def test_a_user_mistake_still_exits_2_without_a_traceback_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from robotool.cli import main

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    assert main(["describe", str(tmp_path / "missing.yaml")]) == 2
    assert "internal error" not in capsys.readouterr().err
    assert not list(tmp_path.glob(f"{TRACEBACK_PREFIX}*"))


@pytest.mark.parametrize(
    "argv",
    [
        ["run", "milk_reaching_near", str(program_path(REFERENCE["milk_reaching_near"]))],
        ["solve", "milk_reaching_near", "--planner", "search"],
    ],
    ids=["run", "solve"],
)
def test_a_world_ended_by_a_controller_bug_exits_70_with_its_one_logged_line(
    argv: list[str],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    caplog: pytest.LogCaptureFixture,
) -> None:
    """``robotool run`` exited 1 and ``robotool solve`` 0 ("solved") when a skill controller raised in a world (a bug
    in robotool, recorded as the rollout's internal error), as for a program's own outcome. Now they print their
    summary and exit 70; the bug is logged in one line as it happens."""
    from robotool.cli import main

    original = ArmController.start

    def breaks_in_world_1(self: ArmController, state: Any, worlds: np.ndarray, skill: str, args: Any) -> Any:
        if 1 in np.asarray(worlds):  # TEST FIXTURE: a fault injected into the controller
            raise FloatingPointError("overflow encountered in the servo reference")
        return original(self, state, worlds, skill, args)

    monkeypatch.setattr(ArmController, "start", breaks_in_world_1)
    with caplog.at_level(logging.ERROR, logger="robotool.sim.lockstep"):
        status = main([*argv, "--worlds", "2", "--backend", "mujoco"])
    out, err = capsys.readouterr()
    assert status == EXIT_INTERNAL_ERROR and "Traceback" not in out + err, err
    assert "internal error: controller error in " in " ".join(out.replace("│", " ").split())  # the summary says it
    logged = [r.getMessage() for r in caplog.records]
    assert logged and all("\n" not in line and "FloatingPointError: overflow" in line for line in logged), logged
    assert logged[0].endswith("(a bug in robotool: its traceback is the rollout's internal_error)")
