"""The planner's predictions of the quadruped's walks on a layout (:mod:`robotool.robots.quadruped.predict`;
no physics)."""

from __future__ import annotations

import itertools

import numpy as np
from fixtures.paths import FIXTURES

from robotool import tasks
from robotool.planner.layout import Box, Layout
from robotool.robots.quadruped.predict import detour, push_staging, walk_violation
from robotool.robots.quadruped.quadruped_config import QUADRUPED
from robotool.robots.quadruped.terrain import FOOT_RADIUS, foot_offsets
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


def _closest_approach(way: list[np.ndarray], start: np.ndarray, half: np.ndarray, box: Box) -> float:
    """The least gap (m) between the body's outline, walked along ``way`` from ``start``, and ``box``'s footprint."""
    points = np.concatenate(
        [np.linspace(a, b, int(np.linalg.norm(b - a) / 0.005) + 2) for a, b in itertools.pairwise([start, *way])]
    )
    gaps = np.maximum(np.maximum(box.lo - (points + half), (points - half) - box.hi), 0.0)
    return float(np.linalg.norm(gaps, axis=1).min())


def test_a_detour_keeps_room_beside_a_movable_box_it_passes() -> None:
    """``staircase_three`` once box_c and box_b are pushed into place: from behind box_b to where box_a's push lines
    up, the shortest way (down past box_a's +x face) puts the hind feet 1 cm inside its edge, and in a perturbed world
    the body ran into box_a and moved it. The way taken now keeps the detour's slack from box_a."""
    task = tasks.load(FIXTURES / "layouts" / "staircase_three.yaml")
    layout = Layout(task).with_moved("box_c", np.array([2.748, 0.0])).with_moved("box_b", np.array([2.346, 0.0]))
    start, goal = np.array([1.791, 0.0]), np.array([1.3, -1.73])
    way = detour(layout, start, goal, task.limits)
    assert np.allclose(way[-1], goal) and walk_violation(layout, start, way, task.limits) is None
    half = np.asarray(task.limits.body_size[:2]) / 2
    assert _closest_approach(way, start, half, layout.box("box_a")) >= QUADRUPED.detour_slack - 1e-9, way


def test_a_detour_passes_close_to_movable_crates_where_the_way_with_room_is_much_longer() -> None:
    """Two heavy crates, 10 m long, leave a passage 2 cm wider than the body each side: the way round them keeps room
    but is 10 m longer, so the way through the passage is taken."""
    half = np.asarray(_step_task(1.0).limits.body_size[:2]) / 2
    crate = {"shape": "box", "size": [10.0, 0.2, 0.5], "movable": True, "mass": 80.0}
    side = 5.0 + half[0] + 0.02
    task = parse_task(
        {
            "format": 1,
            "name": "passage",
            "instruction": "Stand on the mat.",
            "category": "sequential_tool_use",
            "robot": {"type": "quadruped", "position": [0.6, 0.0]},
            "objects": [
                {**crate, "name": "crate_west", "center": [-side, 1.0, 0.25]},
                {**crate, "name": "crate_east", "center": [side, 1.0, 0.25]},
                {"name": "mat", "shape": "box", "center": [0.0, 2.5, 0.01], "size": [1.0, 1.0, 0.02], "movable": False},
            ],
            "goal": {"robot_on": "mat"},
        }
    )
    layout, start, goal = Layout(task), np.array([0.6, 0.0]), np.array([0.0, 2.0])
    assert walk_violation(layout, start, [goal], task.limits) is not None
    way = detour(layout, start, goal, task.limits)
    assert np.allclose(way[-1], goal) and walk_violation(layout, start, way, task.limits) is None
    assert sum(np.linalg.norm(b - a) for a, b in itertools.pairwise([start, *way])) < 3.0, way


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


def test_a_way_round_never_stops_half_on_a_step() -> None:
    """vase_lowering seed 9109's floor: the way round the heavy bag turned at a corner of the bag's grown outline that
    lies within the feet's reach of box_1 (a 0.12 m step, within the step-up limit): the robot stopped there with a
    foot up on the step and the others on the floor, and fell in every world. A way round now turns only where all
    four feet stand on the level it starts on."""
    box = {"shape": "box", "movable": False}
    task = parse_task({
        "format": 1, "name": "steps_and_bag", "instruction": "Climb onto the sofa.", "category": "sequential_tool_use",
        "robot": {"type": "quadruped", "position": [0.0, 0.3]},
        "objects": [
            {**box, "name": "sofa", "center": [-0.44, 3.34, 0.157], "size": [1.5, 0.9, 0.314]},
            {**box, "name": "box_1", "center": [-0.369, 2.288, 0.06], "size": [0.6, 0.4, 0.12]},
            {**box, "name": "box_2", "center": [-0.369, 2.689, 0.12], "size": [0.6, 0.4, 0.24]},
            {"name": "sand_bag", "shape": "box", "center": [-1.057, 1.575, 0.08], "size": [0.5, 0.5, 0.16],
             "mass": 8.6},
        ],
        "goal": {"robot_on": "sofa"},
    })
    layout = Layout(task)
    start, goal = np.array([-2.12, 3.03]), np.array([-0.3695, 1.838])  # to where the climb of box_1 lines up
    way = detour(layout, start, goal, task.limits)
    assert len(way) > 1 and walk_violation(layout, start, way, task.limits) is None
    for turn in way[:-1]:
        assert np.all(layout.heights(turn + foot_offsets(task.limits)) < 0.04), turn


def _crate_task() -> Task:
    """A fixed 0.16 m crate (x 0.5-1.0, y -0.25 to 0.25) just ahead (+x) of the robot, which stands 1 cm behind it."""
    return parse_task({
        "format": 1, "name": "crate_ahead", "instruction": "Stand on the crate.", "category": "sequential_tool_use",
        "robot": {"type": "quadruped", "position": [0.165, 0.0]},
        "objects": [{"name": "crate", "shape": "box", "center": [0.75, 0.0, 0.08], "size": [0.5, 0.5, 0.16],
                     "movable": False}],
        "goal": {"robot_on": "crate"},
    })


def test_a_slanted_walk_away_from_what_the_body_stands_against_is_not_read_as_running_into_it() -> None:
    """The body keeps its heading as it walks, so a slanted walk sweeps the body's box along the way, not a box
    turned along it: walking off mostly -x and a little +y from 1 cm behind a crate passes nothing (the band turned
    along the walk reached 4 cm into the crate behind the body's start), while a slanted walk that does cut the
    crate's corner is still read as running into it."""
    task = _crate_task()
    layout, here = Layout(task), np.array([0.165, 0.0])
    assert walk_violation(layout, here, [np.array([-0.4, 0.1])], task.limits) is None
    assert walk_violation(layout, here, [np.array([-0.4, -0.1])], task.limits) is None
    problem = walk_violation(layout, np.array([0.3, 0.6]), [np.array([1.3, -0.6])], task.limits)
    assert problem is not None


def _low_box_task(movable: bool) -> Task:
    """A 0.1 m box (0.4 m along x, 2 m across) between the robot at x = -1 and x = 1: fixed, or movable (2 kg)."""
    return parse_task({
        "format": 1, "name": "low_box", "instruction": "Stand on the box.", "category": "sequential_tool_use",
        "robot": {"type": "quadruped", "position": [-1.0, 0.0]},
        "objects": [{"name": "box", "shape": "box", "center": [0.0, 0.0, 0.05], "size": [0.4, 2.0, 0.1],
                     "movable": movable, **({"mass": 2.0} if movable else {})}],
        "goal": {"robot_on": "box"},
    })


def test_a_way_round_steps_over_a_low_fixed_box_but_never_onto_a_movable_one() -> None:
    """The feet can step up 0.1 m, so walking over the box is within the limits; a fixed box is walked over, but a
    movable one is no footing on the way (a leg pressing its side shoves it along): the way goes round its end."""
    start, goal = np.array([-1.0, 0.0]), np.array([1.0, 0.0])
    fixed = _low_box_task(movable=False)
    straight = detour(Layout(fixed), start, goal, fixed.limits)
    assert len(straight) == 1 and np.allclose(straight[0], goal)
    loose = _low_box_task(movable=True)
    layout = Layout(loose)
    assert walk_violation(layout, start, [goal], loose.limits) is None  # the limits alone allow it
    way = detour(layout, start, goal, loose.limits)
    assert len(way) > 1 and np.allclose(way[-1], goal)
    feet = [p + foot_offsets(loose.limits) for a, b in itertools.pairwise([start, *way]) for p in np.linspace(a, b, 50)]
    assert np.isnan(layout.top_of("box", np.concatenate(feet))).all()


def _steps_beside_task() -> Task:
    """Fixed steps of 0.12 m (x 0.5-0.9) and 0.24 m (x 0.9-1.3) from y 0.05 to 0.65, beside the robot's way along x
    (vase_lowering 9839: its straight climb onto a low sofa ran along the steps)."""
    return parse_task({
        "format": 1, "name": "steps_beside", "instruction": "Stand on the mat.", "category": "sequential_tool_use",
        "robot": {"type": "quadruped", "position": [0.0, 0.0]},
        "objects": [
            {"name": "step_1", "shape": "box", "center": [0.7, 0.35, 0.06], "size": [0.4, 0.6, 0.12], "movable": False},
            {"name": "step_2", "shape": "box", "center": [1.1, 0.35, 0.12], "size": [0.4, 0.6, 0.24], "movable": False},
            {"name": "mat", "shape": "box", "center": [2.2, 0.0, 0.02], "size": [0.6, 0.6, 0.04], "movable": False},
        ],
        "goal": {"robot_on": "mat"},
    })


def test_a_walk_with_the_left_feet_up_the_steps_and_the_right_ones_on_the_floor_is_predicted_to_roll() -> None:
    """Each foot's path stays within the step limits (up 0.12 m twice, then down 0.24 m), but the left feet stand
    0.24 m above the right ones beside them: the robot climbing straight onto vase_lowering 9839's sofa this way fell in
    every world. A lane 0.25 m further from the steps keeps every foot on the floor; walked across the body (flank
    first), the feet beside each other lead and trail, and that walk is read by the feet's own limits only."""
    task = _steps_beside_task()
    layout = Layout(task)
    problem = walk_violation(layout, np.array([0.0, 0.0]), [np.array([2.2, 0.0])], task.limits)
    assert problem is not None and problem.startswith("the left and right feet would stand on surfaces 0.24 m apart")
    assert walk_violation(layout, np.array([0.0, -0.25]), [np.array([2.2, -0.25])], task.limits) is None
    turned = task.limits.model_copy(update={"body_size": (0.3, 0.65, 0.3)})  # the body turned a quarter
    found = walk_violation(layout, np.array([0.0, -0.2]), [np.array([2.2, -0.2])], turned)
    assert found is None or "left and right" not in found
