"""Goal predicates as named sub-conditions (ManiSkill style), evaluated over batched state.

A :class:`GoalTracker` is updated every control tick (so "at any time" goals such as ``pressed`` can
remember) and reports ``{condition name: (nworld,) bool}``; success is all of them. ``grasped`` and
``pressed`` live here; the quadruped's goal kinds (``robot_on``, ``lifted``, ``lowered``) are
looked up lazily in :mod:`robotool.robots.quadruped.controller` as ``<kind>_goal(scene) -> GoalTracker``.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Protocol

import numpy as np

from robotool.robots.arm.controller import graspable_points, held_objects
from robotool.scene import PRESS_TRAVEL
from robotool.sim.backend import BatchState
from robotool.sim.build import Scene

_LAZY_GOALS = "robotool.robots.quadruped.controller"


class GoalTracker(Protocol):
    """Follows one goal in every world."""

    def update(self, state: BatchState, active: np.ndarray) -> None:
        """Observe the state of the ``active`` worlds after a control tick."""

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        """Named sub-conditions now, each (nworld,) bool."""


class GraspedGoal:
    """``grasped: obj``: the gripper holds ``obj`` and its graspable point is still at the gripper."""

    def __init__(self, scene: Scene):
        self.scene = scene
        self.index = scene.object_index(scene.task.goal.object)
        self.radius = scene.task.limits.grasp_radius  # type: ignore[union-attr]

    def update(self, state: BatchState, active: np.ndarray) -> None:
        """Nothing to remember: the goal holds at the end."""

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        name = self.scene.object_names[self.index]
        gripper = self.scene.model.body("robot_gripper").id
        point = graspable_points(self.scene, state)[:, self.index]
        offset = np.linalg.norm(point - state.xpos[:, gripper], axis=1)
        return {
            f"{name}_held": held_objects(self.scene, state) == self.index,
            f"{name}_in_gripper": offset <= 2 * self.radius,
        }


class PressedGoal:
    """``pressed: button``: its face travelled at least 1 cm at some time."""

    def __init__(self, scene: Scene):
        self.name = scene.task.goal.object
        model = scene.model
        self.adr = model.sensor_adr[model.sensor(f"{self.name}__travel").id]
        self.max_travel: np.ndarray | None = None

    def update(self, state: BatchState, active: np.ndarray) -> None:
        travel = np.where(active, state.sensordata[:, self.adr], -np.inf)
        self.max_travel = travel if self.max_travel is None else np.maximum(self.max_travel, travel)

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        seen = self.max_travel if self.max_travel is not None else state.sensordata[:, self.adr]
        return {f"{self.name}_pressed": seen >= PRESS_TRAVEL}


_GOALS: dict[str, Callable[[Scene], GoalTracker]] = {"grasped": GraspedGoal, "pressed": PressedGoal}


def goal_tracker(scene: Scene) -> GoalTracker:
    """The tracker for the scene's goal kind."""
    kind = scene.task.goal.kind
    factory = _GOALS.get(kind) or getattr(importlib.import_module(_LAZY_GOALS), f"{kind}_goal")
    return factory(scene)
