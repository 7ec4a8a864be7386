"""The quadruped's candidate programs for lowering a vase: where the robot stands to push it off, and the way onto
the sofa planned around the cushion pushed beside it."""

from __future__ import annotations

import numpy as np

from robotool.planner.codegen import Program
from robotool.planner.layout import Layout
from robotool.robots.quadruped.quadruped_macros import candidates
from robotool.robots.quadruped.terrain import foot_offsets
from robotool.task_file import parse_task
from robotool.task_model import Task
from robotool.verify import failure_reason, prepare_code, run_codes


def _box(name: str, center: list[float], size: list[float], **more: object) -> dict[str, object]:
    return {"name": name, "shape": "box", "center": center, "size": size, **more}


def _vase_task(vase: list[float], cushion: list[float], steps_y: float) -> Task:
    """A 0.34 m sofa (x 1.55-2.45, y -1.65 to -0.15) with two fixed steps against its -x side; a glass vase on it
    and a soft cushion on the floor."""
    return parse_task({
        "format": 1, "name": "vase_test", "category": "sequential_tool_use",
        "instruction": "Put the glass vase down on the ground without breaking it.",
        "robot": {"type": "quadruped", "position": [-1.0, -1.0]},
        "objects": [
            _box("sofa", [2.0, -0.9, 0.17], [0.9, 1.5, 0.34], movable=False),
            _box("box_1", [0.95, steps_y, 0.06], [0.4, 0.6, 0.12], movable=False),
            _box("box_2", [1.35, steps_y, 0.12], [0.4, 0.6, 0.24], movable=False),
            _box("glass_vase", [*vase, 0.39], [0.3, 0.1, 0.1], mass=0.5, fragile={"max_drop": 0.3}),
            _box("soft_cushion", [*cushion, 0.08], [0.5, 0.5, 0.16], mass=1.0, soft=True),
        ],
        "goal": {"lowered": {"object": "glass_vase", "height": 0.2}},
    })


def _walk_targets(prog: Program) -> list[np.ndarray]:
    return [m.point.estimate()[:2] for m in prog.motions if m.skill in ("walk_to_position", "climb_to_position")]


def test_the_robot_stands_behind_the_vase_with_every_foot_on_the_sofa() -> None:
    """The vase lies by the sofa's corner above the steps: straight behind it the rear feet would hang over the
    0.24 m step, so the robot stands slid along the vase's face (as the push skill may) with all four on the sofa;
    the program lowers the vase onto the cushion in simulation."""
    task = _vase_task([1.80, -1.45], [-0.15, -1.4], -1.05)
    fine = [p for p in candidates(task, tools=True) if "soft_cushion" in p.objects and p.doubt is None]
    assert fine
    behind = _walk_targets(fine[0])[-1]
    feet = Layout(task).heights(behind + foot_offsets(task.limits), exclude=["glass_vase"])
    assert np.allclose(feet, 0.34, atol=0.01)
    code, rejection, _ = prepare_code(fine[0].code, task)
    assert rejection is None and code is not None
    (rollouts,) = run_codes(task, [code], worlds=1, seed=0)
    assert all(r.success for r in rollouts), failure_reason(rollouts)


def test_the_robot_stops_short_of_a_vase_lying_ahead_of_the_steps() -> None:
    """Fixed steps lead onto a sofa (toward +y) straight at a vase lying 0.35 m past its edge: the climb onto the
    sofa stops with every foot on it and the body clear of the vase, the robot walks around the vase and pushes it
    off the far side onto the cushion, in simulation."""
    task = parse_task({
        "format": 1, "name": "vase_ahead_of_steps", "category": "sequential_tool_use",
        "instruction": "Put the glass vase down on the ground without breaking it.",
        "robot": {"type": "quadruped", "position": [0.0, -1.0]},
        "objects": [
            _box("sofa", [2.0, 1.0, 0.17], [1.5, 0.9, 0.34], movable=False),
            _box("box_1", [1.6, -0.05, 0.06], [0.6, 0.4, 0.12], movable=False),
            _box("box_2", [1.6, 0.35, 0.12], [0.6, 0.4, 0.24], movable=False),
            _box("glass_vase", [1.62, 1.05, 0.39], [0.1, 0.3, 0.1], mass=0.5, fragile={"max_drop": 0.3}),
            _box("soft_cushion", [-0.5, 0.3, 0.08], [0.5, 0.5, 0.16], mass=1.0, soft=True),
        ],
        "goal": {"lowered": {"object": "glass_vase", "height": 0.2}},
    })
    fine = [p for p in candidates(task, tools=True) if "box_2" in p.objects and p.doubt is None]
    assert fine
    layout, top = Layout(task), 0.34
    on_sofa = [xy for xy in _walk_targets(fine[0]) if np.all(layout.heights(xy + foot_offsets(task.limits)) == top)]
    vase = layout.box("glass_vase")
    assert on_sofa and on_sofa[0][1] + task.limits.body_size[1] / 2 < vase.lo[1]
    code, rejection, _ = prepare_code(fine[0].code, task)
    assert rejection is None and code is not None
    (rollouts,) = run_codes(task, [code], worlds=1, seed=0)
    assert all(r.success for r in rollouts), failure_reason(rollouts)
