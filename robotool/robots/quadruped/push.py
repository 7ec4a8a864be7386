"""Pushing for the quadruped: the rules a push must satisfy, and where to stand to push.

A push moves the object along x and y in turn (the shorter leg first), each leg a straight push with
the robot's face flat against the object's face, so an axis-aligned body never pushes on a corner.
For each leg the robot stands on the object's far side; if the straight-on pose or its sweep would run
into something higher than the floor it stands on (another object, a board overhead), the pose slides
along the object's face to the nearest clear one that still overlaps the face. Lined up well off the
centre line of an object that something lies on, the robot pushes with its face turned a little toward
that line (:func:`face_turn`), so that it meets the object nearest the line first.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from itertools import pairwise
from typing import Literal

import numpy as np

from robotool.robots.quadruped.quadruped_config import QUADRUPED
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.terrain import RISE, foot_offsets, foot_paths, rotated

# the push geometry's tunables, documented in QuadrupedConfig
GAP = QUADRUPED.push_gap
MIN_OVERLAP = QUADRUPED.min_overlap
OFFSET_STEP = QUADRUPED.offset_step
SAME_SURFACE = QUADRUPED.same_surface
MIN_LEG = QUADRUPED.min_leg
SIDE_MARGIN = QUADRUPED.side_margin
EXIT_MARGIN = QUADRUPED.exit_margin
FACE_TURN = QUADRUPED.face_turn
FACE_TURN_FROM = QUADRUPED.face_turn_from


@dataclass(frozen=True)
class Leg:
    """One straight push along ``axis`` (0: x, 1: y) that brings the object's centre to ``target``."""

    axis: int
    target: float


def legs(center: np.ndarray, target: np.ndarray) -> list[Leg]:
    """The axis-aligned pushes from ``center`` to ``target`` (x-y), shorter first."""
    delta = np.asarray(target[:2]) - np.asarray(center[:2])
    order = np.argsort(np.abs(delta), kind="stable")
    return [Leg(int(a), float(target[a])) for a in order if abs(delta[a]) >= MIN_LEG]


def rule_violation(
    *,
    movable: bool,
    mass: float,
    riders: list[str],
    stuck: list[str],
    under_robot: bool,
    robot_support_movable: str | None,
    object_support: float,
    robot_support: float,
    limits: QuadrupedLimits,
) -> tuple[str, dict[str, float]] | None:
    """The first push rule broken (reason, measured values), or None when the push is allowed.

    ``mass`` is what the push moves: the object's own mass and that of the ``riders`` on it and of what is ``stuck``
    to it (a magnet's weld).
    """
    if not movable:
        return "it is fixed in place", {}
    if under_robot:
        return "the robot is standing on it", {}
    heavy = mass_violation(mass, riders, stuck, limits)
    if heavy is not None:
        return heavy
    if robot_support_movable is not None:
        return f"the robot stands on {robot_support_movable}, which is movable", {}
    if abs(object_support - robot_support) > SAME_SURFACE:
        return (
            f"it rests at height {object_support:.2f} m, not on the robot's surface at {robot_support:.2f} m",
            {"object_support": object_support, "robot_support": robot_support},
        )
    return None


def mass_violation(
    mass: float, riders: list[str], stuck: list[str], limits: QuadrupedLimits
) -> tuple[str, dict[str, float]] | None:
    """The push limit broken by moving ``mass`` (kg: the object's own with its ``riders`` and what is ``stuck`` to
    it), as :func:`rule_violation` words it, or None."""
    if mass <= limits.max_push_mass:
        return None
    along = [f"{', '.join(names)} {how} it" for names, how in ((riders, "riding on"), (stuck, "stuck to")) if names]
    return (
        f"its mass{' with ' if along else ''}{' and '.join(along)}, {mass:.1f} kg, exceeds the push limit of "
        f"{limits.max_push_mass:.1f} kg",
        {"mass": mass, "limit": limits.max_push_mass, "riders": float(len(riders)), "stuck": float(len(stuck))},
    )


def lateral_offsets(object_width: float, robot_width: float) -> np.ndarray:
    """Candidate offsets of the robot along the object's face, nearest to straight-on first."""
    reach = max(0.0, (object_width + robot_width) / 2 - MIN_OVERLAP)
    steps = np.arange(0.0, reach + 1e-9, OFFSET_STEP)
    both = np.stack([steps, -steps], axis=1).ravel()
    return both[1:] if both.size > 1 else both


def push_poses(
    lo: np.ndarray, hi: np.ndarray, leg: Leg, half: np.ndarray, offsets: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Robot centres (x-y) at the start and end (each (n, 2)) of ``leg`` for an object with x-y bounds ``lo``-``hi``.

    ``half`` is the robot's x-y half size; each of ``offsets`` (n,) shifts the robot along the object's face.
    """
    a, b = leg.axis, 1 - leg.axis
    center = (lo + hi) / 2
    sign = np.sign(leg.target - center[a])
    start = np.zeros((len(offsets), 2))
    start[:, a] = (lo[a] - half[a] - GAP) if sign > 0 else (hi[a] + half[a] + GAP)
    start[:, b] = center[b] + np.asarray(offsets, dtype=float)
    end = start.copy()
    end[:, a] += leg.target - center[a] + sign * GAP
    return start, end


PushTry = tuple[np.ndarray, np.ndarray, float, np.ndarray]  # a leg's start, end, staging distance and staging point


def push_tries(lo: np.ndarray, hi: np.ndarray, leg: Leg, half: np.ndarray, staging: float) -> list[PushTry]:
    """The ways to line up for ``leg`` of a push of an object with x-y bounds ``lo``-``hi`` (``half``: the robot's x-y
    half size), in the order they are tried: at each of the :func:`lateral_offsets` along its face (nearest straight-on
    first) ``staging`` behind the start, then at each from the start itself. Each is the start and end (robot
    centres), how far behind the start the robot lines up and where (its sweep runs from there to the end)."""
    b = 1 - leg.axis
    start, end = push_poses(lo, hi, leg, half, lateral_offsets(float(hi[b] - lo[b]), 2 * float(half[b])))
    along = (end - start) / np.linalg.norm(end - start, axis=1, keepdims=True)
    return [
        (s, e, distance, behind)
        for distance in (staging, 0.0)
        for s, e, behind in zip(start, end, start - along * distance, strict=True)
    ]


def face_turn(start: np.ndarray, end: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
    """How far (rad, counter-clockwise) the body turns its face toward the centre line of an object with x-y bounds
    ``lo``-``hi`` for a push from ``start`` to ``end`` (robot centres): :data:`FACE_TURN` where it lines up off that
    line by more than :data:`FACE_TURN_FROM` of the object's half width across the push, else none (a flat face). The
    face then meets the object at its inner end first: met at its outer end, an object with weight on part of its top
    turns away and slides off the face (the push skill turns the face for such objects only)."""
    u = (end - start) / max(float(np.linalg.norm(end - start)), 1e-9)
    to_centre = (lo + hi) / 2 - start
    offset = float(u[0] * to_centre[1] - u[1] * to_centre[0])  # > 0: the centre line lies to the left
    half_across = float(np.abs([-u[1], u[0]]) @ ((hi - lo) / 2))
    if abs(offset) <= FACE_TURN_FROM * half_across:
        return 0.0
    return -float(np.sign(offset)) * FACE_TURN


def turned_feet_drop(
    heights: Callable[[np.ndarray], np.ndarray],
    start: np.ndarray,
    end: np.ndarray,
    limits: QuadrupedLimits,
    angle: float,
    floor: float,
) -> SweepProblem | None:
    """The drop under the feet of a body turned by ``angle`` (rad) on a push from ``start`` to ``end`` (robot
    centres) over a floor at ``floor`` (None: they stay over the floor); ``heights`` as for :func:`sweep_problem`."""
    points = _feet_paths(start, end, limits, angle)
    return _drop(points, heights(points), floor)


def sweep_points(start: np.ndarray, end: np.ndarray, half: np.ndarray, spacing: float = 0.05) -> np.ndarray:
    """x-y sample points (n, 2) covering the robot's footprint swept from ``start`` to ``end``, grown by
    :data:`SIDE_MARGIN`."""
    lo = np.minimum(start, end) - half - SIDE_MARGIN
    hi = np.maximum(start, end) + half + SIDE_MARGIN
    xs, ys = (np.linspace(lo[k], hi[k], max(2, int(np.ceil((hi[k] - lo[k]) / spacing)) + 1)) for k in range(2))
    return np.column_stack([np.repeat(xs, len(ys)), np.tile(ys, len(xs))])  # x-major, as meshgrid(indexing="ij")


@dataclass(frozen=True)
class SweepProblem:
    """What is wrong with a push sweep: something in the body's way, or a drop under the feet; ``text`` says it."""

    kind: Literal["blocked", "drop"]
    text: str

    def __str__(self) -> str:
        return self.text


def sweep_problem(
    heights: Callable[[np.ndarray], np.ndarray],
    behind: np.ndarray,
    end: np.ndarray,
    limits: QuadrupedLimits,
    floor: float,
) -> SweepProblem | None:
    """What is wrong with a push sweep from ``behind`` to ``end`` (robot centres) over a floor at ``floor``, or None.

    ``heights`` gives the surface under x-y points with the pushed object left out. The body's footprint must meet
    nothing higher than the floor, and the feet's paths nothing lower (no drop, no gap under where it stands).
    """
    half = np.asarray(limits.body_size[:2]) / 2
    if _blocked(heights(sweep_points(behind, end, half)), floor):
        return BLOCKED
    points = _feet_paths(behind, end, limits)
    return _drop(points, heights(points), floor)


TRIES_AT_ONCE = 6  # push sweeps read in one call of the heights


def first_clear_sweep(
    heights: Callable[[np.ndarray], np.ndarray],
    sweeps: list[tuple[np.ndarray, np.ndarray]],
    limits: QuadrupedLimits,
    floor: float,
) -> tuple[int | None, tuple[int, SweepProblem] | None]:
    """The index of the first of ``sweeps`` (``behind``, ``end``) with no :func:`sweep_problem` (None: none), and the
    first drop met before it (its index and the problem; None: none).

    The footprints and the feet's paths of :data:`TRIES_AT_ONCE` sweeps are read in one call of ``heights``, in order
    (the first clear one is most often among the first); ``heights`` must read each point on its own."""
    half = np.asarray(limits.body_size[:2]) / 2
    first_drop = None
    for first in range(0, len(sweeps), TRIES_AT_ONCE):
        chunk = sweeps[first : first + TRIES_AT_ONCE]
        paths = [_feet_paths(behind, end, limits) for behind, end in chunk]
        read = [sweep_points(behind, end, half) for behind, end in chunk] + paths
        z = np.split(heights(np.concatenate(read)), np.cumsum([len(p) for p in read])[:-1])
        for k, points in enumerate(paths):
            if _blocked(z[k], floor):
                continue
            drop = _drop(points, z[len(chunk) + k], floor)
            if drop is None:
                return first + k, first_drop
            first_drop = first_drop or (first + k, drop)
    return None, first_drop


BLOCKED = SweepProblem("blocked", "something stands in its way")


def _blocked(footprint: np.ndarray, floor: float) -> bool:
    """Whether the heights under a sweep's footprint meet something higher than the floor."""
    return bool(np.any(footprint > floor + RISE))


def _feet_paths(behind: np.ndarray, end: np.ndarray, limits: QuadrupedLimits, angle: float = 0.0) -> np.ndarray:
    """Sample points (n, 2) on the feet's paths of a push sweep from ``behind`` to ``end``, the body turned by
    ``angle`` (rad, counter-clockwise) off its axis-aligned pose."""
    u = (end - behind) / max(float(np.linalg.norm(end - behind)), 1e-9)
    feet = rotated(foot_offsets(limits), np.array([angle]))[0] if angle else foot_offsets(limits)
    return foot_paths(behind + feet, u, float(np.linalg.norm(end - behind))).reshape(-1, 2)


def _drop(points: np.ndarray, under: np.ndarray, floor: float) -> SweepProblem | None:
    """The drop under the feet's ``points`` (their heights ``under``) of a sweep over a floor at ``floor``, or None."""
    if under.min() < floor - RISE:
        k = int(under.argmin())
        where = f"[{points[k, 0]:.2f}, {points[k, 1]:.2f}]"
        return SweepProblem("drop", f"it would stand over a drop of {floor - under[k]:.2f} m at {where}")
    return None


def route(start: np.ndarray, goal: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> list[np.ndarray]:
    """Waypoints (x-y) from ``start`` to ``goal`` around the box ``lo``-``hi`` (robot centre space): the shortest of
    :func:`routes`."""
    return routes(start, goal, lo, hi)[0]


def routes(start: np.ndarray, goal: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> list[list[np.ndarray]]:
    """Ways (waypoints, x-y) from ``start`` to ``goal`` around the box ``lo``-``hi`` (robot centre space), shortest
    first.

    The straight line alone when it misses the box; otherwise the paths by the box's corners, each way round. A
    start inside the box (the robot right behind an object it has just pushed, which turned) first leaves it
    straight out through the nearest side. ``[[goal]]`` when there is no way round (the goal inside the box).
    """
    if np.all((start > lo) & (start < hi)):
        out = _nearest_exit(start, lo, hi)
        return [[out, *way] for way in routes(out, goal, lo, hi)]
    if not crosses(start, goal, lo, hi):
        return [[goal]]
    corners = [np.array([x, y]) for x, y in ((lo[0], lo[1]), (hi[0], lo[1]), (hi[0], hi[1]), (lo[0], hi[1]))]
    found: dict[tuple[int, ...], tuple[float, list[np.ndarray]]] = {}
    for i in range(4):
        for direction in (1, -1):
            for count in (1, 2, 3):
                ids = tuple((i + direction * k) % 4 for k in range(count))
                path = [corners[k] for k in ids]
                points = [start, *path, goal]
                if ids in found or any(crosses(p, q, lo, hi) for p, q in pairwise(points)):
                    continue
                found[ids] = (sum(float(np.linalg.norm(q - p)) for p, q in pairwise(points)), [*path, goal])
    ways = [way for _, way in sorted(found.values(), key=lambda f: f[0])]
    return ways or [[goal]]


def _nearest_exit(p: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The point just outside the box ``lo``-``hi`` straight out from ``p`` (inside it) through the nearest side."""
    sides = np.array([p[0] - lo[0], hi[0] - p[0], p[1] - lo[1], hi[1] - p[1]])
    k = int(np.argmin(sides))
    out = np.array(p, dtype=float)
    out[k // 2] = (lo, hi)[k % 2][k // 2] + (EXIT_MARGIN if k % 2 else -EXIT_MARGIN)
    return out


def crosses(p: np.ndarray, q: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    """Whether segment p-q passes through the open box (lo, hi) (slab test)."""
    t0, t1 = 0.0, 1.0
    d = q - p
    for k in range(2):
        if abs(d[k]) < 1e-12:
            if not lo[k] < p[k] < hi[k]:
                return False
            continue
        a, b = (lo[k] - p[k]) / d[k], (hi[k] - p[k]) / d[k]
        t0, t1 = max(t0, min(a, b)), min(t1, max(a, b))
    return t1 - t0 > 1e-6
