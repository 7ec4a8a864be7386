"""A corpus of cheating arm programs: each must fail in every perturbed world, with a reason one can read.

The programs are files in ``tests/fixtures/cheats/arm_*.py``: creeping past the workspace edge in small steps,
huge target coordinates, a held cube let go at the end of a fast run, a single cube rammed at an out-of-reach
button, paper slid under a can with no stick, and a far milk carton tipped over toward the arm with a straight
stick (which works in real physics, so a scene the milk family calls unsolvable must keep its carton out of a
tipped carton's reach; the same program grasps a carton close enough, the control). The honest references on the
same tasks succeed in their own tests
(tests/test_verify.py, tests/robots/arm/test_skills.py).
"""

from __future__ import annotations

from typing import Any

import pytest
from fixtures.paths import FIXTURES

from robotool import tasks
from robotool.rollout import Rollout
from robotool.task_file import parse_task
from robotool.task_model import Task
from robotool.tasks.families import milk_reaching
from robotool.verify import world_failure

CHEATS = FIXTURES / "cheats"
UNSOLVABLE_MILK_SEED = 64  # the milk family's unsolvable instance with the nearest carton among seeds 0-99


def _task(name: str) -> Task:
    if name == "milk_reaching_unsolvable":
        instance = tasks.generate("milk_reaching", UNSOLVABLE_MILK_SEED)
        assert not instance.solvable
        return instance.task
    return tasks.load(name)


CASES = [
    ("arm_creep_past_workspace", "milk_reaching"),
    ("arm_huge_targets", "milk_reaching"),
    ("arm_release_at_speed", "button_pressing"),
    ("arm_ram_one_cube", "button_pressing"),
    ("arm_paper_under_can", "can_grasping"),
    ("arm_topple_milk_with_stick", "milk_reaching_unsolvable"),
]


@pytest.mark.parametrize(("program", "task"), CASES)
def test_cheat_fails_in_every_world_with_a_reason(run_texts: Any, program: str, task: str) -> None:
    rollouts: list[Rollout] = run_texts(_task(task), [(CHEATS / f"{program}.py").read_text()] * 2, seed=11)
    for rollout in rollouts:
        assert not rollout.success, [(c.skill, c.args, c.outcome) for c in rollout.calls]
        assert rollout.error is None, rollout.error  # it ran to its end: the world said no
        assert world_failure(rollout), rollout


def test_tipping_over_a_carton_within_its_reach_succeeds(run_texts: Any) -> None:
    """The control for the tipping cheat: the same program grasps a carton that stands close enough (0.61 m, where
    the family used to put unsolvable ones), so its failure above is the carton's distance, not the program."""
    data = _task("milk_reaching_unsolvable").model_dump(mode="json", exclude_defaults=True)
    for obj in data["objects"]:
        if obj["name"] == "milk":
            obj["center"][0] = obj["graspable_point"][0] = 0.61
    data["name"] = "milk_within_tipping_reach"
    rollouts = run_texts(parse_task(data), [(CHEATS / "arm_topple_milk_with_stick.py").read_text()] * 2, seed=11)
    assert all(r.success for r in rollouts), [world_failure(r) for r in rollouts]


def test_unsolvable_milk_stays_out_of_reach_when_tipped_over() -> None:
    """Tipped toward the arm about its near bottom edge, an unsolvable carton's graspable point lands beyond the
    grasp tolerance of the workspace edge, with the perturbation's shift to spare."""
    for seed in range(50):
        instance = tasks.generate("milk_reaching", seed)
        if instance.solvable:
            continue
        milk = next(o for o in instance.task.objects if o.name == "milk")
        landed = milk.center[0] - milk.size[0] / 2 - (milk.grasp_point[2] - milk.bottom)
        assert landed - 0.005 > milk_reaching.ARM_REACH_X + milk_reaching.GRASP_TOLERANCE, (seed, landed)
