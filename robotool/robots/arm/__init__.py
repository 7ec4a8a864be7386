"""The arm: a Kinova Gen3-like arm whose two-finger gripper translates inside a workspace box.

Everything the rest of robotool knows about it is the :data:`ROBOT` record below; its parts are the modules
of this package: :mod:`.arm_skills` (limits and skills), :mod:`.arm_description`,
:mod:`.arm_concepts`, :mod:`.arm_body` (simulator model), :mod:`.arm_controller` and :mod:`.arm_grasp` (skill
controller), :mod:`.arm_goals` (``grasped``), :mod:`.arm_macros` and :mod:`.arm_candidates` (planner) and
:mod:`.arm_config` (the tunables), :mod:`.arm_checks` (task-file checks).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from robotool.robots.arm import arm_checks, arm_concepts, arm_description
from robotool.robots.arm.arm_skills import ARM_SKILLS, ArmLimits
from robotool.robots.registry import (
    DescriptionHooks,
    FeedbackRules,
    PictureHooks,
    PictureSettings,
    RobotType,
    SearchMacros,
    SimHooks,
    TaskRules,
)
from robotool.rollout import SkillCall
from robotool.task.task_model import Task
from robotool.task.task_problem import Problem

if TYPE_CHECKING:
    from robotool.sim.embodiment import Embodiment, GoalTrackerFactory


def _embodiment(limits: ArmLimits) -> Embodiment:
    from robotool.robots.arm.arm_controller import ArmEmbodiment  # the simulator loads on first use

    return ArmEmbodiment(limits)


def _goal_trackers() -> Mapping[str, GoalTrackerFactory]:
    from robotool.robots.arm.arm_goals import GraspedGoal  # the simulator loads on first use

    return {"grasped": lambda scene, sim: GraspedGoal(scene)}


def _planner() -> SearchMacros:
    from robotool.robots.arm.arm_candidates import candidates  # the planner loads on first use

    return SearchMacros(candidates=candidates, beam=8, rounds=4, work=6000.0)


def _check_robot(task: Task) -> list[Problem]:
    if task.robot.position is not None:
        return [Problem(path="robot.position", message="the arm's base is fixed at [0, 0, 0]; remove 'position'")]
    return []


def _reach(limits: ArmLimits) -> list[tuple[float, float, float]]:
    return [limits.workspace_min, limits.workspace_max]


def _start_xy(task: Task) -> tuple[float, float]:
    from robotool.robots.arm.arm_config import ARM

    return ARM.home[0], ARM.home[1]


def _numerical_hint(call: SkillCall) -> str | None:
    if call.skill == "close_gripper" and call.outcome == "done" and not call.reason:
        return "closed on nothing: the gripper was not at the object's graspable point"
    return None


ROBOT = RobotType(
    name="arm",
    article="an",
    limits=ArmLimits,
    skills=ARM_SKILLS,
    goals=frozenset({"grasped", "pressed", "lifted", "lowered"}),
    rules=TaskRules(
        key_concepts=arm_concepts.key_concepts,
        check_robot=_check_robot,
        check_start=arm_checks.check_start,
        reach=_reach,
    ),
    description=DescriptionHooks(
        section=arm_description.robot_section, ground="the table top", object_facts=arm_description.object_facts
    ),
    sim=SimHooks(embodiment=_embodiment, goal_trackers=_goal_trackers),
    planner=_planner,
    feedback=FeedbackRules(numerical_events=frozenset({"clamped", "grasp_failed"}), numerical_hint=_numerical_hint),
    pictures=PictureHooks(
        # The gripper works on a table top: a higher view keeps it from hiding the objects it reaches for.
        view=PictureSettings(turn=-35.0, elevation=-35.0, floor_square=0.1),
        start_xy=_start_xy,
    ),
)
