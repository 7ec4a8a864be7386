"""Ground-truth key concepts: the quantities that decide whether a task needs a tool.

They are computed from the scene's geometry and the robot's limits alone (never from a task's name or category),
by the robot's own rules (``RobotType.rules.key_concepts``, in ``robotool/robots/<name>/<name>_concepts.py``), and
grade the Analyzer stage. Here: the dispatch, and the scene geometry that several robots' rules share; the typed
record is :class:`robotool.task.key_concept.KeyConcept`.
"""

from __future__ import annotations

import numpy as np

from robotool import robots
from robotool.task import geometry
from robotool.task.key_concept import KeyConcept
from robotool.task.scene import SceneObject
from robotool.task.task_model import Task


def key_concepts(task: Task) -> list[KeyConcept]:
    """The key concepts of a task, computed from its geometry by its robot's rules."""
    return robots.get(task.embodiment).rules.key_concepts(task)


def needs_tool(task: Task) -> bool:
    """Whether some key concept is violated, so the task cannot be done without a tool."""
    return any(not c.satisfied for c in key_concepts(task))


def press_point(button: SceneObject) -> np.ndarray:
    """Centre of a button's face (its local -x side), world frame."""
    rot = geometry.rotation_matrix(button.rpy)
    return np.asarray(button.center) + rot @ np.array([-button.size[0] / 2, 0.0, 0.0])


def load_bearing_solids(task: Task, fixed_only: bool) -> dict[str, list[geometry.Part]]:
    """Parts of each object that can carry load (cloth cannot), of fixed objects only or of all."""
    return {
        o.name: geometry.object_parts(o)
        for o in task.objects
        if o.shape != "cloth" and (o.movable is False or not fixed_only)
    }


def surface_under(task: Task, xy: np.ndarray, exclude: str = "") -> tuple[str, float]:
    """The highest load-bearing surface under a point (ignoring ``exclude``): owner and height."""
    best_name, best = "ground", geometry.GROUND_Z
    for name, parts in load_bearing_solids(task, fixed_only=False).items():
        if name == exclude:
            continue
        _, top = geometry.object_interval(parts, xy[None, :])
        if not np.isnan(top[0]) and top[0] > best:
            best_name, best = name, float(top[0])
    return best_name, best
