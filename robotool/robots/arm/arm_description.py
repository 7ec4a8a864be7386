"""The arm's section of the task description: where it stands, its workspace and its gripper, in words."""

from __future__ import annotations

from robotool.robots.arm.arm_skills import ArmLimits
from robotool.task.describe import number_text, vector_text
from robotool.task.scene import SceneObject
from robotool.task.task_model import Task


def robot_section(task: Task) -> list[str]:
    """What the arm is and its limits, with the task's numbers."""
    limits = task.limits
    assert isinstance(limits, ArmLimits)
    lo, hi = limits.workspace_min, limits.workspace_max
    num = number_text
    return [
        "The robot is an arm fixed at [0, 0, 0] on a table whose top is z = 0, with a two-finger gripper "
        "that translates but does not rotate.",
        "Robot limits:",
        f"- the gripper centre stays inside the workspace x in [{num(lo[0])}, {num(hi[0])}], "
        f"y in [{num(lo[1])}, {num(hi[1])}], z in [{num(lo[2])}, {num(hi[2])}]; a target outside it is "
        "clamped to the workspace;",
        f"- the fingers close along y and open {num(limits.gripper_opening)} m apart; close_gripper holds an "
        "object only when both fingers close on its sides and it is no "
        "wider than the opening (a thin sheet is pinched where both fingertips press on it); a held object moves "
        "rigidly with the gripper and pushes what it meets; aim the gripper centre at the graspable point.",
        f"- it carries at most {num(limits.max_payload)} kg: the held object with what rests on it or is stuck to "
        "it, once lifted off its support; a push, drag or press that moves things takes its share too (its force "
        "counts as the weight it would hold up; pressing into a support that gives no way is free).",
    ]


def object_facts(obj: SceneObject) -> list[str]:
    """A movable object's graspable point (where the gripper holds it)."""
    return [f"graspable point {vector_text(obj.grasp_point)}"] if obj.movable else []
