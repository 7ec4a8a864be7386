"""The planner's predictions of the quadruped's walks on a layout (:mod:`robotool.robots.quadruped.predict`;
no physics)."""

from __future__ import annotations

import numpy as np
from fixtures.paths import FIXTURES

from robotool import tasks
from robotool.planner.layout import Layout
from robotool.robots.quadruped.predict import detour, push_staging, walk_violation
from robotool.robots.quadruped.terrain import FOOT_RADIUS
from robotool.task.task_file import parse_task
from robotool.task.task_model import Task


def _step_task(width: float) -> Task:
    """A fixed 0.12 m step ``width`` wide along x in front (+y) of the robot, which walks flank first onto it."""
    return parse_task({
        "format": 1, "name": "narrow_step", "instruction": "Stand on the step.", "category": "sequential_tool_use",
        "robot": {"type": "quadruped", "position": [0.0, 0.0]},
        "objects": [{"name": "step", "shape": "box", "center": [0.0, 0.5, 0.06], "size": [width, 0.4, 0.12],
                     "movable": False}],
        "goal": {"robot_on": "step"},
    })


def test_a_step_under_every_foot_is_climbed_though_narrower_than_the_body() -> None:
    """The feet's centres sit one foot radius inside the body's outline: a step 5 mm wider than they are apart
    carries all four, so nothing stands between the feet higher than they are."""
    body = _step_task(1.0).limits.body_size[0]
    task = _step_task(body - 2 * FOOT_RADIUS + 0.01)
    assert walk_violation(Layout(task), np.array([0.0, 0.0]), [np.array([0.0, 0.5])], task.limits) is None


def test_a_step_between_the_feet_is_run_into() -> None:
    body = _step_task(1.0).limits.body_size[0]
    task = _step_task(body - 2 * FOOT_RADIUS - 0.03)
    problem = walk_violation(Layout(task), np.array([0.0, 0.0]), [np.array([0.0, 0.5])], task.limits)
    assert problem is not None and "runs into" in problem


def test_detour_finds_the_way_round_a_cluttered_floor() -> None:
    """From the start to where a push of the soft cushion lines up, behind a heavy cushion: the way goes round the
    heavy cushion's far side (the gap between the two cushions is 2 cm too narrow with the side margins), which takes
    more than a few dozen predicted stretches among the corners of six objects."""
    box = {"shape": "box", "movable": False}
    task = parse_task({
        "format": 1, "name": "cluttered", "instruction": "Stand on the sofa.", "category": "sequential_tool_use",
        "robot": {"type": "quadruped", "position": [-0.2546, -0.98]},
        "objects": [
            {**box, "name": "sofa", "center": [-0.72, 2.02, 0.173], "size": [1.5, 0.9, 0.346]},
            {**box, "name": "box_1", "center": [-1.083, 0.968, 0.06], "size": [0.6, 0.4, 0.12]},
            {**box, "name": "box_2", "center": [-1.083, 1.369, 0.12], "size": [0.6, 0.4, 0.24]},
            {**box, "name": "vase", "center": [-1.123, 2.037, 0.397], "size": [0.1, 0.3, 0.1], "movable": True},
            {**box, "name": "soft_cushion", "center": [-1.067, 0.225, 0.08], "size": [0.5, 0.5, 0.16],
             "movable": True, "mass": 1.0, "soft": True},
            {**box, "name": "sand_cushion", "center": [0.123, 0.061, 0.08], "size": [0.5, 0.5, 0.16],
             "movable": True, "mass": 7.4, "soft": True},
        ],
        "goal": {"robot_on": "sofa"},
    })
    layout, start, goal = Layout(task), np.array([-0.2546, -0.98]), np.array([-0.3115, 0.4746])
    assert walk_violation(layout, start, [goal], task.limits) is not None
    way = detour(layout, start, goal, task.limits)
    assert len(way) > 1 and np.allclose(way[-1], goal)
    assert walk_violation(layout, start, way, task.limits) is None


def test_remembered_walks_are_told_apart_by_layout_and_task() -> None:
    """Walk predictions are remembered: the same walk with the step moved away, or on another task with a lower
    step, is predicted afresh."""
    tall, low = (
        parse_task({**_step_task(1.0).model_dump(mode="json", exclude_none=True), "objects": [
            {"name": "step", "shape": "box", "center": [0.0, 0.5, h / 2], "size": [1.0, 0.4, h], "movable": False}]})
        for h in (0.3, 0.06)
    )
    start, goal = np.array([0.0, 0.0]), np.array([0.0, 0.5])
    away = Layout(tall).with_moved("step", np.array([3.0, 0.5]))
    for _ in range(2):
        assert walk_violation(Layout(tall), start, [goal], tall.limits) is not None
        assert walk_violation(away, start, [goal], tall.limits) is None
        assert walk_violation(Layout(low), start, [goal], low.limits) is None


def test_a_push_stance_slides_just_clear_of_what_stands_beside_it() -> None:
    """A block beside where the robot lines up to push a chair along -x reaches 6 mm past the straight-on stance's
    flank: the stance slides along the chair's face just clear of it (2 cm), not a coarse step, so the push stays
    nearly centred."""
    box = {"shape": "box", "movable": False}
    task = parse_task({
        "format": 1, "name": "push_beside", "instruction": "Stand on the step.", "category": "sequential_tool_use",
        "robot": {"type": "quadruped", "position": [1.5, 0.0]},
        "objects": [
            {**box, "name": "chair", "center": [0.0, 0.0, 0.115], "size": [0.4, 0.5, 0.23], "movable": True,
             "mass": 3.0},
            {**box, "name": "block", "center": [0.65, -0.322, 0.1], "size": [0.7, 0.356, 0.2]},
            {**box, "name": "step", "center": [-2.0, 0.0, 0.05], "size": [0.6, 0.6, 0.1]},
        ],
        "goal": {"robot_on": "step"},
    })
    staging = push_staging(Layout(task), "chair", np.array([-0.8, 0.0]), task.limits, 0.0)
    assert staging is not None and 0.0 < staging[1] <= 0.02 + 1e-9



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


def _vase_step_task(fragile: bool) -> Task:
    """A 0.10 m object lying on the floor across the robot's way: a step the legs climb, unless it is fragile."""
    vase = {"name": "vase", "shape": "box", "center": [0.0, 0.6, 0.05], "size": [1.0, 0.1, 0.1], "movable": True,
            "mass": 0.5}
    return parse_task({
        "format": 1, "name": "vase_in_the_way", "instruction": "Lower the vase.", "category": "sequential_tool_use",
        "robot": {"type": "quadruped", "position": [0.0, 0.0]},
        "objects": [{**vase, **({"fragile": {"max_drop": 0.3}} if fragile else {})}],
        "goal": {"lowered": {"object": "vase", "height": 0.05}},
    })


def test_a_fragile_object_is_no_footing_however_low() -> None:
    walk = (np.array([0.0, 0.0]), [np.array([0.0, 1.2])])
    plain = _vase_step_task(fragile=False)
    assert walk_violation(Layout(plain), *walk, plain.limits) is None
    task = _vase_step_task(fragile=True)
    problem = walk_violation(Layout(task), *walk, task.limits)
    assert problem is not None and "stand on vase, which is fragile" in problem
