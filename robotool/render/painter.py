"""Draw a scene's state headless with MuJoCo's renderer (:mod:`robotool.render.offscreen`), from a fixed camera,
with its objects labelled.

Off screen on Linux without a display this uses EGL (``MUJOCO_GL=egl``, set by ``import robotool`` when
no display is present); Mesa's software EGL works on machines without a GPU.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import mujoco
import numpy as np
from PIL import Image

from robotool import gl_backend, robots
from robotool.errors import RobotoolError
from robotool.render.camera import fit_camera, geom_corners, visible_geoms
from robotool.render.offscreen import OffscreenRenderer
from robotool.render.overlay import CaptionLine, Label, draw_caption, draw_labels, to_image
from robotool.render.picture_model import ROBOT_RGBA, RenderModel, render_model
from robotool.sim.compiled_scene import Scene


class RenderError(RobotoolError):
    """The picture cannot be drawn here (no OpenGL context, a size over the limit)."""


def _renderer(model: mujoco.MjModel, width: int, height: int) -> OffscreenRenderer:
    limit = (model.vis.global_.offwidth, model.vis.global_.offheight)
    if not (16 <= width <= limit[0] and 16 <= height <= limit[1]):
        raise RenderError(f"picture size {width}x{height} is outside 16x16 .. {limit[0]}x{limit[1]} pixels")
    if gl_backend.UNAVAILABLE is not None:
        raise RenderError(gl_backend.UNAVAILABLE)
    try:
        return OffscreenRenderer(model, width, height)
    except Exception as e:  # the GL back ends raise several kinds (ImportError, RuntimeError, their own)
        raise RenderError(
            f"cannot open an OpenGL context for rendering (MUJOCO_GL={os.environ.get('MUJOCO_GL', '')!r}): {e}; "
            f"without a display, set MUJOCO_GL=egl before Python starts and install the Debian packages "
            f"{gl_backend.GL_PACKAGES}"
        ) from e


def _rgb255(rgba: Sequence[float]) -> tuple[int, int, int]:
    return (round(255 * rgba[0]), round(255 * rgba[1]), round(255 * rgba[2]))


class Painter:
    """Pictures of one scene at ``width`` x ``height`` pixels from one camera.

    The camera keeps in view every geom in each of ``frame_qpos`` (states (T, nq) to be shown; default the
    start state), so a whole rollout can be shown from one viewpoint; :meth:`frame` fits it to other states
    (one painter, and one OpenGL context, for many pictures). ``shadows`` applies when a scene is given.
    Call :meth:`close` when done.
    """

    def __init__(
        self,
        scene: Scene | RenderModel,
        width: int,
        height: int,
        frame_qpos: np.ndarray | None = None,
        *,
        shadows: bool = True,
    ):
        self.drawing = scene if isinstance(scene, RenderModel) else render_model(scene, shadows=shadows)
        self.scene = self.drawing.scene
        model = self.drawing.model
        self.data = mujoco.MjData(model)
        self.width, self.height = width, height
        self._renderer = _renderer(model, width, height)
        self.frame(frame_qpos)

    def frame(self, frame_qpos: np.ndarray | None = None) -> None:
        """Fit the camera to keep every geom in view in each state of ``frame_qpos`` (default: the start state),
        and show the first of them."""
        model = self.drawing.model
        states = np.atleast_2d(frame_qpos) if frame_qpos is not None else self.scene.model.qpos0[None, :]
        corners = []
        shown = visible_geoms(model)
        for qpos in states:
            self.data.qpos[:] = qpos
            mujoco.mj_kinematics(model, self.data)
            corners.append(geom_corners(model, self.data, shown))
        self.camera = fit_camera(
            np.concatenate(corners),
            robots.get(self.scene.task.embodiment).pictures.view,
            self.width / self.height,
            float(model.vis.global_.fovy),
        )
        self.set_state(states[0])

    def set_state(self, qpos: np.ndarray, mocap_pos: np.ndarray | None = None) -> None:
        """Show the state ``qpos`` (and the mocap bodies at ``mocap_pos``)."""
        self.data.qpos[:] = qpos
        if mocap_pos is not None and mocap_pos.size:
            self.data.mocap_pos[:] = mocap_pos
        mujoco.mj_kinematics(self.drawing.model, self.data)

    def pixels(self) -> np.ndarray:
        """The current state rendered, (height, width, 3) uint8."""
        self._renderer.update_scene(self.data, self.camera)
        return self._renderer.render()

    def project(self, points: np.ndarray) -> np.ndarray:
        """Pixel (column, row) of world points (n, 3) in the current camera; NaN behind the camera."""
        cams = self._renderer.scene.camera  # two eyes; a mono picture is taken from between them
        glcam = cams[0]
        pos = (np.asarray(cams[0].pos) + np.asarray(cams[1].pos)) / 2
        forward, up = np.asarray(glcam.forward), np.asarray(glcam.up)
        right = np.cross(forward, up)
        rel = np.atleast_2d(points) - pos
        depth = rel @ forward
        near = glcam.frustum_near
        # a zero frustum width means "from the picture's aspect", as the renderer does
        half_width = glcam.frustum_width or (glcam.frustum_top - glcam.frustum_bottom) / 2 * self.width / self.height
        with np.errstate(divide="ignore", invalid="ignore"):
            x = (rel @ right) * near / depth
            y = (rel @ up) * near / depth
        u = (x - (glcam.frustum_center - half_width)) / (2 * half_width)
        v = (y - glcam.frustum_bottom) / (glcam.frustum_top - glcam.frustum_bottom)
        out = np.stack([u * self.width, (1 - v) * self.height], axis=1)
        out[depth <= 0] = np.nan
        return out

    def labels(self) -> list[Label]:
        """A label for the robot and each object, at the top centre of its geoms in the current state."""
        model, scene = self.drawing.model, self.scene
        owner = np.where(scene.robot_body, -2, scene.body_object)[model.geom_bodyid]
        names = [*scene.object_names, "robot"]
        colours = [*self.drawing.object_rgba, ROBOT_RGBA]
        goal = scene.task.goal.object
        anchors, texts, swatches = [], [], []
        for k, name in enumerate(names):
            geoms = np.flatnonzero(owner == (k if k < len(scene.object_names) else -2))
            if geoms.size == 0:
                continue
            top = self._top_centre(geoms)
            anchors.append(top)
            texts.append(f"{name} (goal)" if name == goal else name)
            swatches.append(_rgb255(colours[k]))
        pixels = self.project(np.array(anchors))
        return [
            Label(text, (float(p[0]), float(p[1])), colour)
            for text, p, colour in zip(texts, pixels, swatches, strict=True)
            if np.isfinite(p).all()
        ]

    def _top_centre(self, geoms: np.ndarray) -> np.ndarray:
        """Top centre of the one of ``geoms`` nearest the middle of them all (on the object even for an L)."""
        model = self.drawing.model
        corners = geom_corners(model, self.data, geoms).reshape(len(geoms), 8, 3)
        middle = (corners.min(axis=(0, 1)) + corners.max(axis=(0, 1))) / 2
        centres = corners.mean(axis=1)
        nearest = corners[np.argmin(np.linalg.norm(centres[:, :2] - middle[:2], axis=1))]
        lo, hi = nearest.min(axis=0), nearest.max(axis=0)
        return np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, hi[2]])

    def picture(self, *, title: Sequence[CaptionLine] = (), caption: Sequence[CaptionLine] = ()) -> Image.Image:
        """The current state with a title band on top, a caption band below and the objects labelled."""
        image = to_image(self.pixels())
        bands = [draw_caption(image, title, at_top=True), draw_caption(image, caption, at_top=False)]
        draw_labels(image, self.labels(), avoid=[b for b in bands if b[3] > b[1]])
        return image

    def close(self) -> None:
        """Free the model's render context."""
        self._renderer.close()
