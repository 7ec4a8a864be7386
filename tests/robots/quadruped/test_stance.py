"""The stance read at the goal: a robot left standing on a slope steeper than its feet's friction holds, or pushed
sideways harder than it holds, has fallen.

The simulated body stands on frictionless feet held by world-anchored servos, so it stays on any slope; the goal read
must not count what only that makes possible (robotool/robots/quadruped/stance.py)."""

from __future__ import annotations

from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.robots.quadruped.referee import FALL_CONDITION
from robotool.sandbox import start_sessions
from robotool.task.task_file import parse_task
from robotool.verify import run_worlds, world_failure

LAYOUT = FIXTURES / "layouts" / "seesaw_tipped_onto_a_slippery_arm.yaml"
CHEAT = (FIXTURES / "cheats" / "stand_on_a_tipped_slippery_seesaw.py").read_text()


def test_a_robot_left_on_a_board_tipped_past_its_friction_has_fallen() -> None:
    """Found by an adversarial run (6 of 6 worlds on three seeds): walking past the drum tips the lacquered board and
    leaves the robot on its short arm at 15-22 deg, where friction 0.27 holds about 15; its weight kept the cube lifted
    and the world succeeded. Now the goal read finds the slope under its feet too steep: it has fallen."""
    for rollout in sim.run_sessions(sim.build(tasks.load(LAYOUT)), start_sessions([CHEAT] * 2, "quadruped"), seed=11):
        assert not rollout.success and rollout.conditions[FALL_CONDITION] is False, rollout.conditions
        assert "the robot fell: it stood where it would slide: a slope of" in (world_failure(rollout) or "")
        assert "on board, exceeds the" in (world_failure(rollout) or ""), world_failure(rollout)


def test_the_same_tipped_board_with_grip_enough_holds_the_robot() -> None:
    """The control: the same board with a grippy top (friction 0.6, about 31 deg) holds the robot where it ends."""
    data = tasks.load(LAYOUT).model_dump(mode="json", exclude_defaults=True)
    next(o for o in data["objects"] if o["name"] == "board")["friction"] = 0.6
    task = parse_task(data)
    for rollout in sim.run_sessions(sim.build(task), start_sessions([CHEAT] * 2, "quadruped"), seed=11):
        assert rollout.conditions[FALL_CONDITION] is True, world_failure(rollout)
        assert "would slide" not in (world_failure(rollout) or "")


def test_a_foot_near_a_side_edge_reads_the_slope_along_it() -> None:
    """Found trying to fool the stance read: on a 0.30 m wide ramp tilted 20 deg (friction 0.2), each foot stands 3 cm
    inside a side edge, so the rays 4 cm beside it missed the ramp and no slope was read: a program that stays where
    it starts stood on the ramp in every world. The slope along the ramp is read where its two points lie on it."""
    task = tasks.load(FIXTURES / "layouts" / "narrow_steep_ramp_under_the_start.yaml")
    for rollout in run_worlds(task, ['p = get_position("robot")'] * 2, [0, 1]):
        assert not rollout.success and rollout.conditions[FALL_CONDITION] is False, rollout.conditions
        assert "a slope of 20.0 deg under its" in (world_failure(rollout) or ""), world_failure(rollout)


def test_a_robot_pushed_sideways_harder_than_its_feet_hold_has_fallen() -> None:
    """Found by an adversarial run (every world on three seeds): a 25 kg plank leaning on the robot's side pushed it
    65-77 N sideways on a waxed stage whose friction holds about 46 N, and the world-anchored servos held it there.
    Without the plank the same stance holds."""
    task = tasks.load(FIXTURES / "layouts" / "heavy_plank_leaning_on_the_robot_on_a_waxed_stage.yaml")
    for rollout in run_worlds(task, ['p = get_position("robot")'] * 2, [0, 1]):
        assert not rollout.success and rollout.conditions[FALL_CONDITION] is False, rollout.conditions
        assert "it stood where it would slide: something pushed it" in (world_failure(rollout) or "")
    data = task.model_dump(mode="json", exclude_defaults=True)
    data["objects"] = [o for o in data["objects"] if o["name"] != "plank"]
    for rollout in run_worlds(parse_task(data), ['p = get_position("robot")'] * 2, [0, 1]):
        assert rollout.success, world_failure(rollout)
