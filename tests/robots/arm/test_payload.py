"""The arm's payload limit (``max_payload``, 4 kg by default, a Kinova Gen3's at mid range): the arm's servos and its
120 N grip lift about 10 kg, so a 6 kg block was lifted in every world. What the arm carries is now read from the
simulation, the held object with what rides on it or is stuck to it, and what the gripper holds up by contact
without a grasp (a plate lifted on the open gripper's palm); a world whose arm carries more for 0.3 s fails, the lift
refused with a reason naming the objects and the numbers."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from fixtures.paths import FIXTURES

from robotool import tasks
from robotool.robots.arm.arm_payload import PAYLOAD_CONDITION
from robotool.rollout import Rollout
from robotool.task.task_model import Task
from robotool.verify import world_failure

CHEATS = FIXTURES / "cheats"
LAYOUTS = FIXTURES / "layouts"
BLOCK = LAYOUTS / "arm_six_kg_iron_block.yaml"


def _lift(run_texts: Any, task: Task, program: str) -> list[Rollout]:
    return list(run_texts(task, [(CHEATS / f"{program}.py").read_text()] * 2, seed=11))


def _block(tmp_path: Path, old: str, new: str) -> Task:
    """The 6 kg block's task file with ``old`` written as ``new``."""
    text = BLOCK.read_text()
    assert old in text
    path = tmp_path / "task.yaml"
    path.write_text(text.replace(old, new))
    return tasks.load(path)


def test_a_six_kg_block_is_over_the_payload(run_texts: Any) -> None:
    for rollout in _lift(run_texts, tasks.load(BLOCK), "arm_lift_a_six_kg_iron_block"):
        assert not rollout.success, [(c.skill, c.outcome, c.reason) for c in rollout.calls]
        assert rollout.conditions.get(PAYLOAD_CONDITION) is False, rollout.conditions
        failure = world_failure(rollout) or ""
        assert re.search(r"cannot lift iron_block: .*\d kg.*, over the arm.s 4\.0 kg payload", failure), failure
        lift = rollout.calls[-1]  # the world's masses are perturbed: the block weighs about 6 kg
        assert lift.outcome == "refused" and 4.0 < lift.measured["mass"] <= lift.measured["group_mass"] < 8.0, lift
        assert lift.measured["for"] == pytest.approx(0.3)


def test_a_three_kg_block_is_within_it(run_texts: Any, tmp_path: Path) -> None:
    task = _block(tmp_path, "mass: 6.0", "mass: 3.0")
    for rollout in _lift(run_texts, task, "arm_lift_a_six_kg_iron_block"):
        assert rollout.success, world_failure(rollout)
        assert PAYLOAD_CONDITION not in rollout.conditions  # 3 kg in all: nothing in the scene can be too much


def test_what_rides_on_the_held_object_is_carried_too(run_texts: Any) -> None:
    task = tasks.load(LAYOUTS / "arm_light_tray_under_two_iron_blocks.yaml")
    for rollout in _lift(run_texts, task, "arm_lift_a_tray_under_two_iron_blocks"):
        assert not rollout.success, [(c.skill, c.outcome, c.reason) for c in rollout.calls]
        failure = world_failure(rollout) or ""
        assert re.search(r"cannot lift tray: .*kg with block_a, block_b (riding on|touching) it", failure), failure
        lift = rollout.calls[-1]  # the tray alone weighs 0.3 kg, the blocks 2.5 kg each
        assert lift.outcome == "refused" and lift.measured["riders"] == 2 and lift.measured["mass"] > 4.0, lift


def test_a_task_may_raise_the_payload(run_texts: Any, tmp_path: Path) -> None:
    task = _block(tmp_path, "robot: {type: arm}", "robot: {type: arm, limits: {max_payload: 8}}")
    for rollout in _lift(run_texts, task, "arm_lift_a_six_kg_iron_block"):
        assert rollout.success, world_failure(rollout)
        assert rollout.conditions.get(PAYLOAD_CONDITION, True), rollout.conditions
        assert all(c.outcome != "refused" for c in rollout.calls)


PLATE = LAYOUTS / "arm_six_kg_plate_across_two_stools.yaml"


def _plate(tmp_path: Path, mass: float) -> Task:
    """The plate across two stools, weighing ``mass`` kg, and a 5 kg block on the table out of the way (the scene's
    movable objects could weigh more than the payload: the arm's load is weighed)."""
    text = PLATE.read_text()
    assert "mass: 6.0" in text and text.endswith("plate}\ngoal:\n  lifted: {object: iron_plate, height: 0.10}\n")
    block = "  - {name: anvil, shape: box, center: [0.25, 0.30, 0.03], size: [0.06, 0.06, 0.06], mass: 5.0}\n"
    path = tmp_path / "plate.yaml"
    path.write_text(text.replace("mass: 6.0", f"mass: {mass}").replace("goal:\n", block + "goal:\n"))
    return tasks.load(path)


def test_a_plate_lifted_on_the_palm_is_carried_too(run_texts: Any) -> None:
    """The payload is what the arm bears, however: a 6 kg plate pushed up off two stools on the open gripper's palm
    and fingers, never grasped, was lifted 0.17 m in every world."""
    for rollout in _lift(run_texts, tasks.load(PLATE), "arm_lift_a_plate_on_the_palm"):
        assert not rollout.success, [(c.skill, c.outcome, c.reason) for c in rollout.calls]
        assert rollout.conditions.get(PAYLOAD_CONDITION) is False, rollout.conditions
        failure = world_failure(rollout) or ""
        assert re.search(r"cannot lift iron_plate: \d+\.\d kg borne on the gripper, over the arm.s 4\.0 kg", failure)
        lift = rollout.calls[-1]
        assert lift.outcome == "refused" and lift.measured["contact"] == 1.0, lift
        assert 4.0 < lift.measured["mass"] <= lift.measured["group_mass"] < 8.0, lift


def test_a_light_plate_lifted_on_the_palm_is_within_it(run_texts: Any, tmp_path: Path) -> None:
    for rollout in _lift(run_texts, _plate(tmp_path, 2.0), "arm_lift_a_plate_on_the_palm"):
        assert rollout.success, world_failure(rollout)
        assert rollout.conditions.get(PAYLOAD_CONDITION) is True, rollout.conditions
        assert all(c.outcome != "refused" for c in rollout.calls)
