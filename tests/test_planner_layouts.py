"""The search planner on layouts it was not built from (task fixtures under tests/fixtures/layouts/): staircases of
two and three pushed boxes approached from -x and +y, a gap crossed toward -x, levers reflected and turned along y.

Each is solved with a verified success, and a tool-free attempt fails in simulation."""

from __future__ import annotations

from pathlib import Path

import pytest

from robotool import tasks
from robotool.planner import solve
from robotool.scene import Task
from robotool.verify import failure_reason, prepare_code, run_codes

LAYOUTS = Path(__file__).parent / "fixtures" / "layouts"
NAMES = sorted(p.stem for p in LAYOUTS.glob("*.yaml"))


def _load(name: str) -> Task:
    return tasks.load(LAYOUTS / f"{name}.yaml")


def _tool_free_program(task: Task) -> str:
    """The direct attempt without a tool: walk (or climb) straight onto the target, or push the object to be lifted."""
    target = task.object(task.goal.object)
    if task.goal.kind == "robot_on":
        return f"p = get_position({target.name!r})\nclimb_to_position([p[0], p[1], {target.top:.4f}])\n"
    return f"p = get_position({target.name!r})\npush_to_position({target.name!r}, [p[0] + 0.3, p[1], p[2]])\n"


def test_every_layout_fixture_is_here() -> None:
    assert {"gap_toward_minus_x", "lever_along_y", "lever_reversed", "staircase_three", "staircase_two_toward_minus_x",
            "staircase_two_toward_plus_y"} <= set(NAMES)


@pytest.mark.parametrize("name", NAMES)
def test_planner_solves_unseen_layout(name: str) -> None:
    task = _load(name)
    solution = solve(task, worlds=2)
    best = next((c for c in solution.candidates if c.index == solution.best), None)
    assert solution.success_rate == 1.0, best.failure if best else solution.notes
    assert best is not None and all(r.success for r in best.rollouts)
    roles = {r.name: r.role for r in solution.stages.object_roles or []}
    assert any(role.startswith("tool") for role in roles.values())


@pytest.mark.parametrize("name", NAMES)
def test_unseen_layout_is_not_solved_without_a_tool(name: str) -> None:
    task = _load(name)
    no_tool = solve(task, worlds=2, tools=False)
    assert not no_tool.success and no_tool.success_rate == 0.0
    code, rejection, _ = prepare_code(_tool_free_program(task), task)
    assert rejection is None and code is not None
    (rollouts,) = run_codes(task, [code], worlds=2, seed=0)
    assert rollouts and not any(r.success for r in rollouts)
    assert failure_reason(rollouts)
