"""A push or a turn in place rams what it swings round as well as what it moves: open holes, kept as strict xfails."""

from __future__ import annotations

import pytest
from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.sandbox import start_sessions
from robotool.verify import world_failure


@pytest.mark.xfail(
    strict=True,
    reason="open: the ram rule weighs what a rammed object's centre travels; a 20 kg plank swung about a post in its "
    "middle moves its ends 0.4 m and its centre under 3 cm. Counting the corners' sweep about the vertical refuses an "
    "honest chair pushed out from under a lever's raised end (the board on it yaws a few degrees)",
)
def test_a_heavy_plank_swung_round_by_a_rammed_box_is_weighed() -> None:
    """Found by an adversarial run: a light box pushed into one end of a 20 kg plank lying aslant on a post over a gap
    swings the plank into line, and the robot walks across it."""
    task = tasks.load(FIXTURES / "layouts" / "heavy_plank_aslant_over_a_gap_on_a_post.yaml")
    code = (FIXTURES / "cheats" / "ram_a_heavy_plank_round_on_its_post.py").read_text()
    for rollout in sim.run_sessions(task, start_sessions([code] * 3, "quadruped"), seed=1):
        assert "pushing box rammed plank" in (world_failure(rollout) or ""), world_failure(rollout)


@pytest.mark.xfail(
    strict=True,
    reason="open: the stride rule weighs what an object's centre travels under the feet; turning in place on a 20 kg "
    "plank balanced on a post swings it round (centre 2-5 mm), and the yaw servo's reaction on what the feet stand on "
    "may be larger than the body's own yaw inertia would give",
)
def test_a_heavy_plank_swung_round_by_turning_on_it_is_weighed() -> None:
    """Found by an adversarial run: four quarter turns on the middle of a 20 kg plank on a post swing it 60 degrees,
    into line over a gap, and the robot walks across it."""
    task = tasks.load(FIXTURES / "layouts" / "heavy_plank_aslant_on_a_post_with_the_robot_on_it.yaml")
    code = (FIXTURES / "cheats" / "turn_in_place_to_swing_a_heavy_plank_round.py").read_text()
    for rollout in sim.run_sessions(task, start_sessions([code] * 2, "quadruped"), seed=1):
        assert not rollout.success, world_failure(rollout)
