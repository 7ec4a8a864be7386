"""The quadruped's quarter turn in place (``turn_to_heading``): what it turns, where it is refused, and the planner's
programs that open with it where the robot fits only turned."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from robotool import sim, tasks
from robotool.planner.solve import solve
from robotool.robots.quadruped.quadruped_skills import QUADRUPED_SKILLS
from robotool.robots.skills import SkillArgumentError, check_arguments
from robotool.rollout import Rollout
from robotool.sandbox import start_sessions
from robotool.task.task_model import Task

LAYOUTS = Path(__file__).resolve().parents[2] / "fixtures" / "layouts"
TURN = next(s for s in QUADRUPED_SKILLS if s.name == "turn_to_heading")


def _task(name: str) -> Task:
    return tasks.load(LAYOUTS / f"{name}.yaml")


def _run(task: Task, code: str, worlds: int = 2) -> list[Rollout]:
    return sim.run_sessions(task, start_sessions([code] * worlds, "quadruped"), seed=5)


def _calls(rollout: Rollout) -> list[tuple[str, str, Any]]:
    return [(c.skill, c.outcome, c.reason or c.result) for c in rollout.calls]


def test_a_quarter_turn_swaps_the_bodys_sizes_and_turns_back() -> None:
    code = (
        "print(get_size('robot'))\nturn_to_heading(90)\nprint(get_size('robot'))\n"
        "turn_to_heading(-90)\nprint(get_size('robot'))\nturn_to_heading(0)\nprint(get_size('robot'))\n"
    )
    for rollout in _run(_task("platform_narrower_than_the_robot_is_long"), code):
        sizes = [c.result for c in rollout.calls if c.skill == "get_size"]
        assert sizes == [[0.65, 0.3, 0.3], [0.3, 0.65, 0.3], [0.3, 0.65, 0.3], [0.65, 0.3, 0.3]], _calls(rollout)
        assert all(c.outcome == "done" for c in rollout.calls), _calls(rollout)
        assert rollout.conditions["robot_has_not_fallen"] and rollout.conditions["robot_shoved_nothing"]


def test_a_heading_between_quarter_turns_is_refused() -> None:
    (rollout,) = _run(_task("platform_narrower_than_the_robot_is_long"), "turn_to_heading(45)\n", worlds=1)
    (call,) = rollout.calls
    assert call.outcome == "refused" and "quarter turns" in (call.reason or ""), _calls(rollout)


@pytest.mark.parametrize("value", ["90", True, float("nan"), [90], 10**400])
def test_a_heading_that_is_not_a_finite_number_is_a_wrong_argument(value: object) -> None:
    with pytest.raises(SkillArgumentError, match="heading must be a"):
        check_arguments(TURN, (value,))


def test_a_heading_in_degrees_is_taken_as_a_float() -> None:
    assert check_arguments(TURN, (90,)) == (90.0,)


def test_the_robot_fits_on_a_platform_narrower_than_it_is_long_only_turned() -> None:
    task = _task("platform_narrower_than_the_robot_is_long")
    straight = _run(task, "climb_to_position([0.0, 0.5, 0.1])\n")
    turned = _run(task, "turn_to_heading(90)\nclimb_to_position([0.0, 0.5, 0.1])\n")
    assert not any(r.success for r in straight), [_calls(r) for r in straight]
    assert all(r.success for r in turned), [_calls(r) for r in turned]


def test_a_turn_that_would_sweep_into_a_wall_is_refused_naming_it() -> None:
    (rollout,) = _run(_task("turn_beside_a_wall"), "turn_to_heading(90)\n", worlds=1)
    (call,) = rollout.calls
    assert call.outcome == "refused" and "wall stands in the body's way" in (call.reason or ""), _calls(rollout)


def test_a_turn_that_would_put_a_foot_over_an_edge_is_refused() -> None:
    code = "climb_to_position([2.0, -1.0, 0.1])\nturn_to_heading(90)\n"
    (rollout,) = _run(_task("turn_beside_a_wall"), code, worlds=1)
    climb, turn = rollout.calls
    assert climb.outcome == "done", _calls(rollout)
    assert turn.outcome == "refused" and "m drop at" in (turn.reason or ""), _calls(rollout)
    assert rollout.success  # it still stands on the box


@pytest.mark.slow  # a whole planner search
def test_the_planner_turns_where_the_robot_fits_only_turned() -> None:
    solution = solve(_task("platform_narrower_than_the_robot_is_long"), worlds=2)
    assert solution.success_rate == 1.0
    assert solution.code is not None and solution.code.startswith("turn_to_heading(90)\n"), solution.code


def test_a_wall_taller_than_the_rays_start_reads_as_high_as_the_start() -> None:
    """Found by an adversarial run: a downward ray that starts inside a wall meets the wall where it leaves it, at its
    bottom, level with the floor: the 1.5 m wall of a sled read as floor, and walks and turns drove the torso into
    it. A ray that starts inside a geom reads that geom at the ray's start."""
    import numpy as np

    from robotool.robots.quadruped.quadruped_controller import QuadrupedController
    from robotool.sim.backend_choice import make_sim

    task = _task("sled_rams_a_board_across_a_gap")
    simulator = make_sim(sim.build(task), 1)
    simulator.step(1, np.ones(1, dtype=bool))
    rays = QuadrupedController(simulator, task.limits).plans.rays
    xs = np.arange(-1.0, -0.6, 0.002)
    heights, objects = rays.heights(0, np.column_stack([xs, np.zeros_like(xs)]), 0.95)
    wall = heights == 0.95  # the sled's upright, 12 mm thick, up to 1.84 m
    assert 4 <= wall.sum() <= 7 and np.all(objects[wall] == task.object_names.index("sled")), xs[wall]
    assert np.all((xs[wall] > -0.72) & (xs[wall] < -0.69))
    assert np.all(heights[~wall] < 0.37)  # the sled's plate and the sofa read as they are


def test_after_a_quarter_turn_each_corner_of_the_turned_outline_has_its_own_foot() -> None:
    """Facing +y, the rear-left foot stands at the outline's -x, -y corner and the front-left at its -x, +y one: walks
    planned on the turned outline read each foot's level, and name each foot, by where it stands."""
    from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
    from robotool.robots.quadruped.terrain import FOOT_NAMES, turned_feet

    names = [[FOOT_NAMES[i] for i in turned_feet(QuadrupedLimits(), q)] for q in range(4)]
    assert names[0] == list(FOOT_NAMES)
    assert names[1] == ["rear-left", "front-left", "rear-right", "front-right"]
    assert names[2] == ["front-left", "front-right", "rear-left", "rear-right"]


@pytest.mark.parametrize(("heading", "turned"), [(1e20, None), (90.0 * (2**44 + 1), True), (-720.0, False)])
def test_a_heading_of_many_turns_is_read_exactly(heading: float, turned: bool | None) -> None:
    """Found by an adversarial run: a heading of many turns passed the quarter-turn check (1e20 / 90 is a whole number)
    and turned the body to an angle off the quarters; each is now read as its remainder of a whole turn."""
    code = f"turn_to_heading({heading!r})\nprint(get_size('robot'))\n"
    (rollout,) = _run(_task("platform_narrower_than_the_robot_is_long"), code, worlds=1)
    turn = rollout.calls[0]
    if turned is None:
        assert turn.outcome == "refused" and "quarter turns" in (turn.reason or ""), _calls(rollout)
    else:
        assert turn.outcome == "done", _calls(rollout)
        assert rollout.calls[1].result == ([0.3, 0.65, 0.3] if turned else [0.65, 0.3, 0.3]), _calls(rollout)
