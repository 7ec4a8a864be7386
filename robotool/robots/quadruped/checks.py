"""The quadruped's task-file checks: it needs a start position, and must start standing on a surface."""

from __future__ import annotations

import numpy as np

from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.task import geometry
from robotool.task.task_model import Task
from robotool.task.task_problem import Problem


def check_robot(task: Task) -> list[Problem]:
    """A quadruped needs a start [x, y]."""
    if task.robot.position is None:
        return [Problem(path="robot.position", message="a quadruped needs a start [x, y]")]
    return []


def check_start(task: Task) -> list[Problem]:
    """The quadruped must start with its body centre over the surface it stands on."""
    if task.robot.position is None:
        return []
    parts = {o.name: geometry.object_parts(o) for o in task.objects}
    problem = _check_start(task, parts)
    return [problem] if problem else []


def _check_start(task: Task, parts: dict[str, list[geometry.Part]]) -> Problem | None:
    """The quadruped must start with its body centre over the surface it stands on."""
    limits = task.limits
    assert isinstance(limits, QuadrupedLimits)
    x, y = task.robot.required_position()
    sx, sy, _ = limits.body_size
    gx, gy = np.meshgrid(np.linspace(x - sx / 2, x + sx / 2, 9), np.linspace(y - sy / 2, y + sy / 2, 5))
    footprint = np.column_stack([gx.ravel(), gy.ravel()])
    solids = [p for n, p in parts.items() if task.object(n).shape != "cloth"]
    stand = float(geometry.surface_height(footprint, solids).max())
    under_centre = float(geometry.surface_height(np.array([[x, y]]), solids)[0])
    if stand - under_centre > limits.max_step_up:
        return Problem(
            path="robot.position",
            message=f"the robot at [{x}, {y}] is not over a surface: its centre hangs over "
            f"a {stand - under_centre:.2f} m drop at the edge of what it would stand on",
        )
    return None
