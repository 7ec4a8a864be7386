"""Task -> the natural-language description the language-model stages read.

This is the paper's F_Q and F_C: the instruction, every object with its numbers, the robot's
limits and its skills with their exact meaning. The robot's section, and the object facts only its skills
use, come from its package (``RobotType.description``); nothing here depends on which
task this is.
"""

from __future__ import annotations

import numpy as np

from robotool import robots
from robotool.robots.registry import RobotType
from robotool.task import geometry
from robotool.task.concepts import press_point
from robotool.task.scene import PRESS_TRAVEL, SceneObject, number_text
from robotool.task.task_model import Task


def vector_text(values: tuple[float, ...] | list[float] | np.ndarray) -> str:
    """A vector in metres as the description writes it: ``[0.1, 0, 0.25]``."""
    return "[" + ", ".join(f"{float(v):.3f}".rstrip("0").rstrip(".") if v else "0" for v in values) + "]"


def _shape_words(obj: SceneObject) -> str:
    if obj.shape == "cylinder":
        return f"cylinder with its axis along {obj.axis}"
    if obj.shape == "hook":
        return (
            f"L-shaped hook: a handle along x over its full length and a head along +y at its +x end, "
            f"both {number_text(obj.thickness)} m thick"
        )
    if obj.shape == "cloth":
        return "flexible cloth strip (it cannot carry load across a gap)"
    if obj.shape == "button":
        return (
            f"button housing; its face on the -x side counts as pressed after {number_text(PRESS_TRAVEL)} m of "
            "travel, "
            f"against a spring of {number_text(obj.button_stiffness)} N/m"
        )
    return "box"


def _object_line(obj: SceneObject, robot: RobotType) -> str:
    size = geometry.axis_aligned_size(obj.size, geometry.rotation_matrix(obj.rpy))
    parts = [f"- {obj.name}: {_shape_words(obj)}; centre {vector_text(obj.center)}, size {vector_text(size)}"]
    if any(obj.rpy):
        parts.append(f"turned by roll/pitch/yaw {vector_text(obj.rpy)} degrees; its own size {vector_text(obj.size)}")
    parts.append(f"top at z = {number_text(obj.top)}")
    if obj.movable:
        parts.append(f"movable, mass {number_text(obj.effective_mass)} kg")
    else:
        parts.append("fixed in place")
    parts += robot.description.object_facts(obj)
    if obj.shape == "button":
        parts.append(f"face centre {vector_text(press_point(obj))}")
    if obj.magnetic:
        parts.append("magnetic (sticks to other magnetic objects on contact)")
    if obj.soft:
        parts.append("soft (a safe landing surface)")
    if obj.fragile is not None:
        parts.append(
            f"fragile (breaks if it falls more than {number_text(obj.fragile.max_drop)} m onto a surface "
            "that is not soft)"
        )
    if obj.friction is not None:
        parts.append(f"friction {number_text(obj.friction)}")
    line = "; ".join(parts) + "."
    if obj.notes:
        line += f" {obj.notes[0].upper()}{obj.notes[1:]}."
    return line


def _fragile_goal(task: Task) -> bool:
    return task.goal.lowered is not None and task.object(task.goal.lowered.object).fragile is not None


def describe(task: Task) -> str:
    """The full natural-language description of a task, with numbers in metres and kilograms."""
    robot = robots.get(task.embodiment)
    lines = [
        f"Task: {task.instruction}",
        f"Success: {task.goal.sentence(unbroken=_fragile_goal(task))}",
        "",
        f"Scene (metres, world frame, z up; {robot.description.ground} is z = 0; sizes are along x, y, z, a turned "
        "object's axes matched to the nearest of them):",
        *(_object_line(o, robot) for o in task.objects),
        "",
        *robot.description.section(task),
        "",
        "Skills (Python functions the program calls; positions are [x, y, z] lists in metres):",
        *(f"- {s.signature} -> {s.returns}: {s.semantics}" for s in robot.skills),
    ]
    return "\n".join(lines)
