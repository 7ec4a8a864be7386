"""The scene as the planner reasons about it: object boxes, surfaces, and hypothetical placements.

Everything here reads only the task file (objects, limits) through :mod:`robotool.geometry`. A
:class:`Layout` can move objects to hypothetical x-y placements, so macros can check a placement
(does it overlap something?) and predict a walk (:func:`walk_violation`) before anything is simulated.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from robotool import geometry
from robotool.embodiments import QuadrupedLimits
from robotool.scene import SceneObject, Task

CONTACT = 0.02  # m: boxes closer than this touch
SAMPLE = 0.02  # m between terrain samples along a walk
FOOT_INSET = 0.02  # m: the feet sit this far inside the body's outline
PUSH_OVERLAP = 0.08  # m of an object's face the robot's face keeps covering when it slides along it
SLACK = 0.01  # m a measured step, gap or drop may exceed its limit (the simulator's own measurement slack)
SIDE_MARGIN = 0.01  # m beside the body's flanks (and its corners, on a slanted move) that must be clear
BRUSH = 0.03  # m: something this much higher than the surface under the feet, at the flanks, is in the way


@dataclass(frozen=True)
class Box:
    """An object's axis-aligned bounds in the world: x-y ``lo``/``hi`` and heights ``bottom``/``top``."""

    name: str
    lo: np.ndarray
    hi: np.ndarray
    bottom: float
    top: float

    @classmethod
    def of(cls, obj: SceneObject) -> Box:
        bounds = [p.aabb() for p in geometry.object_parts(obj)]
        lo = np.min([b[0] for b in bounds], axis=0)
        hi = np.max([b[1] for b in bounds], axis=0)
        return cls(obj.name, lo[:2], hi[:2], float(lo[2]), float(hi[2]))

    @property
    def center(self) -> np.ndarray:
        return (self.lo + self.hi) / 2

    @property
    def half(self) -> np.ndarray:
        return (self.hi - self.lo) / 2

    def moved_to(self, xy: np.ndarray) -> Box:
        """The same box with its x-y centre at ``xy``."""
        shift = np.asarray(xy, dtype=float) - self.center
        return Box(self.name, self.lo + shift, self.hi + shift, self.bottom, self.top)

    def overlap(self, other: Box) -> float:
        """How far the two boxes' x-y footprints overlap (<= 0: apart by that much)."""
        return float(np.min(np.minimum(self.hi, other.hi) - np.maximum(self.lo, other.lo)))

    def touches(self, other: Box) -> bool:
        return self.overlap(other) > -CONTACT


@dataclass
class Layout:
    """Load-bearing solids of a scene (cloth excluded), some possibly moved to new x-y centres."""

    task: Task
    moved: dict[str, np.ndarray] = field(default_factory=dict)

    def box(self, name: str) -> Box:
        box = Box.of(self.task.object(name))
        return box.moved_to(self.moved[name]) if name in self.moved else box

    def boxes(self, exclude: Iterable[str] = ()) -> list[Box]:
        skip = set(exclude)
        return [self.box(o.name) for o in self.task.objects if o.name not in skip]

    def with_moved(self, name: str, xy: np.ndarray) -> Layout:
        """A copy with ``name`` moved so that its x-y centre is ``xy``."""
        return Layout(self.task, {**self.moved, name: np.asarray(xy, dtype=float)})

    def solids(self, exclude: Iterable[str] = ()) -> list[list[geometry.Part]]:
        skip = set(exclude)
        return [self._parts(o.name) for o in self.task.objects if o.shape != "cloth" and o.name not in skip]

    def heights(self, xy: np.ndarray, exclude: Iterable[str] = ()) -> np.ndarray:
        """Surface height under each point (n, 2)."""
        return geometry.surface_height(np.atleast_2d(xy), self.solids(exclude))

    def collides(self, box: Box, ignore: Iterable[str] = (), margin: float = 0.005) -> str | None:
        """The first other object that overlaps ``box``'s x-y footprint (not just touching) somewhere between
        ``box``'s bottom and top, or None."""
        skip = {box.name, *ignore}
        for obj in self.task.objects:
            if obj.name in skip or obj.shape == "cloth":
                continue
            other = self.box(obj.name)
            if box.overlap(other) <= margin or other.top <= box.bottom + margin or other.bottom >= box.top - margin:
                continue
            lo, hi = np.maximum(box.lo, other.lo) + margin, np.minimum(box.hi, other.hi) - margin
            grid = np.stack(np.meshgrid(np.linspace(lo[0], hi[0], 6), np.linspace(lo[1], hi[1], 6)), -1).reshape(-1, 2)
            low, high = geometry.object_interval(self._parts(obj.name), grid)
            if np.any((low < box.top - margin) & (high > box.bottom + margin)):
                return obj.name
        return None

    def _parts(self, name: str) -> list[geometry.Part]:
        obj = self.task.object(name)
        parts = geometry.object_parts(obj)
        if name in self.moved:
            shift = np.append(self.moved[name] - Box.of(obj).center, 0.0)
            parts = [geometry.Part(p.kind, p.center + shift, p.half, p.rot) for p in parts]
        return parts


def walk_violation(layout: Layout, start: np.ndarray, waypoints: Iterable[np.ndarray], limits: QuadrupedLimits,
                   exclude: Iterable[str] = ()) -> str | None:
    """Predict whether walking through ``waypoints`` breaks a limit: the first violation in words, or None.

    The body (axis-aligned, ``limits.body_size``) reads the highest surface across its width along each
    straight segment, from its rear edge at the start to its front edge at the end. Just outside its flanks
    (on a slanted move, the band its corners sweep) nothing may stand higher than what its feet are on: the
    simulator lifts the body only for what lies under its central band, so the legs would run into it.
    """
    half = np.asarray(limits.body_size[:2]) / 2
    here = np.asarray(start, dtype=float)
    for goal in waypoints:
        goal = np.asarray(goal, dtype=float)
        delta = goal - here
        length = float(np.linalg.norm(delta))
        if length < 1e-6:
            continue
        u = delta / length
        extent = float(np.abs(u) @ half)
        lateral = np.array([-u[1], u[0]])
        width = float(np.abs(lateral) @ half) - FOOT_INSET
        s = np.arange(0.0, length + 2 * extent + 1e-9, SAMPLE)
        rear = here - u * extent
        points = rear + s[:, None] * u
        flank = float(np.abs(lateral) @ half) + SIDE_MARGIN
        across = np.stack([points + k * lateral for k in (-width, 0.0, width, -flank, flank)])
        heights = layout.heights(across.reshape(-1, 2), exclude).reshape(5, -1)
        h = heights[:3].max(axis=0)
        problem = _scan(h, limits)
        if problem is None and (rub := heights[3:].max(axis=0) - h).max() > BRUSH:
            problem = f"the body brushes against something {float(rub.max()):.2f} m higher at its side"
        if problem:
            return f"{problem} on the way to [{goal[0]:.2f}, {goal[1]:.2f}]"
        here = goal
    return None


def _scan(h: np.ndarray, limits: QuadrupedLimits) -> str | None:
    """The first limit a height profile breaks (step up, gap, drop), in words, or None."""
    current = float(h[0])
    k = 1
    while k < len(h):
        z = float(h[k])
        if z - current > limits.max_step_up + SLACK:
            return f"step up of {z - current:.2f} m"
        if current - z > limits.max_step_up:
            back = np.flatnonzero(h[k:] >= current - limits.max_step_up)
            if back.size:
                width = back[0] * SAMPLE
                if width > limits.max_gap + SLACK:
                    return f"gap of {width:.2f} m"
                k += int(back[0])
                continue
            if current - z > limits.max_step_down + SLACK:
                return f"drop of {current - z:.2f} m"
        current = z
        k += 1
    return None


def detour(layout: Layout, start: np.ndarray, goal: np.ndarray, limits: QuadrupedLimits,
           exclude: Iterable[str] = ()) -> list[np.ndarray]:
    """Waypoints from ``start`` to ``goal``: straight when the walk is predicted fine, else through the
    shortest one of the L-corners and the corners of nearby objects (grown by the body) that makes it fine."""
    skip = list(exclude)
    if walk_violation(layout, start, [goal], limits, skip) is None:
        return [goal]
    half = np.asarray(limits.body_size[:2]) / 2 + 0.1
    vias = [np.array([goal[0], start[1]]), np.array([start[0], goal[1]])]
    for box in layout.boxes(skip):
        lo, hi = box.lo - half, box.hi + half
        vias += [np.array([x, y]) for x in (lo[0], hi[0]) for y in (lo[1], hi[1])]
    vias.sort(key=lambda v: float(np.linalg.norm(v - start) + np.linalg.norm(goal - v)))
    for via in vias[:12]:
        if walk_violation(layout, start, [via, goal], limits, skip) is None:
            return [via, goal]
    return [goal]


def push_problem(layout: Layout, name: str, dest: np.ndarray, body_half: np.ndarray,
                 floor: float) -> tuple[str | None, np.ndarray]:
    """Predict a push of ``name`` to ``dest`` (x-y) as the skill makes it: one straight leg per axis, the
    shorter first, the robot's face against the object's, slid along the face to the nearest offset whose
    sweep is clear. Returns what blocks it (or None) and where the robot ends."""
    box = layout.box(name)
    pos = box.center.copy()
    robot = pos.copy()
    delta = np.asarray(dest, dtype=float) - pos
    for axis in np.argsort(np.abs(delta), kind="stable"):
        if abs(delta[axis]) < 0.02:
            continue
        end = pos.copy()
        end[axis] = dest[axis]
        hit = next((h for f in np.linspace(0.0, 1.0, max(2, int(abs(delta[axis]) / 0.05) + 1))
                    if (h := layout.collides(box.moved_to(pos + f * (end - pos)), ignore=[name]))), None)
        if hit:
            return f"{name} would run into {hit}", robot
        across = 1 - axis
        reach = max(0.0, box.half[across] + body_half[across] - PUSH_OVERLAP)
        offsets = sorted(np.concatenate([np.arange(0.0, reach + 1e-9, 0.05), -np.arange(0.05, reach + 1e-9, 0.05)]),
                         key=abs)
        behind = next((b for o in offsets if not _robot_blocked(layout, b := _behind(pos, end, box, body_half, axis, o),
                                                                  end - pos, body_half, floor, name)), None)
        if behind is None:
            return f"no clear place to stand behind {name}", robot
        robot = behind + (end - pos)
        pos = end
    return None, robot


def _behind(pos: np.ndarray, end: np.ndarray, box: Box, body_half: np.ndarray, axis: int, offset: float) -> np.ndarray:
    """The robot's centre lined up behind the object at ``pos`` to push it toward ``end`` along ``axis``."""
    out = pos.copy()
    out[axis] -= np.sign(end[axis] - pos[axis]) * (box.half[axis] + body_half[axis] + 0.03)
    out[1 - axis] += offset
    return out


def _robot_blocked(layout: Layout, start: np.ndarray, travel: np.ndarray, body_half: np.ndarray, floor: float,
                   name: str) -> bool:
    """Whether the body, swept from ``start`` by ``travel``, meets anything above its floor but the pushed object."""
    lo = np.minimum(start, start + travel) - body_half
    hi = np.maximum(start, start + travel) + body_half
    return layout.collides(Box("robot", lo, hi, floor, floor + 0.3), ignore=[name], margin=0.015) is not None
