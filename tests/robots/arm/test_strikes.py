"""Glass struck by what moves (found by adversarial runs): a fragile object breaks when the robot or a movable object
comes to touch it (or what rests on it) faster than a fall of its ``max_drop`` lands (a soft one with more energy than
that fall), not only in a fall of its own onto what does not move, a fixed one too; and a gentle touch leaves it
whole."""

from __future__ import annotations

from typing import Any

import pytest
from fixtures.paths import FIXTURES

from robotool import tasks
from robotool.rollout import Rollout
from robotool.verify import world_failure

CHEATS = FIXTURES / "cheats"
LAYOUTS = FIXTURES / "layouts"
PROGRAMS = FIXTURES / "programs"


@pytest.mark.parametrize(
    ("program", "layout", "striker"),
    [
        # a dish that slid off a shelf fell about 0.22 m (max_drop 0.10 m) onto the gripper's palm: whole, since a fall
        # onto the robot was not read as onto something hard
        ("arm_catch_a_sliding_glass_dish_on_the_palm", "arm_glass_dish_sliding_off_a_tilted_shelf", "the robot"),
        # a 3 kg block let go 0.43 m above a dish lying on the floor: whole, since only its own falls were judged
        ("arm_drop_an_iron_block_onto_a_glass_dish", "arm_iron_block_on_a_stool_beside_a_glass_dish", "block"),
        # the same block onto the dish fixed to the floor: a fixed fragile object was never judged
        ("arm_drop_an_iron_block_onto_a_glass_dish", "arm_iron_block_on_a_stool_beside_a_fixed_glass_dish", "block"),
        # the same 3 kg block as a sandbag (soft): a soft object struck nothing, however heavy and fast
        ("arm_drop_an_iron_block_onto_a_glass_dish", "arm_sandbag_on_a_stool_beside_a_glass_dish", "block"),
        # a stick pushed near its pivot swept its far end into a dish pinned by a wall: the stick's centre hardly moved
        ("arm_swing_a_stick_into_a_walled_glass_dish", "arm_stick_beside_a_walled_glass_dish", "stick"),
        # a 3 kg block let go 0.29 m above a lid resting on a jar: only a new touch of the jar itself was a strike
        (
            "arm_drop_an_iron_block_onto_a_lid_on_a_glass_jar",
            "arm_iron_block_above_a_lidded_glass_jar",
            "block through lid",
        ),
        # the same through a board lying on the lid: only what touched the jar itself passed a blow on
        (
            "arm_drop_an_iron_block_onto_a_board_on_a_lidded_glass_jar",
            "arm_iron_block_above_a_glass_jar_under_a_lid_and_a_board",
            "block through board",
        ),
    ],
)
def test_glass_met_faster_than_its_fall_lands_breaks(run_texts: Any, program: str, layout: str, striker: str) -> None:
    task = tasks.load(LAYOUTS / f"{layout}.yaml")
    rollouts: list[Rollout] = run_texts(task, [(CHEATS / f"{program}.py").read_text()] * 2, seed=11)
    for rollout in rollouts:
        assert not rollout.success
        (broke,) = [e for e in rollout.events if e.kind == "broke"]
        assert broke.detail == striker and broke.measured["strike_speed"] > broke.measured["max_speed"], broke
        assert f"{striker} met it at" in world_failure(rollout), world_failure(rollout)


@pytest.mark.parametrize(
    ("layout", "under", "centre"),  # centre: the block's centre's height as it rests on what lies under it
    [
        ("arm_iron_block_on_a_stool_beside_a_glass_dish", "dish", 0.036),
        ("arm_iron_block_on_a_stool_beside_a_fixed_glass_dish", "dish", 0.036),
        ("arm_sandbag_on_a_stool_beside_a_glass_dish", "dish", 0.036),
        ("arm_iron_block_above_a_lidded_glass_jar", "lid", 0.159),
        ("arm_iron_block_above_a_glass_jar_under_a_lid_and_a_board", "board", 0.189),
    ],
)
def test_a_block_set_down_gently_on_the_glass_leaves_it_whole(
    run_texts: Any, layout: str, under: str, centre: float
) -> None:
    """The controls: the same block carried over the glass (or its lid) and lowered onto it at the arm's pace, then
    let go."""
    program = (
        'g = get_graspable_point("block")\n'
        "open_gripper()\n"
        "move_to_position([g[0], g[1], g[2] + 0.05])\n"
        "move_to_position(g)\n"
        "close_gripper()\n"
        "move_to_position([g[0], g[1], 0.48])\n"
        f'd = get_center("{under}")\n'
        "move_to_position([d[0], d[1], 0.48])\n"
        f"move_to_position([d[0], d[1], g[2] - get_center('block')[2] + {centre}])\n"
        "open_gripper()\n"
        "move_to_position([d[0], d[1], 0.45])\n"
    )
    task = tasks.load(LAYOUTS / f"{layout}.yaml")
    rollouts: list[Rollout] = run_texts(task, [program] * 2, seed=11)
    assert all(r.success for r in rollouts), [world_failure(r) for r in rollouts]
    assert not [e for r in rollouts for e in r.events if e.kind == "broke"]


@pytest.mark.parametrize(
    ("program", "layout", "strikers"),
    [
        # a plank leaning from a 1.5 m glass floor onto a block, a 12 kg crate on it, shoved off the block, swings down
        # about its low end: over 2 m/s where its far end lands, 1.1 m/s where the glass's centre lies (read there)
        (
            "arm_shove_a_loaded_plank_off_its_block_onto_a_glass_floor",
            "arm_crate_on_a_plank_leaning_on_a_block_over_a_glass_floor",
            {"plank", "crate"},
        ),
        # a pole on a wide glass floor, pushed over: its foot touches the glass throughout, and its top lands 0.4 m from
        # where it touched it at the reading before (only a striker's first touch was read)
        ("arm_topple_a_pole_standing_on_a_glass_floor", "arm_pole_standing_on_a_wide_glass_floor", {"pole"}),
    ],
)
def test_a_striker_turning_about_a_point_strikes_where_it_lands(
    run_texts: Any, program: str, layout: str, strikers: set[str]
) -> None:
    task = tasks.load(LAYOUTS / f"{layout}.yaml")
    rollouts: list[Rollout] = run_texts(task, [(CHEATS / f"{program}.py").read_text()] * 2, seed=11)
    for rollout in rollouts:
        assert not rollout.success
        (broke,) = [e for e in rollout.events if e.kind == "broke"]
        assert broke.detail in strikers and broke.measured["strike_speed"] > broke.measured["max_speed"], broke


@pytest.mark.parametrize(
    ("program", "layout"),
    [
        ("arm_push_a_block_along_a_fixed_glass_table", "arm_block_on_a_fixed_glass_table"),
        ("arm_roll_a_pin_across_a_fixed_glass_plate", "arm_rolling_pin_on_a_fixed_glass_plate"),
    ],
)
@pytest.mark.parametrize("seed", [0, 1])
def test_what_slides_or_rolls_on_fixed_glass_leaves_it_whole(
    run_texts: Any, program: str, layout: str, seed: int
) -> None:
    """The controls of fixed glass (found by a run that looked for honest programs the judge fails, once fixed fragile
    objects were judged): a fixed table or floor is read where it is nearest each striker and at the speed toward it
    there, not where its centre lies (a pin's spin reached there at 1.0-1.27 m/s) nor at a speed away from it (fingers
    rising past a block's side)."""
    task = tasks.load(LAYOUTS / f"{layout}.yaml")
    rollouts: list[Rollout] = run_texts(task, [(PROGRAMS / f"{program}.py").read_text()] * 2, seed=seed)
    assert not [e for r in rollouts for e in r.events if e.kind == "broke"], [world_failure(r) for r in rollouts]


def test_a_block_let_go_a_little_above_the_glass_breaks_it(run_texts: Any) -> None:
    """A block let go 0.18 m above a plate (max_drop 0.12 m: limit 1.53 m/s) lands at about 1.8 m/s between two control
    ticks (0.1 s on the arm), each of which read it slower than the limit: a striker that could strike that fast before
    the next tick is read every physics step."""
    task = tasks.load(LAYOUTS / "arm_iron_block_on_a_stool_beside_a_glass_plate.yaml")
    program = (CHEATS / "arm_drop_an_iron_block_a_little_above_a_glass_plate.py").read_text()
    rollouts: list[Rollout] = run_texts(task, [program] * 2, seed=11)
    for rollout in rollouts:
        assert not rollout.success
        (broke,) = [e for e in rollout.events if e.kind == "broke"]
        assert broke.detail == "block" and broke.measured["strike_speed"] > 1.6, broke


def test_glass_driven_into_a_fixed_wall_faster_than_its_fall_lands_breaks(run_texts: Any) -> None:
    """Found by an adversarial run: a stick shoved a dish (max_drop 0.002 m: 0.20 m/s) sideways into a fixed wall at
    0.50 m/s and it stayed whole, since fixed objects struck nothing and the fall rule reads only its centre's drop.
    Here a sponge (soft: no striker) shoves a dish (0.14 m/s) into a wall at the arm's pace in every world: the wall,
    met anew faster than the limit, breaks it."""
    task = tasks.load(LAYOUTS / "arm_sponge_behind_a_glass_dish_before_a_wall.yaml")
    program = (CHEATS / "arm_shove_a_glass_dish_into_a_wall_through_a_sponge.py").read_text()
    rollouts: list[Rollout] = run_texts(task, [program] * 4, seed=11)
    for rollout in rollouts:
        assert not rollout.success
        (broke,) = [e for e in rollout.events if e.kind == "broke"]
        assert broke.detail == "wall" and broke.measured["strike_speed"] > 0.2, broke
        assert "dish broke: wall met it at" in world_failure(rollout), world_failure(rollout)


def test_glass_shoved_short_of_a_fixed_wall_stays_whole(run_texts: Any) -> None:
    """The control: the same push 8 cm shorter: the dish slides about 2 cm towards the wall, read at every physics step
    as it could reach the wall too fast, and stops about 1 cm short of it."""
    task = tasks.load(LAYOUTS / "arm_sponge_behind_a_glass_dish_before_a_wall.yaml")
    program = (CHEATS / "arm_shove_a_glass_dish_into_a_wall_through_a_sponge.py").read_text()
    program = program.replace("s[1] + 0.08", "s[1] + 0.0")
    assert "s[1] + 0.0," in program
    rollouts: list[Rollout] = run_texts(task, [program] * 4, seed=11)
    assert all(r.success for r in rollouts), [world_failure(r) for r in rollouts]
    assert "dish" in rollouts[0].touched and not [e for r in rollouts for e in r.events if e.kind == "broke"]


def test_a_tall_glass_column_knocked_over_breaks_where_its_top_lands(run_texts: Any) -> None:
    """Found by an adversarial run: a 0.5 m glass column knocked off a low stool drops its centre less than its
    ``max_drop`` but lands on its top's edge faster than such a fall lands: it breaks where it lands."""
    task = tasks.load(LAYOUTS / "arm_tall_glass_column_on_a_low_stool.yaml")
    rollouts = run_texts(task, [(CHEATS / "arm_knock_a_tall_glass_column_off_its_stool.py").read_text()] * 2, seed=5)
    for rollout in rollouts:
        assert rollout.conditions["column_lowered"] and not rollout.success
        (broke,) = [e for e in rollout.events if e.kind == "broke"]
        assert broke.measured["strike_speed"] > broke.measured["max_speed"], broke
        assert broke.detail in ("the ground", "stool", "stool and the ground"), broke


def test_a_short_glass_block_knocked_over_the_same_way_is_whole(run_texts: Any) -> None:
    """The control: a glass block 0.14 m tall on the same stool, knocked over at its top, lands slower than the
    limit."""
    task = tasks.load(LAYOUTS / "arm_tall_glass_column_on_a_low_stool.yaml")
    column = next(o for o in task.objects if o.name == "column")
    short = column.model_copy(update={"size": [0.08, 0.08, 0.14], "center": [0.30, 0.0, 0.13]})
    task = task.model_copy(update={"objects": [short if o is column else o for o in task.objects]})
    program = (CHEATS / "arm_knock_a_tall_glass_column_off_its_stool.py").read_text().replace("0.45", "0.17")
    for rollout in run_texts(task, [program] * 2, seed=5):
        assert rollout.conditions["column_unbroken"], world_failure(rollout)
        assert not any(e.kind == "broke" for e in rollout.events)


def test_a_tall_glass_column_tipped_over_onto_a_soft_cushion_is_whole(run_texts: Any) -> None:
    """The control, found by an adversarial run as a false alarm: the column's bottom edge pivots on its stool, whose
    contact comes and goes as it tips, while its top falls onto a soft cushion; the stool touched anew is no landing
    for the top, high in the air then."""
    task = tasks.load(LAYOUTS / "arm_tall_glass_column_beside_a_soft_cushion.yaml")
    program = (FIXTURES / "programs" / "arm_tip_a_tall_glass_column_onto_a_cushion.py").read_text()
    for rollout in run_texts(task, [program] * 3, seed=1):
        assert rollout.success, world_failure(rollout)
