"""Held-out checks of the arm's contact physics: grasps by the fingers, rigid holds, a button that needs a
press, and failure reasons that tell what happened (C backend)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from fixtures.paths import FIXTURES
from fixtures.reference import REFERENCE, program

from robotool import sim, tasks
from robotool.eval.failure_classes import TaskFacts, classify, tools_used
from robotool.robots.arm.arm_controller import ArmController
from robotool.task.task_file import parse_task
from robotool.verify import world_failure

CLEAR = 0.08  # m above a grasp point to approach from


def _grasp_at(offset: tuple[float, float, float], name: str):
    """A trusted program that closes the gripper at ``offset`` from ``name``'s graspable point."""

    def grasp(robot: Any) -> None:
        p = [v + d for v, d in zip(robot.get_graspable_point(name), offset, strict=True)]
        robot.open_gripper()
        robot.move_to_position([p[0], p[1], p[2] + CLEAR])
        robot.move_to_position(p)
        robot.close_gripper()
        robot.move_to_position([p[0], p[1], p[2] + 0.05])

    return grasp


def _grasp_events(rollout: Any) -> list[Any]:
    return [e for e in rollout.events if e.kind in ("grasped", "grasp_failed")]


def test_closing_beside_the_graspable_point_holds_nothing(sim_scene: Any) -> None:
    """1.5 cm off across the fingers, one finger lands on the carton's top: nothing is held, and the call says why."""
    scene = sim_scene("milk_reaching_near")
    beside, centred = sim.run_programs(
        scene, [_grasp_at((0.0, 0.015, 0.0), "milk"), _grasp_at((0.0, 0.0, 0.0), "milk")], seed=1
    )
    assert not beside.success and not beside.conditions["milk_held"]
    (failed,) = _grasp_events(beside)
    assert failed.kind == "grasp_failed" and failed.object == "milk" and failed.cause in ("on_top", "one_finger")
    close = beside.calls[failed.call]
    assert close.skill == "close_gripper" and "held nothing" in close.reason
    assert "held nothing" in world_failure(beside)
    assert centred.success and [e.kind for e in _grasp_events(centred)] == ["grasped"]


def test_a_carton_wider_than_the_opening_is_not_held() -> None:
    """The carton lying on its side, its 0.16 m length across the fingers: they rest on it and hold nothing."""
    data = tasks.load("milk_reaching_near").model_dump(mode="json", exclude_defaults=True)
    milk = next(o for o in data["objects"] if o["name"] == "milk")
    x, y = 0.40, 0.15  # clear of the lock
    milk |= {"center": [x, y, 0.022], "rpy": [90.0, 0.0, 0.0], "graspable_point": [x, y, 0.044]}
    task = parse_task(data)
    (r,) = sim.run_programs(task, [_grasp_at((0.0, 0.0, 0.0), "milk")], perturb=False)
    assert not r.success
    (failed,) = _grasp_events(r)
    assert failed.cause == "too_wide" and failed.measured["width"] == pytest.approx(0.16, abs=0.005)
    assert failed.measured["width"] > failed.measured["opening"]
    assert "wider than" in r.calls[failed.call].reason


def _chain(robot: Any) -> float:
    """Grasp magnetic_cube1 and touch the other two cubes end to end along +x; returns the chain's height."""
    g = robot.get_graspable_point("magnetic_cube1")
    robot.open_gripper()
    robot.move_to_position([g[0], g[1], g[2] + CLEAR])
    robot.move_to_position(g)
    robot.close_gripper()
    z = g[2] + 0.004
    robot.move_to_position([g[0], g[1], z])
    edge = robot.get_size("magnetic_cube1")[0]
    for k, name in enumerate(("magnetic_cube2", "magnetic_cube3"), start=1):
        c = robot.get_center(name)
        robot.move_to_position([c[0] - k * edge - 0.05, c[1], z])
        robot.move_to_position([c[0] - k * edge + 0.004, c[1], z])
    return z


def _chain_heading(robot: Any) -> float:
    a, b = robot.get_center("magnetic_cube1"), robot.get_center("magnetic_cube3")
    return math.degrees(math.atan2(b[1] - a[1], b[0] - a[0]))


def test_magnetic_chain_pushed_sideways_against_the_button_stays_straight(sim_scene: Any) -> None:
    """The held chain shoved sideways into the button face by the servo bends by less than 2 degrees."""
    headings: list[float] = []

    def shove(robot: Any) -> None:
        _chain(robot)
        headings.append(_chain_heading(robot))
        b, size = robot.get_center("button"), robot.get_size("button")
        side = b[1] + 0.4 * size[1] + 0.015  # the chain's -y side at the face's +y side
        robot.move_to_position([0.45, 0.0, b[2] + 0.05])
        robot.move_to_position([0.45, 0.0, b[2]])
        for push in (0.0, 0.005, 0.01, 0.015, 0.019):  # into the face, up to just short of a stall
            robot.move_to_position([0.45, side - push, b[2]])
            headings.append(_chain_heading(robot))

    (r,) = sim.run_programs(sim_scene("button_pressing"), [shove], perturb=False)
    assert r.error is None and len(headings) == 6
    loaded = [c for c in r.calls if c.skill == "move_to_position" and c.outcome != "done"]
    assert loaded, "the chain never met the button"
    bend = max(abs(h - headings[0]) for h in headings[1:])
    assert bend < 2.0, headings


def test_a_held_cube_does_not_twist_when_it_pushes(sim_scene: Any) -> None:
    """A 50 g cube held off-centre pushes another cube along the table: it stays square to the gripper."""
    headings: list[float] = []

    def push(robot: Any) -> None:
        g = robot.get_graspable_point("magnetic_cube1")
        robot.open_gripper()
        robot.move_to_position([g[0], g[1] + 0.005, g[2] + CLEAR])
        robot.move_to_position([g[0], g[1] + 0.005, g[2]])
        robot.close_gripper()
        c = robot.get_center("magnetic_cube2")
        robot.move_to_position([g[0], g[1], g[2] + 0.004])
        robot.move_to_position([c[0] - 0.1, c[1] + 0.012, g[2] + 0.004])
        for _ in range(3):
            robot.move_to_position([c[0] - 0.04, c[1] + 0.012, g[2] + 0.004])
            a, b = robot.get_center("magnetic_cube1"), robot.get_center("magnetic_cube2")
            headings.append(math.degrees(math.atan2(b[1] - a[1], b[0] - a[0])))

    (r,) = sim.run_programs(sim_scene("button_pressing"), [push], perturb=False)
    assert r.error is None and headings
    assert max(headings) - min(headings) < 2.0, headings


def test_button_needs_a_few_newtons(sim_scene: Any) -> None:
    """The face's spring takes newtons to press: its stiffness and travel are task data with defaults."""
    scene = sim_scene("button_pressing")
    button = scene.task.object("button")
    model = scene.model
    joint = model.joint("button__travel")
    assert model.jnt_stiffness[joint.id] == pytest.approx(button.button_stiffness)
    assert 2.0 <= button.button_stiffness * 0.01 <= 10.0  # N needed to press it 1 cm
    assert model.jnt_range[joint.id][1] == pytest.approx(button.button_travel)
    data = scene.task.model_dump(mode="json", exclude_defaults=True)
    next(o for o in data["objects"] if o["name"] == "button").update(stiffness=500.0, travel=0.015)
    stiff = sim.build(parse_task(data)).model
    assert stiff.jnt_stiffness[joint.id] == pytest.approx(500.0) and stiff.jnt_range[joint.id][1] == 0.015


def test_paper_dragged_edge_first_into_the_can_does_not_bring_it_in(sim_scene: Any) -> None:
    """Without the stick, dragging the paper sideways into the can and then in does not bring the can in reach."""

    def drag(robot: Any) -> None:
        p, size = robot.get_graspable_point("strip_of_paper"), robot.get_size("strip_of_paper")
        can, can_size = robot.get_center("can"), robot.get_size("can")
        robot.open_gripper()
        robot.move_to_position([p[0], p[1], p[2] + CLEAR])
        robot.move_to_position(p)
        robot.close_gripper()
        y = can[1] - can_size[1] / 2 - 0.02 + size[1] / 2  # the paper's near edge driven 2 cm past the can
        robot.move_to_position([p[0], y, p[2] + 0.001])
        robot.move_to_position([p[0] - (can[0] - 0.35), y, p[2] + 0.001])
        robot.open_gripper()
        c = robot.get_graspable_point("can")
        robot.move_to_position([c[0], c[1], c[2] + CLEAR])
        robot.move_to_position(c)
        robot.close_gripper()

    rollouts = sim.run_programs(sim_scene("can_grasping"), [drag] * 3, seed=2)
    for r in rollouts:
        assert r.error is None and not r.success, r.conditions
        assert any(e.kind == "clamped" for e in r.events)  # the can stayed beyond the workspace


def test_can_pushed_onto_the_paper_rides_on_it(sim_scene: Any, run_texts: Any) -> None:
    """The paper's intended use: the can pushed onto it with the stick comes along when the paper is pulled."""
    (r,) = run_texts(sim_scene("can_grasping"), [program("can_grasping")], perturb=False)
    assert r.success, world_failure(r)


def test_papers_button_program_succeeds(sim_scene: Any, run_texts: Any) -> None:
    """The paper's generated program: grasp cube 1, carry it to cube 2's centre, cube 3's centre, the button's."""
    rollouts = run_texts(sim_scene("button_pressing"), [program("button_pressing_paper")] * 3, seed=0)
    assert any(r.success for r in rollouts), [world_failure(r) for r in rollouts]


def test_papers_hammer_program_fails_and_says_why(sim_scene: Any, run_texts: Any) -> None:
    """The paper's failed milk program: the carry is clamped, the swept hammer shoves the milk away, no grasp."""
    rollouts = run_texts(sim_scene("milk_reaching"), [program("milk_reaching_paper")] * 3, seed=0)
    for r in rollouts:
        assert not r.success and r.error is None
        kinds = {e.kind for e in r.events}
        assert {"clamped", "pushed_out", "grasp_failed"} <= kinds
        assert any(e.kind == "pushed_out" and e.object == "milk" for e in r.events)
        reason = world_failure(r)
        assert reason.startswith("goal not reached: milk_held")
        assert "clamped" in reason and "milk was pushed" in reason and "held nothing" in reason
        facts = TaskFacts.of(sim_scene("milk_reaching").task, needs_tool=True, needed=frozenset({"hammer"}))
        assert tools_used(r, facts) == {"hammer"} and classify(r, facts) == "numerical"  # from typed events


def test_a_lifted_sheet_carries_nothing(sim_scene: Any) -> None:
    """Held up by its edge, paper droops: a can resting on it is not carried up into the air."""
    data = sim_scene("can_grasping").task.model_dump(mode="json", exclude_defaults=True)
    can = next(o for o in data["objects"] if o["name"] == "can")
    can["center"] = [0.4, 0.2, 0.0405]  # standing on the paper, within reach
    heights: list[float] = []

    def lift(robot: Any) -> None:
        p = robot.get_graspable_point("strip_of_paper")
        robot.open_gripper()
        robot.move_to_position([p[0], p[1], p[2] + CLEAR])
        robot.move_to_position(p)
        robot.close_gripper()
        robot.move_to_position([p[0], p[1], 0.15])
        heights.append(robot.get_center("can")[2])

    (r,) = sim.run_programs(parse_task(data), [lift], perturb=False)
    assert r.error is None and heights and heights[0] < 0.06, heights


def test_button_fields_are_checked() -> None:
    data = tasks.load("button_pressing").model_dump(mode="json", exclude_defaults=True)
    for obj, field, value, words in (
        ("button", "travel", 0.005, "exceed"),
        ("magnetic_cube1", "stiffness", 100.0, "buttons only"),
    ):
        bad = {**data, "objects": [o | {field: value} if o["name"] == obj else o for o in data["objects"]]}
        with pytest.raises(ValueError, match=words):
            parse_task(bad)


@pytest.mark.parametrize(("depth", "held"), [(0.004, False), (0.007, False), (0.010, True), (0.016, True)])
def test_a_grip_holds_only_as_deep_as_it_engages_the_object(sim_scene: Any, depth: float, held: bool) -> None:
    """Closed ``depth`` into a cube's -x side (the pads are 16 mm wide): a pinch of its last few millimetres, less
    than half of what the pads could cover, holds nothing and says what it measured; deeper, the cube is held."""
    offset = -(0.015 + 0.008 - depth)  # gripper centre from the cube's centre: the pads' +x edge ``depth`` into it
    (r,) = sim.run_programs(sim_scene("button_pressing"), [_grasp_at((offset, 0.0, 0.0), "magnetic_cube1")], seed=2)
    (event,) = _grasp_events(r)
    assert (event.kind == "grasped") == held, event
    if not held:
        assert event.cause == "weak_grip" and event.object == "magnetic_cube1"
        assert f"grip {1000 * event.measured['depth']:.0f} mm deep on magnetic_cube1" in world_failure(r)
        assert "a pinch at its edge; needs 8 mm" in world_failure(r)
        assert abs(event.measured["depth"] - depth) < 0.002


HEAVY_JOIN = {
    "format": 1,
    "name": "arm_heavy_join",
    "category": "tool_manufacturing",
    "instruction": "Grasp the cube.",
    "robot": {"type": "arm"},
    "objects": [
        {
            "name": "cube",
            "shape": "box",
            "center": [0.2, 0.0, 0.015],
            "size": [0.03, 0.03, 0.03],
            "mass": 0.05,
            "magnetic": True,
        },
        {
            "name": "anvil",
            "shape": "box",
            "center": [0.3, 0.0, 0.03],
            "size": [0.1, 0.1, 0.06],
            "mass": 3.0,
            "magnetic": True,
        },
    ],
    "goal": {"grasped": "cube"},
}


def test_a_grip_lets_go_when_more_is_joined_to_it_than_it_can_carry() -> None:
    """A cube held by a full grip is touched to a 3 kg magnetic block, which joins it: the grip's friction couple
    (grip_force across the 16 mm pads) cannot carry the block's torque about the pads, so the gripper lets go and
    the move says so with what it measured; the same grip carries the cube alone."""

    def join(robot: Any) -> None:
        p = robot.get_graspable_point("cube")
        robot.open_gripper()
        robot.move_to_position([p[0], p[1], p[2] + CLEAR])
        robot.move_to_position(p)
        robot.close_gripper()
        robot.move_to_position([p[0], p[1], p[2] + 0.004])
        robot.move_to_position([p[0] + 0.052, p[1], p[2] + 0.004])
        robot.move_to_position([p[0] + 0.052, p[1], p[2] + 0.05])

    (r,) = sim.run_programs(parse_task(HEAVY_JOIN), [join], perturb=False)
    assert [e.kind for e in _grasp_events(r)] == ["grasped", "grasp_failed"], r.events
    slip = _grasp_events(r)[1]
    assert slip.cause == "weak_grip" and slip.measured["joined"] == 1 and slip.measured["weight"] > 29
    assert not r.success and "needs" in world_failure(r) and "cube and 1 joined to it" in world_failure(r)


def test_goal_memory_skips_states_in_which_the_grip_is_past_its_friction(
    sim_scene: Any, run_texts: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A press seen only in states where a held tool pushes harder than the pads' friction holds did not happen (a real
    grip slides first): the reference program's press, with every state marked so, does not count, and counts when
    the arm reads the states itself (the held cube pushes the button with a few newtons)."""
    scene, code = sim_scene("button_pressing"), program(REFERENCE["button_pressing"])
    (honest,) = run_texts(scene, [code], seed=1)
    assert honest.success
    monkeypatch.setattr(ArmController, "overloaded", lambda self, state: np.ones(len(state.time), dtype=bool))
    (skipped,) = run_texts(scene, [code], seed=1)
    assert not skipped.success and skipped.conditions["button_pressed"] is False


@pytest.mark.parametrize(("friction", "held"), [(0.05, False), (0.3, True), (None, True)])
def test_the_pads_grip_a_slippery_object_by_its_own_friction(friction: float | None, held: bool) -> None:
    """Found by an adversarial run: a bar declared greased (friction 0.001) was held by the 120 N pad grip as if it
    were rubber (MuJoCo takes the larger of two surfaces' frictions, and the grip rule read the pads' alone). The
    pads grip an object of the default friction (0.5) or more at their own friction, a more slippery one at its own:
    a 3 kg block at 0.05 weighs 29 N against 6 N of grip, and slips; at 0.3 it is held (36 N)."""
    data = tasks.load(FIXTURES / "layouts" / "arm_six_kg_iron_block.yaml").model_dump(
        mode="json", exclude_defaults=True
    )
    block = data["objects"][0] | {"mass": 3.0} | ({} if friction is None else {"friction": friction})
    task = parse_task(data | {"objects": [block]})
    (r,) = sim.run_programs(task, [_grasp_at((0.0, 0.0, 0.0), "iron_block")], perturb=False)
    events = _grasp_events(r)
    assert [e.kind for e in events] == (["grasped"] if held else ["grasp_failed"]), events
    if not held:
        assert events[0].cause == "weak_grip" and events[0].measured["most_weight"] < events[0].measured["weight"]
