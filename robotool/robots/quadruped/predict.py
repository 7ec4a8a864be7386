"""The quadruped's walks and pushes predicted on the planner's layout, before anything is simulated.

Everything here reads only the task file (objects, limits) through :mod:`robotool.geometry` and a
:class:`~robotool.planner.layout.Layout`, which can move objects to hypothetical x-y placements, so macros can
predict a walk (:func:`walk_violation`) or a push (:func:`push_problem`) on a planned placement.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from robotool.planner.layout import Box, Layout
from robotool.robots.quadruped.push import GAP, Leg, lateral_offsets, legs, push_pose, route, sweep_problem
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.terrain import check_walk

SAMPLE = 0.02  # m between terrain samples along a walk
FOOT_INSET = 0.02  # m: the feet sit this far inside the body's outline
SIDE_MARGIN = 0.01  # m beside the body's flanks (and its corners, on a slanted move) that must be clear
BRUSH = 0.03  # m: something this much higher than the surface under the feet, at the flanks, is in the way
PUSH_STAGING = 0.15  # m behind the push pose where the push skill lines the robot up
PUSH_RISE = 0.015  # m above the robot's floor that the push skill's sweep tolerates


def walk_violation(
    layout: Layout,
    start: np.ndarray,
    waypoints: Iterable[np.ndarray],
    limits: QuadrupedLimits,
    exclude: Iterable[str] = (),
) -> str | None:
    """Predict whether walking through ``waypoints`` breaks a limit: the first violation in words, or None.

    The feet's paths are checked as the simulator checks them (:func:`.terrain.check_walk`). Just outside
    the body's flanks (on a slanted move, the band its corners sweep) nothing may stand higher than what its feet
    are on, or the body would run into it.
    """
    skip = list(exclude)
    goals = [np.asarray(g, dtype=float) for g in waypoints]
    finding = check_walk(lambda xy: layout.heights(xy, skip), np.asarray(start, dtype=float), goals, limits)
    if finding is not None:
        return finding.describe()
    half = np.asarray(limits.body_size[:2]) / 2
    here = np.asarray(start, dtype=float)
    for goal in goals:
        delta = goal - here
        length = float(np.linalg.norm(delta))
        if length < 1e-6:
            continue
        u = delta / length
        extent = float(np.abs(u) @ half)
        lateral = np.array([-u[1], u[0]])
        s = np.arange(0.0, length + 2 * extent + 1e-9, SAMPLE)
        points = here - u * extent + s[:, None] * u
        width, flank = float(np.abs(lateral) @ half) - FOOT_INSET, float(np.abs(lateral) @ half) + SIDE_MARGIN
        across = np.stack([points + k * lateral for k in (-width, 0.0, width, -flank, flank)])
        heights = layout.heights(across.reshape(-1, 2), skip).reshape(5, -1)
        if (rub := heights[3:].max(axis=0) - heights[:3].max(axis=0)).max() > BRUSH:
            return (
                f"the body brushes against something {float(rub.max()):.2f} m higher at its side on the way to "
                f"[{goal[0]:.2f}, {goal[1]:.2f}]"
            )
        here = goal
    return None


def detour(
    layout: Layout, start: np.ndarray, goal: np.ndarray, limits: QuadrupedLimits, exclude: Iterable[str] = ()
) -> list[np.ndarray]:
    """Waypoints from ``start`` to ``goal``: straight when the walk is predicted fine, else through the
    shortest one (or, failing that, two) of the L-corners and the corners of nearby objects (grown by the body)
    that makes it fine."""
    skip = list(exclude)
    if walk_violation(layout, start, [goal], limits, skip) is None:
        return [goal]
    half = np.asarray(limits.body_size[:2]) / 2 + 0.1
    vias = [np.array([goal[0], start[1]]), np.array([start[0], goal[1]])]
    for box in layout.boxes(skip):
        lo, hi = box.lo - half, box.hi + half
        vias += [np.array([x, y]) for x in (lo[0], hi[0]) for y in (lo[1], hi[1])]
        vias += [np.array([x, goal[1]]) for x in (lo[0], hi[0])] + [np.array([goal[0], y]) for y in (lo[1], hi[1])]
    vias.sort(key=lambda v: float(np.linalg.norm(v - start) + np.linalg.norm(goal - v)))
    vias = vias[:24]

    def fine(p: np.ndarray, q: np.ndarray) -> bool:
        return walk_violation(layout, p, [q], limits, skip) is None

    for via in vias[:12]:
        if fine(start, via) and fine(via, goal):
            return [via, goal]
    out = [v for v in vias if fine(start, v)]
    into = [v for v in vias if fine(v, goal)]
    pairs = sorted(
        ((a, b) for a in out for b in into if a is not b),
        key=lambda p: float(np.linalg.norm(p[0] - start) + np.linalg.norm(p[1] - p[0]) + np.linalg.norm(goal - p[1])),
    )
    for a, b in pairs[:40]:  # around two corners
        if fine(a, b):
            return [a, b, goal]
    return [goal]


@dataclass(frozen=True)
class PushBlock:
    """What blocks a predicted push of ``object``: it would run into ``blocker`` (``collides``), there is no clear
    place to stand behind it (``no_stance``), or the walk to where the push lines up breaks a limit (``approach``,
    the walk's problem in ``walk``). ``str()`` renders it for people."""

    kind: Literal["collides", "no_stance", "approach"]
    object: str
    blocker: str | None = None
    walk: str | None = None

    def __str__(self) -> str:
        if self.kind == "collides":
            return f"{self.object} would run into {self.blocker}"
        if self.kind == "no_stance":
            return f"no clear place to stand behind {self.object}"
        return f"the way to push {self.object}: {self.walk}"


def push_problem(
    layout: Layout, name: str, dest: np.ndarray, limits: QuadrupedLimits, floor: float, here: np.ndarray | None = None
) -> tuple[PushBlock | None, np.ndarray]:
    """Predict a push of ``name`` to ``dest`` (x-y) as the skill makes it (:mod:`robotool.robots.quadruped.push`): one
    straight leg per axis, the shorter first, the robot's face against the object's, slid along the face to the
    nearest offset whose sweep (from where it lines up, else from the start pose, to the end of the push plus the
    gap) meets nothing above its floor and keeps its feet over the floor. With the robot's position ``here``, the walk
    around the object to where it lines up is predicted too. Returns what blocks it (or None) and where the robot
    ends."""
    box = layout.box(name)
    half = np.asarray(limits.body_size[:2]) / 2
    robot = np.asarray(here, dtype=float) if here is not None else box.center.copy()
    for leg in legs(box.center, np.asarray(dest, dtype=float)):
        axis = leg.axis
        end_center = box.center.copy()
        end_center[axis] = leg.target
        steps = max(2, int(abs(end_center[axis] - box.center[axis]) / 0.05) + 1)
        hit = next(
            (
                h
                for f in np.linspace(0.0, 1.0, steps)
                if (h := layout.collides(box.moved_to(box.center + f * (end_center - box.center)), ignore=[name]))
            ),
            None,
        )
        if hit:
            return PushBlock("collides", name, blocker=hit), robot
        pose = _push_pose(layout, name, box, leg, limits, floor)
        if pose is None:
            return PushBlock("no_stance", name), robot
        start, end, staging = pose
        if here is not None:
            around = route(robot, staging, box.lo - half - GAP / 2, box.hi + half + GAP / 2)
            problem = walk_violation(layout, robot, [*around, start], limits, exclude=[name])
            if problem:
                return PushBlock("approach", name, walk=problem), robot
        robot = end - (end - start) / np.linalg.norm(end - start) * GAP
        box = box.moved_to(end_center)
        layout = layout.with_moved(name, end_center)
    return None, robot


def push_staging(
    layout: Layout, name: str, dest: np.ndarray, limits: QuadrupedLimits, floor: float
) -> np.ndarray | None:
    """Where the push skill lines the robot up for the first leg of a push of ``name`` to ``dest`` (None: no leg, or
    nowhere clear to stand)."""
    box = layout.box(name)
    first = legs(box.center, np.asarray(dest, dtype=float))
    pose = _push_pose(layout, name, box, first[0], limits, floor) if first else None
    return None if pose is None else pose[2]


def _push_pose(
    layout: Layout, name: str, box: Box, leg: Leg, limits: QuadrupedLimits, floor: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The skill's choice of start and end poses for one leg, and its staging point (None: nowhere clear)."""
    half = np.asarray(limits.body_size[:2]) / 2
    offsets = lateral_offsets(float(box.hi[1 - leg.axis] - box.lo[1 - leg.axis]), 2 * float(half[1 - leg.axis]))
    poses = [push_pose(box.lo, box.hi, leg, half, float(o)) for o in offsets]

    def heights(xy: np.ndarray) -> np.ndarray:
        return layout.heights(xy, exclude=[name])

    for staging in (PUSH_STAGING, 0.0):
        for start, end in poses:
            behind = start - (end - start) / np.linalg.norm(end - start) * staging
            if sweep_problem(heights, behind, end, limits, floor) is None:
                return start, end, behind
    return None
