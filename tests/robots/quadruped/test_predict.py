"""The quadruped's walks predicted on the planner's layout (no physics)."""

from __future__ import annotations

import numpy as np

from robotool.planner.layout import Layout
from robotool.robots.quadruped.predict import walk_violation
from robotool.robots.quadruped.terrain import FOOT_RADIUS
from robotool.task_file import parse_task
from robotool.task_model import Task


def _step_task(width: float) -> Task:
    """A fixed 0.12 m step ``width`` wide along x in front (+y) of the robot, which walks flank first onto it."""
    return parse_task({
        "format": 1, "name": "narrow_step", "instruction": "Stand on the step.", "category": "sequential_tool_use",
        "robot": {"type": "quadruped", "position": [0.0, 0.0]},
        "objects": [{"name": "step", "shape": "box", "center": [0.0, 0.5, 0.06], "size": [width, 0.4, 0.12],
                     "movable": False}],
        "goal": {"robot_on": "step"},
    })


def test_a_step_under_every_foot_is_climbed_though_narrower_than_the_body() -> None:
    """The feet's centres sit one foot radius inside the body's outline: a step 5 mm wider than they are apart
    carries all four, so nothing stands between the feet higher than they are."""
    body = _step_task(1.0).limits.body_size[0]
    task = _step_task(body - 2 * FOOT_RADIUS + 0.01)
    assert walk_violation(Layout(task), np.array([0.0, 0.0]), [np.array([0.0, 0.5])], task.limits) is None


def test_a_step_between_the_feet_is_run_into() -> None:
    body = _step_task(1.0).limits.body_size[0]
    task = _step_task(body - 2 * FOOT_RADIUS - 0.03)
    problem = walk_violation(Layout(task), np.array([0.0, 0.0]), [np.array([0.0, 0.5])], task.limits)
    assert problem is not None and "runs into" in problem
