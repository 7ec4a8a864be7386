"""A push or a turn in place moves what it swings round as well as what it shifts: open holes (found by an
adversarial run), kept as strict xfails. A 20 kg plank lying aslant on a post in the middle of a gap, swung into line
over the gap, lets the robot walk across it."""

from __future__ import annotations

import pytest
from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.sandbox import start_sessions
from robotool.verify import world_failure

CASES = [
    pytest.param(
        "heavy_plank_aslant_over_a_gap_on_a_post",
        "ram_a_heavy_plank_round_on_its_post",  # a light box pushed into one end of the plank
        marks=pytest.mark.xfail(
            strict=True,
            reason="open: the ram rule weighs what a rammed object's centre travels (the plank's, under 3 cm; its "
            "ends, 0.4 m). Counting the corners' sweep about the vertical refused an honest chair pushed out from "
            "under a lever's raised end (the board on it yaws a few degrees as it comes down)",
        ),
        id="rammed by a pushed box",
    ),
    pytest.param(
        "heavy_plank_aslant_on_a_post_with_the_robot_on_it",
        "turn_in_place_to_swing_a_heavy_plank_round",  # four quarter turns on the plank's middle
        marks=pytest.mark.xfail(
            strict=True,
            reason="open: the stride rule weighs what an object's centre travels under the feet (2-5 mm here), and "
            "the yaw servo's reaction on what the feet stand on may be larger than the body's yaw inertia would give",
        ),
        id="turned on by the robot",
    ),
]


@pytest.mark.parametrize(("layout", "program"), CASES)
def test_a_heavy_plank_swung_round_into_a_bridge_is_weighed(layout: str, program: str) -> None:
    task = tasks.load(FIXTURES / "layouts" / f"{layout}.yaml")
    code = (FIXTURES / "cheats" / f"{program}.py").read_text()
    for rollout in sim.run_sessions(task, start_sessions([code] * 2, "quadruped"), seed=1):
        assert not rollout.success, world_failure(rollout)
