"""Analytic scene geometry: convex parts, vertical rays, overlaps and support surfaces.

Every object in a task is a union of convex parts (oriented boxes and cylinders). These helpers
answer the questions the validator and the ground-truth key concepts ask of a static scene: what
surface lies under a point, how far an object floats or sinks, whether two solids overlap.
All lengths are metres, world frame, z up; the ground is the plane z = 0.
"""

from __future__ import annotations

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
        low, high = PartStack.of([[self]]).intervals(xy)
        return low[0], high[0]

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


@dataclass(frozen=True)
class PartStack:
    """The parts of several solids as arrays, so that a vertical ray query runs once over all of them.

    Part ``i`` belongs to the solid whose first part is the last ``first`` entry at or before ``i`` (parts are stored
    solid by solid). Build it once per scene (:meth:`of`) and query it many times: a ray is crossed only with the
    parts whose x-y bounds it passes through (a ray outside them misses).
    """

    cylinder: np.ndarray  # (m,) bool: a cylinder (else a box)
    upright: np.ndarray  # indices of the boxes not turned at all (their rotation the identity)
    turned: np.ndarray  # indices of the other parts
    center: np.ndarray  # (m, 3)
    half: np.ndarray  # (m, 3)
    rot: np.ndarray  # (m, 3, 3)
    first: np.ndarray  # (s,) index of each solid's first part
    lo: np.ndarray  # (m, 2) x-y bounds of each part, grown by BOUNDS_SLACK
    hi: np.ndarray  # (m, 2)

    BOUNDS_SLACK = 1e-9  # m: rays this close outside a part's bounds are still crossed with it exactly

    @classmethod
    def of(cls, solids: list[list[Part]]) -> PartStack:
        parts = [p for solid in solids for p in solid]
        bounds = [p.aabb() for p in parts]
        cylinder = np.array([p.kind == "cylinder" for p in parts], dtype=bool)
        upright = ~cylinder & np.array([np.array_equal(p.rot, np.eye(3)) for p in parts], dtype=bool)
        return cls(
            cylinder=cylinder,
            upright=np.flatnonzero(upright),
            turned=np.flatnonzero(~upright),
            center=np.array([p.center for p in parts], dtype=float).reshape(-1, 3),
            half=np.array([p.half for p in parts], dtype=float).reshape(-1, 3),
            rot=np.array([p.rot for p in parts], dtype=float).reshape(-1, 3, 3),
            first=np.cumsum([0] + [len(solid) for solid in solids[:-1]]).astype(int) if solids else np.zeros(0, int),
            lo=np.array([b[0][:2] for b in bounds], dtype=float).reshape(-1, 2) - cls.BOUNDS_SLACK,
            hi=np.array([b[1][:2] for b in bounds], dtype=float).reshape(-1, 2) + cls.BOUNDS_SLACK,
        )

    @property
    def solids(self) -> int:
        return len(self.first)

    def intervals(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where vertical lines through ``xy`` (n, 2) cross each part: (z_low, z_high), each (m, n); NaN where
        a line misses a part."""
        low, high = np.full((len(self.center), len(xy)), np.nan), np.full((len(self.center), len(xy)), np.nan)
        if self.upright.size:  # a box not turned: crossed from its bottom to its top within its x-y sides
            center, half = self.center[self.upright], self.half[self.upright]
            inside = np.abs(xy[None, :, 0] - center[:, 0, None]) <= half[:, 0, None]
            inside &= np.abs(xy[None, :, 1] - center[:, 1, None]) <= half[:, 1, None]
            o = 0.0 - center[:, 2]  # (the values the general crossing below gives these boxes, in fewer steps)
            t_lo, t_hi = -half[:, 2] - o, half[:, 2] - o
            hit = inside & (t_lo <= t_hi)[:, None]
            low[self.upright] = np.where(hit, t_lo[:, None], np.nan)
            high[self.upright] = np.where(hit, t_hi[:, None], np.nan)
        if self.turned.size:
            turned = self.turned
            x, y = xy[None, :, 0], xy[None, :, 1]
            near = (x >= self.lo[turned, 0, None]) & (x <= self.hi[turned, 0, None]) & (y >= self.lo[turned, 1, None])
            near &= y <= self.hi[turned, 1, None]
            part, point = np.nonzero(near)
            if part.size:
                low[turned[part], point], high[turned[part], point] = self._crossings(turned[part], xy[point])
        return low, high

    def _crossings(self, part: np.ndarray, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where the vertical line through each ``xy`` (K, 2) crosses its ``part`` (K,): (z_low, z_high), NaN
        where it misses."""
        origin = np.column_stack([xy, np.zeros(len(xy))]) - self.center[part]
        o_local = np.empty_like(origin)  # (K, 3): R^T (p - c), one matrix product per part
        for i in np.unique(part):
            rows = part == i
            o_local[rows] = origin[rows] @ self.rot[i]
        d_local = self.rot[part, 2, :]  # (K, 3): R^T e_z
        half, cylinder = self.half[part], self.cylinder[part]
        t_lo, t_hi = np.full(len(part), -np.inf), np.full(len(part), np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            for k in range(3):
                o, d, h = o_local[:, k], d_local[:, k], half[:, k]
                slab = ~cylinder if k < 2 else np.ones(len(part), dtype=bool)  # a cylinder: only its caps
                parallel = np.abs(d) < 1e-12
                a, b = (-h - o) / d, (h - o) / d
                crossing = slab & ~parallel
                t_lo = np.where(crossing, np.maximum(t_lo, np.minimum(a, b)), t_lo)
                t_hi = np.where(crossing, np.minimum(t_hi, np.maximum(a, b)), t_hi)
                t_lo = np.where(slab & parallel & (np.abs(o) > h), np.inf, t_lo)
            if cylinder.any():
                t_lo, t_hi = _round_side(cylinder, half[:, 0], o_local, d_local, t_lo, t_hi)
        hit = t_lo <= t_hi
        return np.where(hit, t_lo, np.nan), np.where(hit, t_hi, np.nan)

    def solid_intervals(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lowest and highest z of each solid along vertical lines through ``xy``: each (s, n), NaN where missed."""
        low, high = self.intervals(xy)
        if len(self.first) == len(self.center):  # one part each (or none at all)
            return low, high
        return np.fmin.reduceat(low, self.first, axis=0), np.fmax.reduceat(high, self.first, axis=0)


def _round_side(
    cylinder: np.ndarray, r: np.ndarray, o_local: np.ndarray, d_local: np.ndarray, t_lo: np.ndarray, t_hi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``t_lo``/``t_hi`` (K,) cut by the round sides of the ``cylinder`` rows (radius ``r``); box rows unchanged."""
    qa = d_local[:, 0] ** 2 + d_local[:, 1] ** 2
    qb = 2 * (o_local[:, 0] * d_local[:, 0] + o_local[:, 1] * d_local[:, 1])
    qc = o_local[:, 0] ** 2 + o_local[:, 1] ** 2 - r * r
    upright = cylinder & (qa < 1e-12)
    tilted = cylinder & ~(qa < 1e-12)
    disc = qb * qb - 4 * qa * qc
    ok = disc >= 0
    root = np.sqrt(np.where(ok, disc, 0.0))
    t_lo = np.where(upright & (qc > 0), np.inf, t_lo)
    t_lo = np.where(tilted, np.where(ok, np.maximum(t_lo, (-qb - root) / (2 * qa)), np.inf), t_lo)
    t_hi = np.where(tilted, np.minimum(t_hi, (-qb + root) / (2 * qa)), t_hi)
    return t_lo, t_hi


def object_interval(parts: list[Part], xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest z of an object's parts along vertical lines (NaN where missed)."""
    low, high = PartStack.of([parts]).solid_intervals(xy)
    return low[0], high[0]


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


def surface_height(xy: np.ndarray, solids: list[list[Part]] | PartStack, below: np.ndarray | None = None) -> np.ndarray:
    """Height of the highest surface under each point: the ground or the top of a solid.

    With ``below`` (one z per point), only solids whose top is at most that high count, so the
    result is the surface a body with its bottom at ``below`` would rest on.
    """
    stack = solids if isinstance(solids, PartStack) else PartStack.of(solids)
    if not stack.solids:
        return np.full(xy.shape[0], GROUND_Z)
    return highest_top(stack.solid_intervals(xy)[1], below)


def highest_top(top: np.ndarray, below: np.ndarray | None = None) -> np.ndarray:
    """The highest surface under each point, from each solid's top over it (s, n; NaN where it is not): the ground
    or a top (with ``below``, one at most that high)."""
    ok = ~np.isnan(top)
    if below is not None:
        ok &= top <= below
    best = np.full(top.shape[1], GROUND_Z)
    return np.maximum(best, np.where(ok, top, -np.inf).max(axis=0, initial=-np.inf))


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


CYLINDER_SIDES = 128  # a cylinder's overlaps are found as those of the prism of this many sides around it


def overlap_depth(a: Part, b: Part) -> float:
    """Penetration depth of two parts: how far one must move to clear the other (<= 0 when they do not overlap)."""
    return penetration(a, b)[0]


def penetration(a: Part, b: Part) -> tuple[float, np.ndarray]:
    """Penetration depth of two parts and the direction (a unit vector) along which they separate soonest.

    The depth is the least, over directions, of how far the parts' projections overlap (the separating-axis test):
    exact for boxes (their face normals and the cross products of their edges), and for a cylinder its true
    projection tried on the directions of the prism of :data:`CYLINDER_SIDES` sides circumscribing it, so a cylinder
    standing beside a box's corner or under a tilted board is not taken for its bounding box; the depth found exceeds
    the true one by at most 0.031 % of the cylinder's radius (of each, for two). A depth <= 0: they do not overlap.
    """
    normals_a, edges_a = _directions(a)
    normals_b, edges_b = _directions(b)
    cross = np.cross(edges_a[:, None, :], edges_b[None, :, :]).reshape(-1, 3)
    norm = np.linalg.norm(cross, axis=1)
    axes = np.concatenate([normals_a, normals_b, cross[norm > 1e-9] / norm[norm > 1e-9, None]])
    overlap = _radius(a, axes) + _radius(b, axes) - np.abs(axes @ (b.center - a.center))
    best = int(np.argmin(overlap))
    return float(overlap[best]), axes[best]


def _directions(part: Part) -> tuple[np.ndarray, np.ndarray]:
    """A part's face normals and edge directions (k, 3): a box's axes; for a cylinder its axis and the radial
    directions of the prism around it (its side faces' normals, and, as the sides are even, its rims' edges)."""
    if part.kind == "box":
        return part.rot.T, part.rot.T
    angle = np.arange(CYLINDER_SIDES // 2) * (2 * np.pi / CYLINDER_SIDES)
    radial = np.outer(np.cos(angle), part.rot[:, 0]) + np.outer(np.sin(angle), part.rot[:, 1])
    both = np.vstack([part.rot[:, 2], radial])
    return both, both


def _radius(part: Part, axes: np.ndarray) -> np.ndarray:
    """Half the length of the part's projection on each unit axis (k, 3)."""
    if part.kind == "box":
        return np.abs(axes @ part.rot) @ part.half
    along = np.abs(axes @ part.rot[:, 2])
    return part.half[0] * np.sqrt(np.clip(1.0 - along**2, 0.0, None)) + part.half[2] * along


def solids_overlap(a: list[Part], b: list[Part]) -> float:
    """Largest penetration depth between any part of ``a`` and any part of ``b`` (<= 0: they do not overlap)."""
    return solids_penetration(a, b)[0]


def solids_penetration(a: list[Part], b: list[Part]) -> tuple[float, np.ndarray]:
    """The deepest :func:`penetration` between a part of ``a`` and a part of ``b``: its depth and direction."""
    return max((penetration(pa, pb) for pa in a for pb in b), key=lambda found: found[0])


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
