"""MuJoCo's ``mj_ray`` for many rays at once: each ray against every eligible geom, the nearest hit kept.

The per-shape tests follow MuJoCo's own (``engine_ray.c``) and run compiled (:mod:`robotool.sim.ray_kernel`): the ray
is mapped into the geom's frame, a plane is hit from its front only and within its size (a size of 0: unbounded), a
sphere, capsule, ellipsoid, cylinder or box by its surface at the least non-negative distance, with the same
bounding-sphere rejections; a geom is eligible unless it belongs to the excluded body, is invisible (alpha 0, its
material's when it has one) or lies in a left-out group. Ties go to the lower geom index, as in ``mj_ray``. Meshes,
height fields and SDF geoms are not handled: a scene with an eligible one is refused (:class:`UnsupportedGeom`). The
answers are ``mj_ray``'s bit for bit (the same arithmetic in the same order; tests compare them ray by ray on built
scenes and on every primitive shape), at a small fraction of the cost of one call per ray.
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
    bound: np.ndarray  # (ngeom,) the squared radius of the bounding sphere a ray must meet first (0: none tested)

    @classmethod
    def of(cls, model: mujoco.MjModel) -> RayGeoms:
        alpha = model.geom_rgba[:, 3].copy()
        material = model.geom_matid >= 0
        alpha[material] = model.mat_rgba[model.geom_matid[material], 3]
        kind, size = model.geom_type.astype(int).copy(), model.geom_size.astype(float).copy()
        return cls(
            type=kind,
            size=size,
            body=model.geom_bodyid.astype(int).copy(),
            group=np.clip(model.geom_group, 0, NGROUP - 1).astype(int),
            visible=alpha != 0,
            bound=_bound(kind, size),
        )

    def eligible(self, groups: np.ndarray, exclude_body: int) -> np.ndarray:
        """Indices of the geoms a ray may hit (``groups``: 1 where a group is included)."""
        keep = self.visible & (self.body != exclude_body) & (np.asarray(groups)[self.group] != 0)
        index = np.flatnonzero(keep)
        odd = sorted({int(t) for t in self.type[index]} - _SUPPORTED)
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
    rejection)."""
    from robotool.sim import ray_kernel  # Warp loads on the first ray cast, not on every import

    shape = pnt.shape[:2]
    if not len(index):
        return np.full(shape, -1.0), np.full(shape, -1, dtype=int)
    x, hit = ray_kernel.cast(
        geoms.type[index],
        geoms.size[index],
        geoms.bound[index],
        geoms.body[index],
        xpos,
        xmat,
        pnt,
        vec,
        np.full(shape, -1) if exclude is None else exclude,
    )
    return x, np.where(hit >= 0, index[np.maximum(hit, 0)], -1)


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


_SUPPORTED = {_PLANE, _SPHERE, _CAPSULE, _ELLIPSOID, _CYLINDER, _BOX}  # the shapes the ray tests handle


def _bound(kind: np.ndarray, size: np.ndarray) -> np.ndarray:
    """The squared radius of the sphere ``mj_ray`` tests first, by shape (capsule, cylinder, box; 0 for the rest)."""
    s0, s1, s2 = size[:, 0], size[:, 1], size[:, 2]
    return np.select(
        [kind == _CAPSULE, kind == _CYLINDER, kind == _BOX],
        [(s0 + s1) * (s0 + s1), s0 * s0 + s1 * s1, s0 * s0 + s1 * s1 + s2 * s2],
        0.0,
    )
