"""The feet's grip where a cloth lies, under a pushed object's whole footprint, and against what a push drags or rams.

The feet meet a cloth lying on a surface, not the surface under it: a walk or a push from an oily tarp is refused, and
sliding a crate on a limp rubber mat takes the rubber's friction. A pushed object's friction is read under its whole
footprint (a crate on rubber with an ice seam under its centre slides on the rubber), and what it bears up in part
(an anvil lying partly on a pushed sled, partly on a fixed rail) loads the push. While a push moves, the force the
robot puts on what it pushes may exceed what its feet hold, wherever they stand as it goes (a push carried on from
rubber onto ice), only for ``push_strain_time`` in all (a light box ramming rubber-footed crates). Each cheat fails in
every world for the reason it names; the same moves on ordinary surfaces are the controls.
"""

from __future__ import annotations

import pytest
from fixtures.corpus_runs import reasons, run_quadruped
from fixtures.paths import FIXTURES

from robotool import tasks
from robotool.verify import run_worlds, world_failure

CLOTH = pytest.mark.slow  # a cloth's many links are many contacts to simulate


@pytest.mark.parametrize(
    ("layout", "program", "said"),
    [
        pytest.param(
            "oily_tarp_before_a_platform",
            "walk_across_an_oily_tarp_onto_a_platform",
            ["tarp is too slippery to walk on"],
            marks=CLOTH,
        ),
        pytest.param(
            "box_before_an_oily_tarp_on_a_stage",
            "push_a_box_off_a_stage_from_an_oily_tarp",
            ["cannot push box: sliding it takes", "the robot's feet hold (", "on tarp at friction"],
            marks=CLOTH,
        ),
        (
            "crate_on_a_rubber_mat_on_a_waxed_deck",
            "push_a_crate_off_a_deck_on_a_mat",
            ["cannot push crate: sliding it takes", "on rubber_mat at friction", "its feet would slip"],
        ),
        (
            "crate_over_an_ice_seam_in_a_rubber_deck",
            "push_a_crate_over_an_ice_seam_off_a_deck",
            ["cannot push crate: sliding it takes", "on rubber_", "its feet would slip"],
        ),
        (
            "anvil_on_a_sled_and_a_rail",
            "push_a_sled_dragging_what_lies_on_it_and_a_rail",
            ["cannot push sled: sliding it takes", "to drag anvil", "its feet would slip"],
        ),
    ],
)
def test_a_move_the_feet_cannot_hold_is_refused_at_its_start(layout: str, program: str, said: list[str]) -> None:
    """Read at the skill's start: the tarp under the feet (0.005), the rubber mat under the crate (2.0, not the waxed
    deck under it), the rubber under the crate's footprint (not the ice seam under its centre), the anvil's weight on
    the sled and its drag along the rail."""
    for rollout in run_quadruped(layout, program):
        move = next(c for c in rollout.calls if c.outcome != "done")
        assert not rollout.success and move.outcome == "refused", reasons([rollout])
        assert all(s in (move.reason or "") for s in said), move.reason
        m = move.measured
        assert m["force"] > m["limit"] if "force" in m else m["friction"] < m["limit"], m


def test_ramming_crates_the_feet_cannot_push_is_refused_as_it_moves() -> None:
    """A 0.8 kg box rams two rubber-footed crates (4.2 kg in all, within the push limit) off a waxed stage, along a
    rubber runner: the push takes about 67 N, over the about 24 N the feet hold on the wax for more than half a
    second, and over twice what sliding 5 kg on the box's support takes (whichever rule says it first)."""
    for rollout in run_quadruped(
        "light_box_before_rubber_footed_crates_on_a_waxed_stage", "ram_crates_off_a_stage_with_a_light_box"
    ):
        push = rollout.calls[-1]
        assert not rollout.success and push.outcome == "refused", reasons([rollout])
        reason = push.reason or ""
        assert reason.startswith("pushing box_a (touching crate_b, crate_c) took over"), reason
        feet = "the most the robot's feet hold on stage at friction" in reason and "feet would slip" in reason
        assert feet or "2 times what sliding 5.0 kg, the push limit, on its support takes" in reason, reason


@pytest.mark.parametrize(
    ("layout", "program"),
    [
        pytest.param("canvas_tarp_before_a_platform", "walk_across_an_oily_tarp_onto_a_platform", marks=CLOTH),
        pytest.param("box_before_a_canvas_tarp_on_a_stage", "push_a_box_off_a_stage_from_an_oily_tarp", marks=CLOTH),
        pytest.param("crate_on_a_felt_mat_on_a_wooden_deck", "push_a_crate_off_a_deck_on_a_mat", marks=CLOTH),
        ("crate_over_an_ice_seam_beside_a_rubber_deck", "push_a_crate_over_an_ice_seam_off_a_deck"),
        ("light_box_before_felt_footed_crates_on_a_wooden_stage", "ram_crates_off_a_stage_with_a_light_box"),
        ("weight_on_a_sled_and_a_rail", "push_a_sled_dragging_what_lies_on_it_and_a_rail"),
    ],
)
def test_the_same_moves_succeed_on_ordinary_surfaces(layout: str, program: str) -> None:
    """The controls: a canvas tarp (0.8), a felt mat on a wooden deck, the robot on rubber before the seam, felt-footed
    crates on a wooden stage, a 1 kg weight on the sled."""
    rollouts = run_quadruped(layout, program)
    assert all(r.success for r in rollouts), reasons(rollouts)


def test_a_push_carried_on_from_rubber_onto_ice_is_refused_where_the_feet_slip() -> None:
    """Found by an adversarial run (5 of 6 worlds on three seeds): the feet's hold was read once, at the push's start on
    rubber, and kept while the robot walked on onto ice that holds less than sliding the crate takes. Now it is read
    at every tick the push is weighed. (In a world whose perturbation leaves the ice grip enough, the push holds.)"""
    task = tasks.load(FIXTURES / "layouts" / "crate_pushed_from_rubber_onto_ice.yaml")
    program = (FIXTURES / "cheats" / "push_a_crate_on_from_rubber_onto_ice.py").read_text()
    for rollout in run_worlds(task, [program] * 3, [1, 2, 3]):
        assert not rollout.success, rollout.conditions
        assert "the most the robot's feet hold on ice_right at friction" in (world_failure(rollout) or "")
        assert "its feet would slip" in (world_failure(rollout) or ""), world_failure(rollout)
