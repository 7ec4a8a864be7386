"""Procedural task families: valid, deterministic task files whose ground truth follows the geometry."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest
import yaml

from robotool import tasks
from robotool.task.concepts import key_concepts, needs_tool
from robotool.task.geometry import object_parts
from robotool.task.task_file import load_task, parse_task
from robotool.tasks.families import button_pressing, sofa_traversing, vase_lowering
from robotool.tasks.families._common import RigidPlacement, thing

SEEDS = range(50)
FAMILIES = tasks.families()


@functools.cache
def _instance(family: str, seed: int) -> tasks.Instance:
    return tasks.generate(family, seed)


def test_families_listed() -> None:
    expected = ["milk_reaching", "can_grasping", "button_pressing", "sofa_traversing", "sofa_climbing",
                "cube_lifting", "vase_lowering"]
    assert sorted(expected) == FAMILIES


@pytest.mark.parametrize("family", FAMILIES)
def test_instances_validate_round_trip_and_follow_the_geometry(family: str) -> None:
    for seed in SEEDS:
        instance = _instance(family, seed)
        task = instance.task
        assert task.name == f"{family}_{seed}"
        assert parse_task(yaml.safe_load(task.to_yaml())) == task
        assert instance.needs_tool == needs_tool(task)
        assert (task.category == "no_tool") == (not instance.needs_tool)
        assert set(instance.decoys) <= set(task.object_names)
        assert set(instance.tools) <= set(task.object_names) and len(set(instance.tools)) == len(instance.tools)
        assert bool(instance.tools) == (instance.solvable and instance.needs_tool)  # a list of names, never text


@pytest.mark.parametrize("family", FAMILIES)
def test_variety(family: str) -> None:
    instances = [_instance(family, seed) for seed in SEEDS]
    assert any(not i.solvable for i in instances)
    assert any(i.decoys for i in instances)
    assert any(i.mirrored for i in instances)
    if family == "cube_lifting":  # a lifted goal always needs the lever: the robot cannot raise things itself
        assert all(i.needs_tool for i in instances)
    else:
        assert sum(not i.needs_tool for i in instances) >= len(instances) // 5


@pytest.mark.parametrize("family", FAMILIES)
def test_deterministic(family: str) -> None:
    for seed in (0, 3, 17):
        assert tasks.generate(family, seed) == _instance(family, seed)
    assert tasks.generate(family, 1).task != tasks.generate(family, 2).task


def test_write_instance(tmp_path: Path) -> None:
    instance = _instance("sofa_traversing", 3)
    path = tasks.write_instance(instance, tmp_path / "t.yaml")
    assert load_task(path) == instance.task
    assert path.read_text().startswith("# generated: family sofa_traversing, seed 3")


def test_unknown_family() -> None:
    with pytest.raises(ValueError, match="families: button_pressing"):
        tasks.generate("juggling", 0)


@pytest.mark.parametrize(("gap", "tool"), [(0.08, False), (0.30, True)])
def test_gap_decides_the_tool(gap: float, tool: bool) -> None:
    data = tasks.load("sofa_traversing").model_dump(mode="json", exclude_defaults=True)
    data["objects"] = [o for o in data["objects"] if not o["name"].startswith("sofa")]
    data["objects"] += [o.model_dump(mode="json", exclude_defaults=True) for o in sofa_traversing.sofas(gap, 0.34)]
    task = parse_task(data)
    concept = next(c for c in key_concepts(task) if c.kind == "gap_width")
    assert concept.value == pytest.approx(gap, abs=2e-3)
    assert needs_tool(task) is tool


def test_ground_truth_per_family() -> None:
    """The deciding quantity sits on the side of its limit that ``needs_tool`` says."""
    for seed in SEEDS:
        for family, kind in (("sofa_traversing", "gap_width"), ("sofa_climbing", "climb_height"),
                             ("milk_reaching", "workspace_excess"), ("button_pressing", "workspace_excess"),
                             ("cube_lifting", "lift_height")):
            instance = _instance(family, seed)
            concepts = [c for c in key_concepts(instance.task) if c.kind == kind]
            assert concepts or not instance.needs_tool
            assert any(not c.satisfied for c in concepts) == instance.needs_tool
        vase = _instance("vase_lowering", seed).task
        assert (vase.object("sofa").top > 0.12) == needs_tool(vase)


def test_arm_layouts_stay_in_reach() -> None:
    """Mirroring keeps every handle and near edge the arm grasps inside its workspace."""
    for family in ("milk_reaching", "can_grasping"):
        for seed in SEEDS:
            instance = _instance(family, seed)
            if not instance.solvable or not instance.tools:
                continue
            for name in instance.tools:
                x, y, _ = instance.task.object(name).grasp_point
                assert -0.30 <= x <= 0.45 and -0.45 <= y <= 0.45


def test_mirrored_hook_is_turned_over() -> None:
    """A hook mirrored in y is the mirror image of the original (roll 180), not a copy with its head the same way."""
    hook = thing("hammer", "hook", (0.05, -0.25, 0.015), (0.4, 0.2, 0.03), graspable_point=(-0.05, -0.34, 0.03))
    mirrored = RigidPlacement(mirror="y").place(hook)
    assert mirrored.rpy == (180.0, 0.0, 0.0)
    assert mirrored.graspable_point == (-0.05, 0.34, 0.03)
    before = np.array([p.center for p in object_parts(hook)])
    after = np.array([p.center for p in object_parts(mirrored)])
    np.testing.assert_allclose(after, before * [1, -1, 1], atol=1e-9)


def test_quarter_turn_swaps_sizes() -> None:
    box = thing("sofa", "box", (1.0, 0.0, 0.17), (1.5, 0.9, 0.34), movable=False)
    turned = RigidPlacement(turns=1, shift=(0.5, 0.0)).place(box)
    assert turned.size == (0.9, 1.5, 0.34) and turned.rpy == (0.0, 0.0, 0.0)
    assert turned.center == (0.5, 1.0, 0.17)


@pytest.mark.parametrize(("family", "board"), [("cube_lifting", "surfboard"), ("sofa_traversing", "surfboard")])
def test_boards_the_robot_walks_along_carry_its_feet_in_any_turn(family: str, board: str) -> None:
    """The robot never turns: along a board lying along y it walks flank first, its feet as far apart across the
    board as its body is long, so the board must be wider than that (a 0.55 m lever in a turned scene was not)."""
    turned = 0
    for seed in SEEDS:
        task = _instance(family, seed).task
        if board not in task.object_names:
            continue
        bounds = [p.aabb() for p in object_parts(task.object(board))]
        extent = np.max([b[1] for b in bounds], axis=0) - np.min([b[0] for b in bounds], axis=0)
        along = int(np.argmax(extent[:2]))
        feet_apart = task.limits.body_size[1 - along]  # the body's size across the board
        assert extent[1 - along] > feet_apart, f"{task.name}: {extent[1 - along]:.2f} m wide"
        turned += along == 1
    assert turned  # some scenes are turned a quarter


@pytest.mark.parametrize(("vase_y", "vase_x", "room"), [(0.7, 2.85, True), (0.5, 2.85, False), (0.5, 3.1, True)])
def test_room_to_land_where_the_steps_lead_beside_or_past_the_vase(vase_y: float, vase_x: float, room: bool) -> None:
    """The vase lies 0.15 m past the sofa's edge. Beside the middle of the step (y 0.7), the robot climbing along its
    length stops on a line across the step that misses the vase; across the middle (y 0.5) every line meets it, head
    first or flank first; 0.4 m past the edge the robot lands before it flank first (after a quarter turn on the
    floor, which a turned scene once ruled out: the planner solved vase_lowering seed 9814, labelled unsolvable so)."""
    sofa = thing("sofa", "box", (3.0, 0.2, 0.17), (0.9, 1.5, 0.34), movable=False)
    step = thing("box_2", "box", (2.35, 0.5, 0.12), (0.4, 0.6, 0.24), movable=False)
    vase = thing("glass_vase", "box", (vase_x, vase_y, 0.39), (0.3, 0.1, 0.1), mass=0.5)
    assert vase_lowering.room_to_land(sofa, step, vase) is room


def test_a_vase_where_the_steps_lead_onto_a_sofa_level_with_them_can_be_pushed_aside_from_the_step() -> None:
    """The sofa's top is 1 cm below the top step's: the robot on the step pushes the vase out of its way."""
    sofa = thing("sofa", "box", (3.0, 0.2, 0.115), (0.9, 1.5, 0.23), movable=False)
    step = thing("box_2", "box", (2.35, 0.5, 0.12), (0.4, 0.6, 0.24), movable=False)
    vase = thing("glass_vase", "box", (2.85, 0.7, 0.28), (0.3, 0.1, 0.1), mass=0.5)
    assert vase_lowering.room_to_land(sofa, step, vase)


def test_a_vase_scene_the_planner_solved_after_a_quarter_turn_is_labelled_solvable() -> None:
    """vase_lowering seed 9814 was labelled unsolvable (no room to land flank first, the only way a robot that never
    turns climbs in that turned scene), yet the search planner solved it in every world, fresh ones too: the robot
    turned a quarter on the floor, climbed head first beside the vase and pushed it off onto the cushion."""
    instance = tasks.generate("vase_lowering", 9814)
    assert instance.solvable and "lead onto" not in instance.description


def test_vase_scenes_without_room_to_land_are_unsolvable() -> None:
    blocked = [i for i in (_instance("vase_lowering", seed) for seed in range(100)) if "lead onto" in i.description]
    assert blocked and all(not i.solvable and not i.tools and {"box_1", "box_2"} <= set(i.decoys) for i in blocked)


def test_unsolvable_buttons_lie_beyond_two_cubes_held_or_pushed_loose() -> None:
    """Two joined cubes shoved loose by the closed fingers reach 2.3 cm further than two held at the centre of the
    first (tests/robots/arm/test_cheats.py runs that program: it presses the built-in button). The family counts it
    as honest tool use, so an unsolvable face lies beyond it: its 1 cm press needs 1.5 cm more than they reach."""
    assert button_pressing.push_reach(2) > button_pressing.chain_reach(2)
    for seed in range(200):
        instance = tasks.generate("button_pressing", seed)
        if instance.solvable:
            continue
        button = next(o for o in instance.task.objects if o.name == "button")
        face = button.center[0] - button.size[0] / 2
        assert face + button_pressing.PRESS > button_pressing.push_reach(2) + 0.015, (seed, face)


def test_a_chair_under_a_light_cubes_lever_is_pushable_with_the_board_in_every_world() -> None:
    """cube_lifting 12010 (a 2 kg cube): pushing the 3 kg chair out dragged the 2 kg board along, 5.1 kg in a world
    whose masses were perturbed up, over the 5 kg push limit, though the instance was labelled solvable. A light cube
    does not hold the board down, so its chair and the board weigh under the limit in every perturbed world."""
    from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
    from robotool.task.scene import MASS_NOISE

    light = [i for i in (_instance("cube_lifting", s) for s in [*SEEDS, 12010]) if i.task.object("cube").mass < 6]
    assert light and all(i.solvable for i in light)
    for instance in light:
        chair, board = instance.task.object("chair"), instance.task.object("surfboard")
        worst = (chair.mass + board.mass) * (1 + MASS_NOISE)
        assert worst <= QuadrupedLimits().max_push_mass, (instance.seed, worst)


def test_a_family_registers_like_a_robot_for_a_block_only() -> None:
    """A family from outside the package (here the milk family's builder under another name) generates instances
    named after it; the scoped registration leaves the families as they were; a taken name is refused."""
    from robotool.tasks.families import milk_reaching

    before = tasks.families()
    with tasks.registered_families(milk_again=milk_reaching.build):
        assert tasks.families() == sorted([*before, "milk_again"])
        made = tasks.generate("milk_again", 3)
        assert made.family == "milk_again" and made.task.name == "milk_again_3"
        assert made.task == tasks.generate("milk_reaching", 3).task.model_copy(update={"name": "milk_again_3"})
        tasks.register_family("milk_again", milk_reaching.build)  # the same builder again: nothing happens
        with pytest.raises(ValueError, match="'milk_reaching' is already registered"):
            tasks.register_family("milk_reaching", button_pressing.build)
    assert tasks.families() == before
    with pytest.raises(ValueError, match="unknown task family 'milk_again'"):
        tasks.generate("milk_again", 3)
