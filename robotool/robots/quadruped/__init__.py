"""The quadruped: a Unitree Go1-sized legged robot that walks, climbs and pushes.

Everything the rest of robotool knows about it is the :data:`ROBOT` record below; its parts are the modules
of this package: :mod:`.quadruped_skills` (limits and skills), :mod:`.checks`
(task-file checks), :mod:`.quadruped_description`, :mod:`.quadruped_concepts`, the
simulator's :mod:`.quadruped_controller` (the composition of :mod:`.plans`, :mod:`.move_runner`,
:mod:`.terrain_following`, :mod:`.referee`, :mod:`.rays` and :mod:`.sensing`) with its :mod:`.body`,
:mod:`.push` and :mod:`.support`, the one terrain model of
its legs (:mod:`.terrain`, read by the controller, the planner and the key concepts),
:mod:`.quadruped_goals` (``robot_on``), the planner's
:mod:`.quadruped_macros`, :mod:`.quadruped_routes` and :mod:`.quadruped_writer` with their walk and push prediction
(:mod:`.predict`), and the tunables of all of them in :mod:`.quadruped_config`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from robotool.robots.quadruped import checks, quadruped_concepts, quadruped_description, terrain
from robotool.robots.quadruped.quadruped_skills import QUADRUPED_SKILLS, QuadrupedLimits
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
from robotool.task.task_model import Task

if TYPE_CHECKING:
    from robotool.sim.embodiment import Embodiment, GoalTrackerFactory


def _embodiment(limits: QuadrupedLimits) -> Embodiment:
    from robotool.robots.quadruped.quadruped_controller import QuadrupedEmbodiment  # the simulator loads on first use

    return QuadrupedEmbodiment(limits)


def _goal_trackers() -> Mapping[str, GoalTrackerFactory]:
    from robotool.robots.quadruped.quadruped_goals import RobotOnGoal  # the simulator loads on first use

    return {"robot_on": RobotOnGoal}


def _planner() -> SearchMacros:
    from robotool.robots.quadruped.quadruped_macros import candidates  # the planner loads on first use

    return SearchMacros(candidates=candidates, beam=3, rounds=4, work=1800.0, first=1, doubted_rounds=2)


def _start_xy(task: Task) -> tuple[float, float]:
    return task.robot.required_position()  # checks.check_robot makes it required


def _footprint(task: Task) -> tuple[float, float]:
    limits = task.limits
    assert isinstance(limits, QuadrupedLimits)
    return limits.body_size[0], limits.body_size[1]


ROBOT = RobotType(
    name="quadruped",
    article="a",
    limits=QuadrupedLimits,
    skills=QUADRUPED_SKILLS,
    goals=frozenset({"robot_on", "lifted", "lowered"}),
    rules=TaskRules(
        key_concepts=quadruped_concepts.key_concepts,
        check_robot=checks.check_robot,
        check_start=checks.check_start,
        planar=True,
    ),
    description=DescriptionHooks(section=quadruped_description.robot_section),
    # more and longer skills to simulate, and a larger planner search, than the arm's
    sim=SimHooks(embodiment=_embodiment, goal_trackers=_goal_trackers, run_cost=3.0),
    planner=_planner,
    # a refused step, gap or drop measures its kind
    feedback=FeedbackRules(placement_measures=frozenset(terrain.KINDS)),
    pictures=PictureHooks(
        # It walks along its scene: a three-quarter view from the side shows the heights it climbs.
        view=PictureSettings(turn=-20.0, elevation=-28.0, floor_square=0.5),
        start_xy=_start_xy,
        footprint=_footprint,
    ),
)
