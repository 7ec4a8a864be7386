"""The contract every registered robot meets, checked the same way for each: the built-in robots and the toy point
robot from outside the package (tests/fixtures/point_robot.py), registered for these tests only.

A robot is its :class:`~robotool.robots.RobotType` record: its limits build with their defaults, its skills are
listed once each, its goal kinds are ones the task format has and each is tracked in the simulator, the task file's
checks pass a valid task, the description states its section and every skill, and its controller builds in a
simulated world and runs a short program there (a query and a motion), whose goal conditions are evaluated.
A new robot needs a sample here (:data:`SAMPLES`), or the suite fails naming it.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any, get_args

import pytest
from fixtures.point_robot import ROBOT as POINT

from robotool import robots, tasks
from robotool.execute import run
from robotool.robots.skills import SkillArgumentError
from robotool.sim.goals import OBJECT_GOALS
from robotool.task.describe import describe
from robotool.task.key_concept import KeyConcept
from robotool.task.task_file import parse_task
from robotool.task.task_goal import GoalKind
from robotool.task.task_model import Task

POINT_TASK = {
    "format": 1,
    "name": "puck_to_pad",
    "category": "no_tool",
    "instruction": "Slide onto the pad.",
    "robot": {"type": "point", "position": [0.0, 0.0]},
    "objects": [
        {"name": "pad", "shape": "box", "center": [0.6, 0.2, 0.005], "size": [0.2, 0.2, 0.01], "movable": False}
    ],
    "goal": {"robot_on": "pad"},
}

SAMPLES: dict[str, tuple[str | dict[str, Any], str]] = {
    "arm": ("milk_reaching_near", 'c = get_center("milk")\nopen_gripper()\n'),
    "quadruped": (
        "sofa_traversing_small_gap",
        'p = get_position("robot")\nwalk_to_position([p[0] + 0.1, p[1], 0.0])\n',
    ),
    "point": (POINT_TASK, 'p = get_position("robot")\nmove_to([p[0] + 0.1, p[1]])\n'),
}
"""Robot -> a valid task for it (a built-in name or a task file's data) and a short program: a query, then a
motion."""

ROBOTS = sorted({*robots.names(), POINT.name})


@pytest.fixture
def robot(request: pytest.FixtureRequest) -> Iterator[robots.RobotType[Any]]:
    """The robot under test, with the point robot registered for the test only."""
    with robots.registered(POINT):
        yield robots.get(request.param)


def _task(name: str) -> Task:
    source, _ = SAMPLES[name]
    return tasks.load(source) if isinstance(source, str) else parse_task(source)


def test_every_registered_robot_has_a_sample() -> None:
    with robots.registered(POINT):
        assert set(robots.names()) - set(SAMPLES) == set(), "add a sample task and program to SAMPLES"


@pytest.mark.parametrize("robot", ROBOTS, indirect=True)
def test_the_record_is_whole(robot: robots.RobotType[Any]) -> None:
    assert robot.article in ("a", "an")
    robot.limits()  # every limit has a default
    names = [s.name for s in robot.skills]
    assert names and len(names) == len(set(names)) and robot.skill_names == set(names)
    assert {s.kind for s in robot.skills} <= {"query", "motion"}
    assert robot.goals and robot.goals <= set(get_args(GoalKind))
    assert robot.goals - set(OBJECT_GOALS) <= set(robot.sim.goal_trackers()), "a goal kind without a tracker"
    view = robot.pictures.view
    assert all(math.isfinite(v) for v in (view.turn, view.elevation)) and view.floor_square > 0
    if robot.planner is not None:
        macros = robot.planner()
        assert macros.beam >= 1 and macros.rounds >= 1 and macros.work > 0


@pytest.mark.parametrize("robot", ROBOTS, indirect=True)
def test_a_valid_task_passes_its_checks_and_is_described(robot: robots.RobotType[Any]) -> None:
    task = _task(robot.name)
    assert task.embodiment == robot.name
    assert robot.rules.check_robot(task) == [] and robot.rules.check_start(task) == []
    assert all(isinstance(c, KeyConcept) for c in robot.rules.key_concepts(task))
    assert all(len(point) == 3 for point in robot.rules.reach(task.limits))
    section = robot.description.section(task)
    assert section and all(isinstance(line, str) and line for line in section)
    text = describe(task)
    assert all(line in text for line in section)
    assert all(f"- {s.signature}" in text for s in robot.skills), "every skill is described"
    start = robot.pictures.start_xy(task)
    assert len(start) == 2 and all(math.isfinite(v) for v in start)
    footprint = robot.pictures.footprint(task)
    assert footprint is None or (len(footprint) == 2 and min(footprint) > 0)


@pytest.mark.parametrize("robot", ROBOTS, indirect=True)
def test_an_unknown_skill_is_refused_naming_the_robots_skills(robot: robots.RobotType[Any]) -> None:
    with pytest.raises(SkillArgumentError, match=f"unknown skill 'fly' for the {robot.name}") as caught:
        robot.check_call("fly", ())
    assert all(s.name in str(caught.value) for s in robot.skills)


@pytest.mark.parametrize("robot", ROBOTS, indirect=True)
def test_the_controller_runs_a_query_and_a_motion_and_the_goal_is_evaluated(robot: robots.RobotType[Any]) -> None:
    task = _task(robot.name)
    _, code = SAMPLES[robot.name]
    report = run(task, code, worlds=1, backend="mujoco")
    (world,) = report.rollouts
    assert world.error is None, world.error
    assert [c.skill for c in world.calls] == [line.split("(")[0].split("= ")[-1] for line in code.splitlines()]
    assert {robot.skill(c.skill).kind for c in world.calls} == {"query", "motion"}
    assert world.calls[-1].outcome == "done", world.calls[-1]
    assert world.conditions and world.sim_time > 0
