"""Analytic scene geometry: convex parts, vertical rays, overlaps and support surfaces.

Every object in a task is a union of convex parts (oriented boxes and cylinders). These helpers
answer the questions the validator and the ground-truth key concepts ask of a static scene: what
surface lies under a point, how far an object floats or sinks, whether two solids overlap.
All lengths are metres, world frame, z up; the ground is the plane z = 0.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np

GROUND_Z = 0.0


class Solid(Protocol):
    """What :func:`object_parts` reads of an object (a :class:`~robotool.task.scene.SceneObject` is one)."""

    @property
    def shape(self) -> str: ...
    @property
    def center(self) -> tuple[float, float, float]: ...
    @property
    def size(self) -> tuple[float, float, float]: ...
    @property
    def rpy(self) -> tuple[float, float, float]: ...
    @property
    def axis(self) -> Literal["x", "y", "z"]: ...
    @property
    def thickness(self) -> float: ...


def rotation_matrix(rpy_deg: tuple[float, float, float] | np.ndarray) -> np.ndarray:
    """Rotation from roll, pitch, yaw in degrees about the fixed x, y, z axes (R = Rz Ry Rx)."""
    r, p, y = np.radians(np.asarray(rpy_deg, dtype=float))
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def axis_aligned_size(size: tuple[float, float, float] | np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """A box's size along the world x, y, z after ``rotation`` (box frame to world), each world axis taking the
    box axis nearest to it: a quarter turn about z swaps the x and y sizes, a tilt of a few degrees changes
    nothing."""
    weight = np.abs(np.asarray(rotation, dtype=float))  # [world axis, box axis]
    out = np.zeros(3)
    free_world, free_box = {0, 1, 2}, {0, 1, 2}
    for flat in np.argsort(-weight, axis=None, kind="stable"):
        world, box = divmod(int(flat), 3)
        if world in free_world and box in free_box:
            out[world] = size[box]
            free_world.remove(world)
            free_box.remove(box)
    return out


@dataclass(frozen=True)
class Part:
    """A convex primitive in the world frame.

    A box has half-extents ``half``; a cylinder has its axis along its local z, radius ``half[0]``
    and half-length ``half[2]``. ``rot`` maps local to world coordinates.
    """

    kind: Literal["box", "cylinder"]
    center: np.ndarray
    half: np.ndarray
    rot: np.ndarray

    def vertical_interval(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where vertical lines through points ``xy`` (n, 2) cross the part: (z_low, z_high).

        Lines that miss the part get NaN in both.
        """
        n = xy.shape[0]
        origin = np.column_stack([xy, np.zeros(n)]) - self.center
        o_local = origin @ self.rot  # (n, 3): R^T (p - c)
        d_local = self.rot[2]  # R^T e_z
        t_lo = np.full(n, -np.inf)
        t_hi = np.full(n, np.inf)
        axes = range(3) if self.kind == "box" else (2,)
        for k in axes:
            o, d, h = o_local[:, k], d_local[k], self.half[k]
            if abs(d) < 1e-12:
                outside = np.abs(o) > h
                t_lo[outside] = np.inf
                continue
            a, b = (-h - o) / d, (h - o) / d
            t_lo = np.maximum(t_lo, np.minimum(a, b))
            t_hi = np.minimum(t_hi, np.maximum(a, b))
        if self.kind == "cylinder":
            r = self.half[0]
            qa = d_local[0] ** 2 + d_local[1] ** 2
            qb = 2 * (o_local[:, 0] * d_local[0] + o_local[:, 1] * d_local[1])
            qc = o_local[:, 0] ** 2 + o_local[:, 1] ** 2 - r * r
            if qa < 1e-12:
                t_lo[qc > 0] = np.inf
            else:
                disc = qb * qb - 4 * qa * qc
                ok = disc >= 0
                root = np.sqrt(np.where(ok, disc, 0.0))
                t_lo = np.where(ok, np.maximum(t_lo, (-qb - root) / (2 * qa)), np.inf)
                t_hi = np.minimum(t_hi, (-qb + root) / (2 * qa))
        hit = t_lo <= t_hi
        return np.where(hit, t_lo, np.nan), np.where(hit, t_hi, np.nan)

    def corners(self) -> np.ndarray:
        """The 8 corners of the part's oriented bounding box, world frame (8, 3)."""
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        return self.center + (signs * self.half) @ self.rot.T

    def aabb(self) -> tuple[np.ndarray, np.ndarray]:
        """World axis-aligned bounds (lo, hi) of the part's bounding box."""
        c = self.corners()
        return c.min(axis=0), c.max(axis=0)


def object_parts(obj: Solid) -> list[Part]:
    """The convex parts that make up a task object, placed in the world."""
    center = np.asarray(obj.center, dtype=float)
    size = np.asarray(obj.size, dtype=float)
    rot = rotation_matrix(obj.rpy)
    if obj.shape == "cylinder":
        axis_rot = {
            "z": np.eye(3),
            "x": rotation_matrix((0.0, 90.0, 0.0)),
            "y": rotation_matrix((-90.0, 0.0, 0.0)),
        }[obj.axis]
        axis_index = "xyz".index(obj.axis)
        across = [size[i] for i in range(3) if i != axis_index]
        half = np.array([min(across) / 2, min(across) / 2, size[axis_index] / 2])
        return [Part("cylinder", center, half, rot @ axis_rot)]
    if obj.shape == "hook":
        t = min(obj.thickness, size[0], size[1])
        local_parts = [
            (np.array([0.0, -size[1] / 2 + t / 2, 0.0]), np.array([size[0] / 2, t / 2, size[2] / 2])),
            (np.array([size[0] / 2 - t / 2, 0.0, 0.0]), np.array([t / 2, size[1] / 2, size[2] / 2])),
        ]
        return [Part("box", center + rot @ c, h, rot) for c, h in local_parts]
    return [Part("box", center, size / 2, rot)]


def object_interval(parts: list[Part], xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest z of an object's parts along vertical lines (NaN where missed)."""
    lows, highs = zip(*(p.vertical_interval(xy) for p in parts), strict=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns: lines that miss
        return np.nanmin(np.vstack(lows), axis=0), np.nanmax(np.vstack(highs), axis=0)


def footprint_grid(parts: list[Part], spacing: float = 0.01, max_per_axis: int = 61) -> np.ndarray:
    """Sample points (n, 2) covering the x-y footprint of a set of parts."""
    lo = np.min([p.aabb()[0] for p in parts], axis=0)
    hi = np.max([p.aabb()[1] for p in parts], axis=0)
    axes = []
    for k in range(2):
        count = int(np.clip(np.ceil((hi[k] - lo[k]) / spacing) + 1, 3, max_per_axis))
        axes.append(np.linspace(lo[k], hi[k], count))
    gx, gy = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([gx.ravel(), gy.ravel()])


def surface_height(xy: np.ndarray, solids: list[list[Part]], below: np.ndarray | None = None) -> np.ndarray:
    """Height of the highest surface under each point: the ground or the top of a solid.

    With ``below`` (one z per point), only solids whose top is at most that high count, so the
    result is the surface a body with its bottom at ``below`` would rest on.
    """
    best = np.full(xy.shape[0], GROUND_Z)
    for parts in solids:
        _, top = object_interval(parts, xy)
        ok = ~np.isnan(top)
        if below is not None:
            ok &= top <= below
        best = np.where(ok & (top > best), top, best)
    return best


@dataclass(frozen=True)
class Contact:
    """How an object's underside meets what is under it."""

    gap: float  # smallest clearance between its bottom and the surface below (> 0: floating)
    penetration: float  # deepest its bottom sinks into a solid below or the ground
    into: str  # what it sinks into ("ground" or an object's name); "" when it does not


def resting_contact(
    parts: list[Part], others: dict[str, list[Part]], center_z: float, tolerance: float = 0.01
) -> Contact:
    """Measure how an object rests: clearance to its support and penetration into solids below.

    A solid counts as below when its centre is lower than the object's centre.
    """
    xy = footprint_grid(parts)
    bottom, _ = object_interval(parts, xy)
    inside = ~np.isnan(bottom)
    xy, bottom = xy[inside], bottom[inside]
    support = surface_height(xy, list(others.values()), below=bottom + tolerance)
    gap = float(np.min(bottom - support))
    penetration, into = float(GROUND_Z - bottom.min()), "ground"
    for name, other in others.items():
        other_center_z = float(np.mean([p.center[2] for p in other]))
        if other_center_z >= center_z:
            continue
        low, top = object_interval(other, xy)
        crossing = ~np.isnan(top) & (low < bottom)
        if crossing.any():
            depth = float(np.max(top[crossing] - bottom[crossing]))
            if depth > penetration:
                penetration, into = depth, name
    return Contact(gap=gap, penetration=penetration, into=into if penetration > 0 else "")


def overlap_depth(a: Part, b: Part) -> float:
    """Penetration depth of two parts' oriented bounding boxes (<= 0 when they do not overlap)."""
    axes = [a.rot[:, i] for i in range(3)] + [b.rot[:, i] for i in range(3)]
    for i in range(3):
        for j in range(3):
            cross = np.cross(a.rot[:, i], b.rot[:, j])
            norm = np.linalg.norm(cross)
            if norm > 1e-9:
                axes.append(cross / norm)
    depth = np.inf
    delta = b.center - a.center
    for axis in axes:
        ra = np.sum(np.abs(a.rot.T @ axis) * a.half)
        rb = np.sum(np.abs(b.rot.T @ axis) * b.half)
        depth = min(depth, ra + rb - abs(float(delta @ axis)))
    return float(depth)


def solids_overlap(a: list[Part], b: list[Part]) -> float:
    """Largest bounding-box penetration between any part of ``a`` and any part of ``b``."""
    return max(overlap_depth(pa, pb) for pa in a for pb in b)


def height_profile(
    start_xy: np.ndarray, end_xy: np.ndarray, solids: list[list[Part]], step: float = 0.01
) -> tuple[np.ndarray, np.ndarray]:
    """Surface heights along the straight segment from ``start_xy`` to ``end_xy``.

    Returns (distance along the segment, surface height) sampled every ``step`` metres.
    """
    length = float(np.linalg.norm(end_xy - start_xy))
    count = max(int(np.ceil(length / step)) + 1, 2)
    s = np.linspace(0.0, length, count)
    direction = (end_xy - start_xy) / length if length > 0 else np.zeros(2)
    xy = start_xy + s[:, None] * direction
    return s, surface_height(xy, solids)


def distance_to_parts(parts: list[Part], point: np.ndarray | tuple[float, float, float]) -> float:
    """How far ``point`` lies outside the union of ``parts`` (0 inside or on the surface), metres."""
    p = np.asarray(point, dtype=float)
    best = np.inf
    for part in parts:
        local = (p - part.center) @ part.rot
        if part.kind == "box":
            excess = np.maximum(np.abs(local) - part.half, 0.0)
        else:
            radial = max(float(np.hypot(local[0], local[1])) - part.half[0], 0.0)
            excess = np.array([radial, max(abs(float(local[2])) - part.half[2], 0.0)])
        best = min(best, float(np.linalg.norm(excess)))
    return best
