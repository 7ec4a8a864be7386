"""A fixed camera that keeps a set of points in view, looking from a side chosen per robot.

The points are the corners of every drawn geom's box (robot, tools, furniture, goal markers) over all the
states to be shown, so the robot's whole path stays in the frame. The camera looks across the longer
horizontal side of those bounds at an angle the robot chose (``RobotType.pictures.view``), and backs off until every
point is inside the picture with a margin.
"""

from __future__ import annotations

import mujoco
import numpy as np

from robotool.robots import PictureSettings

MARGIN = 1.08  # distance factor over the tightest fit (room for the labels)
PLANE = mujoco.mjtGeom.mjGEOM_PLANE


def visible_geoms(model: mujoco.MjModel) -> np.ndarray:
    """Indices of the geoms that are drawn and bounded (not planes, not fully transparent)."""
    return np.flatnonzero((model.geom_type != PLANE) & (model.geom_rgba[:, 3] > 0))


def geom_corners(model: mujoco.MjModel, data: mujoco.MjData, geoms: np.ndarray) -> np.ndarray:
    """World corners (8 * len(geoms), 3) of the bounding boxes of ``geoms`` in ``data``'s state."""
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    centre, half = model.geom_aabb[geoms, :3], model.geom_aabb[geoms, 3:]
    local = centre[:, None, :] + signs[None, :, :] * half[:, None, :]  # (n, 8, 3)
    rot = data.geom_xmat[geoms].reshape(-1, 3, 3)
    world = np.einsum("nij,nkj->nki", rot, local) + data.geom_xpos[geoms][:, None, :]
    return world.reshape(-1, 3)


def fit_camera(points: np.ndarray, view: PictureSettings, aspect: float, fovy_deg: float) -> mujoco.MjvCamera:
    """A free camera that sees every point of ``points`` (n, 3) at ``aspect`` (width / height)."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    lookat = (lo + hi) / 2
    extent = hi - lo
    # Look across the longer horizontal side: along +y when the scene is long in x, else along -x.
    side = 90.0 if extent[0] >= extent[1] else 180.0
    azimuth = side + view.turn
    az, el = np.radians(azimuth), np.radians(view.elevation)
    forward = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rel = points - lookat
    depth, across, rise = rel @ forward, rel @ right, rel @ up
    tan_v = np.tan(np.radians(fovy_deg) / 2)
    tan_h = tan_v * aspect
    distance = float(np.max(np.maximum(np.abs(across) / tan_h, np.abs(rise) / tan_v) - depth))
    camera = mujoco.MjvCamera()
    camera.type = mujoco.mjtCamera.mjCAMERA_FREE
    camera.lookat[:] = lookat
    camera.azimuth, camera.elevation = azimuth, view.elevation
    camera.distance = max(distance * MARGIN, 0.2)
    return camera
