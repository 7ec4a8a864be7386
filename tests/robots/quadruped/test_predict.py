"""The planner's predictions of the quadruped's walks on a layout (:mod:`robotool.robots.quadruped.predict`)."""

from __future__ import annotations

import numpy as np
from fixtures.paths import FIXTURES

from robotool import tasks
from robotool.planner.layout import Layout
from robotool.robots.quadruped.predict import detour, walk_violation


def test_a_detour_finds_the_long_way_round_a_lever() -> None:
    """The robot starts beside the lever's low end and must reach the far side of the chair under its raised end: the
    straight walk crosses the raised board, and a toolbox and a potted plant stand by the near side; the way found (past
    the roller, over the board's low half, within the step limit) is predicted fine stretch by stretch."""
    task = tasks.load(FIXTURES / "layouts" / "lever_prop_beside_a_toolbox.yaml")
    layout, start, goal = Layout(task), np.asarray(task.robot.position), np.array([0.95, 1.5369])
    assert walk_violation(layout, start, [goal], task.limits) is not None
    way = detour(layout, start, goal, task.limits)
    assert len(way) > 1 and np.allclose(way[-1], goal)
    assert walk_violation(layout, start, way, task.limits) is None
