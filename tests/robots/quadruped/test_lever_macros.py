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
