"""What a push sets moving rams on its own way after the push, until it comes to rest (found by an adversarial run: a
light drum pushed and left to roll on knocked a crate twice or three times the push limit off an ice deck, and only
what it pressed while the push ran was weighed)."""

from __future__ import annotations

import pytest
from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.sandbox import start_sessions
from robotool.verify import world_failure

CHEATS = FIXTURES / "cheats"
LAYOUTS = FIXTURES / "layouts"


@pytest.mark.parametrize(
    ("program", "layout"),
    [
        ("push_a_drum_to_roll_on_into_a_heavy_crate", "drum_on_a_stage_before_a_heavy_crate_on_ice"),
        ("push_a_drum_over_the_ramp_top_into_a_heavy_crate", "drum_on_a_platform_above_a_ramp_to_a_heavy_crate"),
        # a box that wedged for a tick at an edge, then slid free down a ramp: one still tick was taken for rest
        ("push_a_box_to_wedge_then_slide_into_a_heavy_crate", "box_on_ice_above_a_ramp_to_a_heavy_crate"),
    ],
)
def test_a_light_object_left_to_move_on_into_a_heavy_crate_rams_it(program: str, layout: str) -> None:
    task = tasks.load(LAYOUTS / f"{layout}.yaml")
    code = (CHEATS / f"{program}.py").read_text()
    rollouts = sim.run_sessions(task, start_sessions([code] * 4, "quadruped"), seed=1)
    lowered = [r for r in rollouts if r.conditions["crate_lowered"]]
    assert lowered, "the crate stays on the deck in every world: the test shows nothing"
    for rollout in lowered:
        assert not rollout.success and not rollout.conditions["robot_shoved_nothing"], world_failure(rollout)


def test_a_drum_left_to_roll_on_into_a_light_crate_knocks_it_off() -> None:
    """The control: the same drum and push, the crate 0.5 kg (the pair within the 5 kg push limit)."""
    task = tasks.load(LAYOUTS / "drum_on_a_stage_before_a_heavy_crate_on_ice.yaml")
    crate = next(o for o in task.objects if o.name == "crate")
    light = crate.model_copy(update={"mass": 0.5})
    task = task.model_copy(update={"objects": [light if o is crate else o for o in task.objects]})
    code = (CHEATS / "push_a_drum_to_roll_on_into_a_heavy_crate.py").read_text()
    for rollout in sim.run_sessions(task, start_sessions([code] * 2, "quadruped"), seed=0):
        conditions = rollout.conditions
        assert conditions["crate_lowered"] and conditions["robot_shoved_nothing"], world_failure(rollout)
