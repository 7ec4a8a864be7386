"""The lift and tilt motors' load rests on what the feet stand on: a board balanced on a thin pillar tips under a
robot the lift carries onto it, in every world, while the same climb onto a board a wide block holds succeeds."""

from __future__ import annotations

from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.rollout import Rollout
from robotool.sandbox import start_sessions

LAYOUTS = FIXTURES / "layouts"
NWORLD = 6
CLIMB = """b = get_position("board")
climb_to_position([b[0], b[1], b[2]])
print(get_position("board")[2], get_size("board")[2])
"""
TIPPED_REASONS = ("slope of", "fell at", "ran into board")  # the refusals and the fall a tipping board gives
UP = 0.2  # m: the board's centre above this is still up where it lay (0.23), not fallen to the floor
TIPPED = 0.04  # m: the board's height as it is turned (0.02 level): over this it tilts more than about 1.3 deg


def _climb(layout: str) -> list[Rollout]:
    scene = sim.build(tasks.load(LAYOUTS / f"{layout}.yaml"))
    return sim.run_sessions(scene, start_sessions([CLIMB] * NWORLD, "quadruped"), world_seeds=list(range(NWORLD)))


def _board(rollout: Rollout) -> tuple[float, float]:
    """The board's centre height and its height as it is turned, at the end."""
    centre, height = (float(v) for v in rollout.output.split()[-2:])
    return centre, height


def test_a_climb_onto_a_board_balanced_on_a_pillar_tips_it_in_every_world() -> None:
    """The board tips under the front feet as the lift carries the body onto it: the climb is refused on the tilted
    board (a slope steeper than its friction holds), the board swings into the torso (ran into it), or the robot
    falls; it never ends standing on the board up on its pillar (regression: the lift carried the whole weight across,
    and the board, loaded only once the robot stood over the pillar, held it)."""
    for rollout in _climb("board_on_a_pillar"):
        reason = next((c.reason for c in rollout.calls if c.outcome in ("refused", "fell") and c.reason), "")
        assert not rollout.success, (_board(rollout), [(c.outcome, c.reason) for c in rollout.calls])
        assert any(tipped in reason for tipped in TIPPED_REASONS), reason


def test_the_same_climb_onto_a_board_a_wide_block_holds_succeeds_in_every_world() -> None:
    rollouts = _climb("board_on_a_block")
    assert all(r.success for r in rollouts), [(r.conditions, [c.reason for c in r.calls]) for r in rollouts]
    assert all(_board(r)[0] > UP and _board(r)[1] < TIPPED for r in rollouts), [_board(r) for r in rollouts]
