"""robotool: creative robot tool use with language models.

Public API, re-exported by name; everything else may move.
"""

from robotool import tasks
from robotool.scene import Problem, Task, TaskFileError, load_task

__all__ = ["Problem", "Task", "TaskFileError", "load_task", "tasks"]
