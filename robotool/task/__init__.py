"""The task model: one task file read and checked, its scene, goal and geometry, its ground-truth key concepts, and
the description the language-model stages read.

:mod:`~robotool.task.task_model` (``Task``), :mod:`~robotool.task.task_file` (reading and checking a file, its
text parsed by :mod:`~robotool.task.task_text`), :mod:`~robotool.task.limit_rules` (the robot limits' bounds),
:mod:`~robotool.task.task_goal`, :mod:`~robotool.task.task_problem`, :mod:`~robotool.task.scene`,
:mod:`~robotool.task.geometry`, :mod:`~robotool.task.key_concept`, :mod:`~robotool.task.concepts` and
:mod:`~robotool.task.describe`. The built-in task files and procedural families are :mod:`robotool.tasks`.
"""
