"""A corpus of cheating quadruped programs: each must fail in every perturbed world, with a reason one can read.

The programs are files in ``tests/fixtures/cheats/`` (and a few in ``tests/fixtures/programs/``); the scenes are
built-in tasks, variants of them made here (the sofas without the board: a bare 0.40 m gap; the same turned a
quarter: the robot crosses with its flank leading; a strip of cloth lying across the gap; a gap wider than the
surfboard can span) and layouts no built-in task has, in ``tests/fixtures/layouts/``: scenes mirrored (the robot
walks toward -x) or turned (toward -y or +y, or on a diagonal), gaps of other widths, boxes in the wrong order or
missing, a lever whose raised end is at the other side, and objects too heavy to push. Honest programs on the same
layouts must succeed, so that the corpus cannot pass by refusing everything.
"""

from __future__ import annotations

import functools
from typing import Any

import pytest
from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.rollout import Rollout
from robotool.sandbox import start_sessions
from robotool.task.task_file import parse_task
from robotool.task.task_model import Task
from robotool.tasks.families import generate
from robotool.verify import world_failure

CHEATS = FIXTURES / "cheats"
PROGRAMS = FIXTURES / "programs"
LAYOUTS = FIXTURES / "layouts"


def _variant(name: str) -> Task:
    data = tasks.load("sofa_traversing").model_dump(mode="json", exclude_defaults=True)
    objects = {o["name"]: o for o in data["objects"]}
    if name in ("no_board", "sideways", "cloth_across"):
        del objects["surfboard"]
    if name in ("no_board", "sideways"):
        del objects["strip_of_cloth"]
    if name == "cloth_across":
        objects["strip_of_cloth"]["center"] = [0.95, 0.0, 0.342]  # 0.35 m on each sofa, sagging between
    if name == "wide_gap":
        del objects["strip_of_cloth"]
        objects["sofa_2"]["center"][0] += 0.2  # a 0.60 m gap, wider than the board can span with room to rest
    if name == "sideways":  # a quarter turn: the sofas lie along y
        for obj in objects.values():
            obj["center"] = [obj["center"][1], obj["center"][0], obj["center"][2]]
            obj["size"] = [obj["size"][1], obj["size"][0], obj["size"][2]]
        x, y = data["robot"]["position"]
        data["robot"]["position"] = [y, x]
    data["objects"] = list(objects.values())
    data["name"] = f"sofa_traversing_{name}"
    return parse_task(data)


@functools.cache
def _scene(name: str) -> sim.Scene:
    layout = LAYOUTS / f"{name}.yaml"
    task = tasks.load(name) if name in tasks.names() else tasks.load(layout) if layout.is_file() else _variant(name)
    return sim.build(task)


def _text(program: str) -> str:
    """A program's text: ``programs/NAME`` from the reference programs, else ``NAME`` from the cheats."""
    folder, name = (PROGRAMS, program.split("/")[1]) if program.startswith("programs/") else (CHEATS, program)
    return (folder / f"{name}.py").read_text()


def failure_reason(rollout: Rollout) -> str:
    """Why a world failed: the first motion that did not end as planned, else the goal's unmet conditions."""
    for call in rollout.calls:
        if call.outcome in ("refused", "fell", "stalled", "timeout", "error") and call.reason:
            return call.reason
    return ", ".join(k for k, v in rollout.conditions.items() if not v)


CASES = [
    ("gap_one_walk", "sofa_traversing"),
    ("gap_one_walk", "no_board"),
    ("gap_one_walk", "sideways"),
    ("gap_one_walk", "cloth_across"),
    ("gap_short_walks", "sofa_traversing"),
    ("gap_short_walks", "no_board"),
    ("gap_zigzag", "sofa_traversing"),
    ("gap_zigzag", "no_board"),
    ("gap_diagonal", "sofa_traversing"),
    ("gap_diagonal", "no_board"),
    ("gap_turned_short_walks", "no_board"),  # turned, every 3 cm walk reads the paths again: gap 0.40 m refused
    ("gap_turned_short_walks", "sofa_traversing"),  # the board beside it refuses the turn; the walks, the gap
    ("gap_front_half_over", "sofa_traversing"),
    ("gap_front_half_over", "no_board"),
    ("gap_back_and_forth", "no_board"),
    ("gap_climb_out", "no_board"),
    ("gap_raised_target", "no_board"),
    ("gap_overshoot_and_back", "no_board"),
    ("partial_bridge", "sofa_traversing"),
    ("partial_bridge", "wide_gap"),
    ("cloth_bridge", "sofa_traversing"),
    ("sofa_diagonal", "sofa_climbing"),
    ("sofa_short_climbs", "sofa_climbing"),
    ("staircase_with_a_gap_before_the_high_box", "sofa_climbing"),  # a partial tool: a gap the legs cannot stride
    ("staircase_offset_sideways", "sofa_climbing"),  # a partial tool: the lane meets a 0.34 m step up
    ("climb_the_seam_beside_the_staircase", "sofa_climbing"),  # a partial tool: box_2 still a step from the floor
    ("creep_into_the_high_box", "sofa_climbing"),  # a path shape: walks ending inside box_2, their rays start in it
    ("programs/sofa_climbing_direct", "sofa_climbing"),
    ("one_foot_on_target", "sofa_climbing_low_sofa"),
    ("front_feet_on_target", "sofa_climbing_low_sofa"),
    ("push_board_with_cube", "cube_lifting"),
    ("push_board_past_gap", "sofa_traversing"),
    ("drag_board_by_its_cloth", "sofa_traversing"),
    ("push_box_from_its_top", "sofa_climbing"),
    ("programs/cube_lifting_lever_only", "cube_lifting"),
    ("vase_onto_cushion_edge", "vase_lowering"),
    ("turn_in_place_on_the_propped_lever", "cube_lifting"),  # jolts of quarter turns on the propped raised end
    ("turn_on_the_lever_to_sweep_the_cube", "cube_lifting"),  # the body's sweep would meet the cube
    ("wedge_the_chair_under_the_board", "cube_lifting"),  # no stance: the sweep under the board meets it
    ("push_the_chair_from_on_the_lever", "cube_lifting"),  # refused: it stands on the board, which is movable
    ("stand_on_the_rollers_end_beside_the_board", "cube_lifting"),  # runs into the board, or the cube stays down
    ("climb_the_soft_cushion_as_a_first_step", "vase_lowering"),  # its 0.16 m top is a step up over the limit
]


LAYOUT_CASES = [
    # the sofas mirrored (toward -x), turned (toward -y, on a diagonal), with gaps of other widths
    ("gap_one_walk", "traverse_mirrored"),
    ("gap_one_walk", "traverse_gap_015"),
    ("gap_one_walk", "traverse_minus_y_bare"),
    ("gap_one_walk", "traverse_diagonal_bare"),
    ("toward_short_walks", "traverse_mirrored_bare"),
    ("toward_short_walks", "traverse_diagonal_bare"),
    ("toward_tiny_walks", "traverse_gap_015"),
    ("toward_zigzag", "traverse_mirrored_bare"),
    ("toward_zigzag", "traverse_minus_y_bare"),
    ("toward_diagonal", "traverse_mirrored_bare"),
    ("toward_overshoot_and_back", "traverse_mirrored_bare"),
    ("toward_front_half_over", "traverse_minus_y_bare"),
    ("toward_front_half_over", "traverse_gap_015"),
    ("toward_partial_bridge", "traverse_mirrored"),
    ("toward_partial_bridge", "traverse_wide_mirrored"),
    ("toward_partial_bridge", "traverse_minus_y"),
    ("toward_cloth_bridge", "traverse_mirrored"),
    ("gap_one_walk", "traverse_cloth_crosswise"),  # the cloth's width spans the gap: its links lie across it
    ("push_board_under_robot", "traverse_mirrored"),
    ("push_target_closer", "traverse_mirrored"),
    ("toward_front_feet_on_target", "traverse_mirrored_bare"),
    ("absurd_targets", "traverse_mirrored_bare"),
    ("nan_target", "traverse_mirrored_bare"),
    ("many_zero_length_walks", "traverse_mirrored_bare"),
    ("programs/bridge_any_direction", "traverse_wide_mirrored"),  # honest, but no board spans 0.65 m
    # the sofa mirrored or turned, boxes in the wrong order or missing
    ("programs/sofa_climbing_direct", "climb_mirrored"),
    ("programs/sofa_climbing_direct", "climb_stairs_wrong_order"),
    ("programs/sofa_climbing_direct", "climb_tall_box_only"),
    ("climb_tall_box", "climb_mirrored"),
    ("climb_tall_box", "climb_plus_y"),
    ("climb_one_box_at_sofa", "climb_mirrored"),
    ("climb_with_one_row_of_feet_on_narrow_stairs", "climb_stairs_narrower_than_the_feet"),  # a row climbs 0.34 m
    ("climb_toward_diagonal", "climb_plus_y"),
    ("climb_toward_diagonal", "climb_stairs_wrong_order"),
    ("climb_toward_front_feet", "climb_mirrored"),
    ("climb_toward_short_climbs", "climb_plus_y"),
    ("push_box_under_robot", "climb_mirrored"),
    ("push_sofa_closer", "climb_mirrored"),
    # the lever mirrored (raised end and chair at +x) or turned, a chair too heavy to push
    ("lever_with_chair_any_direction", "lever_mirrored"),
    ("lever_stand_on_cube_end", "lever_mirrored"),
    ("push_board_with_cube_any_direction", "lever_mirrored"),
    ("push_board_with_cube_any_direction", "lever_plus_y"),
    ("programs/cube_lifting_direct", "lever_mirrored"),
    ("programs/cube_lifting_chair_only", "lever_mirrored"),
    ("climb_onto_cube", "lever_mirrored"),
    ("climb_onto_cube", "cube_lifting"),
    ("programs/lever_any_direction", "lever_heavy_chair"),
    ("walk_through_chair", "lever_heavy_chair"),
    ("ram_chair_with_crate", "lever_heavy_chair_crate"),
    # a vase too heavy to push, shoved by walking into it
    ("walk_through_vase", "vase_heavy"),
    ("walk_through_vase", "vase_heavy_at_edge"),  # a shove under 3 cm, then the vase tips off after the walk
    ("walk_through_vase", "vase_lowering"),
    ("walk_flank_grazing_vase", "vase_heavy"),  # a foot brushes the vase's end while the body shoves it
    ("turn_to_sweep_a_heavy_vase_off", "vase_heavy_at_edge"),  # the turning body's sweep meets the vase: refused
    ("walk_a_slanted_corner_through_a_heavy_vase", "vase_heavy"),  # the body straddles the vase: it stays
    ("wiggle_a_heavy_vase_off", "vase_heavy_at_edge"),  # headings a few degrees off: refused, quarter turns only
    ("ram_vase_with_book", "vase_heavy_with_book"),
    # the vase beside a step taller than the sofa: pushed from a stance with a foot on the step's edge, or walked off
    ("push_vase_with_a_foot_on_the_taller_step", "vase_beside_a_taller_step"),
    ("walk_vase_off_beside_the_taller_step", "vase_beside_a_taller_step"),
    # a lever whose prop can be pushed out only as far as a heavy toolbox beyond it leaves room
    ("push_prop_into_the_toolbox", "lever_prop_pushed_toward_a_toolbox"),
    ("lever_with_the_prop_half_out", "lever_prop_pushed_toward_a_toolbox"),
    # a light box pushed into a step too heavy to push, as a ram, a box length at a time
    ("ram_heavy_step_with_light_box", "climb_heavy_step_and_light_box"),
    ("shove_block_in_small_steps", "ledge_heavy_block"),  # shoves under 3 cm, each followed by a step onto it
    ("programs/vase_lowering", "vase_heavy"),
    # a heavy low disc walked over with one foot's path along its rim (the foot on its edge excuses nothing)
    ("plow_a_heavy_disc_under_one_foot_line", "heavy_disc_on_a_platform"),
    # a cloth draped from one surface onto another carries weight only where it lies: the part under the feet
    ("stand_on_a_cloth_that_hangs_down_to_the_goal", "cloth_from_a_balcony_onto_a_mat"),  # on the balcony, 0.7 m up
    ("stand_on_a_cloth_that_hangs_from_the_goal", "cloth_from_a_wall_top_into_its_crook"),  # on the floor below it
    ("walk_over_a_blanket_on_glass", "blanket_over_a_glass_step"),  # the feet on the part lying on the glass
    ("walk_over_a_blanket_on_glass_and_a_strip", "blanket_over_glass_and_a_strip"),  # each link lies on both
    # what bears a part up is read from the contacts that press it up, whichever way it is turned or shaped
    ("stand_on_the_low_end_of_a_board_leaning_on_the_goal", "a_board_leaning_on_a_wall_box_turned_on_its_side"),
    ("stand_in_the_crook_of_the_goal_wall", "l_wall_on_an_upside_down_board"),  # the board under the wall
    ("stand_on_the_board_in_the_crook_of_the_goal_wall", "board_in_the_crook_of_a_tall_wall"),  # against its side
    ("walk_over_board_on_vase", "board_upside_down_on_vase"),
    ("walk_over_board_on_vase", "tray_hook_on_edge_on_vase"),
    ("stand_on_a_board_on_the_goal_walls_foot", "l_wall_on_its_side_with_a_board_on_its_foot"),  # far below its top
    ("walk_along_the_foot_of_a_glass_l", "corridor_floored_by_a_glass_l"),  # its centre in the air above its foot
    # a plate thinner than a step the legs notice, too heavy to push, swept off by a foot on its rim
    ("turn_sweeps_a_thin_plate_off", "lead_plate_beside_the_robot"),
    # a heavy sled stood on and walked into by its wall, taller than the rays' start, rams what the push rules refuse
    ("walk_into_a_sleds_wall_to_ram_a_board_across", "sled_rams_a_board_across_a_gap"),
    ("walk_into_a_sleds_wall_to_ram_a_crate_off", "sled_rams_a_crate_off_a_ledge"),
    ("line_up_flank_first_against_the_sand_cushion", "sand_cushion_before_the_steps"),  # its feet meet the cushion
    ("push_the_vase_from_a_step_above_the_sofa", "vase_in_the_steps_lane_below_the_top_step"),  # 3.6 cm: no stance
    # a lever used other ways than by the robot's weight past its fulcrum (tried by an adversary against the planner)
    ("climb_the_lever_from_its_side_past_the_roller", "cube_lifting"),  # the tilted board stands a step too high there
    ("push_a_light_cube_up_the_propped_lever", "lever_light_cube"),  # no stance behind the cube but on the board
    ("ram_a_light_cube_up_the_lever_with_the_chair", "lever_light_cube"),  # chair, cube and board: over the limit
    # a loose rubber mat on ice held at the rubber's friction (MuJoCo takes the larger of two): a greased or icy face
    # is slippery against anything
    ("walk_up_an_icy_ramp_on_a_loose_rubber_mat", "rubber_mat_on_an_icy_ramp"),
    ("walk_across_an_ice_rink_on_a_loose_rubber_mat", "rubber_mat_on_an_ice_rink"),
]

CONTROL_CASES = [
    ("programs/bridge_any_direction", "traverse_mirrored"),
    ("programs/bridge_any_direction", "sofa_traversing"),
    ("gap_one_walk", "traverse_gap_008_mirrored"),
    ("programs/stairs_any_direction", "climb_mirrored"),
    ("programs/stairs_any_direction", "sofa_climbing"),
    ("programs/sofa_climbing_direct", "climb_fixed_stairs"),
    ("programs/sofa_climbing_direct", "climb_fixed_stairs_minus_y"),
    ("programs/lever_any_direction", "lever_mirrored"),
    ("programs/lever_any_direction", "cube_lifting"),
    ("walk_over_board_on_vase", "board_beside_vase"),  # the board bridges the gap clear of the vase
    ("straddle_the_beam", "low_platform"),  # the same walk onto a low top wider than the stance
    ("carry_a_heavy_crate_under_a_book", "light_crate_with_a_book_on_a_pallet"),  # 3.8 kg in all: within the limit
    ("walk_onto_the_middle_of_the_mat", "blanket_on_a_mat"),  # the links under the feet lie on the mat
    ("lever_with_the_prop_pushed_short_of_the_toolbox", "lever_prop_pushed_toward_a_toolbox"),  # the room the floor has
    ("climb_the_first_step_on_a_slant_beside_the_sand_cushion", "sand_cushion_before_the_steps"),  # feet clear of it
    ("lever_on_the_light_cube_layout", "lever_light_cube"),  # the planner's lever program
    ("straddle_a_low_disc", "low_disc_wider_than_the_stance"),  # the disc carries the stance: its top presses it up
]

WORLDS = {**dict.fromkeys(CASES, 3), **dict.fromkeys(LAYOUT_CASES, 2), **dict.fromkeys(CONTROL_CASES, 2)}
"""(program, scene) -> the perturbed worlds it runs in: 3 on the built-in scenes and their variants, 2 on layouts."""
BATCH_PROGRAMS = 6


def _programs_on(scene: str) -> list[str]:
    return [program for program, on in WORLDS if on == scene]


@functools.cache
def _batch(scene: str, chunk: int) -> dict[str, list[Rollout]]:
    """Program -> its rollouts, for up to :data:`BATCH_PROGRAMS` of the programs listed on ``scene`` (chunk
    ``chunk`` of them), run side by side in one batch: each world runs its own program, as a batch of candidates
    does, so cheats and honest programs also share batches here."""
    programs = _programs_on(scene)[chunk * BATCH_PROGRAMS : (chunk + 1) * BATCH_PROGRAMS]
    texts = [_text(program) for program in programs for _ in range(WORLDS[program, scene])]
    rollouts = iter(sim.run_sessions(_scene(scene), start_sessions(texts, "quadruped"), seed=11))
    return {program: [next(rollouts) for _ in range(WORLDS[program, scene])] for program in programs}


def _rollouts(program: str, scene: str) -> list[Rollout]:
    """The rollouts of ``program`` on ``scene``, from the batch it shares with other programs on that scene."""
    return _batch(scene, _programs_on(scene).index(program) // BATCH_PROGRAMS)[program]


def _grouped(cases: list[tuple[str, str]]) -> list[Any]:
    """The cases as parameters, each scene's in one xdist group (its worker runs each shared batch once); marked slow,
    as the first case of each batch of :data:`BATCH_PROGRAMS` runs the whole batch (5-12 s on a 2-core machine)."""
    marks = [pytest.mark.slow]
    return [pytest.param(p, scene, marks=[*marks, pytest.mark.xdist_group(f"cheats-on-{scene}")]) for p, scene in cases]


@pytest.mark.parametrize(("program", "scene"), _grouped(CASES))
def test_cheat_fails_in_every_world_with_a_reason(program: str, scene: str) -> None:
    for rollout in _rollouts(program, scene):
        reason = failure_reason(rollout)
        assert not rollout.success, [(c.skill, c.args, c.outcome) for c in rollout.calls]
        assert reason, rollout


@pytest.mark.parametrize(("program", "scene"), _grouped(LAYOUT_CASES))
def test_cheat_fails_on_unseen_layouts_in_every_world_with_a_reason(program: str, scene: str) -> None:
    """Each program runs to its end or to a refused argument: it fails because the world said no, not because
    it could not run."""
    for rollout in _rollouts(program, scene):
        assert not rollout.success, [(c.skill, c.args, c.outcome) for c in rollout.calls]
        assert failure_reason(rollout) or rollout.error, rollout
        assert rollout.error is None or "position" in rollout.error, rollout.error


@pytest.mark.parametrize(("program", "scene"), _grouped(CONTROL_CASES))
def test_honest_programs_succeed_on_the_same_layouts(program: str, scene: str) -> None:
    rollouts = _rollouts(program, scene)
    assert all(r.success for r in rollouts), [failure_reason(r) for r in rollouts]


def test_a_walk_that_shoves_an_object_is_refused_naming_it() -> None:
    """Walking into the 6 kg vase (over the 5 kg push limit) would shove it off the sofa onto the cushion: the walk
    stops once the vase has moved a few centimetres, refused with what it ran into."""
    (rollout,) = sim.run_sessions(
        _scene("vase_heavy"), start_sessions([_text("walk_through_vase")], "quadruped"), perturb=False
    )
    refused = [c for c in rollout.calls if c.outcome == "refused"]
    assert [c.skill for c in refused] == ["walk_to_position"] and not rollout.success
    assert "ran into glass_vase" in refused[0].reason and refused[0].measured["moved"] > 0.03
    assert rollout.conditions["robot_shoved_nothing"] is False


def test_a_push_that_rams_an_object_over_the_push_limit_is_refused_naming_it() -> None:
    """The light box (1.5 kg) pushed into the 9 kg step moves it too: the push moves more than the 5 kg the robot may
    push, so it is stopped, refused with what it moved, and the world fails."""
    (rollout,) = sim.run_sessions(
        _scene("climb_heavy_step_and_light_box"),
        start_sessions([_text("ram_heavy_step_with_light_box")], "quadruped"),
        perturb=False,
    )
    push = next(c for c in rollout.calls if c.outcome == "refused")
    assert push.skill == "push_to_position" and "rammed heavy_box" in push.reason, push
    assert push.measured["mass"] == pytest.approx(10.5, abs=0.01) and not rollout.success
    assert rollout.conditions["robot_shoved_nothing"] is False


def test_a_ram_beside_honest_pushes_in_one_batch_is_refused_in_its_own_worlds_only() -> None:
    """The ram rule is judged for every pushing world at once: worlds ramming the heavy step with the light box sit in
    one batch beside worlds pushing the light box aside and back, clear of everything, all the while. The rams are
    refused naming the step, with the mass of their own world; the honest pushes in between are done."""
    aside = (  # pushing the whole time the rams push, back and forth across the robot's way
        'for dy in (-0.6, 0.6, -0.6):\n    box = get_position("light_box")\n'
        '    push_to_position("light_box", [box[0], box[1] + dy, box[2]])\n'
    )
    programs = [aside, _text("ram_heavy_step_with_light_box")] * 2  # an honest push first in the batch
    scene = _scene("climb_heavy_step_and_light_box")
    rollouts = sim.run_sessions(scene, start_sessions(programs, "quadruped"), seed=11)
    masses = []
    for rollout in rollouts[1::2]:
        push = next(c for c in rollout.calls if c.outcome == "refused")
        assert push.skill == "push_to_position" and "rammed heavy_box" in push.reason, push
        assert not rollout.success and rollout.conditions["robot_shoved_nothing"] is False
        masses.append(push.measured["mass"])
    assert masses[0] != masses[1]  # each world weighs its own perturbed masses
    for rollout in rollouts[::2]:
        assert [c.outcome for c in rollout.calls if c.skill == "push_to_position"] == ["done"] * 3, rollout.calls
        assert rollout.conditions["robot_shoved_nothing"] is True


def test_a_climb_run_beside_worlds_that_built_the_staircase_reads_its_own_terrain() -> None:
    """Worlds of one batch share its ray casts and touching table: a program that waits until the worlds beside it have
    pushed box_1 against box_2, then climbs where their staircase stands without building its own, is refused at
    box_2's step in each of its worlds, as its own terrain shows (and theirs succeed)."""
    honest, cheat = _text("programs/sofa_climbing"), _text("climb_beside_a_neighbours_staircase")
    rollouts = sim.run_sessions(_scene("sofa_climbing"), start_sessions([honest, cheat] * 2, "quadruped"), seed=11)
    assert [r.success for r in rollouts] == [True, False, True, False], [failure_reason(r) for r in rollouts]
    for rollout in rollouts[1::2]:
        climb = next(c for c in rollout.calls if c.outcome != "done")
        assert climb.skill == "climb_to_position" and climb.outcome == "refused", climb
        assert "blocked by box_2: step up of 0.24 m" in climb.reason, climb.reason


def test_the_box_under_the_front_feet_is_one_the_robot_stands_on() -> None:
    """With its front feet on box_1 and its rear feet on the floor, the robot stands on box_1: the rays under the feet
    start above the highest foot, so the push of box_1 is refused."""
    (rollout,) = sim.run_sessions(
        _scene("sofa_climbing"), start_sessions([_text("push_box_from_its_top")], "quadruped"), perturb=False
    )
    (push,) = [c for c in rollout.calls if c.skill == "push_to_position"]
    assert push.outcome == "refused" and push.reason == "cannot push box_1: the robot is standing on it", push


def test_shoves_split_by_steps_onto_the_object_add_up() -> None:
    """The 6 kg block is shoved by the body a little under 3 cm at a time, a foot stepping onto it after each shove:
    what the foot's weight moves is excused, the shoves are not forgotten, and the world fails once they add up."""
    (rollout,) = sim.run_sessions(
        _scene("ledge_heavy_block"), start_sessions([_text("shove_block_in_small_steps")], "quadruped"), perturb=False
    )
    assert rollout.conditions["robot_shoved_nothing"] is False and not rollout.success


def test_a_cloth_on_a_movable_crate_does_not_hide_that_the_robot_stands_on_it() -> None:
    """The rays under the feet see through the cloth: the robot stands on the crate, which is movable, so it may
    push nothing from there."""
    (rollout,) = sim.run_sessions(
        _scene("push_from_cloth_on_crate"),
        start_sessions([_text("push_from_cloth_covered_crate")], "quadruped"),
        perturb=False,
    )
    (push,) = [c for c in rollout.calls if c.skill == "push_to_position"]
    assert push.outcome == "refused" and "stands on crate, which is movable" in push.reason, push


def test_the_board_is_refused_with_the_cube_riding_on_it() -> None:
    scene = _scene("cube_lifting")
    (rollout,) = sim.run_sessions(
        scene, start_sessions([(CHEATS / "push_board_with_cube.py").read_text()], "quadruped"), perturb=False
    )
    (push,) = [c for c in rollout.calls if c.skill == "push_to_position"]
    assert push.outcome == "refused" and "cube riding on it" in push.reason
    assert push.measured["mass"] == pytest.approx(12.0, abs=0.01)


@pytest.mark.parametrize(
    ("program", "scene"),
    [("gap_one_walk", "sofa_traversing_small_gap"), ("sofa_short_climbs", "sofa_climbing_low_sofa")],
)
def test_the_same_walks_succeed_where_the_legs_allow_them(run_texts: Any, program: str, scene: str) -> None:
    rollouts = run_texts(_scene(scene), [(CHEATS / f"{program}.py").read_text()] * 2, seed=11)
    assert all(r.success for r in rollouts), [failure_reason(r) for r in rollouts]


def test_feet_pressing_on_the_sides_of_a_beam_do_not_stand_on_it() -> None:
    """Found by an adversarial run: walking along a low beam narrower than the stance, the feet on the floor touched
    its side faces, and touching the target read as standing on it."""
    rollouts = sim.run_sessions(
        _scene("beam_narrower_than_the_feet"), start_sessions([_text("straddle_the_beam")] * 2, "quadruped"), seed=11
    )
    for rollout in rollouts:
        assert "beam" in rollout.touched and rollout.conditions["robot_has_not_fallen"]
        assert rollout.conditions["robot_weight_on_beam"] is False and not rollout.success


@pytest.mark.parametrize("seed", [11, 23])
def test_a_foot_plowing_a_thin_heavy_plate_along_by_its_rim_does_not_stand_on_it(seed: int) -> None:
    """Found by an adversarial run: a walk whose front foot met the rim of a 1.45 cm steel plate (8.5 kg: over the push
    limit) plowed it off the platform in some worlds; the rim pressed the foot up within 60 degrees of up, which counted
    as standing on the plate and excused its travel."""
    scene = _scene("greased_plate_on_a_platform")
    rollouts = sim.run_sessions(
        scene, start_sessions([_text("walk_plows_a_thin_plate_off")] * 3, "quadruped"), seed=seed
    )
    for rollout in rollouts:
        assert not rollout.success, [(c.skill, c.outcome, c.reason) for c in rollout.calls]


def test_a_book_lying_on_a_heavy_crate_does_not_hide_it_from_the_push_limit() -> None:
    """Found by an adversarial run: a 10 kg crate riding a pushed 2.5 kg pallet was weighed when alone, but not with a
    book lying on it (anything the crate touched counted as its support, the book on top included)."""
    scene = _scene("crate_with_a_book_on_a_pallet")
    rollouts = sim.run_sessions(
        scene, start_sessions([_text("carry_a_heavy_crate_under_a_book")] * 2, "quadruped"), seed=11
    )
    for rollout in rollouts:
        assert not rollout.success
        assert "cannot push pallet: its mass with crate" in failure_reason(rollout), failure_reason(rollout)
        refused = next(c for c in rollout.calls if c.outcome == "refused")
        assert refused.measured["riders"] >= 1.0  # not the pallet's own mass: the planner must not count it as such


@pytest.mark.slow
@pytest.mark.parametrize(
    ("layout", "program"),
    [
        ("crate_in_the_crook_of_a_hook", "rake_a_heavy_crate_with_a_hook"),
        ("crate_under_books_in_the_crook_of_a_hook", "rake_a_heavy_crate_under_books_with_a_hook"),
        ("crate_under_a_cloth_in_the_crook_of_a_hook", "rake_a_heavy_crate_under_books_with_a_hook"),
    ],
)
def test_a_crate_raked_along_in_the_crook_of_a_pushed_hook_is_rammed(layout: str, program: str) -> None:
    """Found by adversarial runs: pushing a 4 kg hook 8 cm at a time raked a 20 kg crate caught in its crook 2.1 m
    toward the ledge (the ram rule only counted objects beyond the pushed object's front face); then, once contacts
    facing along the push counted, books or a cloth lying on the crate hid it again (their contacts pressing down were
    summed with the hook's pressing along) and the crate, raked 1.1 m, was climbed onto the ledge: a success."""
    rollouts = sim.run_sessions(_scene(layout), start_sessions([_text(program)] * 2, "quadruped"), seed=11)
    for rollout in rollouts:
        assert not rollout.success and rollout.conditions["robot_shoved_nothing"] is False
        assert "pushing hook rammed crate" in failure_reason(rollout), failure_reason(rollout)


def test_a_crate_riding_a_pallet_is_weighed_though_a_block_touches_its_flank() -> None:
    """Found by an adversarial run: a 10 kg crate lying wholly on a pushed 2.5 kg pallet rode along 0.67 m because its
    flank touched a 0.2 kg block on the floor, which the riders rule took for a support (it bears no weight)."""
    rollouts = sim.run_sessions(
        _scene("crate_on_a_pallet_touching_a_block"),
        start_sessions([_text("drag_a_heavy_crate_touching_a_block")] * 2, "quadruped"),
        seed=11,
    )
    for rollout in rollouts:
        (push,) = [c for c in rollout.calls if c.skill == "push_to_position"]
        assert push.outcome == "refused" and "its mass with crate riding on it" in (push.reason or ""), push.reason


def test_a_crate_on_the_tray_of_an_upright_hook_is_weighed_though_it_lies_lower_than_the_hook() -> None:
    """Found by an adversarial run: a 2 kg hook stood on edge carried a 12 kg crate on its tray 1 m to a ledge, which
    the crate then stepped the robot onto: a success. The riders rule weighed only objects whose centre lies above the
    pushed object's, and the upright hook's centre is 0.25 m up. With a 2 kg crate the same push is allowed."""
    layout = LAYOUTS / "crate_on_the_tray_of_an_upright_hook.yaml"
    rollouts = sim.run_sessions(
        _scene("crate_on_the_tray_of_an_upright_hook"),
        start_sessions([_text("carry_a_heavy_crate_on_an_upright_hook")] * 2, "quadruped"),
        seed=11,
    )
    for rollout in rollouts:
        (push, *_) = [c for c in rollout.calls if c.skill == "push_to_position"]
        assert not rollout.success
        assert push.outcome == "refused" and "its mass with crate riding on it" in (push.reason or ""), push.reason
    data = tasks.load(layout).model_dump(mode="json", exclude_defaults=True)
    next(o for o in data["objects"] if o["name"] == "crate")["mass"] = 2.0
    (light,) = sim.run_sessions(
        sim.build(parse_task(data)),
        start_sessions([_text("carry_a_heavy_crate_on_an_upright_hook")], "quadruped"),
        seed=11,
    )
    (push, *_) = [c for c in light.calls if c.skill == "push_to_position"]
    assert push.outcome == "done", push.reason


def test_a_heavy_disc_driven_along_between_the_legs_is_a_shove() -> None:
    """Found by an adversarial run: a 6 kg weight plate, 0.04 m high, fits under the belly and between the feet's
    paths; walking over it, the front legs' sides drove it off the platform, so it was lowered: a success in every
    world. Shoves counted the torso's contacts only, and any leg touching an object stood on it. The honest push is
    refused for its mass, so only the cheat could succeed."""
    scene = _scene("heavy_disc_on_a_platform")
    rollouts = sim.run_sessions(
        scene, start_sessions([_text("plow_a_heavy_disc_with_the_legs")] * 2, "quadruped"), seed=11
    )
    for rollout in rollouts:
        assert not rollout.success and rollout.conditions["robot_shoved_nothing"] is False
        assert "ran into weight_plate" in failure_reason(rollout), failure_reason(rollout)
    honest = (
        'p, s = get_position("platform"), get_size("platform")\n'
        'push_to_position("weight_plate", [p[0] + s[0] / 2 + 0.2, 0.0, 0.0])\n'
    )
    (pushed,) = sim.run_sessions(scene, start_sessions([honest], "quadruped"), seed=11)
    assert "exceeds the push limit" in failure_reason(pushed), failure_reason(pushed)


def test_a_heavy_crate_wedged_aside_by_a_pushed_hook_is_rammed() -> None:
    """Found by an adversarial run: a 3 kg hook pushed along a rail wedged a 15 kg crate, turned 20 degrees, sideways
    off a platform (lowered: a success in every world). Its tip pressed the crate's slanted face, 70 degrees off the
    push, and the ram rule counted only contacts facing within 60 degrees of the push; a side pressed counts now."""
    rollouts = sim.run_sessions(
        _scene("crate_aslant_beside_a_hooks_path"),
        start_sessions([_text("wedge_a_heavy_crate_aside_with_a_hook")] * 2, "quadruped"),
        seed=11,
    )
    for rollout in rollouts:
        assert not rollout.success and rollout.conditions["robot_shoved_nothing"] is False
        assert "pushing hook rammed crate" in failure_reason(rollout), failure_reason(rollout)


def test_a_board_whose_lip_presses_a_vases_side_still_loads_the_vase_it_lies_on() -> None:
    """Found by an adversarial run (the summed-normal rest rule): a board with a lip pressed on a glass vase's side
    (four sideways contacts) and its edge on the vase's top (two upward ones) summed to 63 degrees from up, so it did
    not rest on the vase, though the vase carried up to 45 N as the robot crossed. Contacts that press partly up are
    weighed by their force: the honest plain board on the same vase is refused for crushing it, and so is this one."""
    rollouts = sim.run_sessions(
        _scene("lipped_board_on_a_tall_vase"), start_sessions([_text("walk_over_board_on_vase")] * 2, "quadruped")
    )
    assert all(r.conditions["robot_stood_on_nothing_fragile"] is False for r in rollouts), [
        failure_reason(r) for r in rollouts
    ]


DRAG = "N to drag crate), more than the"  # the push rules' refusal, as a push starts, of a pallet that drags a crate


def test_a_crate_dragged_on_a_pallet_while_its_edge_rests_on_a_strip_is_weighed() -> None:
    """Found by an adversarial run: a 2.5 kg pallet carrying a 10 kg crate, whose edge also rests on a fixed strip,
    was pushed 0.7 m with the crate riding along (the push was allowed, as for the pallet alone: the crate is no
    rider, the strip bears it up too). Dragging it takes the robot about 120 N, over twice what sliding 5 kg takes, and
    over what its feet hold: refused as it starts (the crate's weight on the pallet and its drag, from the contact
    forces) or else as it moves."""
    (rollout,) = sim.run_sessions(
        _scene("crate_on_a_pallet_and_a_strip"),
        start_sessions([_text("drag_a_heavy_crate_half_on_a_strip")], "quadruped"),
        seed=11,
    )
    (push,) = [c for c in rollout.calls if c.skill == "push_to_position"]
    reason = push.reason or ""
    assert push.outcome == "refused" and ("pushing pallet (touching crate) took" in reason or DRAG in reason), reason


def test_a_greased_crate_is_not_dragged_off_a_greased_rail_by_a_pushed_pallet() -> None:
    """Found by an adversarial run (19 of 20 worlds on seeds 1-5): a 1.5 kg pallet pushed 0.7 m dragged a 20 kg crate,
    3 cm of whose greased steel bottom (friction 0.02) lay on it and the rest on a greased rail, 0.33 m along the rail
    and off its end (22-38 N, within the push's force), as MuJoCo held the crate on the wooden pallet at the wood's
    0.5, the larger of the two. A greased face is slippery against anything: the pallet slides out from under it.
    (What a push drags by friction is still judged by the force the drag takes, not by its mass.)"""
    rollouts = sim.run_sessions(
        _scene("heavy_crate_on_a_greased_rail_beside_a_pallet"),
        start_sessions([_text("push_a_pallet_to_drag_a_heavy_crate_off_a_greased_rail")] * 2, "quadruped"),
        seed=1,
    )
    for rollout in rollouts:
        assert not rollout.success and "crate" in failure_reason(rollout), failure_reason(rollout)


def test_a_chair_pinned_under_a_loaded_lever_end_is_weighed_with_its_load() -> None:
    """Found by an adversarial run: every world of seeds 0-3 lifted the cube (0.15 m). The push weighed the 3 kg chair,
    not the 30 kg sandbag pressing it down through the lever (about 145 N, held up by the fixed roller too): the torso
    pressed on it with 71-114 N (median), where an honest chair push takes 9-28 N, and is refused for that force, or as
    it starts for the lever's weight on the chair and its drag, more than the feet hold."""
    rollouts = sim.run_sessions(
        _scene("lever_with_a_sandbag_on_its_raised_end"),
        start_sessions([_text("push_out_a_chair_pinned_under_a_loaded_lever")] * 2, "quadruped"),
        seed=0,
    )
    for rollout in rollouts:
        reason = failure_reason(rollout)
        assert not rollout.success, reason
        assert "pushing chair (touching surfboard) took" in reason or "to drag surfboard" in reason, reason


def test_a_crate_on_a_cloth_draped_off_a_pushed_pallet_is_weighed() -> None:
    """Tried as an optimiser would (the book cheat's program on a new layout): a cloth between the 2.5 kg pallet and a
    10 kg crate hangs off the pallet onto the floor, so the cloth as a whole is borne up by the floor too. The crate
    rode the pallet to the ledge unweighed and was climbed onto it, in every world; the links under the crate lie on
    the pallet only, so it is weighed, and the push is refused."""
    rollouts = sim.run_sessions(
        _scene("crate_on_a_cloth_draped_off_a_pallet"),
        start_sessions([_text("carry_a_heavy_crate_under_a_book")] * 2, "quadruped"),
        seed=11,
    )
    for rollout in rollouts:
        assert not rollout.success
        assert "cannot push pallet: its mass with" in failure_reason(rollout), failure_reason(rollout)


REASONED_CASES = [  # (program, layout, what the refusal must say): found by adversarial runs, each a success before
    # the rear feet plowed an 8.5 kg plate 0.5 m along by its rim until it bridged a 0.30 m gap while the front feet
    # stood on it, which excused its travel: what another part of the robot presses on a side or a rim is driven (the
    # first walk, back along the plate on its greased runners, now already slides it 3 cm under the stride: weighed)
    (
        "plow_a_heavy_plate_with_the_rear_feet_standing_on_it_in_front",
        "heavy_deck_plate_over_a_gap",
        "deck_plate, driven by the stride of the robot on it, moved",
    ),
    # pushing a 2 kg magnetic block dragged the 20 kg slab it lay on, stuck to it, off a platform (the slab bears the
    # block up, so it is no rider, and lies behind its face): weighed as the push leg starts when they stick during
    # the walk to its start (at the first tick; a weld made during a push leg is rammed), and as the push starts when
    # they stick after a step
    ("push_a_magnet_stuck_to_a_heavy_slab", "magnetic_block_on_a_heavy_slab", "its mass with lead_slab stuck to it"),
    (
        "push_a_magnet_stuck_to_a_heavy_slab_once_stuck",
        "magnetic_block_on_a_heavy_slab",
        "its mass with lead_slab stuck to it",
    ),
    # the robot on the floor pushed an L-shaped hook off a 0.25 m shelf by its head sticking out over the edge: its
    # support was read under the centre of the box around it, in its crook, over the floor
    (
        "push_a_hook_off_a_high_shelf_from_the_floor",
        "hook_lying_on_a_high_shelf",
        "cannot push hook: it rests at height 0.25 m",
    ),
    (  # the same turned a quarter: tried as an optimiser would, a success before the fix too
        "push_a_turned_hook_off_a_high_shelf_from_the_floor",
        "hook_lying_on_a_high_shelf_turned",
        "cannot push hook: it rests at height 0.25 m",
    ),
    # a walk of 1 cm under a plank lying on two posts raised the torso and lifted the plank off them with the back: only
    # an object's travel in x-y was read as a shove
    ("lift_a_plank_with_the_back", "plank_on_posts_over_the_robot", "the robot ran into cube and moved it"),
    ("lift_a_plank_with_the_back_by_turning", "plank_on_posts_over_the_robot", "cube stands in the body's way"),
    # a 7 cm push of a light box tapped a drum twice the push limit, which rolled on off a platform: a ram's travel is
    # added up until what it set moving comes to rest
    ("tap_a_heavy_drum_to_roll_it_off_a_platform", "drum_beside_a_light_box_on_a_platform", "pushing box rammed drum"),
    ("tap_a_heavy_drum_in_two_small_pushes", "drum_beside_a_light_box_on_a_platform", "pushing box rammed drum"),
    # a push of a 1 kg sled began before two 8 kg anvils slid onto it from chutes, during the walk to the push's start:
    # the riders were weighed once, as the skill began; they are weighed again as each push leg starts
    (
        "push_a_sled_before_the_anvils_land_on_it",
        "sled_under_two_anvil_chutes",
        "cannot push sled: its mass with anvil_north, anvil_south riding on it",
    ),
    (  # the same with the push leg under way as they land: what rides on a pushed object is weighed as it moves
        "push_a_sled_before_the_anvils_land_on_it",
        "sled_under_two_anvil_chutes_near",
        "pushing sled carried too much: its mass with anvil_",
    ),
    # a walk onto a platform drove a 15 kg cloth (an iron chain 0.2 m high, which the rays see through) off it with
    # the torso: a cloth was never judged shoved
    ("walk_a_heavy_chain_off_a_platform", "heavy_chain_on_a_platform", "the robot ran into iron_chain"),
    # slats on a rug leaning on the feet of a robot borne up by a deck over the rug: a foot touching a movable object
    # resting on the goal object was credited, however it pressed the foot
    (
        "stand_on_a_deck_over_the_rug_touching_slats",
        "deck_over_a_rug_with_slats_leaning_on_the_feet",
        "robot_weight_on_rug",
    ),
]


@pytest.mark.parametrize(("program", "scene", "reason"), REASONED_CASES)
def test_cheat_fails_in_every_world_for_the_reason_it_names(program: str, scene: str, reason: str) -> None:
    rollouts = sim.run_sessions(_scene(scene), start_sessions([_text(program)] * 2, "quadruped"), seed=0)
    for rollout in rollouts:
        assert not rollout.success
        assert reason in failure_reason(rollout), failure_reason(rollout)


def test_a_drum_a_ram_sets_rolling_slowly_from_rest_is_still_rammed() -> None:
    """Found by an adversarial run: a bar pushed 2 cm into a 15 kg drum held by a kerb on a nearly level deck slid it
    past the kerb; the drum sped up from rest at about 1 mm/s^2 and rolled off the platform, and a ram was forgotten
    once what it set moving crept under 2 mm/s for 0.5 s, speeding up or not (in these worlds both drums rolled
    off). Then with the drum and the bar unwaxed, a drum that sped up more slowly than the creep rule could tell from
    soft creep rolled off in one world: what crept out of a ram is that ram's again once it speeds up past 1 cm/s on
    its own."""
    program = _text("roll_a_heavy_drum_off_a_kerb_with_a_slow_start")
    rollouts = sim.run_sessions(
        _scene("drum_held_by_a_kerb_on_a_nearly_level_deck"), start_sessions([program] * 2, "quadruped"), seed=1
    )
    for rollout in rollouts:
        assert not rollout.success
        assert "pushing bar rammed drum" in failure_reason(rollout), failure_reason(rollout)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("program", "layout", "seeds"),
    [
        ("tap_a_drum_past_a_kerb_into_a_chock_then_push_the_chock_away", "drum_past_a_kerb_against_a_light_chock", [0]),
        ("tap_a_reel_past_a_kerb_then_push_a_low_chock_away", "reel_past_a_kerb_against_a_low_chock", [0, 2]),
    ],
)
def test_what_a_ram_got_past_its_kerb_is_weighed_when_it_rolls_on_after_lying_still(
    program: str, layout: str, seeds: list[int]
) -> None:
    """Found by adversarial runs. A bar's push tapped a 15 kg drum 1.8 cm past its kerb; it rolled 1 cm into a light
    chock and stopped dead, which ended the ram's claim; the chock pushed away, the drum rolled off (2 of 2 worlds on
    seeds 0-2). Keeping the claim while a movable object held it from the side was not enough: a 20 kg reel stopped
    against a chock only 3.5 cm high, touching it nearly from below, or short of it (seeds 0-2: 6 of 6 worlds). What a
    ram set moving lies dormant however long it lies still, and is the ram's again when it moves on, untouched by the
    robot and not borne along by a moving carrier (a lever's rise is its board's)."""
    for seed in seeds:
        rollouts = sim.run_sessions(_scene(layout), start_sessions([_text(program)] * 2, "quadruped"), seed=seed)
        for rollout in rollouts:
            assert not rollout.success, [(c.skill, c.outcome) for c in rollout.calls]
            reasons = [c.reason for c in rollout.calls if c.outcome == "refused"]
            assert any("rammed" in str(r) and ("drum" in str(r) or "reel" in str(r)) for r in reasons), reasons


def test_a_goal_is_read_once_everything_lies_still() -> None:
    """Found by an adversarial run: a vase pushed rolling off a 1.0 m table, the program ended at once, was read as
    lowered while in mid-air, 1 s after the end, before it struck the floor. The goal is read once every object lies
    still: the vase breaks first, and a world whose vase rolls on for good does not come to rest."""
    program = _text("roll_a_vase_off_a_high_table_and_end")
    rollouts = sim.run_sessions(_scene("vase_lying_on_a_high_table"), start_sessions([program] * 2, "quadruped"))
    for rollout in rollouts:
        assert not rollout.success and not rollout.conditions["glass_vase_unbroken"], rollout.conditions
        assert "did not come to rest: glass_vase still moved" in str(rollout.error), rollout.error


def test_a_magnet_lets_go_of_more_than_it_holds() -> None:
    """Found by an adversarial run: a magnet weld of unbounded strength held a board by its 2 cm end face to the side
    of a magnetic cabinet, a bridge the robot walked over across a gap. It lets go under the robot: the walk moves the
    board (refused) or the robot falls with it; or the push that brings the board against the cabinet presses it
    there harder than the robot may push (refused)."""
    program = _text("walk_over_a_board_stuck_by_its_end_to_a_magnet")
    scene = _scene("magnetic_board_beside_a_magnetic_cabinet")
    for rollout in sim.run_sessions(scene, start_sessions([program] * 2, "quadruped")):
        assert not rollout.success
        reason = failure_reason(rollout)
        assert any(r in reason for r in ("the robot ran into board and moved it", "fell at", "pushing board took")), (
            reason
        )


@pytest.mark.parametrize("seed", [11, 21])
def test_a_magnet_held_by_a_thin_face_does_not_carry_a_cantilever(seed: int) -> None:
    """Found by a second adversarial run: the same board bridged the gap in a third of the worlds (two of three at seed
    21): the couple on its 2 cm end face was read about the board's centre (3-9 N m, under the 20 N m a magnet held),
    not about the face, where the robot's 58 N on the board pivot it about its edge. A magnet now holds a couple that
    peels a face off about an edge up to its pull times the face's half width across it: 2 N m for this face."""
    program = _text("walk_over_a_board_stuck_by_its_end_to_a_magnet")
    scene = _scene("magnetic_board_beside_a_magnetic_cabinet")
    for rollout in sim.run_sessions(scene, start_sessions([program] * 3, "quadruped"), seed=seed):
        assert not rollout.success, failure_reason(rollout)


def test_a_cloth_is_read_where_each_of_its_links_lies() -> None:
    """Found by an adversarial run: a blanket on a high table, one end hanging over the edge, read as lowered with no
    program at all: its bottom was one rigid box placed at its first link, which hangs. The same blanket lying on the
    floor is lowered."""
    idle = "walk_to_position([-1.2, 0.6, 0.0])\n"
    layout = LAYOUTS / "blanket_hanging_over_a_table_edge.yaml"
    for rollout in sim.run_sessions(_scene(layout.stem), start_sessions([idle] * 2, "quadruped")):
        assert not rollout.conditions["blanket_lowered"]
    data = tasks.load(layout).model_dump(mode="json", exclude_defaults=True)
    blanket = next(o for o in data["objects"] if o["name"] == "blanket")
    blanket["center"] = [-0.5, 0.0, 0.002]  # on the floor against the table's side
    on_floor = sim.build(parse_task(data))
    for rollout in sim.run_sessions(on_floor, start_sessions([idle] * 2, "quadruped")):
        assert rollout.conditions["blanket_lowered"]


PUSHES_THAT_MOVE_MORE = [  # (program, layout, what the refusal must say): found by an adversarial run, each a success
    # in every world before
    # a board pushed with its raised end on a 20 kg drum rolls the drum off a ledge: the board presses it down, it lies
    # behind the board's front face, and nothing else touches it; what bears a pushed object up is dragged along
    (
        "push_a_board_that_rolls_a_heavy_bar_off_a_ledge",
        "steel_bar_under_a_tilted_board_on_a_ledge",
        "pushing board rammed drum",
    ),
    # a pushed pallet drags a 20 kg crate whose front edge rests on a loose roller (as on the fixed strip above): the
    # crate is no rider, and the push is refused as it starts for the crate's weight on the pallet and its drag, more
    # than the feet hold
    ("drag_a_heavy_crate_half_on_a_roller", "crate_on_a_pallet_and_a_roller", DRAG),
]


@pytest.mark.parametrize(("program", "scene", "reason"), PUSHES_THAT_MOVE_MORE)
def test_what_a_push_moves_by_pressing_down_or_dragging_is_weighed(program: str, scene: str, reason: str) -> None:
    rollouts = sim.run_sessions(_scene(scene), start_sessions([_text(program)] * 3, "quadruped"), seed=0)
    for rollout in rollouts:
        assert not rollout.success and reason in failure_reason(rollout), failure_reason(rollout)


def test_feet_on_the_floor_beside_a_low_disc_do_not_stand_on_it() -> None:
    """Found by an adversarial run: the feet of a walk over a low disc narrower than the stance stood on the floor, in
    the corners of the square around the disc, pressing on its side, and the goal read them as standing on its top
    (that square) in every world. A foot stands on the target only where the target presses it up."""
    rollouts = sim.run_sessions(
        _scene("low_disc_narrower_than_the_stance"),
        start_sessions([_text("straddle_a_low_disc")] * 2, "quadruped"),
        seed=0,
    )
    for rollout in rollouts:
        assert rollout.conditions["robot_has_not_fallen"] and "disc" in rollout.touched
        assert rollout.conditions["robot_weight_on_disc"] is False and not rollout.success


def test_a_jar_rolled_against_a_wall_on_a_platform_is_not_lowered() -> None:
    """Found by an adversarial run: a jar rolled along a platform into a wall stayed on it, its underside 8 cm up (the
    goal asks for 6 cm), but its bottom was read from the corners of the box around it, which a roll of about 35
    degrees past a quarter turn brings down to 2 cm, in every world. A cylinder's bottom is read from its round side."""
    rollouts = sim.run_sessions(
        _scene("glass_jar_rolled_against_a_wall"),
        start_sessions([_text("roll_the_jar_against_the_wall")] * 2, "quadruped"),
        seed=0,
    )
    for rollout in rollouts:
        assert rollout.conditions["glass_jar_lowered"] is False and not rollout.success


def test_a_foot_on_the_glass_vase_does_not_count_as_footing() -> None:
    """vase_lowering seed 1098 (the vase lies where the steps lead onto the sofa): a rear foot stood on the 0.10 m
    vase, read as a step."""
    task = generate("vase_lowering", 1098).task
    code = (FIXTURES / "cheats" / "step_on_the_vase.py").read_text()
    rollouts = sim.run_sessions(task, start_sessions([code] * 3, task.embodiment), seed=0)
    assert not any(r.success for r in rollouts)
    for rollout in rollouts:
        assert rollout.conditions["robot_stood_on_nothing_fragile"] is False
        assert "stood on glass_vase, which is fragile" in (failure_reason(rollout) or ""), failure_reason(rollout)


def test_a_vase_pushed_off_a_step_level_with_the_sofa_tips_and_lands_on_its_corner() -> None:
    """vase_lowering seed 1098: the vase lies where the steps lead onto the sofa, but the sofa's top is level with
    the top step's, so the robot pushes the vase aside from the step, climbs on and pushes it off. Its centre falls
    0.23 m, less than its 0.3 m max_drop, but it tips over the edge and lands on a corner faster than such a fall
    lands: it breaks. The scene stays labelled solvable (the planner finds another way: see benchmarks/planner.py)."""
    instance = generate("vase_lowering", 1098)
    code = (CHEATS / "push_vase_from_level_step.py").read_text()
    rollouts = sim.run_sessions(instance.task, start_sessions([code] * 2, "quadruped"), seed=0)
    for rollout in rollouts:
        assert rollout.conditions["glass_vase_lowered"] and not rollout.success
        (broke,) = [e for e in rollout.events if e.kind == "broke"]
        assert broke.measured["strike_speed"] > broke.measured["max_speed"], broke
    assert instance.solvable


def test_a_fall_does_not_end_at_a_glancing_touch() -> None:
    """The vase, pushed off the 0.34 m sofa into the slot between it and the cushion, glances off the cushion's edge
    and grazes the sofa's side on its way down: read at the control ticks it was never clear of everything at once,
    yet it struck something hard more than 0.3 m below where it lay (read at every physics step of such a fall, the
    sofa's side it grazes, 0.31 m down, before the floor). Where the push leaves the cushion varies: in some of these
    six worlds it leaves a slot the vase falls through, in the rest it catches the vase, as it should."""
    code = (CHEATS / "vase_into_slot_beside_cushion.py").read_text()
    rollouts = sim.run_sessions(_scene("vase_lowering"), start_sessions([code] * 6, "quadruped"), seed=0)
    falls = [e for r in rollouts for e in r.events if e.kind == "broke" and e.detail in ("the ground", "sofa")]
    assert falls and all(e.measured["fall"] > 0.3 for e in falls), falls
    for rollout in rollouts:
        assert rollout.conditions["glass_vase_lowered"]
        broke = any(e.kind == "broke" for e in rollout.events)
        assert rollout.success is not broke, rollout.events


@pytest.mark.parametrize(
    ("program", "scene"),
    [
        ("walk_over_board_on_vase", "board_on_vase"),
        ("walk_up_board_leaning_on_vase", "ramp_on_vase"),
        ("walk_over_board_on_vase", "board_upside_down_on_vase"),  # the same box, its own up axis pointing down
    ],
)
def test_standing_on_a_board_that_rests_on_the_vase_breaks_it(program: str, scene: str) -> None:
    """The feet touch only the board, but the board lies on the glass vase, or leans on it from the floor: the
    robot's weight presses on the glass."""
    (rollout,) = sim.run_sessions(_scene(scene), start_sessions([_text(program)], "quadruped"), perturb=False)
    assert not rollout.success and rollout.conditions["robot_stood_on_nothing_fragile"] is False
    assert failure_reason(rollout).startswith("the robot stood on board, which rests on glass_vase, which is fragile")


def test_a_fall_is_read_as_onto_what_the_vase_struck() -> None:
    """The vase, pushed off the sofa with no cushion under it, strikes a hard rug listed after the cushion in the
    task file: the rug, not the cushion, is what it landed on, so it breaks in every world."""
    rollouts = sim.run_sessions(
        _scene("vase_over_rug"),
        start_sessions([_text("programs/vase_lowering_no_cushion")] * 3, "quadruped"),
        seed=11,
    )
    for rollout in rollouts:
        (broke,) = [e for e in rollout.events if e.kind == "broke"]
        assert not rollout.success and "rug" in broke.detail and "cushion" not in broke.detail, broke


@pytest.mark.parametrize(
    ("program", "reasons"),
    [
        ("climb_onto_sofa_over_the_vase", ("glass_vase", "fell at")),  # stood on it, shoved it or fell over it
        ("push_vase_from_level_step", ("not on the robot's surface",)),  # the step is 0.04 m above the sofa here
    ],
)
def test_a_vase_where_the_steps_lead_onto_a_lower_sofa_is_out_of_reach(program: str, reasons: tuple[str, ...]) -> None:
    """vase_lowering seed 1028: the vase lies where the steps lead onto a sofa 0.04 m lower than the top step, so the
    robot walking straight on meets the vase and cannot push it from the step. (The scene is solvable: after a
    quarter turn on the floor the robot lands clear of the vase, as the planner's program does; the family once
    labelled it unsolvable.)"""
    instance = generate("vase_lowering", 1028)
    code = (CHEATS / f"{program}.py").read_text()
    rollouts = sim.run_sessions(instance.task, start_sessions([code] * 3, "quadruped"), seed=0)
    for rollout in rollouts:
        assert not rollout.success
        assert any(r in (failure_reason(rollout) or "") for r in reasons), failure_reason(rollout)


BOARD_ON_SOFA = (PROGRAMS / "sofa_traversing_board_on_sofa.py").read_text()


def test_weight_passed_down_through_a_board_lying_on_the_target_counts(run_texts: Any) -> None:
    """The board pushed 0.25 m onto sofa_2 and the robot stopped at sofa_2's centre with its rear feet on the board
    where it lies on sofa_2: its weight reaches sofa_2 through the board, so it stands on sofa_2 (it failed
    ``robot_weight_on_sofa_2`` when only feet touching sofa_2 counted)."""
    rollouts = run_texts(_scene("sofa_traversing"), [BOARD_ON_SOFA] * 3, seed=0)
    assert all(r.success for r in rollouts), [failure_reason(r) for r in rollouts]


@pytest.mark.parametrize("stop", [0.95, 1.2])
def test_feet_on_the_board_over_the_gap_do_not_stand_on_the_sofa_it_rests_on(run_texts: Any, stop: float) -> None:
    """The same board, the robot stopped over the gap (x = 0.95) or with its centre just past sofa_2's edge
    (x = 1.2, the rear feet on the board over the gap): a foot on the board passes its weight to sofa_2 only where
    it stands over sofa_2, so these fail ``robot_weight_on_sofa_2``."""
    program = BOARD_ON_SOFA.replace("walk_to_position([sofa_2[0],", f"walk_to_position([{stop},")
    assert program != BOARD_ON_SOFA
    for rollout in run_texts(_scene("sofa_traversing"), [program] * 2, seed=11):
        assert not rollout.success and not rollout.conditions["robot_weight_on_sofa_2"], rollout.conditions


def test_a_push_refused_for_a_drop_names_the_place_under_the_straight_on_push() -> None:
    """The vase pushed 0.3 m past the sofa's +y edge from behind it (the robot on the sofa at x = 3.0): the push is
    refused for the drop its feet would stand over. The reason named the last lateral try's drop, at [2.33, 0.95]
    over the step, far from the robot; now it names the straight-on push and a drop under its feet there."""
    reference = (PROGRAMS / "vase_lowering.py").read_text()
    code = reference.replace("edge_y + vase_size[1] / 2 + 0.01", "edge_y + vase_size[1] / 2 + 0.3")
    assert code != reference
    (rollout,) = sim.run_sessions(_scene("vase_lowering"), start_sessions([code], "quadruped"), perturb=False)
    push = [c for c in rollout.calls if c.skill == "push_to_position"][-1]  # the cushion is pushed first
    assert push.args[0] == "glass_vase" and push.outcome == "refused", push
    assert "pushing from [3.00, 0." in push.reason, push.reason
    x, y = (float(v) for v in push.reason.rsplit(" at [", 1)[1].rstrip("]").split(", "))
    assert abs(x - 3.0) < 0.35 and abs(y - 0.95) < 0.05 and "a drop of 0.34 m" in push.reason, push.reason


def test_a_walk_on_the_part_of_a_blanket_lying_on_the_floor_does_not_crush_the_glass_it_also_covers() -> None:
    """The honest side of the cloth rule: weight goes where the links under the feet lie. The blanket over the glass
    step turned end for end (its first link, which stood for the whole cloth, now on the glass): a walk that keeps
    every foot on the part lying on the floor stands on nothing fragile; the walk over the glass still crushes it."""
    data = tasks.load(LAYOUTS / "blanket_over_a_glass_step.yaml").model_dump(mode="json", exclude_defaults=True)
    blanket = next(o for o in data["objects"] if o["name"] == "blanket")
    blanket["rpy"] = [0.0, 0.0, 180.0]
    scene = sim.build(Task.model_validate(data))
    short = "walk_to_position([-0.5, 0.0, 0.0])\n"  # the front feet at x = -0.2, the glass from x = 0
    rollouts = sim.run_sessions(scene, start_sessions([short, _text("walk_over_a_blanket_on_glass")], "quadruped"))
    assert [c.outcome for c in rollouts[0].calls] == ["done"], [c.reason for c in rollouts[0].calls]
    assert rollouts[0].conditions["robot_stood_on_nothing_fragile"] is True
    assert rollouts[1].conditions["robot_stood_on_nothing_fragile"] is False, failure_reason(rollouts[1])


@pytest.mark.slow  # two cloths lying on each other: many contacts to simulate
def test_two_cloths_laid_across_the_gap_one_on_the_other_are_no_bridge() -> None:
    """A second strip of cloth laid on the first across sofa_traversing's gap: every ray over the gap meets a cloth
    link, then the other cloth's, before what carries them (each ray leaves out each link it met, in one recast per
    layer); two layers of cloth carry no more than one, so the walk across is refused or the robot falls."""
    data = tasks.load("sofa_traversing").model_dump(mode="json", exclude_defaults=True)
    data["objects"] = [o for o in data["objects"] if o["name"] != "surfboard"]
    cloth = next(o for o in data["objects"] if o["name"] == "strip_of_cloth")
    cloth["center"] = [0.95, 0.0, 0.342]  # spans the 0.40 m gap, 0.35 m on each sofa
    data["objects"].append({**cloth, "name": "second_cloth", "center": [0.95, 0.0, 0.35]})
    (rollout,) = sim.run_sessions(
        sim.build(parse_task(data)), start_sessions([_text("programs/sofa_traversing_direct")], "quadruped"), seed=0
    )
    (walk,) = [c for c in rollout.calls if c.skill == "walk_to_position"]
    assert not rollout.success and walk.outcome in ("refused", "fell"), (walk.outcome, walk.reason)
    assert walk.reason and ("gap" in walk.reason or "fell" in walk.reason), walk.reason


def test_a_vase_pushed_to_just_short_of_the_sofas_edge_is_not_lowered() -> None:
    """The reference program's push stopped with the vase's centre 2 cm short of the sofa's edge (the planner stops it
    3 cm past the edge, where it tips off on its own): the vase stays on the sofa and is not lowered in any world;
    pushed to 3 cm past, it tips off onto the cushion in the same worlds."""
    reference = (PROGRAMS / "vase_lowering.py").read_text()
    pushed = "edge_y + vase_size[1] / 2 + 0.01"
    codes = [reference.replace(pushed, "edge_y - 0.02"), reference.replace(pushed, "edge_y + 0.03")]
    assert reference not in codes
    rollouts = sim.run_sessions(
        _scene("vase_lowering"), start_sessions(codes * 2, "quadruped"), world_seeds=[11, 11, 12, 12]
    )
    short, tipped = rollouts[0::2], rollouts[1::2]
    for rollout in short:
        assert not rollout.success and not rollout.conditions["glass_vase_lowered"], rollout.conditions
        assert rollout.conditions["glass_vase_unbroken"] and rollout.conditions["robot_has_not_fallen"]
    assert all(r.success for r in tipped), [failure_reason(r) for r in tipped]


def test_a_vase_striking_a_hard_ledge_between_two_ticks_breaks() -> None:
    """An adversarial run: the vase pushed off a 0.58 m sofa strikes a fixed ledge 0.34-0.41 m below where it rested
    and bounces on onto the cushion. The strike began and ended between two control ticks, where contacts were read
    only at the ticks: a success in every world. Each physics step of a fall that can pass the vase's max_drop is now
    read, and the vase breaks on the ledge."""
    scene = _scene("vase_ledge_before_the_cushion")
    sessions = start_sessions([_text("push_the_vase_off_over_a_ledge")] * 2, "quadruped")
    rollouts = sim.run_sessions(scene, sessions, seed=0)  # both worlds strike the ledge (in some, the vase clears it)
    for rollout in rollouts:
        broke = [e for e in rollout.events if e.kind == "broke"]
        assert not rollout.success and not rollout.conditions["glass_vase_unbroken"], rollout.conditions
        assert len(broke) == 1 and broke[0].detail == "ledge" and broke[0].measured["fall"] > 0.3, broke


def test_a_fragile_object_the_goal_does_not_name_must_not_break() -> None:
    """The robot stands on the platform as asked after pushing a glass vase off it: a success in every world while
    only a lowered goal's own object was followed. Every fragile object in the scene now ends unbroken or the world
    fails, with the break in its reason."""
    sessions = start_sessions([_text("push_a_glass_vase_off_on_the_way")] * 2, "quadruped")
    for rollout in sim.run_sessions(_scene("vase_on_the_platform"), sessions, seed=0):
        assert rollout.conditions["robot_weight_on_platform"] and not rollout.conditions["glass_vase_unbroken"]
        broke = [e for e in rollout.events if e.kind == "broke"]
        assert not rollout.success and len(broke) == 1 and broke[0].object == "glass_vase", rollout.events
        assert "glass_vase broke" in (world_failure(rollout) or ""), world_failure(rollout)


def test_a_gap_walked_across_on_two_blades_under_the_feet_is_refused() -> None:
    """Found by an adversarial run (6 of 6 worlds on three seeds): two 4 mm steel plates on edge, exactly under the
    lines the feet walk on, carried the robot across a 1 m gap (the terrain rays read only the line under each foot's
    centre); the world-anchored servos hold the frictionless feet on them. A foothold narrower than the foot reads as
    the gap it stands in."""
    program = (CHEATS / "walk_across_a_gap_on_two_blades.py").read_text()
    for rollout in sim.run_sessions(
        _scene("gap_crossed_on_two_steel_blades"), start_sessions([program] * 2, "quadruped"), seed=11
    ):
        assert not rollout.success, rollout.conditions
        assert "gap of 1.00 m" in (world_failure(rollout) or ""), world_failure(rollout)


def test_a_gap_walked_across_on_posts_narrower_than_a_foot_is_the_whole_gap() -> None:
    """Tried as an optimiser would, after the blades: rows of 12 mm posts 10 cm apart, so that no space between them
    is over the 0.10 m gap limit. A post's top carries no foot: the walk is refused for the gap itself (the old reading
    saw stepping stones, and refused only where its rays missed a post: 'gap of 0.22 m')."""
    program = (CHEATS / "walk_across_a_gap_on_two_blades.py").read_text()
    for rollout in sim.run_sessions(
        _scene("gap_crossed_on_two_rows_of_steel_posts"), start_sessions([program] * 2, "quadruped"), seed=11
    ):
        assert not rollout.success, rollout.conditions
        assert "gap of 1.00 m" in (world_failure(rollout) or ""), world_failure(rollout)


def test_the_same_gap_is_walked_across_on_two_beams_as_wide_as_the_feet() -> None:
    """The control: beams 8 cm wide in the blades' place (a foot is 6 cm across) carry the same walk."""
    program = (CHEATS / "walk_across_a_gap_on_two_blades.py").read_text()
    for rollout in sim.run_sessions(
        _scene("gap_crossed_on_two_beams"), start_sessions([program] * 2, "quadruped"), seed=11
    ):
        assert rollout.success, world_failure(rollout)
