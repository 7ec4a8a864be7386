"""The quadruped's lever programs (:func:`~robotool.robots.quadruped.quadruped_macros.candidates`, a lifted goal)."""

from __future__ import annotations

from fixtures.paths import FIXTURES

from robotool import tasks
from robotool.planner.layout import Layout
from robotool.robots.quadruped.quadruped_macros import candidates


def test_the_prop_is_pushed_well_clear_of_the_board_or_just_clear() -> None:
    """A board resting on the chair is dragged sideways with it until the chair leaves it behind, so each side's lever
    program comes twice: with the chair pushed 0.5 m clear of the board's side (where the board's dragged end no longer
    reaches it), and just clear (0.2 m), for when the far spot is taken."""
    task = tasks.load(FIXTURES / "layouts" / "lever_plus_y.yaml")
    board = Layout(task).box("surfboard")
    chair = task.object("chair")
    clear = []
    for prog in candidates(task, tools=True):
        (push,) = [m for m in prog.motions if m.obj == "chair"]
        x = float(push.point.estimate()[0])  # the board runs along y: the chair goes out along x
        clear.append(round(max(board.lo[0] - (x + chair.size[0] / 2), (x - chair.size[0] / 2) - board.hi[0]), 3))
    assert sorted(clear) == [0.2, 0.2, 0.5, 0.5]


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
