"""``get_size`` answers along the world axes as an object is turned now, on both robots."""

from __future__ import annotations

from typing import Any

import pytest

from robotool import sim, tasks
from robotool.task.task_file import parse_task
from robotool.task.task_model import Task


def turned(name: str, obj: str, rpy: list[float]) -> Task:
    data = tasks.load(name).model_dump(mode="json", exclude_defaults=True)
    next(o for o in data["objects"] if o["name"] == obj)["rpy"] = rpy
    return parse_task(data)


@pytest.mark.parametrize(
    ("name", "obj", "expected"),
    [("sofa_climbing", "box_1", [0.6, 0.4, 0.12]), ("milk_reaching", "stuffed_toy", [0.05, 0.08, 0.05])],
)
def test_get_size_of_an_object_turned_a_quarter_turn_swaps_x_and_y(name: str, obj: str, expected: list[float]) -> None:
    answers: list[Any] = []

    def probe(robot: Any) -> None:
        answers.append(robot.get_size(obj))

    task = turned(name, obj, [0, 0, 90])
    rollouts = sim.run_programs(task, [probe, probe], seed=5)  # perturbed worlds: a 2 degree turn changes nothing
    assert len(rollouts) == 2
    assert answers == [pytest.approx(expected), pytest.approx(expected)]
