"""The motors' and servos' load rests on what the feet stand on: a board balanced on a thin pillar tips under a
robot the lift carries onto it, in every world, while the same climb onto a board a wide block holds succeeds; a
stride along a board on free rollers rolls it back, so that a walk along it falls short of the dock beyond it, while
the same walk along the board on fixed blocks reaches the dock."""

from __future__ import annotations

import numpy as np
import pytest
from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.rollout import Rollout
from robotool.sandbox import start_sessions
from robotool.verify import world_failure

LAYOUTS = FIXTURES / "layouts"
PROGRAM = (FIXTURES / "cheats" / "walk_off_a_cart_onto_the_dock.py").read_text()
NWORLD = 6
CLIMB = """b = get_position("board")
climb_to_position([b[0], b[1], b[2]])
print(get_position("board")[2], get_size("board")[2])
"""
TIPPED_REASONS = ("slope of", "fell at", "ran into board")  # the refusals and the fall a tipping board gives
UP = 0.2  # m: the board's centre above this is still up where it lay (0.23), not fallen to the floor
TIPPED = 0.04  # m: the board's height as it is turned (0.02 level): over this it tilts more than about 1.3 deg


def _walks(layout: str, program: str) -> list[Rollout]:
    scene = sim.build(tasks.load(LAYOUTS / f"{layout}.yaml"))
    return sim.run_sessions(scene, start_sessions([program] * NWORLD, "quadruped"), world_seeds=list(range(NWORLD)))


def _board(rollout: Rollout) -> tuple[float, float]:
    """The board's centre height and its height as it is turned, at the end."""
    centre, height = (float(v) for v in rollout.output.split()[-2:])
    return centre, height


def test_a_climb_onto_a_board_balanced_on_a_pillar_tips_it_in_every_world() -> None:
    """The board tips under the front feet as the lift carries the body onto it: the climb is refused on the tilted
    board (a slope steeper than its friction holds), the board swings into the torso (ran into it), or the robot
    falls; it never ends standing on the board up on its pillar (regression: the lift carried the whole weight across,
    and the board, loaded only once the robot stood over the pillar, held it)."""
    for rollout in _walks("board_on_a_pillar", CLIMB):
        reason = next((c.reason for c in rollout.calls if c.outcome in ("refused", "fell") and c.reason), "")
        assert not rollout.success, (_board(rollout), [(c.outcome, c.reason) for c in rollout.calls])
        assert any(tipped in reason for tipped in TIPPED_REASONS), reason


def test_the_same_climb_onto_a_board_a_wide_block_holds_succeeds_in_every_world() -> None:
    rollouts = _walks("board_on_a_block", CLIMB)
    assert all(r.success for r in rollouts), [(r.conditions, [c.reason for c in r.calls]) for r in rollouts]
    assert all(_board(r)[0] > UP and _board(r)[1] < TIPPED for r in rollouts), [_board(r) for r in rollouts]


STRIDE = """before = get_position("cart")
walk_to_position([-0.6, 0.0, 0.0])
print(get_position("cart")[0] - before[0])
"""
ROLLED_BACK = 0.2  # m: a 0.3 m stride rolls the cart on free rollers back at least this far (it held within 0.02)
MISSED = ("step up of 0.15 m", "gap of", "ran into cart", "ran into roller", "fell at")  # short of the dock


def _why(rollout: Rollout) -> list[tuple[str, str | None]]:
    return [(c.outcome, c.reason) for c in rollout.calls]


def test_a_stride_along_a_board_on_free_rollers_rolls_it_back_in_every_world() -> None:
    """The x-y servos' force goes back through the feet: walking 0.3 m along a loose 1 kg board on free rollers rolls
    it back under the robot (regression: the world-anchored servos moved the body and the board stayed put)."""
    for rollout in _walks("cart_on_rollers_before_a_tall_dock", STRIDE):
        assert float(rollout.output.split()[-1]) < -ROLLED_BACK, (rollout.output, _why(rollout))


def test_a_walk_along_a_cart_on_rollers_onto_the_dock_falls_short_in_every_world() -> None:
    """The stride rolls the cart back to the kerb: the robot is left short of the dock, a step too high from the
    floor before it (or the gap to it too wide), or the cart, rolled back and forth, runs into its legs."""
    for rollout in _walks("cart_on_rollers_before_a_tall_dock", PROGRAM):
        reason = next((c.reason for c in rollout.calls if c.outcome in ("refused", "fell") and c.reason), "")
        assert not rollout.success, _why(rollout)
        assert any(missed in reason for missed in MISSED), reason


def test_the_same_walk_along_the_board_on_fixed_blocks_reaches_the_dock() -> None:
    for rollout in _walks("cart_on_blocks_before_a_tall_dock", PROGRAM):
        assert rollout.success, _why(rollout)
        before, after = (np.array(c.result) for c in rollout.calls if c.skill == "get_position" and c.args[0] == "cart")
        assert abs(after[0] - before[0]) < 0.02, (before, after)


@pytest.mark.parametrize(
    ("layout", "program", "reasons"),
    [
        ("board_on_a_pillar", "climb_onto_a_pillar_board_in_short_steps", (*TIPPED_REASONS, "step up of")),
        ("cart_on_rollers_before_a_tall_dock", "climb_from_a_cart_onto_the_dock", ("step up of", "ran into cart")),
    ],
)
def test_the_same_cheats_in_other_call_orders_fail_in_every_world(
    layout: str, program: str, reasons: tuple[str, ...]
) -> None:
    """Tried as an optimiser would: the pillar climb in short steps (each crossing's ramped load small), and the cart
    crossed by one climb instead of a walk (no stride reaction while the lift carries the body)."""
    text = (FIXTURES / "cheats" / f"{program}.py").read_text()
    for rollout in _walks(layout, text):
        failure = world_failure(rollout) or ""
        assert not rollout.success and any(r in failure for r in reasons), failure
