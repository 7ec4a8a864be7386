"""The quadruped on mujoco_warp (Warp's CPU device): the surfboard bridge, in one batch of 11 worlds.

Kept to one task: the first Warp kernel compile is slow on CPU.
"""

from __future__ import annotations

from typing import Any

import pytest
from fixtures.reference import program

from robotool.rollout import Rollout

pytest.importorskip("mujoco_warp")


@pytest.fixture(scope="session")
def bridge_rollouts(sim_scene: Any, run_texts: Any) -> list[Rollout]:
    """Ten perturbed worlds of the bridge program and one tool-free walk, stepped together on Warp."""
    programs = [program("sofa_traversing")] * 10 + [program("sofa_traversing_direct")]
    return run_texts(sim_scene("sofa_traversing"), programs, seed=5, backend="warp")


def test_bridge_solves_nine_of_ten_worlds_on_warp(bridge_rollouts: list[Rollout]) -> None:
    assert sum(r.success for r in bridge_rollouts[:10]) >= 9


def test_tool_free_walk_is_refused_at_the_gap_on_warp(bridge_rollouts: list[Rollout]) -> None:
    direct = bridge_rollouts[10]
    (walk,) = [c for c in direct.calls if c.skill == "walk_to_position"]
    assert not direct.success and walk.outcome == "refused"
    assert walk.measured["gap"] == pytest.approx(0.30, abs=0.02)  # beyond the end of the overhanging board
