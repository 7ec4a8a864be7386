"""Cloth (``shape: cloth``): a chain of thin links joined by free hinges, so it drapes and sags.

The strip is cut across its long side into links about ``LINK_LENGTH`` long. Each link is a box of
the strip's full width and thickness; neighbours turn freely about the width axis (a little damping,
no stiffness), so the strip lies flat on a surface, hangs over an edge and sags into a gap instead of
spanning it. The first link is the body named after the object (with a free joint); the others are
nested under it, so every link maps to the object. Rays see the links where they really are.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from robotool.task import geometry
from robotool.task.scene import SceneObject

LINK_LENGTH = 0.1  # m
HINGE_DAMPING = 0.002  # N m s/rad
CLOTH_FRICTION = 0.6


def _quat(rot: np.ndarray) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(rot).reshape(-1))
    return q


def add_cloth(spec: mujoco.MjSpec, obj: SceneObject) -> None:
    """Add cloth ``obj`` to ``spec`` as a hinged chain of links along its longer side."""
    sx, sy, sz = obj.size
    along = 0 if sx >= sy else 1
    length, width = (sx, sy) if along == 0 else (sy, sx)
    count = max(2, math.ceil(length / LINK_LENGTH))
    link = length / count
    axis, across = np.eye(3)[along], np.eye(3)[1 - along]
    half = np.abs(axis) * link / 2 + np.abs(across) * width / 2 + np.array([0, 0, sz / 2])
    rot = geometry.rotation_matrix(obj.rpy)
    first = np.asarray(obj.center) + rot @ (axis * (link - length) / 2)
    geom = {
        "type": mujoco.mjtGeom.mjGEOM_BOX,
        "size": half,
        "mass": obj.effective_mass / count,
        "friction": [obj.friction or CLOTH_FRICTION, 0.005, 0.0001],
    }
    body = spec.worldbody.add_body(name=obj.name, pos=first, quat=_quat(rot))
    body.add_freejoint(name=f"{obj.name}__free")
    body.add_geom(**geom)
    for i in range(1, count):
        body = body.add_body(name=f"{obj.name}__link{i}", pos=axis * link)
        body.add_joint(
            name=f"{obj.name}__hinge{i}",
            type=mujoco.mjtJoint.mjJNT_HINGE,
            axis=across,
            pos=-axis * link / 2,
            damping=HINGE_DAMPING,
            armature=1e-4,
        )
        body.add_geom(**geom)
