"""The quadruped pushes only while it stands on the ground or on a fixed object: checked when the push is called, as
each push leg starts and all along the push (found by an adversarial run: a push called from a fixed stage walked the
robot onto a loose deck and pushed a box off it from there)."""

from __future__ import annotations

import pytest
from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.rollout import Rollout
from robotool.sandbox import start_sessions

PROGRAM = (FIXTURES / "cheats" / "push_a_box_off_a_deck_from_the_stage.py").read_text()


def _run(layout: str) -> list[Rollout]:
    task = tasks.load(FIXTURES / "layouts" / f"{layout}.yaml")
    return sim.run_sessions(task, start_sessions([PROGRAM] * 2, "quadruped"), seed=SEED)


SEED = 2


@pytest.mark.parametrize(
    ("layout", "reason"),
    [
        ("box_near_a_loose_decks_edge_by_a_fixed_stage", "the robot came to stand on deck, which is movable, while"),
        ("box_amid_a_loose_deck_by_a_fixed_stage", "the robot stands on deck, which is movable"),
    ],
)
def test_a_push_from_a_loose_deck_is_refused_however_the_robot_got_onto_it(layout: str, reason: str) -> None:
    for rollout in _run(layout):
        (push,) = [c for c in rollout.calls if c.skill == "push_to_position"]
        assert push.outcome == "refused" and f"cannot push box: {reason}" in push.reason, push
        assert not rollout.success


def test_the_same_push_succeeds_where_the_deck_is_fixed() -> None:
    rollouts = _run("box_near_a_fixed_decks_edge_by_a_fixed_stage")
    assert all(r.success for r in rollouts), [[(c.skill, c.outcome, c.reason) for c in r.calls] for r in rollouts]
