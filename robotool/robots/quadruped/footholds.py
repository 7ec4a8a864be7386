"""Footholds narrower than a foot: a round foot stands on a surface only where the surface is about as wide as it.

A downward ray reads the height under a foot's centre, so a 4 mm blade on edge, or the crest of a ridge, reads as full
footing there, though no foot balances on it. Where a ray hits a surface whose top may be narrower than the foot
(:meth:`Footholds.narrow`: a box or an upright cylinder whose top face is narrower than the foot's diameter, a box or
a cylinder tilted so that no face lies level on top, a sphere, a capsule, an ellipsoid), four more rays are read a
foot's radius to either side of it, along the path and across it (:func:`side_points`). Where both rays of a pair
read more than a foot's radius lower (the surface falls away steeper than 45 degrees on both sides: a blade, a ridge,
a ball's crown), the foot has nothing to stand on there and comes down to the higher of that pair
(:func:`comes_down_to`). A surface as wide as the foot on one side of the centre at least (a step's edge, a corner)
carries it as before.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from robotool.robots.quadruped.terrain import FOOT_RADIUS
from robotool.sim.backend import BatchState
from robotool.sim.strikes import GeomFrames

LEVEL = float(np.cos(np.radians(10.0)))  # a face whose normal is within 10 degrees of vertical lies level
_BOX, _CYLINDER, _PLANE = (
    int(t) for t in (mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_CYLINDER, mujoco.mjtGeom.mjGEOM_PLANE)
)


@dataclass(frozen=True)
class Footholds:
    """A model's geoms as footholds: which may have a top narrower than a foot, as they lie in each world."""

    kind: np.ndarray  # (ngeom,) MuJoCo geom types
    size: np.ndarray  # (ngeom, 3) MuJoCo geom sizes
    frames: GeomFrames  # every geom's body and pose in it

    @classmethod
    def of(cls, model: mujoco.MjModel) -> Footholds:
        return cls(model.geom_type.copy(), model.geom_size.copy(), GeomFrames.of(model, np.arange(model.ngeom)))

    def narrow(self, state: BatchState, worlds: np.ndarray, geoms: np.ndarray) -> np.ndarray:
        """Whether the top of each hit geom ``geoms`` (k, ...) (-1: none) in ``worlds`` (k,) may be narrower than a
        foot where the ray met it (module docstring), as the geom lies in that world now."""
        hit = np.unique(geoms[geoms >= 0])
        out = np.zeros(geoms.shape, dtype=bool)
        if not hit.size:
            return out
        frame = state.frames()[worlds[:, None], self.frames.body[hit]] @ self.frames.rot[hit]  # (k, m, 3, 3): axes
        up = np.abs(frame[:, :, 2, :])  # (k, m, 3): how vertical each of the geom's axes lies
        kind, size = self.kind[hit], self.size[hit]
        diameter = 2.0 * FOOT_RADIUS
        vertical = np.argmax(up, axis=2)  # the box axis nearest vertical: its faces across it are the top
        level = np.take_along_axis(up, vertical[..., None], axis=2)[..., 0] >= LEVEL
        others = np.sort(np.stack([np.roll(size, -a, axis=1)[:, 1:] for a in range(3)], axis=1), axis=2)  # (m, 3, 2)
        box_width = 2.0 * np.take_along_axis(others[None, :, :, 0], vertical[..., None], axis=2)[..., 0]
        box_narrow = ~level | (box_width < diameter)
        cylinder_narrow = (up[:, :, 2] < LEVEL) | (2.0 * size[None, :, 0] < diameter)
        flag = np.where(
            kind == _BOX, box_narrow, np.where(kind == _CYLINDER, cylinder_narrow, kind[None, :] != _PLANE)
        )  # a sphere, capsule or ellipsoid has a rounded top
        rows = np.broadcast_to(np.arange(len(worlds)).reshape(-1, *([1] * (geoms.ndim - 1))), geoms.shape)
        at = geoms >= 0
        out[at] = flag[rows[at], np.searchsorted(hit, geoms[at])]
        return out


def side_points(points: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The four points (..., 4, 2) a foot's radius from each of ``points`` (..., 2): ahead and behind along the unit
    directions ``u`` (..., 2; broadcast against ``points``), then left and right across them."""
    across = np.stack([-u[..., 1], u[..., 0]], axis=-1)
    offsets = FOOT_RADIUS * np.stack(np.broadcast_arrays(u, -u, across, -across), axis=-2)
    return points[..., None, :] + offsets


def comes_down_to(centre: np.ndarray, sides: np.ndarray) -> np.ndarray:
    """Which of the four side readings ``sides`` (..., 4) (:func:`side_points`) a foot over a point read at
    ``centre`` (...) comes down to (-1: none, it stands at the centre): where both readings of a pair lie more than a
    foot's radius lower, the higher of that pair (of either pair, where both fall away)."""
    low = sides < centre[..., None] - FOOT_RADIUS
    pair_falls = low[..., 0::2] & low[..., 1::2]  # (..., 2): along the path, across it
    falls = np.repeat(pair_falls, 2, axis=-1)  # each side reading's pair
    best = np.argmax(np.where(falls, sides, -np.inf), axis=-1)
    return np.where(pair_falls.any(axis=-1), best, -1)
