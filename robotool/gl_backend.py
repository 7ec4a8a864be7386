"""Which OpenGL back end MuJoCo's renderer uses, chosen when this module is imported (before MuJoCo is).

Without a display, pictures are drawn off screen through EGL. Where the EGL library is missing (no Mesa or GPU
driver installed), MuJoCo's OpenGL back end is switched off instead, so that ``import mujoco`` still works and
only drawing fails, with :data:`UNAVAILABLE` saying why and how to get it.
"""

from __future__ import annotations

import ctypes
import os
import sys

GL_PACKAGES = "libegl1 libegl-mesa0 libgl1-mesa-dri libopengl0"  # Debian packages behind MUJOCO_GL=egl
EGL_LIBRARY = "libEGL.so.1"

UNAVAILABLE: str | None = None
"""Why nothing can be drawn on this machine (None: a back end was chosen, or the user chose one)."""


def _loadable(library: str) -> bool:
    try:
        ctypes.CDLL(library)
    except OSError:
        return False
    return True


def choose() -> None:
    """Set ``MUJOCO_GL`` for a Linux machine without a display: ``egl`` when its library loads, else ``disable``."""
    global UNAVAILABLE
    if not sys.platform.startswith("linux") or os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return
    if os.environ.get("MUJOCO_GL", "egl").lower().strip() != "egl":
        return  # the user's choice
    if _loadable(EGL_LIBRARY):
        os.environ.setdefault("MUJOCO_GL", "egl")
        return
    os.environ["MUJOCO_GL"] = "disable"
    UNAVAILABLE = (
        f"no display and no EGL library ({EGL_LIBRARY}) to draw off screen: install the Debian packages {GL_PACKAGES}"
    )


choose()
