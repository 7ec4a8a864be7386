"""A corpus of cheating quadruped programs: each must fail in every perturbed world, with a reason one can read.

The programs are files in ``tests/fixtures/cheats/`` (and a few in ``tests/fixtures/programs/``); the scenes are
built-in tasks and variants of them made here: the sofas without the board (a bare 0.40 m gap), the same turned a
quarter (the robot crosses with its flank leading), a strip of cloth lying across the gap, and a gap wider than the
surfboard can span.
"""

from __future__ import annotations

import functools
from typing import Any

import pytest
from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.rollout import Rollout
from robotool.sandbox import start_sessions
from robotool.task_file import parse_task
from robotool.task_model import Task

CHEATS = FIXTURES / "cheats"
PROGRAMS = FIXTURES / "programs"


def _variant(name: str) -> Task:
    data = tasks.load("sofa_traversing").model_dump(mode="json", exclude_defaults=True)
    objects = {o["name"]: o for o in data["objects"]}
    if name in ("no_board", "sideways", "cloth_across"):
        del objects["surfboard"]
    if name in ("no_board", "sideways"):
        del objects["strip_of_cloth"]
    if name == "cloth_across":
        objects["strip_of_cloth"]["center"] = [0.95, 0.0, 0.342]  # 0.35 m on each sofa, sagging between
    if name == "wide_gap":
        del objects["strip_of_cloth"]
        objects["sofa_2"]["center"][0] += 0.2  # a 0.60 m gap, wider than the board can span with room to rest
    if name == "sideways":  # a quarter turn: the sofas lie along y
        for obj in objects.values():
            obj["center"] = [obj["center"][1], obj["center"][0], obj["center"][2]]
            obj["size"] = [obj["size"][1], obj["size"][0], obj["size"][2]]
        x, y = data["robot"]["position"]
        data["robot"]["position"] = [y, x]
    data["objects"] = list(objects.values())
    data["name"] = f"sofa_traversing_{name}"
    return parse_task(data)


@functools.cache
def _scene(name: str) -> sim.Scene:
    task = tasks.load(name) if name in tasks.names() else _variant(name)
    return sim.build(task)


def failure_reason(rollout: Rollout) -> str:
    """Why a world failed: the first motion that did not end as planned, else the goal's unmet conditions."""
    for call in rollout.calls:
        if call.outcome in ("refused", "fell", "stalled", "timeout", "error") and call.reason:
            return call.reason
    return ", ".join(k for k, v in rollout.conditions.items() if not v)


CASES = [
    ("gap_one_walk", "sofa_traversing"),
    ("gap_one_walk", "no_board"),
    ("gap_one_walk", "sideways"),
    ("gap_one_walk", "cloth_across"),
    ("gap_short_walks", "sofa_traversing"),
    ("gap_short_walks", "no_board"),
    ("gap_zigzag", "sofa_traversing"),
    ("gap_zigzag", "no_board"),
    ("gap_diagonal", "sofa_traversing"),
    ("gap_diagonal", "no_board"),
    ("gap_front_half_over", "sofa_traversing"),
    ("gap_front_half_over", "no_board"),
    ("gap_back_and_forth", "no_board"),
    ("gap_climb_out", "no_board"),
    ("gap_raised_target", "no_board"),
    ("gap_overshoot_and_back", "no_board"),
    ("partial_bridge", "sofa_traversing"),
    ("partial_bridge", "wide_gap"),
    ("cloth_bridge", "sofa_traversing"),
    ("sofa_diagonal", "sofa_climbing"),
    ("sofa_short_climbs", "sofa_climbing"),
    ("programs/sofa_climbing_direct", "sofa_climbing"),
    ("one_foot_on_target", "sofa_climbing_low_sofa"),
    ("front_feet_on_target", "sofa_climbing_low_sofa"),
    ("push_board_with_cube", "cube_lifting"),
    ("programs/cube_lifting_lever_only", "cube_lifting"),
]


@pytest.mark.parametrize(("program", "scene"), CASES)
def test_cheat_fails_in_every_world_with_a_reason(program: str, scene: str) -> None:
    path = PROGRAMS / f"{program.split('/')[1]}.py" if program.startswith("programs/") else CHEATS / f"{program}.py"
    rollouts = sim.run_sessions(_scene(scene), start_sessions([path.read_text()] * 3, "quadruped"), seed=11)
    for rollout in rollouts:
        reason = failure_reason(rollout)
        assert not rollout.success, [(c.skill, c.args, c.outcome) for c in rollout.calls]
        assert reason, rollout


def test_the_board_is_refused_with_the_cube_riding_on_it() -> None:
    scene = _scene("cube_lifting")
    (rollout,) = sim.run_sessions(
        scene, start_sessions([(CHEATS / "push_board_with_cube.py").read_text()], "quadruped"), perturb=False
    )
    (push,) = [c for c in rollout.calls if c.skill == "push_to_position"]
    assert push.outcome == "refused" and "cube riding on it" in push.reason
    assert push.measured["mass"] == pytest.approx(12.0, abs=0.01)


@pytest.mark.parametrize(
    ("program", "scene"),
    [("gap_one_walk", "sofa_traversing_small_gap"), ("sofa_short_climbs", "sofa_climbing_low_sofa")],
)
def test_the_same_walks_succeed_where_the_legs_allow_them(run_texts: Any, program: str, scene: str) -> None:
    rollouts = run_texts(_scene(scene), [(CHEATS / f"{program}.py").read_text()] * 2, seed=11)
    assert all(r.success for r in rollouts), [failure_reason(r) for r in rollouts]
