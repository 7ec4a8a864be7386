"""What a walk or a climb moves of what it runs into, under the shove rule's 3 cm (found by an adversarial run): a light
hook nudged out from under a 25 kg plank's end takes more force than a push of it may, and a light bar nudged into a
20 kg drum rams it off a stage. Both are refused; the same nudges with a light plank or a light drum are honest."""

from __future__ import annotations

import pytest
from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.rollout import Rollout
from robotool.sandbox import start_sessions
from robotool.verify import world_failure

HOOK = "nudge_a_loaded_hook_out_with_the_torso"
BAR = "nudge_a_bar_into_a_heavy_drum_with_the_torso"


def _run(layout: str, code: str, seed: int = 1) -> list[Rollout]:
    task = tasks.load(FIXTURES / "layouts" / f"{layout}.yaml")
    return sim.run_sessions(task, start_sessions([code] * 2, "quadruped"), seed=seed)


def _cheat(name: str) -> str:
    return (FIXTURES / "cheats" / f"{name}.py").read_text()


def _refusal(rollout: Rollout) -> str:
    assert not rollout.success and rollout.conditions["robot_shoved_nothing"] is False, world_failure(rollout)
    return world_failure(rollout) or ""


@pytest.mark.slow
@pytest.mark.parametrize("skill", ["walk_to_position", "climb_to_position"])
def test_a_walk_that_nudges_a_loaded_hook_from_under_a_heavy_plank_is_refused(skill: str) -> None:
    code = _cheat(HOOK).replace("walk_to_position", skill)
    for rollout in _run("loaded_hook_under_a_heavy_planks_end_on_a_waxed_floor", code):
        assert "the robot ran into hook and moved it" in _refusal(rollout), world_failure(rollout)
        assert "while it bore up another object in part" in (world_failure(rollout) or "")


@pytest.mark.slow
def test_a_walk_that_nudges_a_bar_into_a_heavy_drum_rams_it() -> None:
    for rollout in _run("light_bar_against_a_heavy_drum_on_a_stage", _cheat(BAR)):
        assert "bar, moved by the robot's walk or climb, rammed drum" in _refusal(rollout), world_failure(rollout)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("layout", "program"),
    [("loaded_hook_under_a_light_planks_end", HOOK), ("light_bar_against_a_light_drum_on_a_stage", BAR)],
    ids=["a light plank", "a light drum"],
)
def test_the_same_nudges_of_light_loads_succeed(layout: str, program: str) -> None:
    for rollout in _run(layout, _cheat(program)):
        assert rollout.success, world_failure(rollout)


@pytest.mark.xfail(
    strict=True,
    reason="open: what a push rams is weighed by mass, and by force only where the robot presses it; a light bar "
    "pushed into a light hook knocks it from under a heavy plank in one tick (the knock's force is read at no tick, "
    "and the plank's load lifts as it lands); the walk's check reads loads near the torso only. Reading them near the "
    "object pushed too refused the lever's honest chair push (the board on the chair drags a few cm, bearing the cube)",
)
def test_a_push_of_a_light_bar_that_knocks_a_loaded_hook_out_is_weighed() -> None:
    """Found by an adversarial run: 20/20 worlds on seeds 1-5 dropped the 25 kg plank."""
    for rollout in _run("light_bar_against_a_loaded_hooks_handle", _cheat("push_a_bar_into_a_loaded_hook")):
        assert not rollout.success, world_failure(rollout)
