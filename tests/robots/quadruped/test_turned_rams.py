"""A push or a turn in place moves what it swings round as well as what it shifts (found by an adversarial run): a
20 kg plank lying aslant on a post in the middle of a gap, swung into line over the gap, lets the robot walk across
it. A light box rammed into one end of the plank swings it while its centre barely moves: the ram rule counts the
sweep of the plank's corners (the same ram with a 2 kg plank is an honest push). Four quarter turns in place on the
plank's middle swing it too: the stride rule counts the sweep of what the feet carry round (the same turns on a 4 kg
plank are an honest stride)."""

from __future__ import annotations

import pytest
from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.rollout import Rollout
from robotool.sandbox import start_sessions
from robotool.verify import world_failure


def _run(layout: str, program: str, seed: int = 1) -> list[Rollout]:
    task = tasks.load(FIXTURES / "layouts" / f"{layout}.yaml")
    code = (FIXTURES / "cheats" / f"{program}.py").read_text()
    return sim.run_sessions(task, start_sessions([code] * 2, "quadruped"), seed=seed)


@pytest.mark.slow
def test_a_light_box_rammed_into_a_heavy_planks_end_to_swing_it_round_is_refused() -> None:
    for rollout in _run("heavy_plank_aslant_over_a_gap_on_a_post", "ram_a_heavy_plank_round_on_its_post"):
        push = next(c for c in rollout.calls if c.outcome != "done")
        assert push.skill == "push_to_position" and push.outcome == "refused", world_failure(rollout)
        assert "pushing box rammed plank" in push.reason and push.measured["mass"] > 20.0, push
        assert not rollout.success and rollout.conditions["robot_shoved_nothing"] is False


@pytest.mark.slow
def test_the_same_ram_on_a_light_plank_swings_it_into_a_bridge() -> None:
    """The control (the plank's swing is the same; its weight is within the push limit). On other draws of the
    perturbed worlds the robot's stance behind the box can end on the plank's swung end, and the footing rule refuses
    that push: these two worlds keep to the stage."""
    for rollout in _run("light_plank_aslant_over_a_gap_on_a_post", "ram_a_heavy_plank_round_on_its_post", seed=3):
        assert rollout.success, world_failure(rollout)


@pytest.mark.slow
def test_turning_in_place_on_a_heavy_plank_to_swing_it_round_is_refused() -> None:
    """The stride rule counts the sweep of the corners of what it carries round under the feet (the plank's centre
    moves 2-5 mm)."""
    for rollout in _run(
        "heavy_plank_aslant_on_a_post_with_the_robot_on_it", "turn_in_place_to_swing_a_heavy_plank_round"
    ):
        turn = rollout.calls[0]
        assert turn.skill == "turn_to_heading" and turn.outcome == "refused", world_failure(rollout)
        assert turn.reason.startswith("plank, driven by the stride of the robot on it, moved"), turn.reason
        assert not rollout.success and rollout.conditions["robot_shoved_nothing"] is False


@pytest.mark.slow
def test_the_same_turns_on_a_light_plank_swing_it_into_a_bridge() -> None:
    for rollout in _run(
        "light_plank_aslant_on_a_post_with_the_robot_on_it", "turn_in_place_to_swing_a_heavy_plank_round"
    ):
        assert rollout.success, world_failure(rollout)


# Found by a second adversarial run, against the first versions of the sweeps: a box pushed along the plank's top drags
# it round by friction (no side pressed), and a light mat between the feet and the plank turns with the robot (the
# plank only touched what the stride carried).
BYPASSES = [
    ("heavy_plank_aslant_with_a_light_box_on_its_end", "drag_a_heavy_plank_round_by_a_box_on_its_end", "rammed plank"),
    (
        "heavy_plank_aslant_with_a_box_on_its_end_and_a_ram",
        "ram_a_box_on_a_heavy_planks_end_to_swing_it_round",
        "rammed plank",
    ),
    (
        "heavy_plank_aslant_on_a_post_under_a_light_mat",
        "turn_in_place_on_a_mat_to_swing_a_heavy_plank_round",
        "(mat, plank)",
    ),
]


@pytest.mark.slow
@pytest.mark.parametrize(
    ("layout", "program", "named"), BYPASSES, ids=["a box on its end", "a box rammed on its end", "a mat on it"]
)
def test_a_heavy_plank_swung_round_through_what_lies_on_it_is_weighed(layout: str, program: str, named: str) -> None:
    for rollout in _run(layout, program):
        assert not rollout.success and rollout.conditions["robot_shoved_nothing"] is False, world_failure(rollout)
        assert named in (world_failure(rollout) or ""), world_failure(rollout)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("layout", "program", "seed"),
    [(BYPASSES[0][0], BYPASSES[0][1], 1), (BYPASSES[1][0], BYPASSES[1][1], 2), (BYPASSES[2][0], BYPASSES[2][1], 2)],
    ids=["a box on its end", "a box rammed on its end", "a mat on it"],
)
def test_the_same_with_a_light_plank_swings_it_into_a_bridge(layout: str, program: str, seed: int) -> None:
    """The controls: on other draws of the worlds a light plank can tip under the robot as it walks on, a fall."""
    for rollout in _run(layout.replace("heavy", "light"), program, seed=seed):
        assert rollout.success, world_failure(rollout)
