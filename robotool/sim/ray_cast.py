"""MuJoCo's ``mj_ray`` for many rays at once, in numpy: each ray against every eligible geom, the nearest hit kept.

The per-shape tests follow MuJoCo's own (``engine_ray.c``): the ray is mapped into the geom's frame, a plane is hit
from its front only and within its size (a size of 0: unbounded), a sphere, capsule, ellipsoid, cylinder or box by
its surface at the least non-negative distance, with the same bounding-sphere rejections; a geom is eligible unless
it belongs to the excluded body, is invisible (alpha 0, its material's when it has one) or lies in a left-out group.
Ties go to the lower geom index, as in ``mj_ray``. Meshes, height fields and SDF geoms are not handled: a scene
with an eligible one is refused (:class:`UnsupportedGeom`). The answers are ``mj_ray``'s bit for bit (the same
arithmetic in the same order; tests compare them ray by ray on built scenes and on every primitive shape), at a small
fraction of the cost of one call per ray.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

MINVAL = 1e-15  # MuJoCo's mjMINVAL
NGROUP = 6  # MuJoCo's mjNGROUP
_PLANE, _SPHERE, _CAPSULE, _ELLIPSOID, _CYLINDER, _BOX = (
    int(t)
    for t in (
        mujoco.mjtGeom.mjGEOM_PLANE,
        mujoco.mjtGeom.mjGEOM_SPHERE,
        mujoco.mjtGeom.mjGEOM_CAPSULE,
        mujoco.mjtGeom.mjGEOM_ELLIPSOID,
        mujoco.mjtGeom.mjGEOM_CYLINDER,
        mujoco.mjtGeom.mjGEOM_BOX,
    )
)


class UnsupportedGeom(ValueError):
    """An eligible geom's type has no ray test here (mesh, height field, SDF)."""


@dataclass(frozen=True)
class RayGeoms:
    """A model's geom facts the ray tests read (types, sizes, bodies, groups, visibility)."""

    type: np.ndarray  # (ngeom,)
    size: np.ndarray  # (ngeom, 3)
    body: np.ndarray  # (ngeom,)
    group: np.ndarray  # (ngeom,) clipped to [0, NGROUP - 1]
    visible: np.ndarray  # (ngeom,) bool

    @classmethod
    def of(cls, model: mujoco.MjModel) -> RayGeoms:
        alpha = model.geom_rgba[:, 3].copy()
        material = model.geom_matid >= 0
        alpha[material] = model.mat_rgba[model.geom_matid[material], 3]
        return cls(
            type=model.geom_type.astype(int).copy(),
            size=model.geom_size.astype(float).copy(),
            body=model.geom_bodyid.astype(int).copy(),
            group=np.clip(model.geom_group, 0, NGROUP - 1).astype(int),
            visible=alpha != 0,
        )

    def eligible(self, groups: np.ndarray, exclude_body: int) -> np.ndarray:
        """Indices of the geoms a ray may hit (``groups``: 1 where a group is included)."""
        keep = self.visible & (self.body != exclude_body) & (np.asarray(groups)[self.group] != 0)
        index = np.flatnonzero(keep)
        odd = sorted({int(t) for t in self.type[index]} - set(_TESTS))
        if odd:
            names = ", ".join(mujoco.mjtGeom(t).name for t in odd)
            raise UnsupportedGeom(f"rays cannot be cast against geoms of type {names}")
        return index


def cast(
    geoms: RayGeoms,
    index: np.ndarray,
    xpos: np.ndarray,
    xmat: np.ndarray,
    pnt: np.ndarray,
    vec: np.ndarray,
    exclude: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Rays ``pnt + x * vec`` (w, n, 3) against geoms ``index`` (k,) posed at ``xpos`` (w, k, 3) and ``xmat``
    (w, k, 9), world by world: the least distance x >= 0 (-1 where nothing is hit) and the geom (-1), (w, n).
    ``exclude`` (w, n), when given, is a body each ray leaves out (-1: none), as if its geoms were not in ``index``.

    A capsule, cylinder or box is tested only against the rays that meet its bounding sphere (``mj_ray``'s own first
    rejection), each such pair alone; the other shapes against every ray."""
    shape = pnt.shape[:2]
    if not len(index):
        return np.full(shape, -1.0), np.full(shape, -1, dtype=int)
    x = np.full((*shape, len(index)), -1.0)
    kinds = geoms.type[index]
    with np.errstate(invalid="ignore", divide="ignore"):  # the tests mask what a zero or a NaN makes of a ray
        for kind, test in _TESTS.items():
            cols = np.flatnonzero(kinds == kind)
            if not cols.size:
                continue
            size = geoms.size[index[cols]]  # (c, 3)
            pos, mat = xpos[:, cols], xmat[:, cols]
            if kind not in _BOUND:
                x[..., cols] = test(pos[:, None], mat[:, None], size, pnt[:, :, None], vec[:, :, None])
                continue
            near = _sphere_hit(pos[:, None], _BOUND[kind](size), pnt[:, :, None], vec[:, :, None]) >= 0
            w, n, c = np.nonzero(near)
            x[w, n, cols[c]] = test(pos[w, c], mat[w, c], size[c], pnt[w, n], vec[w, n])
    hit = x >= 0
    if exclude is not None:
        hit &= geoms.body[index][None, None, :] != exclude[:, :, None]
    best = np.argmin(np.where(hit, x, np.inf), axis=2)[..., None]  # the first of equals, as mj_ray keeps the earlier
    found = np.take_along_axis(hit, best, axis=2)[..., 0]
    return np.where(found, np.take_along_axis(x, best, axis=2)[..., 0], -1.0), np.where(found, index[best[..., 0]], -1)


def _local(pos: np.ndarray, mat: np.ndarray, pnt: np.ndarray, vec: np.ndarray) -> tuple[np.ndarray, ...]:
    """The ray in the geom's frame: lpnt = mat' (pnt - pos), lvec = mat' vec, as (x, y, z) components."""
    d0, d1, d2 = pnt[..., 0] - pos[..., 0], pnt[..., 1] - pos[..., 1], pnt[..., 2] - pos[..., 2]
    v0, v1, v2 = vec[..., 0], vec[..., 1], vec[..., 2]
    m = [mat[..., i] for i in range(9)]
    return (
        m[0] * d0 + m[3] * d1 + m[6] * d2,
        m[1] * d0 + m[4] * d1 + m[7] * d2,
        m[2] * d0 + m[5] * d1 + m[8] * d2,
        m[0] * v0 + m[3] * v1 + m[6] * v2,
        m[1] * v0 + m[4] * v1 + m[7] * v2,
        m[2] * v0 + m[5] * v1 + m[8] * v2,
    )


def _quad(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both roots of a x^2 + 2 b x + c = 0 (-1 when none are real) and the least non-negative one (-1: none)."""
    det = b * b - a * c
    ok = (det >= 0) & (a >= MINVAL)
    root = np.sqrt(np.where(ok, det, 0.0))
    x0 = np.where(ok, (-b - root) / np.where(ok, a, 1.0), -1.0)
    x1 = np.where(ok, (-b + root) / np.where(ok, a, 1.0), -1.0)
    least = np.where(x0 >= 0, x0, np.where(x1 >= 0, x1, -1.0))
    return x0, x1, least


def _sphere_hit(pos: np.ndarray, radius_sqr: np.ndarray, pnt: np.ndarray, vec: np.ndarray) -> np.ndarray:
    """MuJoCo's ray_sphere: the least non-negative distance to a sphere of squared radius ``radius_sqr`` (-1)."""
    d0, d1, d2 = pnt[..., 0] - pos[..., 0], pnt[..., 1] - pos[..., 1], pnt[..., 2] - pos[..., 2]
    v0, v1, v2 = vec[..., 0], vec[..., 1], vec[..., 2]
    a = v0 * v0 + v1 * v1 + v2 * v2
    b = v0 * d0 + v1 * d1 + v2 * d2
    c = d0 * d0 + d1 * d1 + d2 * d2 - radius_sqr
    return _quad(a, b, c)[2]


def _nearest(x: np.ndarray, sol: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """``x`` replaced by ``sol`` where ``ok`` and ``sol`` is nearer (or ``x`` is no hit yet)."""
    return np.where(ok & ((x < 0) | (sol < x)), sol, x)


def _plane(pos: np.ndarray, mat: np.ndarray, size: np.ndarray, pnt: np.ndarray, vec: np.ndarray) -> np.ndarray:
    p0, p1, p2, v0, v1, v2 = _local(pos, mat, pnt, vec)
    front = v2 <= -MINVAL
    x = -p2 / np.where(front, v2, -1.0)
    a, b = p0 + x * v0, p1 + x * v1
    inside = ((size[..., 0] <= 0) | (np.abs(a) <= size[..., 0])) & ((size[..., 1] <= 0) | (np.abs(b) <= size[..., 1]))
    return np.where(front & (x >= 0) & inside, x, -1.0)


def _sphere(pos: np.ndarray, mat: np.ndarray, size: np.ndarray, pnt: np.ndarray, vec: np.ndarray) -> np.ndarray:
    return _sphere_hit(pos, size[..., 0] * size[..., 0], pnt, vec)


def _capsule(pos: np.ndarray, mat: np.ndarray, size: np.ndarray, pnt: np.ndarray, vec: np.ndarray) -> np.ndarray:
    r, h = size[..., 0], size[..., 1]
    p0, p1, p2, v0, v1, v2 = _local(pos, mat, pnt, vec)
    x = np.full(np.broadcast_shapes(p0.shape, r.shape), -1.0)
    sol = _quad(v0 * v0 + v1 * v1, v0 * p0 + v1 * p1, p0 * p0 + p1 * p1 - r * r)[2]
    x = _nearest(x, sol, (sol >= 0) & (np.abs(p2 + sol * v2) <= h))
    a = v0 * v0 + v1 * v1 + v2 * v2
    for side in (1.0, -1.0):  # the top cap's upper half, then the bottom cap's lower half
        q2 = p2 - side * h
        roots = _quad(a, v0 * p0 + v1 * p1 + v2 * q2, p0 * p0 + p1 * p1 + q2 * q2 - r * r)[:2]
        for root in roots:
            beyond = (p2 + root * v2 >= h) if side > 0 else (p2 + root * v2 <= -h)
            x = _nearest(x, root, (root >= 0) & beyond)
    return x


def _ellipsoid(pos: np.ndarray, mat: np.ndarray, size: np.ndarray, pnt: np.ndarray, vec: np.ndarray) -> np.ndarray:
    p0, p1, p2, v0, v1, v2 = _local(pos, mat, pnt, vec)
    s0, s1, s2 = (1 / (size[..., i] * size[..., i]) for i in range(3))
    a = s0 * v0 * v0 + s1 * v1 * v1 + s2 * v2 * v2
    b = s0 * v0 * p0 + s1 * v1 * p1 + s2 * v2 * p2
    c = s0 * p0 * p0 + s1 * p1 * p1 + s2 * p2 * p2 - 1
    return _quad(a, b, c)[2]


def _cylinder(pos: np.ndarray, mat: np.ndarray, size: np.ndarray, pnt: np.ndarray, vec: np.ndarray) -> np.ndarray:
    r, h = size[..., 0], size[..., 1]
    p0, p1, p2, v0, v1, v2 = _local(pos, mat, pnt, vec)
    x = np.full(np.broadcast_shapes(p0.shape, r.shape), -1.0)
    axial = np.abs(v2) > MINVAL
    for side in (-1.0, 1.0):
        sol = (side * h - p2) / np.where(axial, v2, 1.0)
        a, b = p0 + sol * v0, p1 + sol * v1
        x = _nearest(x, sol, axial & (sol >= 0) & (a * a + b * b <= r * r))
    sol = _quad(v0 * v0 + v1 * v1, v0 * p0 + v1 * p1, p0 * p0 + p1 * p1 - r * r)[2]
    x = _nearest(x, sol, (sol >= 0) & (np.abs(p2 + sol * v2) <= h))
    return x


def _box(pos: np.ndarray, mat: np.ndarray, size: np.ndarray, pnt: np.ndarray, vec: np.ndarray) -> np.ndarray:
    """The six faces at once (axis-major, each axis's -side first): the nearest face met within its rectangle."""
    local = np.stack(_local(pos, mat, pnt, vec))  # (6, ...): the point's x, y, z, then the direction's
    lp, lv = local[:3], local[3:]
    half = np.stack(np.broadcast_arrays(*(size[..., i] for i in range(3))))  # (3, ...)
    axis, j, k = np.array([0, 0, 1, 1, 2, 2]), np.array([1, 1, 0, 0, 0, 0]), np.array([2, 2, 2, 2, 1, 1])
    side = np.array([-1.0, 1.0] * 3).reshape(6, *([1] * (local.ndim - 1)))
    facing = np.abs(lv[axis]) > MINVAL
    sol = (side * half[axis] - lp[axis]) / np.where(facing, lv[axis], 1.0)
    a, b = lp[j] + sol * lv[j], lp[k] + sol * lv[k]
    ok = facing & (sol >= 0) & (np.abs(a) <= half[j]) & (np.abs(b) <= half[k])
    return np.where(ok.any(axis=0), np.where(ok, sol, np.inf).min(axis=0), -1.0)


def contains(geoms: RayGeoms, geom: np.ndarray, xpos: np.ndarray, xmat: np.ndarray, pnt: np.ndarray) -> np.ndarray:
    """Whether each point ``pnt`` (n, 3) lies inside its geom ``geom`` (n,) posed at ``xpos`` (n, 3) and ``xmat``
    (n, 9): a ray cast from inside a geom meets it where it leaves it (``mj_ray``'s answer), not where it enters. A
    plane holds nothing."""
    zero = np.zeros_like(pnt)
    p0, p1, p2 = _local(xpos, xmat, pnt, zero)[:3]
    size, kind = geoms.size[geom], geoms.type[geom]
    s0, s1, s2 = size[:, 0], size[:, 1], size[:, 2]
    radial = p0 * p0 + p1 * p1
    inside = {
        _SPHERE: lambda: p0 * p0 + p1 * p1 + p2 * p2 < s0 * s0,
        _CAPSULE: lambda: radial + np.maximum(np.abs(p2) - s1, 0.0) ** 2 < s0 * s0,
        _ELLIPSOID: lambda: (p0 / s0) ** 2 + (p1 / s1) ** 2 + (p2 / s2) ** 2 < 1.0,
        _CYLINDER: lambda: (radial < s0 * s0) & (np.abs(p2) < s1),
        _BOX: lambda: (np.abs(p0) < s0) & (np.abs(p1) < s1) & (np.abs(p2) < s2),
    }
    out = np.zeros(len(geom), dtype=bool)
    with np.errstate(invalid="ignore", divide="ignore"):
        for shape in np.unique(kind):  # only the shapes there are
            if int(shape) in inside:
                out |= (kind == shape) & inside[int(shape)]()
    return out


_BOUND = {  # the squared radius of the sphere mj_ray tests first, by shape
    _CAPSULE: lambda size: (size[:, 0] + size[:, 1]) * (size[:, 0] + size[:, 1]),
    _CYLINDER: lambda size: size[:, 0] * size[:, 0] + size[:, 1] * size[:, 1],
    _BOX: lambda size: size[:, 0] * size[:, 0] + size[:, 1] * size[:, 1] + size[:, 2] * size[:, 2],
}
_TESTS = {
    _PLANE: _plane,
    _SPHERE: _sphere,
    _CAPSULE: _capsule,
    _ELLIPSOID: _ellipsoid,
    _CYLINDER: _cylinder,
    _BOX: _box,
}
