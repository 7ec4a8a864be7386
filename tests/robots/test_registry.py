"""Robots are plug-ins: a third robot from the test suite (tests/fixtures/point_robot.py) registers through the
``ROBOTOOL_ROBOTS`` variable or an entry point and runs a task through ``robotool run``, without any change to the
package; the registry's errors; no module outside a robot's package names a robot."""

from __future__ import annotations

import dataclasses
import os
import re
import subprocess
import sys
from collections.abc import Iterator
from importlib import metadata
from pathlib import Path

import pytest
from fixtures.paths import FIXTURES, REPO

from robotool import robots
from robotool.cli import main
from robotool.planner.solve import NoPlannerError, solve
from robotool.robots import limits_table, registry
from robotool.task.task_file import TaskFileError, load_task, parse_task

PLUGIN = "fixtures.point_robot"
"""The point robot's module, as a user names it in ROBOTOOL_ROBOTS (tests/ is on the path)."""
TASK = """\
format: 1
name: puck_to_pad
category: no_tool
instruction: Slide onto the pad.
robot:
  type: point
  position: [0.0, 0.0]
objects:
  - name: pad
    shape: box
    center: [0.6, 0.2, 0.005]
    size: [0.2, 0.2, 0.01]
    movable: false
goal:
  robot_on: pad
"""
ONTO_PAD = 'pad = get_position("pad")\nmove_to([pad[0], pad[1]])\n'
SHORT_OF_PAD = "move_to([0.3, -0.2])\n"


@pytest.fixture
def point_robot(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """The point robot's module named in ROBOTOOL_ROBOTS; the registry restored afterwards."""
    monkeypatch.setenv(robots.MODULES_VARIABLE, PLUGIN)
    with robots.registered():
        yield


@pytest.fixture
def task_file(tmp_path: Path) -> Path:
    path = tmp_path / "puck.yaml"
    path.write_text(TASK)
    return path


def run(capsys: pytest.CaptureFixture[str], tmp_path: Path, task: Path, code: str) -> tuple[int, str]:
    program = tmp_path / "program.py"
    program.write_text(code)
    status = main(["run", str(task), str(program), "--worlds", "2", "--backend", "mujoco"])
    out = capsys.readouterr().out
    assert "Traceback" not in out
    return status, out


def test_a_plugin_robot_runs_a_task_through_robotool_run(
    point_robot: None,
    task_file: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("COLUMNS", "200")
    assert "point" in robots.names()
    status, out = run(capsys, tmp_path, task_file, ONTO_PAD)
    assert status == 0, out
    assert "every world succeeded: success rate 100%" in out
    status, out = run(capsys, tmp_path, task_file, SHORT_OF_PAD)  # the physics judges the plug-in's goal too
    assert status != 0
    assert "robot_over_pad no" in out


def test_a_plugin_robot_is_described_and_checked_from_its_record(point_robot: None, task_file: Path) -> None:
    task = load_task(task_file)
    assert main(["describe", str(task_file)]) == 0
    assert robots.get(task.embodiment).skill_names == {"get_position", "move_to"}
    with pytest.raises(TaskFileError, match="a point robot needs a start"):
        parse_task({**load_task(task_file).model_dump(mode="json", exclude_defaults=True), "robot": {"type": "point"}})
    with pytest.raises(TaskFileError, match="a point cannot have a 'grasped' goal"):
        parse_task({**task.model_dump(mode="json", exclude_defaults=True), "goal": {"grasped": "pad"}})
    with pytest.raises(NoPlannerError, match="no macros for the point robot"):
        solve(task)


def test_a_plugin_robot_works_in_a_fresh_process(task_file: Path, tmp_path: Path) -> None:
    program = tmp_path / "program.py"
    program.write_text(ONTO_PAD)
    env = {
        **os.environ,
        robots.MODULES_VARIABLE: PLUGIN,
        "COLUMNS": "200",
        "PYTHONPATH": os.pathsep.join([str(REPO), str(FIXTURES.parent)]),
    }
    done = subprocess.run(
        [sys.executable, "-m", "robotool", "run", str(task_file), str(program), "--worlds", "1", "--backend", "mujoco"],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "success rate 100%" in done.stdout


def test_an_unknown_robot_type_lists_the_registered_ones() -> None:
    data = load_task(REPO / "robotool/tasks/data/sofa_climbing.yaml").model_dump(mode="json")
    data["robot"]["type"] = "quadrupd"
    with pytest.raises(TaskFileError) as caught:
        parse_task(data)
    assert "robot.type: unknown robot type 'quadrupd' (did you mean 'quadruped'?); registered: arm, quadruped" in str(
        caught.value
    )


def test_a_plugin_that_cannot_load_is_a_clear_error(
    monkeypatch: pytest.MonkeyPatch, task_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv(robots.MODULES_VARIABLE, "no_such_robot_module")
    with robots.registered():
        assert main(["describe", str(task_file)]) != 0
    err = capsys.readouterr().err
    assert "cannot load robot module 'no_such_robot_module' (from ROBOTOOL_ROBOTS): ModuleNotFoundError" in err
    assert "Traceback" not in err


def test_a_taken_name_cannot_be_registered_again() -> None:
    arm = robots.get("arm")
    with robots.registered():
        robots.register(arm)  # the same record again: nothing happens
        with pytest.raises(robots.RobotPluginError, match="'arm' is already registered"):
            robots.register(dataclasses.replace(arm))


def test_a_scoped_registration_leaves_the_registry_as_it_was() -> None:
    from fixtures.point_robot import ROBOT as POINT

    before, limits = robots.names(), dict(limits_table.LIMITS_MODELS)
    with robots.registered(POINT):
        assert robots.get("point") is POINT and limits_table.limits_model("point") is POINT.limits
    assert robots.names() == before == ("arm", "quadruped") and limits == limits_table.LIMITS_MODELS
    with pytest.raises(robots.UnknownRobotError), robots.registered(POINT):
        raise robots.UnknownRobotError("the block fails")
    assert "point" not in robots.names()


def test_no_module_outside_a_robot_package_names_a_robot() -> None:
    """Robot-specific code lives in robotool/robots/<name>/; tasks may name robots, and the package's
    ``__init__`` registers the built-in ones."""
    package = Path(robots.__file__).parent.parent
    allowed = {package / "__init__.py"}
    named = re.compile(r"(?<![/.])\b(quadruped|arm)s?\b", re.IGNORECASE)  # a path such as tests/robots/arm/ is no name
    found = [
        f"{path.relative_to(package)}:{number}: {line.strip()}"
        for path in sorted(package.rglob("*.py"))
        if path not in allowed
        and not path.is_relative_to(package / "tasks")
        and not any(path.is_relative_to(package / "robots" / name) for name in ("arm", "quadruped"))
        for number, line in enumerate(path.read_text().splitlines(), 1)
        if named.search(line)
    ]
    assert not found, "\n".join(found)


def test_an_entry_point_registers_its_robot(monkeypatch: pytest.MonkeyPatch) -> None:
    """An installed package declares ``[project.entry-points."robotool.robots"] point = "<module>:ROBOT"``."""
    monkeypatch.delenv(robots.MODULES_VARIABLE, raising=False)
    point = metadata.EntryPoint(name="point", value=f"{PLUGIN}:ROBOT", group=robots.ENTRY_POINT_GROUP)
    monkeypatch.setattr(registry.metadata, "entry_points", lambda group: [point] if group == point.group else [])
    with robots.registered(reload_plugins=True):
        assert robots.names() == ("arm", "point", "quadruped")
        assert robots.get("point").skill_names == {"get_position", "move_to"}
    assert robots.names() == ("arm", "quadruped")


def test_a_plugin_whose_import_raises_names_itself_and_keeps_its_cause(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """TEST FIXTURE: a plug-in module with a bug at import time. The error names the plug-in and the line that
    raised, and chains the plug-in's own exception (with its traceback) as its cause."""
    (tmp_path / "broken_robot_plugin.py").write_text("ROBOT = None\nSCALE = 1 / 0\n", encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv(robots.MODULES_VARIABLE, "broken_robot_plugin")
    with robots.registered(reload_plugins=True), pytest.raises(robots.RobotPluginError) as caught:
        robots.names()
    message = str(caught.value)
    assert message.startswith("cannot load robot module 'broken_robot_plugin' (from ROBOTOOL_ROBOTS): ")
    assert "ZeroDivisionError: division by zero" in message
    assert message.endswith(f"(at {tmp_path / 'broken_robot_plugin.py'}, line 2)")
    assert isinstance(caught.value.__cause__, ZeroDivisionError) and caught.value.__cause__.__traceback__ is not None


def test_a_plugin_module_that_is_not_there_names_no_line_of_robotool(monkeypatch: pytest.MonkeyPatch) -> None:
    """Found by an adversarial run: a missing module was said to fail "at robotool/robots/registry.py, line 304",
    robotool's own line, as if it were the plug-in's."""
    monkeypatch.setenv(robots.MODULES_VARIABLE, "no_such_robot_plugin_module")
    with robots.registered(reload_plugins=True), pytest.raises(robots.RobotPluginError) as caught:
        robots.names()
    assert str(caught.value).endswith("ModuleNotFoundError: No module named 'no_such_robot_plugin_module'")
