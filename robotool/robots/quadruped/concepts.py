"""Ground-truth key concepts: the quantities that decide whether a task needs a tool.

They are computed from the scene's geometry and the robot's limits alone (never from a task's
name or category) and grade the Analyzer stage: gap width vs the gap limit, height to climb vs
the climb limit, how far a target lies outside the arm's workspace, mass vs the push limit, and
how far a fragile object would fall. Gaps are what :mod:`.terrain` finds under the feet on the straight
walk to the target (the simulator's and the planner's terrain model: a slit narrower than a foot carries it and
is no gap), and every leg limit is judged by :func:`robotool.robots.quadruped.terrain.exceeds`.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import BaseModel, Field

from robotool import geometry
from robotool.robots.quadruped.terrain import exceeds, survey_walk
from robotool.robots.skills import ArmLimits, QuadrupedLimits
from robotool.scene import SceneObject
from robotool.task_model import Task

ConceptKind = Literal[
    "workspace_excess", "climb_height", "drop_height", "gap_width", "mass", "fall_height", "lift_height", "other"
]


class KeyConcept(BaseModel):
    """One quantity that decides feasibility, compared with the limit it must respect."""

    name: str = Field(description="what is measured, naming the objects, e.g. 'gap between sofa_1 and sofa_2'")
    kind: ConceptKind = Field(
        "other",
        description=(
            "workspace_excess | climb_height | drop_height | gap_width | mass | fall_height | lift_height | other"
        ),
    )
    value: float = Field(description="the measured value")
    unit: str = Field("m", description="SI unit of value and limit: m or kg")
    limit: float = Field(description="the robot or object limit it is compared with")
    limit_name: str = Field(description="which limit, e.g. 'max_gap' or 'workspace'")
    satisfied: bool = Field(description="true when the value respects the limit without a tool")


def key_concepts(task: Task) -> list[KeyConcept]:
    """The key concepts of a task, computed from its geometry."""
    limits = task.limits
    if isinstance(limits, ArmLimits):
        return _arm_concepts(task, limits)
    assert isinstance(limits, QuadrupedLimits)
    return _quadruped_concepts(task, limits)


def needs_tool(task: Task) -> bool:
    """Whether some key concept is violated, so the task cannot be done without a tool."""
    return any(not c.satisfied for c in key_concepts(task))


def _arm_concepts(task: Task, limits: ArmLimits) -> list[KeyConcept]:
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


def press_point(button: SceneObject) -> np.ndarray:
    """Centre of a button's face (its local -x side), world frame."""
    rot = geometry.rotation_matrix(button.rpy)
    return np.asarray(button.center) + rot @ np.array([-button.size[0] / 2, 0.0, 0.0])


def workspace_excess(point: np.ndarray, limits: ArmLimits) -> float:
    """Euclidean distance from a point to the arm's workspace box (0 inside)."""
    lo, hi = np.asarray(limits.workspace_min), np.asarray(limits.workspace_max)
    return float(np.linalg.norm(np.maximum(lo - point, 0) + np.maximum(point - hi, 0)))


def _solids(task: Task, fixed_only: bool) -> dict[str, list[geometry.Part]]:
    return {
        o.name: geometry.object_parts(o)
        for o in task.objects
        if o.shape != "cloth" and (o.movable is False or not fixed_only)
    }


def start_surface(task: Task) -> tuple[str, float]:
    """What the quadruped starts on (an object's name or 'ground') and that surface's height."""
    x, y = task.robot.position  # type: ignore[misc]
    return surface_under(task, np.array([x, y]))


def surface_under(task: Task, xy: np.ndarray, exclude: str = "") -> tuple[str, float]:
    """The highest load-bearing surface under a point (ignoring ``exclude``): owner and height."""
    best_name, best = "ground", geometry.GROUND_Z
    for name, parts in _solids(task, fixed_only=False).items():
        if name == exclude:
            continue
        _, top = geometry.object_interval(parts, xy[None, :])
        if not np.isnan(top[0]) and top[0] > best:
            best_name, best = name, float(top[0])
    return best_name, best


def _quadruped_concepts(task: Task, limits: QuadrupedLimits) -> list[KeyConcept]:
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
        lift = task.goal.lifted.height  # type: ignore[union-attr]
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
        if obj.fragile is not None and obj.bottom > task.goal.lowered.height:  # type: ignore[union-attr]
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
    solids = list(_solids(task, fixed_only=True).values())
    survey = survey_walk(lambda xy: geometry.surface_height(xy, solids), start_xy, end_xy, limits)
    return survey.largest["gap"]
