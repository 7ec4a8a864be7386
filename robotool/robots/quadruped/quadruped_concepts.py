"""The quadruped's ground-truth key concepts: gap width vs the gap limit, height to climb or step down vs the
legs' limits, mass vs the push limit, and how far a fragile object would fall.

They are computed from the scene's geometry and the robot's limits alone (never from a task's name or category).
Gaps are what :mod:`.terrain` finds under the feet on the straight walk to the target (the simulator's and the
planner's terrain model: a slit narrower than a foot carries it and is no gap), and every leg limit is judged by
:func:`.terrain.exceeds`.
"""

from __future__ import annotations

import numpy as np

from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.terrain import exceeds, survey_walk
from robotool.task import geometry
from robotool.task.concepts import KeyConcept, load_bearing_solids, surface_under
from robotool.task.scene import SceneObject
from robotool.task.task_model import Task


def start_surface(task: Task) -> tuple[str, float]:
    """What the quadruped starts on (an object's name or 'ground') and that surface's height."""
    x, y = task.robot.required_position()
    return surface_under(task, np.array([x, y]))


def key_concepts(task: Task) -> list[KeyConcept]:
    """The quadruped's key concepts of a task: heights to climb or step down, gaps, masses, falls."""
    limits = task.limits
    assert isinstance(limits, QuadrupedLimits)
    start_name, h0 = start_surface(task)
    obj = task.object(task.goal.object)
    kind = task.goal.kind
    concepts: list[KeyConcept] = []
    if kind == "robot_on":
        _, h1 = surface_under(task, np.asarray(obj.center[:2]))
        concepts += _height_change(f"{start_name}", obj.name, h0, h1, limits)
        gap = gap_on_the_way(task, np.asarray(task.robot.position), np.asarray(obj.center[:2]), limits)
        if gap > 0:
            concepts.append(
                KeyConcept(
                    name=f"gap between {start_name} and {obj.name}",
                    kind="gap_width",
                    value=round(gap, 4),
                    limit=limits.max_gap,
                    limit_name="max_gap",
                    satisfied=not exceeds("gap", gap, limits),
                )
            )
    elif kind == "lifted":
        lifted = task.goal.lifted
        assert lifted is not None  # the goal's kind
        lift = lifted.height
        concepts.append(
            KeyConcept(
                name=f"height {obj.name} must rise, against what the robot can lift by itself",
                kind="lift_height",
                value=lift,
                limit=0.0,
                limit_name="robot_lift",
                satisfied=False,
            )
        )
        concepts.append(_mass_concept(obj, limits))
    elif kind == "lowered":
        support_name, support_h = surface_under(task, np.asarray(obj.center[:2]), exclude=obj.name)
        if support_name != start_name:
            concepts += _height_change(start_name, support_name, h0, support_h, limits)
        lowered = task.goal.lowered
        assert lowered is not None  # the goal's kind
        if obj.fragile is not None and obj.bottom > lowered.height:
            concepts.append(
                KeyConcept(
                    name=f"fall height of {obj.name} to the ground",
                    kind="fall_height",
                    value=round(obj.bottom, 4),
                    limit=obj.fragile.max_drop,
                    limit_name="max_drop",
                    satisfied=obj.bottom <= obj.fragile.max_drop,
                )
            )
        concepts.append(_mass_concept(obj, limits))
    return concepts


def _height_change(from_name: str, to_name: str, h0: float, h1: float, limits: QuadrupedLimits) -> list[KeyConcept]:
    rise = h1 - h0
    if rise > 1e-6:
        return [
            KeyConcept(
                name=f"height to climb from {from_name} onto {to_name}",
                kind="climb_height",
                value=round(rise, 4),
                limit=limits.max_step_up,
                limit_name="max_step_up",
                satisfied=not exceeds("step", rise, limits),
            )
        ]
    if rise < -1e-6:
        return [
            KeyConcept(
                name=f"height to step down from {from_name} onto {to_name}",
                kind="drop_height",
                value=round(-rise, 4),
                limit=limits.max_step_down,
                limit_name="max_step_down",
                satisfied=not exceeds("drop", -rise, limits),
            )
        ]
    return []


def _mass_concept(obj: SceneObject, limits: QuadrupedLimits) -> KeyConcept:
    mass = obj.effective_mass
    return KeyConcept(
        name=f"mass of {obj.name}",
        kind="mass",
        value=round(mass, 4),
        unit="kg",
        limit=limits.max_push_mass,
        limit_name="max_push_mass",
        satisfied=obj.movable and mass <= limits.max_push_mass,
    )


def gap_on_the_way(task: Task, start_xy: np.ndarray, end_xy: np.ndarray, limits: QuadrupedLimits) -> float:
    """Widest gap the feet meet walking straight from ``start_xy`` to ``end_xy`` over the fixed terrain (what no
    tool changes), as :mod:`.terrain` measures it for the simulator and the planner (0 when none)."""
    solids = list(load_bearing_solids(task, fixed_only=True).values())
    survey = survey_walk(lambda xy: geometry.surface_height(xy, solids), start_xy, end_xy, limits)
    return survey.largest["gap"]
