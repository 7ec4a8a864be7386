"""The quadruped's lever programs (:func:`~robotool.robots.quadruped.quadruped_macros.candidates`, a lifted goal)."""

from __future__ import annotations

import numpy as np
import pytest
from fixtures.paths import FIXTURES

from robotool import tasks
from robotool.planner.layout import Layout
from robotool.planner.search import order
from robotool.robots.quadruped.quadruped_macros import LEVER_STRIDE, candidates
from robotool.tasks.families import generate
from robotool.verify import failure_reason, prepare_code, run_seeded


def test_the_prop_is_pushed_well_clear_of_the_board_or_just_clear() -> None:
    """A board resting on the chair is dragged sideways with it until the chair leaves it behind, so each side's lever
    program comes once for each clearance, the farthest first: with the chair pushed 1.2 m clear of the board's side
    (where the board's dragged end no longer reaches it, even with the chair turned as it slides along the robot's
    face), nearer (0.8 m, 0.5 m), and just clear (0.2 m), for when the far spots are taken."""
    task = tasks.load(FIXTURES / "layouts" / "lever_plus_y.yaml")
    board = Layout(task).box("surfboard")
    chair = task.object("chair")
    clear = []
    for prog in candidates(task, tools=True):
        (push,) = [m for m in prog.motions if m.obj == "chair"]
        x = float(push.point.estimate()[0])  # the board runs along y: the chair goes out along x
        clear.append(round(max(board.lo[0] - (x + chair.size[0] / 2), (x - chair.size[0] / 2) - board.hi[0]), 3))
    assert clear == [1.2, 0.8, 0.5, 0.2] * 2


def test_a_prop_with_little_room_beyond_the_board_is_pushed_far_out_the_other_way_first() -> None:
    """cube_lifting 16002: beyond the board's side away from the robot, a heavy toolbox leaves the chair room to go
    out 0.2 m. Pushed there (2 mm short of the toolbox, the push lined up off the chair's centre under the board), it
    dragged the board 19 cm off its roller or rammed the toolbox in 6 to 8 worlds of 24; pushed 1.2 m out the other
    way, it held in all 24. A push that leaves the board so little room is a less likely choice, for when the far
    spots on both sides are taken."""
    task = generate("cube_lifting", 16002).task
    board, chair = Layout(task).box("surfboard"), task.object("chair")
    (push,) = [m for m in order(candidates(task, tools=True))[0].motions if m.obj == "chair"]
    y = float(push.point.estimate()[1])  # the board runs along x: the chair goes out along y, away from the toolbox
    assert y < chair.center[1] and board.lo[1] - (y + chair.size[1] / 2) == pytest.approx(1.2)


def test_the_step_onto_the_lever_is_placed_by_its_fulcrum_straight_on_from_the_lane() -> None:
    """The prop's push may drag the board along its length (8 cm in some worlds); the fulcrum stays. The spot where the
    robot steps on is read along the board from the fulcrum, a fixed number, and across it from the board as it lies
    then: the climb runs straight on from the lane beside the board. (Placed along the board from its centre, the climb
    ran aslant from the lane, and its front foot met the fulcrum's end sticking out beside a dragged board.)"""
    task = tasks.load(FIXTURES / "layouts" / "lever_plus_y.yaml")  # the lever runs along y, the cube at +y
    fulcrum_y = task.object("yoga_roller").center[1]
    cube_face = Layout(task).box("cube").lo[1]  # the tilted cube's near side
    length, width = task.limits.body_size[:2]
    programs = list(candidates(task, tools=True))
    assert programs
    for prog in programs:
        (climb,) = [m for m in prog.motions if m.skill == "climb_to_position"]
        lane = prog.motions[prog.motions.index(climb) - 1]
        assert climb.point is not None and lane.point is not None and climb.point.along is None
        (x_ref, _), (y_ref, y), _ = climb.point.axes
        assert y_ref is None and x_ref is not None and x_ref.obj == "surfboard"
        assert lane.point.axes[1] == (None, y)  # the lane's walk ends level with the spot: the climb is straight on
        turned = any(m.skill == "turn_to_heading" for m in prog.motions)  # the body's length along the board
        half = (length if turned else width) / 2
        assert y - half >= fulcrum_y + 0.01 - 1e-9  # the feet at least 1 cm short of the fulcrum's centre line
        assert y + half <= cube_face - 0.03 + 1e-9 or y - half >= fulcrum_y + 0.05 + 0.02 - 1e-9  # room kept


def test_the_walk_out_along_the_lever_stops_every_stride_from_the_fulcrum_on() -> None:
    """Past its fulcrum the lever may tip under the robot at any step; the walk to its far end stops level with the
    fulcrum and then every LEVER_STRIDE, so that the board tips under planted feet."""
    task = tasks.load(FIXTURES / "layouts" / "lever_plus_y.yaml")  # the lever runs along y, the cube at +y
    fulcrum_y = task.object("yoga_roller").center[1]
    for prog in candidates(task, tools=True):
        (climb,) = [m for m in prog.motions if m.skill == "climb_to_position"]
        walk_out = prog.motions[prog.motions.index(climb) + 1 :]
        assert walk_out and all(m.skill == "walk_to_position" and m.point is not None for m in walk_out)
        ys = [float(m.point.estimate()[1]) for m in walk_out if m.point is not None]
        assert ys[0] == pytest.approx(fulcrum_y, abs=1e-6)
        steps = np.diff(ys)
        assert np.all(steps < 0) and np.all(-steps <= LEVER_STRIDE + 1e-6)  # toward -y, the raised end


@pytest.mark.slow
def test_a_lever_tipping_under_the_walking_robot_no_longer_throws_it() -> None:
    """cube_lifting 8214: walking out along the lever in one stride, the robot rode the board's tip mid-step and fell
    (no support under the front feet) in these perturbed worlds; stopping every stride past the fulcrum, it holds."""
    task = generate("cube_lifting", 8214).task
    best = order(candidates(task, tools=True))[0]
    code, rejection, _ = prepare_code(best.code, task)
    assert rejection is None and code is not None
    (rollouts,) = run_seeded(task, [(code, [20007, 20008])])
    assert all(r.success for r in rollouts), failure_reason(rollouts)


def test_a_lane_beside_the_board_blocked_by_a_heavy_box_is_walked_around() -> None:
    """cube_lifting 8009: an 11.3 kg toolbox stands 0.43 m beyond the chair's side, where the lane beside the board
    (0.25 m from it) runs: every lever program walked into the toolbox on its way to push the chair out (a step up of
    0.25 m under a foot, predicted) or pushed the chair into the toolbox, and the planner failed in every world. The
    robot now goes around what stands in the lane to where the push lines up, and back out the same way."""
    task = generate("cube_lifting", 8009).task
    fine = [p for p in candidates(task, True) if p.doubt is None]
    assert fine
    layout = Layout(task)
    toolbox = layout.box("toolbox")
    for prog in fine:
        for motion in prog.motions:
            if motion.skill == "walk_to_position":
                xy = motion.point.estimate()[:2]
                assert np.any(np.abs(xy - toolbox.center) > toolbox.half + np.array(task.limits.body_size[:2]) / 2)


@pytest.mark.parametrize(("seed", "why"), [(41, "cannot outweigh cube's 27.6 kg"), (13, "chair weighs 6 kg, over")])
def test_a_lever_the_robot_cannot_tip_or_a_prop_it_cannot_push_is_predicted_to_fail(seed: int, why: str) -> None:
    """cube_lifting 41 (a 27.6 kg cube on the lowered end, the 12 kg robot on the raised one, the roller near the
    board's middle) and 13 (a 6 kg chair under the raised end, over the 5 kg push limit): every lever held still or
    every push was refused in every world, and the search tried them all (24 s) before it gave up. Every lever program
    now carries the reason as its doubt, so that the search gives up after its doubted rounds."""
    programs = list(candidates(generate("cube_lifting", seed).task, True))
    assert programs and all(p.doubt is not None and why in p.doubt for p in programs)


def test_a_cube_the_robot_outweighs_on_the_lever_is_not_doubted() -> None:
    """The built-in scene (a 10 kg cube, a 3 kg chair) and one with the heaviest cube the family makes solvable."""
    for task in (tasks.load("cube_lifting"), generate("cube_lifting", 47).task):
        assert all(p.doubt is None for p in candidates(task, True))
