"""Off-screen drawing of a MuJoCo scene into an image, with one OpenGL context per thread shared by every model.

``mujoco.Renderer`` opens an OpenGL context for each renderer, and MuJoCo's render context made in a fresh OpenGL
context costs about 0.15-0.25 s on Mesa's software renderer (its shaders are compiled again): most of the time a
report's pictures took. Here a thread opens its OpenGL context once and keeps it for its lifetime; each model only
gets MuJoCo's render context (its textures and offscreen buffer, the picture's size), about 0.01 s.
"""

from __future__ import annotations

import threading

import mujoco
import numpy as np
from mujoco import gl_context

_THREAD = threading.local()
_CONTEXT_SIZE = (64, 64)  # px of the context's own surface: pictures are drawn in MuJoCo's offscreen buffer


def _current_context() -> gl_context.GLContext:
    """This thread's OpenGL context (opened on first use, kept until the thread ends), made current."""
    context = getattr(_THREAD, "context", None)
    if context is None:
        context = gl_context.GLContext(*_CONTEXT_SIZE)
        _THREAD.context = context
    context.make_current()
    return context


class OffscreenRenderer:
    """Draws states of ``model`` as ``height`` x ``width`` RGB images (the model's offscreen buffer must be at least
    that size); use it from the thread that made it, and :meth:`close` it when done."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int, max_geom: int = 10000) -> None:
        self.model = model
        self.width, self.height = width, height
        self.scene = mujoco.MjvScene(model=model, maxgeom=max_geom)
        self._option = mujoco.MjvOption()
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._context = _current_context()
        buffer = model.vis.global_
        limit = (buffer.offwidth, buffer.offheight)
        try:  # the offscreen buffer the picture's size: the same pixels, a render context made faster
            buffer.offwidth, buffer.offheight = width, height
            self._mjr: mujoco.MjrContext | None = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_50.value)
        finally:
            buffer.offwidth, buffer.offheight = limit
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._mjr)

    def update_scene(self, data: mujoco.MjData, camera: mujoco.MjvCamera) -> None:
        """Take the geometry to draw from ``data``, seen from ``camera``."""
        mujoco.mjv_updateScene(
            self.model, data, self._option, None, camera, mujoco.mjtCatBit.mjCAT_ALL.value, self.scene
        )

    def render(self) -> np.ndarray:
        """The scene drawn, (height, width, 3) uint8, top row first."""
        if self._mjr is None:
            raise RuntimeError("render() after close()")
        self._context.make_current()
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._mjr)
        mujoco.mjr_render(self._rect, self.scene, self._mjr)
        pixels = np.empty((self.height, self.width, 3), dtype=np.uint8)
        mujoco.mjr_readPixels(pixels, None, self._rect, self._mjr)
        return np.flipud(pixels)

    def close(self) -> None:
        """Free MuJoCo's render context (the thread's OpenGL context stays for the next model)."""
        if self._mjr is not None:
            self._context.make_current()
            self._mjr.free()
            self._mjr = None
