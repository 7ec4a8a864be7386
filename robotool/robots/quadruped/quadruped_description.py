"""The quadruped's section of the task description: its body, where it starts and its legs' limits, in words."""

from __future__ import annotations

from robotool.robots.quadruped.quadruped_concepts import start_surface
from robotool.robots.quadruped.quadruped_config import QUADRUPED
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.terrain import FOOT_RADIUS
from robotool.task.describe import number_text, vector_text
from robotool.task.task_model import Task


def robot_section(task: Task) -> list[str]:
    """What the quadruped is, where it starts and its limits, with the task's numbers."""
    limits = task.limits
    assert isinstance(limits, QuadrupedLimits)
    num = number_text
    on, height = start_surface(task)
    where = "the ground" if on == "ground" else on
    return [
        f"The robot is a quadruped with a body of {vector_text(limits.body_size)} m and a mass of "
        f"{num(limits.mass)} kg. Its centre starts at x-y {vector_text(task.robot.position or ())}, standing "
        f"on {where} (surface height {num(height)} m).",
        "Robot limits:",
        f"- it climbs up a step of at most {num(limits.max_step_up)} m;",
        f"- it crosses a gap of at most {num(limits.max_gap)} m;",
        f"- it steps down a drop of at most {num(limits.max_step_down)} m;",
        f"- it pushes only movable objects of at most {num(limits.max_push_mass)} kg, only while standing "
        "on the ground or on a fixed object, only objects on the same surface as itself, and never the "
        "object it stands on.",
        f"- its feet need grip: it walks, climbs and turns only where the friction under them is at least "
        f"{num(round(QUADRUPED.walk_grip, 3))} (on a slope, that plus the slope's tangent), and a push may take no "
        "more force than its feet hold (its weight times the friction under them; sliding an object takes its "
        "weight times the friction under it).",
        f"- its feet are {num(2 * FOOT_RADIUS)} m across and stand only on a surface about as wide: a blade on edge, a "
        "thin rail or a ridge is no foothold.",
        "A skill that would break a limit stops the robot where it is and is refused.",
    ]
