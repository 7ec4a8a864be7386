"""robotool: creative robot tool use with language models.

Public API, re-exported by name; everything else may move.
"""

from robotool import tasks
from robotool.concepts import KeyConcept, key_concepts, needs_tool
from robotool.describe import describe
from robotool.scene import Problem, Task, TaskFileError, load_task

__all__ = [
    "KeyConcept",
    "Problem",
    "Task",
    "TaskFileError",
    "describe",
    "key_concepts",
    "load_task",
    "needs_tool",
    "tasks",
]
