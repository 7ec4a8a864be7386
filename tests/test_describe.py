"""The description carries every object's numbers and the robot's limits, with no task hints."""

from __future__ import annotations

import pytest

from robotool import tasks
from robotool.describe import describe


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
