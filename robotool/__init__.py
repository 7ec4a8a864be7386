"""robotool: creative robot tool use with language models.

Public API, re-exported by name; everything else may move. The simulator- and DSPy-backed names
(``RoboTool``, ``run``, ``Solution``, ``RunReport``) load on first use, so ``import robotool`` stays quick.
"""

from __future__ import annotations

import os
import sys
from importlib import import_module
from typing import TYPE_CHECKING, Any

# MuJoCo picks its OpenGL back end when it is imported; without a display, draw off screen through EGL.
if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
    os.environ.setdefault("MUJOCO_GL", "egl")

from robotool import tasks
from robotool.concepts import KeyConcept, key_concepts, needs_tool
from robotool.describe import describe
from robotool.robots import arm, quadruped, registry
from robotool.task_file import Problem, TaskFileError, load_task
from robotool.task_model import Task

# The built-in robots; plug-ins register on the registry's first lookup.
registry.register(arm.ROBOT)
registry.register(quadruped.ROBOT)

if TYPE_CHECKING:
    from robotool.execute import RunReport, run
    from robotool.lm_program import RoboTool
    from robotool.solution import Solution

_LAZY = {
    "RoboTool": "robotool.lm_program",
    "RunReport": "robotool.execute",
    "Solution": "robotool.solution",
    "run": "robotool.execute",
}

__all__ = [
    "KeyConcept",
    "Problem",
    "RoboTool",
    "RunReport",
    "Solution",
    "Task",
    "TaskFileError",
    "describe",
    "key_concepts",
    "load_task",
    "needs_tool",
    "run",
    "tasks",
]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'robotool' has no attribute {name!r}")
