"""A move needs grip under the feet: the feet are frictionless in the simulation and the body's x-y servos push from
the world, so the judge, not the physics, stops a walk, a turn or a push on ice.

A walk, a climb or a turn is refused where the friction under a foot (its world's, as the perturbation scales it) is
under the body's horizontal acceleration over g plus a slope's tangent; a push, where sliding what it pushes takes
more than the robot's weight times the friction under its feet. The same layouts at ordinary friction are controls.
"""

from __future__ import annotations

import numpy as np
import pytest
from fixtures.corpus_runs import reasons, run_quadruped


def test_the_walk_needs_the_grip_of_the_gaits_gentlest_start() -> None:
    """The walk's setpoint leaves at walk speed and runs at most the leash ahead of the body: the body accelerates at
    least at v^2 / (2 leash), 1.33 m/s^2: 0.136 g."""
    from robotool.robots.quadruped.quadruped_config import QUADRUPED

    assert QUADRUPED.walk_grip == pytest.approx(0.4**2 / (2 * 0.06) / 9.81)
    assert QUADRUPED.walk_grip == pytest.approx(0.136, abs=0.001)


def test_the_first_sample_too_slippery_for_the_walk_and_its_slope_is_found() -> None:
    """The need is the walk's grip plus the slope's tangent (the slope read less the slope rule's 1 degree)."""
    from robotool.robots.quadruped.terrain import first_slip

    flat, ten = 0.0, np.tan(np.radians(10.0))
    tangent = np.array([[flat, flat, flat, flat], [np.nan, ten, ten, ten], [flat] * 4])
    friction = np.array([[0.5, 0.5, 0.1, 0.5], [0.3, 0.3, 0.25, 0.5], [np.inf, 0.2, 0.2, 0.2]])
    index, have, need = first_slip(tangent, friction, 0.136)
    assert index.tolist() == [2, 2, 4]
    assert have[:2].tolist() == [0.1, 0.25]
    assert need[0] == pytest.approx(0.136) and need[1] == pytest.approx(0.136 + np.tan(np.radians(9.0)))


def test_a_walk_on_ice_is_refused_where_the_robot_stands() -> None:
    """Standing on ice (friction 0.001), the walk across the rink onto the iced platform is refused at once, where the
    feet stand, naming the ice and the friction against what the walk needs."""
    for rollout in run_quadruped("ice_rink_before_an_iced_platform", "walk_across_an_ice_rink_onto_a_platform"):
        walk = rollout.calls[-1]
        assert not rollout.success and walk.outcome == "refused", reasons([rollout])
        assert "ice is too slippery to walk on" in (walk.reason or ""), walk.reason
        assert walk.measured["friction"] < 0.0013 and walk.measured["limit"] == pytest.approx(0.136, abs=0.001)
        assert walk.measured["x"] < 0.0, walk.measured  # under a foot where it stands: it never left
        assert rollout.conditions["robot_weight_on_platform"] is False


def test_a_walk_onto_an_iced_platform_stops_before_it() -> None:
    """From a rink of ordinary friction the walk stops before the iced platform's edge (at x = 1.5), refused there."""
    for rollout in run_quadruped("rink_before_an_iced_platform", "walk_across_an_ice_rink_onto_a_platform"):
        walk = rollout.calls[-1]
        assert not rollout.success and walk.outcome == "refused", reasons([rollout])
        assert "platform is too slippery to walk on" in (walk.reason or ""), walk.reason
        assert walk.measured["friction"] < walk.measured["limit"]
        assert 1.45 <= walk.measured["x"] <= 1.55, walk.measured


def test_a_turn_on_ice_is_refused() -> None:
    """A quarter turn in place on the ice is refused: the feet cannot push the body round."""
    for rollout in run_quadruped("ice_rink_before_an_iced_platform", "turn_on_an_ice_rink_then_walk_onto_the_platform"):
        turn = rollout.calls[0]
        assert not rollout.success and turn.outcome == "refused", reasons([rollout])
        assert "ice is too slippery to turn on" in (turn.reason or ""), turn.reason


def test_a_push_from_ice_is_refused() -> None:
    """Standing on ice, the robot may not push a 4.2 kg rubber-footed crate (about 41 N to slide): its feet hold
    about 0.1 N."""
    for rollout in run_quadruped("crate_on_an_ice_deck", "push_a_crate_off_an_ice_deck"):
        push = rollout.calls[-1]
        assert not rollout.success and push.outcome == "refused", reasons([rollout])
        assert "cannot push crate: sliding it takes" in (push.reason or ""), push.reason
        assert "its feet would slip" in (push.reason or "") and "ice_deck" in (push.reason or ""), push.reason
        assert push.measured["force"] > 30.0 and push.measured["limit"] < 0.2, push.measured
        assert rollout.conditions["crate_lowered"] is False


def test_a_push_the_feet_can_walk_on_but_not_hold_is_refused() -> None:
    """On a waxed deck (friction 0.2) the robot may walk, but its feet hold 24 N, under the 41 N that sliding the crate
    takes (both scaled alike by each world's perturbation, the crate's mass by up to 15%): refused with the forces."""
    for rollout in run_quadruped("crate_on_a_waxed_deck", "push_a_crate_off_an_ice_deck"):
        push = rollout.calls[-1]
        assert not rollout.success and push.outcome == "refused", reasons([rollout])
        assert "its feet would slip" in (push.reason or "") and "waxed_deck" in (push.reason or ""), push.reason
        force, holds = push.measured["force"], push.measured["limit"]
        assert force / holds == pytest.approx(4.2 * 1.0 / (12.0 * 0.2), rel=0.16), push.measured


@pytest.mark.parametrize(
    ("layout", "program"),
    [
        ("rink_before_a_platform", "walk_across_an_ice_rink_onto_a_platform"),
        ("rink_before_a_platform", "turn_on_an_ice_rink_then_walk_onto_the_platform"),
        ("crate_on_a_rubber_deck", "push_a_crate_off_an_ice_deck"),
    ],
)
def test_the_same_moves_succeed_at_ordinary_friction(layout: str, program: str) -> None:
    """The controls: the rink and the platform at friction 0.6, the deck at 1.0 (the feet hold 118 N)."""
    rollouts = run_quadruped(layout, program)
    assert all(r.success for r in rollouts), reasons(rollouts)
