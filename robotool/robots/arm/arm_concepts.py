"""The arm's key concept: how far the goal's point (a graspable point, a button's face) lies outside the workspace."""

from __future__ import annotations

import numpy as np

from robotool.robots.arm.arm_skills import ArmLimits
from robotool.task.concepts import KeyConcept, press_point
from robotool.task.task_model import Task


def key_concepts(task: Task) -> list[KeyConcept]:
    """The arm's key concepts of a task."""
    limits = task.limits
    assert isinstance(limits, ArmLimits)
    obj = task.object(task.goal.object)
    if task.goal.kind == "pressed":
        point = press_point(obj)
        what = f"distance of {obj.name}'s face outside the workspace"
    else:
        point = np.asarray(obj.grasp_point)
        what = f"distance of {obj.name}'s graspable point outside the workspace"
    excess = workspace_excess(point, limits)
    return [
        KeyConcept(
            name=what,
            kind="workspace_excess",
            value=round(excess, 4),
            limit=0.0,
            limit_name="workspace",
            satisfied=excess <= 1e-9,
        )
    ]


def workspace_excess(point: np.ndarray, limits: ArmLimits) -> float:
    """Euclidean distance from a point to the arm's workspace box (0 inside)."""
    lo, hi = np.asarray(limits.workspace_min), np.asarray(limits.workspace_max)
    return float(np.linalg.norm(np.maximum(lo - point, 0) + np.maximum(point - hi, 0)))
