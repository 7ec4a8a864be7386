"""Task -> the natural-language description the language-model stages read.

This is the paper's F_Q and F_C: the instruction, every object with its numbers, the robot's
limits and its skills with their exact meaning. One template per embodiment; nothing in it
depends on which task this is.
"""

from __future__ import annotations

import numpy as np

from robotool.robots.quadruped.concepts import press_point, start_surface
from robotool.robots.skills import ArmLimits, QuadrupedLimits, skills
from robotool.scene import PRESS_TRAVEL, SceneObject
from robotool.task_model import Task


def _vec(values: tuple[float, ...] | list[float] | np.ndarray) -> str:
    return "[" + ", ".join(f"{float(v):.3f}".rstrip("0").rstrip(".") if v else "0" for v in values) + "]"


def _num(value: float) -> str:
    return f"{value:.3f}".rstrip("0").rstrip(".")


def _shape_words(obj: SceneObject) -> str:
    if obj.shape == "cylinder":
        return f"cylinder with its axis along {obj.axis}"
    if obj.shape == "hook":
        return (
            f"L-shaped hook: a handle along x over its full length and a head along +y at its +x end, "
            f"both {_num(obj.thickness)} m thick"
        )
    if obj.shape == "cloth":
        return "flexible cloth strip (it cannot carry load across a gap)"
    if obj.shape == "button":
        return (f"button housing; its face on the -x side counts as pressed after {_num(PRESS_TRAVEL)} m of travel, "
                f"against a spring of {_num(obj.button_stiffness)} N/m")
    return "box"


def _object_line(obj: SceneObject, embodiment: str) -> str:
    parts = [
        f"- {obj.name}: {_shape_words(obj)}; centre {_vec(obj.center)}, size {_vec(obj.size)}",
    ]
    if any(obj.rpy):
        parts.append(f"rotated by roll/pitch/yaw {_vec(obj.rpy)} degrees")
    parts.append(f"top at z = {_num(obj.top)}")
    if obj.movable:
        parts.append(f"movable, mass {_num(obj.effective_mass)} kg")
    else:
        parts.append("fixed in place")
    if embodiment == "arm" and obj.movable:
        parts.append(f"graspable point {_vec(obj.grasp_point)}")
    if obj.shape == "button":
        parts.append(f"face centre {_vec(press_point(obj))}")
    if obj.magnetic:
        parts.append("magnetic (sticks to other magnetic objects on contact)")
    if obj.soft:
        parts.append("soft (a safe landing surface)")
    if obj.fragile is not None:
        parts.append(f"fragile (breaks if it falls more than {_num(obj.fragile.max_drop)} m onto a surface "
                     "that is not soft)")
    if obj.friction is not None:
        parts.append(f"friction {_num(obj.friction)}")
    line = "; ".join(parts) + "."
    if obj.notes:
        line += f" {obj.notes[0].upper()}{obj.notes[1:]}."
    return line


def _goal_sentence(task: Task) -> str:
    goal = task.goal
    if goal.robot_on is not None:
        return f"The robot stands on top of {goal.robot_on} at the end."
    if goal.grasped is not None:
        return f"The gripper holds {goal.grasped} at the end."
    if goal.pressed is not None:
        return f"{goal.pressed} is pressed at some moment."
    if goal.lifted is not None:
        return (f"The bottom of {goal.lifted.object} is at least {_num(goal.lifted.height)} m above where it "
                "started, at the end.")
    assert goal.lowered is not None
    extra = ", unbroken" if task.object(goal.lowered.object).fragile is not None else ""
    return (f"The bottom of {goal.lowered.object} is at most {_num(goal.lowered.height)} m above the ground "
            f"at the end{extra}.")


def _robot_section(task: Task) -> list[str]:
    limits = task.limits
    if isinstance(limits, QuadrupedLimits):
        on, height = start_surface(task)
        where = "the ground" if on == "ground" else on
        return [
            f"The robot is a quadruped with a body of {_vec(limits.body_size)} m and a mass of "
            f"{_num(limits.mass)} kg. Its centre starts at x-y {_vec(task.robot.position or ())}, standing "
            f"on {where} (surface height {_num(height)} m).",
            "Robot limits:",
            f"- it climbs up a step of at most {_num(limits.max_step_up)} m;",
            f"- it crosses a gap of at most {_num(limits.max_gap)} m;",
            f"- it steps down a drop of at most {_num(limits.max_step_down)} m;",
            f"- it pushes only movable objects of at most {_num(limits.max_push_mass)} kg, only while standing "
            "on the ground or on a fixed object, only objects on the same surface as itself, and never the "
            "object it stands on.",
            "A skill that would break a limit stops the robot where it is and is refused.",
        ]
    assert isinstance(limits, ArmLimits)
    lo, hi = limits.workspace_min, limits.workspace_max
    return [
        "The robot is an arm fixed at [0, 0, 0] on a table whose top is z = 0, with a two-finger gripper "
        "that translates but does not rotate.",
        "Robot limits:",
        f"- the gripper centre stays inside the workspace x in [{_num(lo[0])}, {_num(hi[0])}], "
        f"y in [{_num(lo[1])}, {_num(hi[1])}], z in [{_num(lo[2])}, {_num(hi[2])}]; a target outside it is "
        "clamped to the workspace;",
        f"- the fingers close along y and open {_num(limits.gripper_opening)} m apart; close_gripper holds an "
        "object only when both fingers close on its sides and it is no "
        "wider than the opening (a thin sheet is pinched where both fingertips press on it); a held object moves "
        "rigidly with the gripper and pushes what it meets; aim the gripper centre at the graspable point.",
    ]


def describe(task: Task) -> str:
    """The full natural-language description of a task, with numbers in metres and kilograms."""
    ground = "the table top" if task.embodiment == "arm" else "the ground"
    lines = [
        f"Task: {task.instruction}",
        f"Success: {_goal_sentence(task)}",
        "",
        f"Scene (metres, world frame, z up; {ground} is z = 0; sizes are bounding boxes along x, y, z):",
        *(_object_line(o, task.embodiment) for o in task.objects),
        "",
        *_robot_section(task),
        "",
        "Skills (Python functions the program calls; positions are [x, y, z] lists in metres):",
        *(f"- {s.signature} -> {s.returns}: {s.semantics}" for s in skills(task.embodiment)),
    ]
    return "\n".join(lines)
