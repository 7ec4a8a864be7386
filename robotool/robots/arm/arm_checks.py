"""The arm's task-file checks: nothing may stand inside the gripper where it starts.

An object placed through the gripper's palm or open fingers at home is pushed out by the simulator while the world
settles, before the program runs (found by an adversarial run: a tray inside the fingers was pressed 2 cm down onto
a spring, and its spring back once the gripper moved off counted as a lift).
"""

from __future__ import annotations

import numpy as np

from robotool.robots.arm.arm_config import ARM, finger_open
from robotool.robots.arm.arm_skills import ArmLimits
from robotool.task import geometry
from robotool.task.task_model import Task
from robotool.task.task_problem import Problem

TOUCH = 0.001  # m an object may reach into the gripper's parts at the start (touching, as objects may touch)


def gripper_parts(limits: ArmLimits) -> list[geometry.Part]:
    """The gripper's palm and its two open fingers at home, as boxes in the world frame."""
    home, upright = np.asarray(ARM.home, dtype=float), np.eye(3)
    palm = home + np.array([0.0, 0.0, ARM.palm_clearance + ARM.palm_half[2]])
    parts = [geometry.Part("box", palm, np.asarray(ARM.palm_half, dtype=float), upright)]
    offset = finger_open(limits.gripper_opening)
    for side in (1.0, -1.0):
        finger = home + np.array([0.0, side * offset, ARM.finger_z])
        parts.append(geometry.Part("box", finger, np.asarray(ARM.finger_half, dtype=float), upright))
    return parts


def check_start(task: Task) -> list[Problem]:
    """Each object that reaches more than :data:`TOUCH` into the gripper's palm or open fingers at home."""
    limits = task.limits
    assert isinstance(limits, ArmLimits)
    gripper = gripper_parts(limits)
    problems = []
    for i, obj in enumerate(task.objects):
        depth = geometry.solids_overlap(geometry.object_parts(obj), gripper)
        if depth > TOUCH:
            x, y, z = ARM.home
            problems.append(
                Problem(
                    path=f"objects[{i}]({obj.name}).center",
                    message=f"{obj.name!r} reaches {depth:.3f} m into the gripper, which starts at [{x:g}, {y:g}, "
                    f"{z:g}] with its fingers open: the simulator would push them apart before the program runs; "
                    "move it clear of the gripper",
                )
            )
    return problems
