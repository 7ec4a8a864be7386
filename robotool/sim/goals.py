"""Goal predicates as named sub-conditions (ManiSkill style), evaluated over batched state.

A :class:`GoalTracker` is updated every control tick (so "at any time" goals such as ``pressed`` can
remember) and reports ``{condition name: (nworld,) bool}``; success is all of them. The object goals any
robot may be given live here (``pressed``) and in :mod:`robotool.sim.object_goals` (``lifted``, ``lowered``); a
robot's own goal kinds (``RobotType.sim.goal_trackers``) are trackers in its package.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from robotool import robots
from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.compiled_scene import Scene
from robotool.sim.embodiment import GoalTracker, ReadAtTicks
from robotool.sim.object_goals import LiftedGoal, LoweredGoal
from robotool.task.scene import PRESS_TRAVEL


class PressedGoal(ReadAtTicks):
    """``pressed: button``: its face travelled at least 1 cm at some time (read at ticks: a press between two ticks is
    missed, never invented)."""

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


OBJECT_GOALS: dict[str, Callable[[Scene], GoalTracker]] = {
    "pressed": PressedGoal,
    "lifted": LiftedGoal,
    "lowered": LoweredGoal,
}
"""Trackers of the goal kinds about objects, which any robot may support."""


def goal_tracker(scene: Scene, sim: BatchedSim) -> GoalTracker:
    """The tracker for the scene's goal kind: an object goal's, or one of the robot's own (run by ``sim``)."""
    kind = scene.task.goal.kind
    if kind in OBJECT_GOALS:
        return OBJECT_GOALS[kind](scene)
    return robots.get(scene.task.embodiment).sim.goal_trackers()[kind](scene, sim)
