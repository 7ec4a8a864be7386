"""Solids stay apart (found by an adversarial run): an object that comes out through a solid, the simulator's soft
contact having given way, fails its world whatever the goal; one that lands on it and stays there does not."""

from __future__ import annotations

from typing import Any

import pytest
from fixtures.paths import FIXTURES

from robotool import tasks
from robotool.verify import world_failure

CHEATS = FIXTURES / "cheats"
LAYOUTS = FIXTURES / "layouts"


@pytest.mark.parametrize(
    ("program", "layout"),
    [
        # a 1 cm rod let fall 0.33 m onto a 2 cm table top came out on the floor under it
        ("arm_drop_a_rod_through_a_table_top", "arm_steel_rod_over_a_table_top_covering_the_reach"),
        # a 2 mm rod let go 1.4 cm above a 1 mm steel table top fell through it
        ("arm_let_a_thin_rod_go_just_above_a_thin_steel_table", "arm_thin_steel_rod_over_a_one_mm_steel_table_top"),
        # the 1 cm rod dropped onto a deck of 2 cm steel bars lying side by side went through a bar's round side
        ("arm_drop_a_rod_through_a_table_top", "arm_steel_rod_over_a_deck_of_steel_bars"),
    ],
)
def test_a_rod_that_comes_out_under_the_table_top_fails(run_texts: Any, program: str, layout: str) -> None:
    task = tasks.load(LAYOUTS / f"{layout}.yaml")
    for rollout in run_texts(task, [(CHEATS / f"{program}.py").read_text()] * 3, seed=2):
        assert rollout.conditions["rod_lowered"], "the rod no longer falls through: the test shows nothing"
        assert not rollout.success and not rollout.conditions["nothing_passed_through"]
        (passed,) = [e for e in rollout.events if e.kind == "passed_through"]
        assert passed.object == "rod" and passed.detail.startswith(("table_top", "bar_")), passed
        assert f"rod passed through {passed.detail}" in world_failure(rollout), world_failure(rollout)


def test_a_rod_let_go_low_stays_on_the_table_top(run_texts: Any) -> None:
    """The control: the same rod let go 2 cm above the 2 cm table top lands on it and nothing is said to pass."""
    task = tasks.load(LAYOUTS / "arm_steel_rod_over_a_table_top_covering_the_reach.yaml")
    program = (CHEATS / "arm_drop_a_rod_through_a_table_top.py").read_text().replace("0.50", "0.20")
    for rollout in run_texts(task, [program] * 2, seed=2):
        assert rollout.conditions == {"rod_lowered": False, "nothing_passed_through": True}
        assert not any(e.kind == "passed_through" for e in rollout.events)
