"""Which OpenGL back end MuJoCo's renderer uses, chosen when this module is imported (before MuJoCo is).

Without a display, pictures are drawn off screen through EGL. Where the EGL library is missing (no Mesa or GPU
driver installed), MuJoCo's OpenGL back end is switched off instead, so that ``import mujoco`` still works and
only drawing fails, with :data:`UNAVAILABLE` saying why and how to get it; so does a ``MUJOCO_GL`` that MuJoCo does
not know, or OSMesa without its library (MuJoCo would not be imported at all).
"""

from __future__ import annotations

import ctypes
import ctypes.util
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


_OFF = ("disable", "disabled", "off", "false", "0")  # the values by which MuJoCo's OpenGL back end is switched off
_ON = ("", "enable", "enabled", "on", "true", "1", "glfw")  # those it takes everywhere, and on each platform:
_PLATFORM_BACK_ENDS = {"linux": ("glx", "egl", "osmesa"), "win32": ("wgl",), "darwin": ("cgl",)}


def _refused(chosen: str) -> str | None:
    """Why MuJoCo cannot be imported with ``MUJOCO_GL=chosen`` here (None: it can): a value it does not know, or
    OSMesa without its library (the import itself fails)."""
    value = chosen.lower().strip()
    platform = next((p for p in _PLATFORM_BACK_ENDS if sys.platform.startswith(p)), "")
    if value not in (*_OFF, *_ON, *_PLATFORM_BACK_ENDS.get(platform, ())):
        return f"MUJOCO_GL={chosen!r} is not an OpenGL back end MuJoCo knows (unset it to let robotool choose)"
    if value == "osmesa" and ctypes.util.find_library("OSMesa") is None:
        return "MUJOCO_GL=osmesa, but the OSMesa library is not installed (Debian: libosmesa6; or unset MUJOCO_GL)"
    return None


def choose() -> None:
    """Set ``MUJOCO_GL`` for a Linux machine without a display: ``egl`` when its library loads, else ``disable``. A
    ``MUJOCO_GL`` with which MuJoCo could not be imported switches drawing off, :data:`UNAVAILABLE` saying why."""
    global UNAVAILABLE
    refused = _refused(os.environ["MUJOCO_GL"]) if "MUJOCO_GL" in os.environ else None
    if refused is not None:
        os.environ["MUJOCO_GL"] = "disable"
        UNAVAILABLE = refused
        return
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
