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

from dataclasses import dataclass, field

import mujoco
import numpy as np

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
    _eligible: dict[tuple[bytes, int], np.ndarray] = field(default_factory=dict, init=False, repr=False, compare=False)
    _picked: dict[bytes, GeomFacts] = field(default_factory=dict, init=False, repr=False, compare=False)

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
        """Indices of the geoms a ray may hit (``groups``: 1 where a group is included), found once per ``groups`` and
        ``exclude_body`` (read-only)."""
        groups = np.asarray(groups)
        key = (groups.tobytes(), int(exclude_body))
        index = self._eligible.get(key)
        if index is None:
            index = np.flatnonzero(self.visible & (self.body != exclude_body) & (groups[self.group] != 0))
            odd = sorted({int(t) for t in self.type[index]} - _SUPPORTED)
            if odd:
                names = ", ".join(mujoco.mjtGeom(t).name for t in odd)
                raise UnsupportedGeom(f"rays cannot be cast against geoms of type {names}")
            self._eligible[key] = index
        return index

    def picked(self, index: np.ndarray) -> GeomFacts:
        """The facts of geoms ``index`` as the kernels read them, found once per ``index`` (read-only)."""
        key = np.asarray(index, dtype=np.int64).tobytes()
        facts = self._picked.get(key)
        if facts is None:
            facts = self._picked[key] = GeomFacts(
                type=self.type[index].astype(np.int32),
                size=np.ascontiguousarray(self.size[index]),
                bound=np.ascontiguousarray(self.bound[index]),
                body=self.body[index].astype(np.int32),
            )
        return facts


@dataclass(frozen=True)
class GeomFacts:
    """Some geoms' facts, as the kernels read them."""

    type: np.ndarray  # (k,) int32
    size: np.ndarray  # (k, 3)
    bound: np.ndarray  # (k,) the squared radius of the bounding sphere a ray must meet first (0: none tested)
    body: np.ndarray  # (k,) int32


def cast(
    geoms: RayGeoms,
    index: np.ndarray,
    xpos: np.ndarray,
    xmat: np.ndarray,
    pnt: np.ndarray,
    vec: np.ndarray,
    exclude: np.ndarray | None = None,
    from_inside: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Rays ``pnt + x * vec`` (w, n, 3) against geoms ``index`` (k,) posed at ``xpos`` (w, k, 3) and ``xmat``
    (w, k, 9), world by world: the least distance x >= 0 (-1 where nothing is hit) and the geom (-1), (w, n).
    ``exclude`` (w, n), when given, is a body each ray leaves out (-1: none), as if its geoms were not in ``index``.
    With ``from_inside``, a ray that starts inside one of the geoms meets it at its start (distance 0; the geom
    :func:`inside` finds), not where it leaves it (``mj_ray``'s answer).

    A capsule, cylinder or box is tested only against the rays that meet its bounding sphere (``mj_ray``'s own first
    rejection)."""
    from robotool.sim import ray_kernel  # Warp loads on the first ray cast, not on every import

    shape = pnt.shape[:2]
    if not len(index):
        return np.full(shape, -1.0), np.full(shape, -1, dtype=int)
    picked = geoms.picked(index)
    x, hit = ray_kernel.cast(
        picked.type,
        picked.size,
        picked.bound,
        picked.body,
        xpos,
        xmat,
        pnt,
        vec,
        np.full(shape, -1) if exclude is None else exclude,
        from_inside,
    )
    return x, np.where(hit >= 0, index[np.maximum(hit, 0)], -1)


def inside(
    geoms: RayGeoms,
    candidates: np.ndarray,
    xpos: np.ndarray,
    xmat: np.ndarray,
    pnt: np.ndarray,
    exclude: np.ndarray | None = None,
) -> np.ndarray:
    """The geom among ``candidates`` (k,), posed at ``xpos`` (w, k, 3) and ``xmat`` (w, k, 9), that each point ``pnt``
    (w, n, 3) lies inside (the last of several; -1: none), (w, n): a ray cast from inside a geom meets it where it
    leaves it (``mj_ray``'s answer), not where it enters. ``exclude`` (w, n), when given, is a body each point leaves
    out (-1: none). A plane holds nothing."""
    from robotool.sim import ray_kernel  # Warp loads on the first use, not on every import

    shape = pnt.shape[:2]
    if not len(candidates):
        return np.full(shape, -1)
    picked = geoms.picked(candidates)
    found = ray_kernel.inside(
        picked.type,
        picked.size,
        picked.body,
        xpos,
        xmat,
        pnt,
        np.full(shape, -1) if exclude is None else exclude,
    )
    return np.where(found >= 0, candidates[np.maximum(found, 0)], -1)


_SUPPORTED = {_PLANE, _SPHERE, _CAPSULE, _ELLIPSOID, _CYLINDER, _BOX}  # the shapes the ray tests handle


def _bound(kind: np.ndarray, size: np.ndarray) -> np.ndarray:
    """The squared radius of the sphere ``mj_ray`` tests first, by shape (capsule, cylinder, box; 0 for the rest)."""
    s0, s1, s2 = size[:, 0], size[:, 1], size[:, 2]
    return np.select(
        [kind == _CAPSULE, kind == _CYLINDER, kind == _BOX],
        [(s0 + s1) * (s0 + s1), s0 * s0 + s1 * s1, s0 * s0 + s1 * s1 + s2 * s2],
        0.0,
    )
