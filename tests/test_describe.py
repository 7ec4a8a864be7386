"""The description carries every object's numbers and the robot's limits, with no task hints."""

from __future__ import annotations

import pytest

from robotool import tasks
from robotool.task.describe import describe
from robotool.task.task_file import parse_task


@pytest.mark.parametrize("name", tasks.names())
def test_description_lists_every_object_and_skill(name: str) -> None:
    task = tasks.load(name)
    text = describe(task)
    for obj in task.objects:
        assert f"- {obj.name}:" in text
    assert task.instruction in text
    assert task.category not in text  # no hint of what kind of task this is
    assert "get_size(name)" in text


def test_quadruped_numbers_and_limits() -> None:
    text = describe(tasks.load("sofa_traversing"))
    assert "centre [1.65, 0, 0.17], size [1, 0.9, 0.34]" in text
    assert "at most 0.12 m" in text and "at most 0.1 m" in text and "at most 5 kg" in text
    assert "standing on sofa_1" in text


def test_arm_numbers_and_limits() -> None:
    text = describe(tasks.load("milk_reaching"))
    assert "graspable point [0.568, 0.01, 0.135]" in text
    assert "x in [-0.3, 0.45]" in text
    assert "move_to_position(position)" in text


def test_a_turned_object_is_described_along_the_world_axes() -> None:
    data = tasks.load("sofa_climbing").model_dump(mode="json", exclude_defaults=True)
    box = next(o for o in data["objects"] if o["name"] == "box_1")
    box["rpy"] = [0, 0, 90]
    own = box["size"]
    text = describe(parse_task(data))
    line = next(line for line in text.splitlines() if line.startswith("- box_1:"))
    turned = "[" + ", ".join(f"{v:g}" for v in (own[1], own[0], own[2])) + "]"
    assert f"size {turned}" in line and "turned by roll/pitch/yaw [0, 0, 90] degrees" in line
