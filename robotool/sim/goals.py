"""Goal predicates as named sub-conditions (ManiSkill style), evaluated over batched state.

A :class:`GoalTracker` is updated every control tick (so "at any time" goals such as ``pressed`` can
remember) and reports ``{condition name: (nworld,) bool}``; success is all of them. The object goals any
robot may be given live here (``pressed``) and in :mod:`robotool.sim.object_goals` (``lifted``, ``lowered``); a
robot's own goal kinds (``RobotType.sim.goal_trackers``) are trackers in its package. Whatever the goal, every fragile
object in the scene must end unbroken and nothing may pass through a solid (:class:`WithSceneRules`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from robotool import robots
from robotool.rollout import Event
from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.compiled_scene import Scene
from robotool.sim.embodiment import GoalTracker, ReadAtTicks, goal_events
from robotool.sim.object_goals import FallTracker, LiftedGoal, LoweredGoal
from robotool.sim.passage import CONDITION, PassageWatch
from robotool.task.scene import PRESS_TRAVEL


class PressedGoal(ReadAtTicks):
    """``pressed: button``: its face travelled at least 1 cm past where it was as the program started, at some time
    (read at ticks: a press between two ticks is missed, never invented). Found by an adversarial run: a plate the task
    file lays on an upturned button's face pressed it past 1 cm while the world settled, and a program that did nothing
    pressed it."""

    def __init__(self, scene: Scene):
        self.name = scene.task.goal.object
        model = scene.model
        self.adr = model.sensor_adr[model.sensor(f"{self.name}__travel").id]
        self.max_travel: np.ndarray | None = None
        self.start: np.ndarray | None = None

    def update(self, state: BatchState, active: np.ndarray, credited: np.ndarray) -> None:
        if self.start is None:
            self.start = np.maximum(state.sensordata[:, self.adr], 0.0)
        travel = np.where(credited, state.sensordata[:, self.adr], -np.inf)
        self.max_travel = travel if self.max_travel is None else np.maximum(self.max_travel, travel)

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        seen = self.max_travel if self.max_travel is not None else state.sensordata[:, self.adr]
        start = self.start if self.start is not None else 0.0
        return {f"{self.name}_pressed": seen - start >= PRESS_TRAVEL}


OBJECT_GOALS: dict[str, Callable[[Scene], GoalTracker]] = {
    "pressed": PressedGoal,
    "lifted": LiftedGoal,
    "lowered": LoweredGoal,
}
"""Trackers of the goal kinds about objects, which any robot may support."""


class WithSceneRules:
    """A goal, and the rules every world keeps whatever its goal: every fragile object in the scene unbroken at the end
    (``<name>_unbroken``: the vase a ``lowered`` goal names, and one knocked off a table on the way to any goal), and
    nothing passed through a solid (``nothing_passed_through``: :mod:`robotool.sim.passage`)."""

    def __init__(self, goal: GoalTracker, falls: list[FallTracker], passage: PassageWatch | None):
        self.goal, self.falls, self.passage = goal, falls, passage

    def update(self, state: BatchState, active: np.ndarray, credited: np.ndarray) -> None:
        self.goal.update(state, active, credited)
        for falls in self.falls:
            falls.update(state, active)
        if self.passage is not None:
            self.passage.update(state, active)

    def watched(self, state: BatchState) -> np.ndarray:
        return np.logical_or.reduce([self.goal.watched(state), *(f.watched(state) for f in self.falls)])

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        nworld = len(state.time)
        kept = {CONDITION: self.passage.kept_apart(nworld)} if self.passage is not None else {}
        return {**self.goal.conditions(state), **{f"{f.name}_unbroken": f.unbroken(nworld) for f in self.falls}, **kept}

    def events(self, world: int) -> list[Event]:
        """The goal's events, each fragile object's ``broke`` event and the ``passed_through`` event in one world."""
        passed = self.passage.events(world) if self.passage is not None else []
        return [*goal_events(self.goal, world), *(e for f in self.falls for e in f.events(world)), *passed]


def goal_tracker(scene: Scene, sim: BatchedSim) -> GoalTracker:
    """The tracker for the scene's goal kind (an object goal's, or one of the robot's own, run by ``sim``), with every
    fragile object kept unbroken and nothing passing through a solid (:class:`WithSceneRules`)."""
    kind = scene.task.goal.kind
    if kind in OBJECT_GOALS:
        goal = OBJECT_GOALS[kind](scene)
    else:
        goal = robots.get(scene.task.embodiment).sim.goal_trackers()[kind](scene, sim)
    falls = [
        FallTracker(scene, sim, index, obj.fragile.max_drop)
        for index, obj in enumerate(scene.task.objects)
        if obj.fragile is not None  # (a fixed one is struck, found by an adversarial run: it was never judged)
    ]
    passage = PassageWatch(scene)
    return WithSceneRules(goal, falls, passage if passage else None) if falls or passage else goal
