"""robotool: creative robot tool use with language models.

Public API, re-exported by name; everything else may move. The simulator- and DSPy-backed names
(``RoboTool``, ``run``, ``Solution``, ``RunReport``) load on first use, so ``import robotool`` stays quick.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

# gl_backend first: MuJoCo picks its OpenGL back end when it is imported (no display: EGL, where installed).
from robotool import gl_backend, tasks  # noqa: F401
from robotool.robots import arm, quadruped, registry
from robotool.task.concepts import KeyConcept, key_concepts, needs_tool
from robotool.task.describe import describe
from robotool.task.task_file import Problem, TaskFileError, load_task
from robotool.task.task_model import Task

# The built-in robots; plug-ins register on the registry's first lookup.
registry.register(arm.ROBOT)
registry.register(quadruped.ROBOT)

if TYPE_CHECKING:
    from robotool.execute import RunReport, run
    from robotool.program.lm_program import RoboTool
    from robotool.solution import Solution

_LAZY = {
    "RoboTool": "robotool.program.lm_program",
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
