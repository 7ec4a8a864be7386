"""A corpus of cheating arm programs: each must fail in every perturbed world, with a reason one can read.

The programs are files in ``tests/fixtures/cheats/arm_*.py``: creeping past the workspace edge in small steps,
huge target coordinates, a held cube let go at the end of a fast run, a single cube rammed at an out-of-reach
button, paper slid under a can with no stick, a flat block beyond reach dragged in by pressing a stick on it again
and again (MuJoCo's soft pyramidal friction let it creep along; the arm's scenes use elliptic cones), and a far
milk carton tipped over toward the arm with a straight stick and then dragged in by pressing the stick on it (a
scene the milk family calls unsolvable must keep its carton out of reach of everything the arm can hold; the same
program grasps a carton within reach, the control), paper slid or laid under a standing can (or slid under it a
millimetre per call) and the can then nudged a few millimetres so that it seemed to have been pushed onto the paper
(the sheet rule let the paper carry it; now an object the sheet got under rests on it only after leaving its
footprint), a short chopstick nudging a can the paper was slid under, degenerate calls at the workspace edge, a
two-cube chain held by a sliver of its first cube and a two-cube stack toppled toward a button beyond their reach,
and a tray twice as wide as the opening held by pressing the open fingers on its face (friction kept them from
closing, both touched it, and it was held; now what lies beside the fingers must lie between them), a cube or the
milk held by the last 4 mm of its edge (any overlap was a grasp; now a pinch of less than half the pads' width holds
nothing), the paper slid under half the can, 2 mm short of its centre, before a nudge (now a sheet that got under
any share of an object's base marks it slid under), and a puck slid up a wall face and flung over its top by the
servo's pent-up pull (now a move's reference stays near the gripper). Each case names what its failure reason must
say. A task named ``family:seed`` is a generated instance the family calls unsolvable. Two magnetic cubes shoved
loose by the closed fingers are honest tool use: they press the built-in button and no unsolvable one. Open (a strict
xfail): a beam pressed 2:1 against the arm raises a light anvil into a button, as a scene whose movable objects are
light is not weighed. The honest references on the same tasks succeed in tests/robots/arm/test_skills.py.
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import pytest
from fixtures.paths import FIXTURES
from fixtures.reference import program

from robotool import sim, tasks
from robotool.robots.arm.arm_config import ARM
from robotool.robots.arm.arm_payload import PAYLOAD_CONDITION
from robotool.rollout import Rollout
from robotool.sim.recorder import StateRecorder
from robotool.task.task_file import parse_task
from robotool.task.task_model import Task
from robotool.tasks.families import milk_reaching
from robotool.tasks.families._common import footprint
from robotool.verify import world_failure

CHEATS = FIXTURES / "cheats"
PROGRAMS = FIXTURES / "programs"
LAYOUTS = FIXTURES / "layouts"
UNSOLVABLE_MILK_SEED = 64  # an unsolvable instance of the milk family (its carton stood at 0.60 m, in tipping reach)


def _task(name: str) -> Task:
    if name == "milk_reaching_unsolvable":
        name = f"milk_reaching:{UNSOLVABLE_MILK_SEED}"
    if ":" in name:
        family, seed = name.split(":")
        instance = tasks.generate(family, int(seed))
        assert not instance.solvable
        return instance.task
    layout = LAYOUTS / f"{name}.yaml"
    return tasks.load(layout) if layout.is_file() else tasks.load(name)


CASES = [  # (program, task, what its failure reason must say, or one of what it may say)
    ("arm_creep_past_workspace", "milk_reaching", "clamped"),
    ("arm_huge_targets", "milk_reaching", "clamped 4.0"),
    ("arm_release_at_speed", "button_pressing", "goal not reached: button_pressed"),
    ("arm_ram_one_cube", "button_pressing", "clamped"),
    # the paper cheats: the can is left where it stood, over 0.2 m beyond reach, when the arm reaches for it
    ("arm_paper_under_can", "can_grasping", "clamped 0.2"),
    ("arm_topple_milk_with_stick", "milk_reaching_unsolvable", "clamped"),
    ("arm_press_drag_block", "arm_block_beyond_reach", "clamped"),  # friction from above dragged a flat block in
    ("arm_slide_paper_under_can_then_nudge", "can_grasping", "clamped 0.2"),  # the nudged can rode the paper
    ("arm_slide_paper_slowly_under_can", "can_grasping", "clamped 0.2"),  # the same, the paper slid 1 mm per call
    ("arm_lay_paper_over_can", "can_grasping", "clamped 0.2"),  # the same, the paper lifted over the can, laid down
    ("arm_slide_paper_half_under_can_then_nudge", "can_grasping", "clamped 0.2"),  # slid short of its centre
    ("arm_chopstick_nudge_over_paper", "can_grasping:74", "clamped 0.2"),
    # paper pinched by its edge and held 9 mm up dragged the can over a 6 mm rail (a held sheet drooped only past 1 cm)
    ("arm_drag_a_can_over_a_kerb_on_raised_paper", "arm_can_beyond_a_kerb_on_paper", "clamped 0.3"),
    # paper pulled out from under a 60 kg crate standing partly on it brought the can on its far end
    ("arm_drag_paper_from_under_a_heavy_crate", "arm_can_on_paper_pinned_by_a_heavy_crate", "clamped 0.3"),
    # paper pulled out from under a 60 kg crate, or a block bolted over it, and lifted: a sheet met nothing but the
    # ground and the robot, so what stood on it never held it back
    ("arm_drag_pinned_paper_out_and_lift", "arm_paper_pinned_under_a_heavy_crate", "6 move_to_position: stalled"),
    ("arm_drag_pinned_paper_out_and_lift", "arm_paper_pinned_under_a_fixed_block", "6 move_to_position: stalled"),
    # the same with the load on a light block standing on the paper, or a heavy cloth lying on it: only the weight of
    # what touched the paper counted, and a cloth never did
    ("arm_drag_pinned_paper_out_and_lift", "arm_paper_under_a_block_loaded_by_a_crate", "6 move_to_position: stalled"),
    ("arm_drag_pinned_paper_out_and_lift", "arm_paper_under_a_heavy_apron", "6 move_to_position: stalled"),
    ("arm_drag_paper_from_under_a_heavy_crate", "arm_can_on_paper_under_a_block_loaded_by_a_crate", "clamped 0.3"),
    # a greased bar pressed against a wall by a held rubber block and slid up it: held at the rubber's and the wall's
    # friction, the larger of each pair
    ("arm_clamp_a_greased_bar_to_a_wall_and_lift", "arm_greased_bar_against_a_wall", "not reached: greased_bar_lifted"),
    ("arm_degenerate_calls", "milk_reaching", "clamped"),
    ("arm_sliver_grasp_chain", "button_pressing:196", "a pinch at its edge"),
    ("arm_sliver_grasp_chain", "button_pressing", "a pinch at its edge"),  # a 4 mm pinch held the chain 19 mm out
    ("arm_sliver_grasp_milk", "milk_reaching", "held nothing"),  # a 4 mm pinch at the workspace edge held the carton
    ("arm_topple_cube_stack", "button_pressing:196", "goal not reached: button_pressed"),  # lands unpressed
    ("arm_press_fingers_on_face", "arm_tray_too_wide", "was not between the fingers"),  # friction jammed the fingers
    ("arm_pinch_a_steel_plate", "arm_steel_plate_lying_flat", "wider than their"),  # 3 mm thin: read as paper
    ("arm_nudge_a_rolled_cube_half_onto_a_ribbon", "arm_rolled_cube_beside_a_narrow_ribbon", "clamped"),  # its side
    # 141 N pushed through a friction grip that holds 120 N: the press the weld passed on is not counted either; 135 N
    # for the centimetre is past the arm's 39 N, which stops it first
    ("arm_drive_a_slat_into_a_stiff_button", "arm_stiff_button_facing_down", "over the 39 N the arm's 4.0 kg payload"),
    # the press was seen at a tick where the stick twisted in the grip past what it holds, before it slipped out
    ("arm_jab_a_stick_up_into_a_stiff_button", "arm_stiff_button_facing_down_over_a_post", "closing axis"),
    # the jug raked in 4 cm steps, re-grasping between them: it stays beyond reach, or the rake's push on it (about
    # 76 N, the gripper dragged a few millimetres as the grip slips: the work of a push at the rating over 5 mm) counts
    (
        "arm_rake_a_heavy_milk_in_regrasped_steps",
        "arm_heavy_milk_beyond_reach",
        ("clamped 0.1", "cannot push with hammer"),
    ),
    # let go 0.40 m above the floor: its fall was measured from the stool it last rested on, not from the hand
    ("arm_drop_the_vase_from_high", "arm_vase_on_a_stool", "vase broke: it fell 0.4"),
    # a program that does nothing, on a button a plate the task file lays on it pressed while the world settled
    ("arm_do_nothing_under_a_button", "arm_plate_lying_on_an_upturned_button", "goal not reached: button_pressed"),
    # a block that tipped off its shelf while the world settled, lifted from the floor: counted from the shelf
    ("arm_lift_a_block_that_tipped_off_its_shelf_from_the_floor", "arm_block_placed_at_a_shelf_edge", "block_lifted"),
    # the glass dropped on the way to lifting the cube: not the goal's object, but broken
    ("arm_drop_the_glass_then_lift_the_cube", "arm_cube_and_a_wine_glass", "glass broke: it fell 0.3"),
    # shoved off a stool past a 0.05 m max_drop, touching the fingers as it went (it tips first: its top lands on the
    # stool faster than such a fall lands, or its centre's fall breaks it on the floor)
    ("arm_shove_the_brittle_vase_off_the_stool", "arm_brittle_vase_on_a_stool", "vase broke: "),
    # a 3.5 kg bar hung by a 3 cm square magnet patch on a post's side, its weight twisting the patch by 9 N m: a magnet
    # held 20 N m of twist whatever its patch
    ("arm_hang_a_steel_bar_on_a_post_by_its_side", "arm_steel_bar_beside_a_magnetic_post", "not reached: bar_lifted"),
    # a 3.5 kg bracket hung by its bar's 3 cm end on a wall: the patch was read from the box around the whole bracket,
    # as tall as its upright
    (
        "arm_hang_a_steel_bracket_on_a_wall_by_its_bar_end",
        "arm_steel_bracket_below_a_magnetic_wall",
        "not reached: bracket_lifted",
    ),
]


PAPER_SLIDES = {  # they once moved the gripper to 1 mm above the paper, below its reach: the slides stalled short
    "arm_paper_under_can",
    "arm_slide_paper_under_can_then_nudge",
    "arm_slide_paper_slowly_under_can",
    "arm_lay_paper_over_can",
    "arm_slide_paper_half_under_can_then_nudge",
}


@pytest.mark.parametrize(("program", "task", "reason"), CASES)
def test_cheat_fails_in_every_world_with_a_reason(
    run_texts: Any, program: str, task: str, reason: str | tuple[str, ...]
) -> None:
    """Each cheat fails in every world for the reason it names (or for one of the reasons it names)."""
    rollouts: list[Rollout] = run_texts(_task(task), [(CHEATS / f"{program}.py").read_text()] * 2, seed=11)
    for rollout in rollouts:
        assert not rollout.success, [(c.skill, c.args, c.outcome) for c in rollout.calls]
        assert rollout.error is None, rollout.error  # it ran to its end: the world said no
        failure = world_failure(rollout) or ""
        assert any(r in failure for r in ((reason,) if isinstance(reason, str) else reason)), failure
        if program in PAPER_SLIDES:  # the paper went where the cheat meant it to: no slide stopped short of it
            assert not any(c.outcome == "stalled" for c in rollout.calls), [c for c in rollout.calls]


def test_a_crate_resting_on_a_held_plank_loads_the_grip(run_texts: Any) -> None:
    """Found by an adversarial run (every world of seeds 11 and 2 succeeded): a 2 kg crate lying on a light plank held
    0.21 m away was lifted with it, as the grip's load counted what is welded to the held object, not what rests on
    it. The grip's load is now what its weld carries: the plank slips out of it."""
    code = (CHEATS / "arm_lift_a_plank_under_a_crate.py").read_text()
    for rollout in run_texts(_task("arm_crate_on_a_plank"), [code] * 2, seed=11):
        assert not rollout.success, [(c.skill, c.outcome, c.reason) for c in rollout.calls]
        assert "plank slipped out of the grip" in world_failure(rollout), world_failure(rollout)
        assert "about the fingers' closing axis" in world_failure(rollout), world_failure(rollout)


def test_a_heavy_jug_raked_in_by_a_held_hammer_overloads_the_grip(run_texts: Any) -> None:
    """Found by an adversarial run (every world of seeds 0 and 1 succeeded): raking a 9 kg jug in with the head of a
    hammer held by its handle end put 91-109 N and 14-18 N m on the weld that stands for a 16 mm friction grip, which
    was checked against the hammer's own weight only. The hammer now slips out of the grip."""
    code = (CHEATS / "arm_rake_a_heavy_milk_with_the_hammer.py").read_text()
    for rollout in run_texts(_task("arm_heavy_milk_beyond_reach"), [code] * 2, seed=0):
        assert not rollout.success, [(c.skill, c.outcome, c.reason) for c in rollout.calls]
        assert "hammer slipped out of the grip" in world_failure(rollout), world_failure(rollout)


@pytest.mark.parametrize(("stiffness", "pressed"), [(700.0, True), (9000.0, False)])
def test_the_slat_presses_a_button_the_arm_can_push(run_texts: Any, stiffness: float, pressed: bool) -> None:
    """The controls for the stiff button: the same program presses the same button on a 700 N/m spring (7 N for the
    centimetre, 36 N at the end of the travel it drives the face to), so its failure above is not the program. On a
    9000 N/m spring (90 N for the centimetre) it once did, within the 120 N the pads' friction holds; but the arm
    (a Kinova Gen3 rated for 4 kg) pushes 39 N at most, through what it holds too."""
    data = _task("arm_stiff_button_facing_down").model_dump(mode="json", exclude_defaults=True)
    next(o for o in data["objects"] if o["name"] == "button")["stiffness"] = stiffness
    code = (CHEATS / "arm_drive_a_slat_into_a_stiff_button.py").read_text()
    for rollout in run_texts(parse_task(data), [code] * 2, seed=11):
        assert rollout.success == pressed, world_failure(rollout)
        assert pressed or "cannot push with stick: " in (world_failure(rollout) or "")


@pytest.mark.parametrize(("stiffness", "pressed"), [(2000.0, False), (300.0, True)])
def test_a_stick_pressed_up_slowly_presses_a_button_its_grip_can_push(
    run_texts: Any, stiffness: float, pressed: bool
) -> None:
    """The controls for the jabbed stick: pressed up in 4 mm steps, it presses the same button on a 300 N/m spring
    (3 N, about 0.5 N m on the grip) and not the 2000 N/m one (it slips out of the grip: only the jab pressed it)."""
    data = _task("arm_stiff_button_facing_down_over_a_post").model_dump(mode="json", exclude_defaults=True)
    next(o for o in data["objects"] if o["name"] == "button")["stiffness"] = stiffness
    code = program("press_up_slowly_with_a_stick")
    for rollout in run_texts(parse_task(data), [code] * 2, seed=11):
        assert rollout.success == pressed, world_failure(rollout)
        assert pressed or "stick slipped out of the grip" in world_failure(rollout)


SLIVER_CHAIN = (CHEATS / "arm_sliver_grasp_chain.py").read_text()


def test_a_sliver_grasp_holds_nothing_on_the_built_in_task(run_texts: Any) -> None:
    """On the built-in button task (which a held three-cube chain solves), the sliver-held two-cube chain pressed the
    button in every world; now the close is refused for the grip it measured, in every world."""
    for rollout in run_texts(_task("button_pressing"), [SLIVER_CHAIN] * 3, seed=11):
        assert not rollout.success
        (failed,) = [e for e in rollout.events if e.kind == "grasp_failed"]
        assert failed.cause == "weak_grip" and failed.object == "magnetic_cube1" and failed.measured["depth"] < 0.006
        assert "grip 4 mm deep on magnetic_cube1 across the pads, a pinch at its edge" in world_failure(rollout)


def test_the_same_two_cube_chain_held_at_the_centre_falls_short(run_texts: Any) -> None:
    """The control for the sliver cheat: the same program holding the first cube by a full grip (its centre) reaches
    no further than that grip allows, and the button stays unpressed: only the sliver reached it."""
    centred = SLIVER_CHAIN.replace("ca[0] - e / 2 - 0.004", "ca[0]")
    assert centred != SLIVER_CHAIN
    for rollout in run_texts(_task("button_pressing"), [centred] * 3, seed=11):
        assert not rollout.success and not any(e.kind == "grasp_failed" for e in rollout.events), rollout.events
        assert rollout.conditions == {"button_pressed": False, "nothing_passed_through": True}


def test_a_grip_just_past_the_half_pad_rule_holds_but_reaches_no_further_than_honest_physics(run_texts: Any) -> None:
    """An optimiser's next try after the sliver: grip the first cube 8.5 mm deep, just past the half-pad rule (8 mm).
    The grip holds, as it should, and the chain still falls short of the built-in button: the rule's threshold
    leaves no reach a held three-cube chain does not have."""
    edge = SLIVER_CHAIN.replace("ca[0] - e / 2 - 0.004", "ca[0] - e / 2 + 0.0005")
    assert edge != SLIVER_CHAIN
    for rollout in run_texts(_task("button_pressing"), [edge] * 3, seed=11):
        assert not rollout.success and not any(e.kind == "grasp_failed" for e in rollout.events), rollout.events
        assert rollout.conditions == {"button_pressed": False, "nothing_passed_through": True}


def test_tipping_over_a_carton_within_its_reach_succeeds(run_texts: Any) -> None:
    """The control for the tipping cheat: the same program grasps a carton that stands close enough (0.61 m, where
    the family used to put unsolvable ones), so its failure above is the carton's distance, not the program."""
    data = _task("milk_reaching_unsolvable").model_dump(mode="json", exclude_defaults=True)
    for obj in data["objects"]:
        if obj["name"] == "milk":
            obj["center"][0] = obj["graspable_point"][0] = 0.61
    data["name"] = "milk_within_tipping_reach"
    rollouts = run_texts(parse_task(data), [(CHEATS / "arm_topple_milk_with_stick.py").read_text()] * 2, seed=11)
    assert all(r.success for r in rollouts), [world_failure(r) for r in rollouts]


def test_unsolvable_milk_stands_beyond_the_reach_of_everything_the_arm_can_hold() -> None:
    """Held at its near end with the gripper at the workspace edge, no movable object reaches an unsolvable carton
    (with the perturbation's shift to spare)."""
    for seed in range(50):
        instance = tasks.generate("milk_reaching", seed)
        if instance.solvable:
            continue
        objects = instance.task.objects
        milk = next(o for o in objects if o.name == "milk")
        longest = max(footprint(o)[2] - footprint(o)[0] for o in objects if o.movable and o.name != "milk")
        assert footprint(milk)[0] - 0.005 > milk_reaching.ARM_REACH_X + longest, (seed, footprint(milk))


GRASP_TRAY = (
    "g = get_graspable_point('tray')\nopen_gripper()\nmove_to_position([g[0], g[1], g[2] + 0.08])\n"
    "move_to_position([g[0], g[1], g[2] - 0.01])\nclose_gripper()\nmove_to_position([g[0], g[1], g[2] + 0.04])\n"
)


def _tray_task(size: tuple[float, float, float], yaw: float = 0.0, backstop: bool = True) -> Task:
    """The wide-tray layout with the tray's size and turn about z changed (and its backstop kept or not)."""
    data = _task("arm_tray_too_wide").model_dump(mode="json", exclude_defaults=True)
    data["objects"] = [o for o in data["objects"] if backstop or o["name"] != "backstop"]
    tray = next(o for o in data["objects"] if o["name"] == "tray")
    tray |= {"size": list(size), "rpy": [0.0, 0.0, yaw]}
    if not backstop:
        tray["center"] = [0.2, 0.0, size[2] / 2]
    data["name"] = "arm_tray_changed"
    return parse_task(data)


def test_a_tray_that_fits_between_the_fingers_is_held(run_texts: Any) -> None:
    """The control for the face-press cheat: against the same backstop, a tray narrower than the opening is held by
    an ordinary grasp at its graspable point, so the cheat's failure is the grasp, not the scene."""
    rollouts = run_texts(_tray_task((0.05, 0.04, 0.04)), [GRASP_TRAY] * 2, seed=11)
    assert all(r.success for r in rollouts), [world_failure(r) for r in rollouts]


def test_a_tray_a_millimetre_wider_than_the_opening_is_not_held(run_texts: Any) -> None:
    """Pressed on by the open fingers, a tray 1 mm wider than their opening wedged between them in one world (its
    soft stops gave); wider than the opening across the fingers is too wide, however it got there."""
    cheat = (CHEATS / "arm_press_fingers_on_face.py").read_text()
    for rollout in run_texts(_tray_task((0.05, 0.061, 0.04)), [cheat] * 3, seed=11):
        assert not rollout.success and rollout.error is None and world_failure(rollout), rollout


def test_a_stick_turned_across_the_fingers_is_held(run_texts: Any) -> None:
    """A long stick turned 45 degrees about z still fits between the fingers where they close on it, and is held:
    the face-press rule looks at what lies beside the fingers, not at the object's whole extent."""
    rollouts = run_texts(_tray_task((0.3, 0.02, 0.03), yaw=45.0, backstop=False), [GRASP_TRAY] * 2, seed=11)
    assert all(r.success for r in rollouts), [world_failure(r) for r in rollouts]


def test_a_sliver_grasp_of_the_milk_at_the_workspace_edge_holds_nothing(run_texts: Any) -> None:
    """The milk pulled only until its near face is 4 mm inside the workspace and pinched there: it was held and
    lifted in three worlds of five (perturbation seed 1); now every world says why nothing is held (the pinch,
    or the carton turned by the pull so the fingers met its face)."""
    cheat = (CHEATS / "arm_sliver_grasp_milk.py").read_text()
    causes = []
    for rollout in run_texts(_task("milk_reaching"), [cheat] * 5, seed=1):
        assert not rollout.success and rollout.error is None
        (failed,) = [e for e in rollout.events if e.kind == "grasp_failed"]
        assert failed.object == "milk" and failed.cause in ("weak_grip", "not_between"), failed
        causes.append(failed.cause)
        if failed.cause == "weak_grip":
            assert "a pinch at its edge" in world_failure(rollout)
    assert causes.count("weak_grip") >= 3, causes


def test_a_can_the_paper_slid_half_under_does_not_ride_it_after_a_nudge(run_texts: Any) -> None:
    """The paper slid under the can's +y half, stopping 2 mm short of its centre, then the can nudged 12 mm onto it
    with the stick: its centre came over the still paper, so it rode in and was grasped in three worlds of five.
    The sheet got under part of its base, not the other way round, so it does not rest on the paper: the drag
    leaves it where it was, out of reach, in every world."""
    cheat = (CHEATS / "arm_slide_paper_half_under_can_then_nudge.py").read_text()
    for rollout in run_texts(_task("can_grasping"), [cheat] * 5, seed=0):
        assert not rollout.success and rollout.error is None
        last = rollout.calls[-1]
        assert last.skill == "move_to_position" and last.measured.get("outside_workspace", 0.0) > 0.15, last
        assert "clamped" in world_failure(rollout) and "can" in world_failure(rollout)


LOOSE_CHAIN = (FIXTURES / "programs" / "button_pressing_loose_chain.py").read_text()


def test_two_cubes_pushed_loose_by_the_closed_fingers_press_the_built_in_button(run_texts: Any) -> None:
    """Honest tool use, not a cheat: two magnetic cubes lined up and joined, shoved unheld into the button by the
    closed fingers, reach 0.45 + 0.008 + 0.06 m, past the built-in face (0.50 m) by more than its 1 cm press."""
    rollouts = run_texts(_task("button_pressing"), [LOOSE_CHAIN] * 3, seed=11)
    assert all(r.success for r in rollouts), [world_failure(r) for r in rollouts]


@pytest.mark.parametrize("seed", [4, 10, 31, 196])
def test_two_cubes_pushed_loose_do_not_press_a_button_labelled_unsolvable(run_texts: Any, seed: int) -> None:
    """On instances the family labels unsolvable (faces 0.53-0.555 m, two magnetic cubes) the same program pushes
    the pair to the workspace edge and the button stays unpressed; the reason tells where the pair was left."""
    for rollout in run_texts(_task(f"button_pressing:{seed}"), [LOOSE_CHAIN] * 2, seed=11):
        assert (
            not rollout.success
            and rollout.error is None
            and rollout.conditions == {"button_pressed": False, "nothing_passed_through": True}
        )
        reason = world_failure(rollout)
        assert reason.startswith("goal not reached: button_pressed") and "magnetic_cube" in reason, reason


def test_a_vase_carried_down_from_a_shelf_and_let_go_just_above_the_floor_is_unbroken(run_texts: Any) -> None:
    """The control of the drops above (an adversarial run): a fall is measured from where the hand let go, so the
    vase carried from a 0.30 m shelf to 2 mm above the floor drops a few millimetres (it was read as a 0.30 m fall
    from the shelf, where it last rested on something other than the robot, and broke in every world)."""
    program = (PROGRAMS / "arm_carry_the_vase_down_from_a_shelf.py").read_text()
    rollouts: list[Rollout] = run_texts(_task("arm_vase_on_a_shelf"), [program] * 2, seed=11)
    assert all(r.success for r in rollouts), [world_failure(r) for r in rollouts]


def test_a_brittle_vase_tipped_over_onto_its_stool_breaks_where_its_top_lands(run_texts: Any) -> None:
    """The fingers ease the vase over the stool's edge and follow it down, so its centre never falls freely past its
    0.05 m max_drop (about 8 mm); but pushed at its top it first tips over onto the stool, its top coming down about
    0.1 m at 1.3 m/s, faster than a 0.05 m fall lands (0.99 m/s): it breaks there."""
    program = (PROGRAMS / "arm_ease_the_brittle_vase_down_along_the_fingers.py").read_text()
    rollouts: list[Rollout] = run_texts(_task("arm_brittle_vase_on_a_stool"), [program] * 2, seed=11)
    for rollout in rollouts:
        (broke,) = [e for e in rollout.events if e.kind == "broke"]
        assert broke.detail == "stool" and broke.measured["strike_speed"] > broke.measured["max_speed"], broke


def test_a_brittle_vase_set_down_in_the_grip_is_unbroken(run_texts: Any) -> None:
    """The control: held at its graspable point, carried off the stool and let go at the floor, the vase is whole."""
    program = (
        'g = get_graspable_point("vase")\nopen_gripper()\nmove_to_position([g[0], g[1], g[2] + 0.05])\n'
        "move_to_position(g)\nclose_gripper()\nmove_to_position([g[0] - 0.15, g[1], g[2]])\n"
        "move_to_position([g[0] - 0.15, g[1], g[2] - 0.125])\nopen_gripper()\n"
        "move_to_position([g[0] - 0.15, g[1], g[2] + 0.05])\n"
    )
    rollouts: list[Rollout] = run_texts(_task("arm_brittle_vase_on_a_stool"), [program] * 2, seed=11)
    assert all(r.success for r in rollouts), [world_failure(r) for r in rollouts]


FLING = "arm_button_beyond_a_table_behind_a_wall"
FLING_CODE = (CHEATS / "arm_fling_a_puck_up_a_wall_into_a_cube.py").read_text()
FARTHEST_PUSH = (  # the puck held by its back end, 8 mm in, pushes the cube at the move speed to the workspace edge
    "p = get_center('puck')\ng = [p[0] - 0.03 + 0.008, p[1], 0.02]\nopen_gripper()\n"
    "move_to_position([g[0], g[1], 0.08])\nmove_to_position(g)\nclose_gripper()\nmove_to_position([g[0], g[1], 0.24])\n"
    "move_to_position([0.30, 0.0, 0.24])\nmove_to_position([0.45, 0.0, 0.235])\nmove_to_position([0.45, 0.0, 0.235])\n"
)
FLING_WORLDS = 2  # the fling runs in worlds 0 and 1; then the farthest push, then the fling aimed below the wall's top


@pytest.fixture(scope="module")
def fling_runs(run_texts: Any) -> tuple[sim.Scene, StateRecorder, list[Rollout]]:
    """The fling, its control and its stalled variant in one batch (seed 11), the fling's worlds recorded."""
    scene = sim.build(_task(FLING))
    recorder = StateRecorder(range(FLING_WORLDS))
    below_the_top = FLING_CODE.replace("0.235]", "0.15]")
    assert below_the_top != FLING_CODE
    codes = [FLING_CODE] * FLING_WORLDS + [FARTHEST_PUSH, below_the_top]
    return scene, recorder, run_texts(scene, codes, seed=11, recorder=recorder)


def _gripper_path(scene: sim.Scene, recorder: StateRecorder, world: int) -> np.ndarray:
    """The gripper centre of ``world`` at each control tick (T, 3)."""
    _, qpos, _ = recorder.tracks[world].arrays()
    adr = int(scene.model.jnt_qposadr[scene.model.joint("robot_x").id])
    return qpos[:, adr : adr + 3]


def test_a_puck_slid_up_a_wall_is_not_flung_over_it_faster_than_the_move_speed(fling_runs: Any) -> None:
    """Found by an adversarial run (every world of seeds 0, 1 and 11 pressed the button): the puck held low slid up
    the wall's face while the x reference ran on at the move speed (the gripper kept rising, so the move did not
    stall); over the top, the x servo's 0.2 m of pent-up error flung the gripper at 3.9 m/s and the puck threw the cube
    into the button. A move's reference now follows its line at the move speed at most and stays within ``max_lead``
    of the gripper: over the top the gripper lurches that far at most, then goes on at the move speed, in every tick
    and on average over every half second."""
    scene, recorder, rollouts = fling_runs
    tick, half_second = scene.control_dt, round(0.5 / scene.control_dt)
    for w, rollout in enumerate(rollouts[:FLING_WORLDS]):
        reason = world_failure(rollout) or ""
        assert not rollout.success and rollout.error is None, reason
        assert reason.startswith("goal not reached: button_pressed"), reason
        assert [c.skill for c in rollout.calls].count("move_to_position") == 5, rollout.calls  # it ran to its end
        travel = np.linalg.norm(np.diff(_gripper_path(scene, recorder, w), axis=0), axis=1)
        assert travel.max() <= ARM.max_lead + 1.2 * ARM.speed * tick, travel.max() / tick  # 0.9 m/s; 1.5-1.8 before
        path = np.concatenate([[0.0], np.cumsum(travel)])
        windows = path[half_second:] - path[:-half_second]
        assert windows.max() <= ARM.max_lead + 1.1 * ARM.speed * 0.5, windows.max() / 0.5  # 0.4 m/s; 0.65 before


def test_the_farthest_honest_push_leaves_the_cube_short_of_the_button(fling_runs: Any) -> None:
    """The control of the fling: the puck held by its back end pushes the cube over the table to the workspace edge at
    the move speed, and the cube stops short of the button's face: only a throw pressed it."""
    rollout = fling_runs[2][FLING_WORLDS]
    assert rollout.error is None and rollout.conditions == {"button_pressed": False, "nothing_passed_through": True}, (
        world_failure(rollout)
    )
    assert all(c.outcome == "done" for c in rollout.calls), [(c.skill, c.outcome, c.reason) for c in rollout.calls]


def test_a_move_held_back_by_the_wall_while_it_rises_still_stalls(fling_runs: Any) -> None:
    """The fling's move aimed below the wall's top: the puck slides up the face until the gripper reaches the target's
    height, held back in x all the while, and the move ends stalled there, 0.29 m short, as before the fix."""
    move = fling_runs[2][FLING_WORLDS + 1].calls[-2]
    assert move.outcome == "stalled" and move.reason.startswith("blocked at [0.160"), move
    assert move.measured["remaining"] == pytest.approx(0.29, abs=0.005)


@pytest.mark.parametrize(
    ("task", "mass", "program"),
    [
        # a 0.5 kg box where the 60 kg crate stood (about 4 N of friction on the paper's two faces, under the 10 N that
        # pins it): the pull brings the can within reach
        ("arm_can_on_paper_pinned_by_a_heavy_crate", 0.5, "arm_drag_paper_from_under_a_heavy_crate"),
        # an 8 kg crate (about 50 N) pins it, but the arm pulls harder: it slides out a tick at a time, and is lifted
        ("arm_paper_pinned_under_a_heavy_crate", 8.0, "arm_drag_pinned_paper_out_and_lift"),
    ],
)
def test_paper_under_a_lighter_load_is_pulled_out(run_texts: Any, task: str, mass: float, program: str) -> None:
    """The controls of the pinned paper: the same pulls with a lighter load where the 60 kg crate stood succeed."""
    heavy = _task(task)
    lighter = heavy.model_copy(
        update={"objects": [o.model_copy(update={"mass": mass}) if o.name == "crate" else o for o in heavy.objects]}
    )
    rollouts: list[Rollout] = run_texts(lighter, [(CHEATS / f"{program}.py").read_text()] * 2, seed=11)
    assert all(r.success for r in rollouts), [world_failure(r) for r in rollouts]


def test_a_bottle_set_down_on_a_gentle_slope_is_not_read_while_it_starts_to_roll(run_texts: Any) -> None:
    """Found by an adversarial run: a bottle set down across a shelf sloping 2.3 degrees rolled at about 0.01 m/s when
    the goal was read (1 s after the end; read as still under 0.02 m/s) and rolled off 4.5 s later. A world whose
    objects speed up is not still: it runs on, and the bottle never comes to rest on the shelf."""
    task = _task("arm_bottle_beside_a_gently_sloping_shelf")
    program = (CHEATS / "arm_set_a_bottle_on_a_gently_sloping_shelf.py").read_text()
    rollouts: list[Rollout] = run_texts(task, [program] * 2)
    for rollout in rollouts:
        assert not rollout.success
        assert "did not come to rest: bottle still moved" in str(rollout.error), rollout.error


LIGHT_LEVER = "arm_light_anvil_on_a_short_lever_under_a_button"
LIGHT_PRESS = (CHEATS / "arm_press_a_light_anvil_up_on_a_short_lever.py").read_text()


@pytest.mark.xfail(
    strict=True,
    reason="open: a scene whose movable objects are light is not weighed; weighing it everywhere over-counts presses "
    "into supports and end stops (an eased-off vase, a puck slid up a wall), and the fix tried opened a wedge's press",
)
def test_a_lever_pressed_past_the_rating_in_a_light_scene_is_over_the_payload(run_texts: Any) -> None:
    """Found by an adversarial run: a beam pressed 2:1 against the arm with 58-100 N raises a 2.8 kg anvil into a
    button in every world, as a scene whose movable objects could not weigh more than the payload (3.1 kg here) is
    not weighed at all; a lever multiplies the push."""
    for rollout in run_texts(_task(LIGHT_LEVER), [LIGHT_PRESS] * 2, seed=11):
        assert not rollout.success and rollout.error is None, [(c.skill, c.outcome, c.reason) for c in rollout.calls]
        assert rollout.conditions.get(PAYLOAD_CONDITION) is False, rollout.conditions
        failure = world_failure(rollout) or ""
        assert re.search(r"cannot press beam: \d+ N on it with anvil touching it, over the 39 N the arm.s", failure)


def test_a_light_lever_pressed_within_the_rating_raises_the_anvil(run_texts: Any) -> None:
    """The control: a 0.8 kg anvil on the same lever (about 19 N on the beam), pressed only as far as that takes (the
    servo's lead under 39 N, the rest of the press into the button's end stop), presses the button."""
    data = _task(LIGHT_LEVER).model_dump(mode="json", exclude_defaults=True)
    next(o for o in data["objects"] if o["name"] == "anvil")["mass"] = 0.8
    code = LIGHT_PRESS.replace("[0.19, 0.0, 0.0]", "[0.19, 0.0, 0.065]")
    assert code != LIGHT_PRESS
    for rollout in run_texts(parse_task(data), [code] * 2, seed=11):
        assert rollout.success, world_failure(rollout)
        assert PAYLOAD_CONDITION not in rollout.conditions, rollout.conditions  # nothing broke it in a light scene


GRIPPY_SLAB = "arm_grippy_slab_on_a_rubber_stool"
SLAB_SHOVE = (CHEATS / "arm_shove_a_grippy_slab_off_a_stool.py").read_text()


@pytest.mark.xfail(
    strict=True,
    reason="open: a scene whose movable objects are light is not weighed (the lever case above); weighing every scene "
    "refuses honest presses into end stops (a slat held into a stiff button's stop, 92 N) and a puck held up a wall",
)
def test_a_slab_shoved_off_a_stool_past_the_rating_in_a_light_scene_is_over_the_payload(run_texts: Any) -> None:
    """Found by an adversarial run: the bare gripper shoves a 3 kg rubber slab off a rubber stool (88 N to slide it,
    44 N to tip it) in every world on two seeds; no lever, a straight push against friction, so a fix aimed at levers
    would not close it."""
    for rollout in run_texts(_task(GRIPPY_SLAB), [SLAB_SHOVE] * 2, seed=11):
        assert not rollout.success and rollout.conditions.get(PAYLOAD_CONDITION) is False, rollout.conditions


def test_the_same_slab_shove_is_refused_once_the_scene_is_weighed(run_texts: Any) -> None:
    """The control: a 1.5 kg weight far off makes the scene heavy enough to be weighed, and the same shove is refused
    naming the push (75-100 N), which is the force the light scene lets through."""
    data = _task(GRIPPY_SLAB).model_dump(mode="json", exclude_defaults=True)
    weight = {"name": "weight", "shape": "box", "center": [0.0, 0.35, 0.03], "size": [0.06] * 3, "mass": 1.5}
    data["objects"].append(weight)
    for rollout in run_texts(parse_task(data), [SLAB_SHOVE] * 2, seed=11):
        assert not rollout.success and rollout.conditions.get(PAYLOAD_CONDITION) is False, rollout.conditions
        assert re.search(r"cannot push slab: \d+ N on it.*over the 39 N the arm.s", world_failure(rollout) or "")
