"""The quadruped in C MuJoCo: reference (and the paper's) programs, refusals from rays, the lever, cloth, the vase."""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import pytest
from fixtures.reference import REFERENCE, program

from robotool import sim, tasks
from robotool.rollout import Rollout
from robotool.sandbox import start_sessions
from robotool.sim.backend import Perturbation
from robotool.task.task_file import parse_task
from robotool.tasks.families import generate
from robotool.verify import world_failure


def run(task: Any, name: str, nworld: int, seed: int = 0) -> list[Rollout]:
    """``nworld`` perturbed worlds of reference program ``name``, sandboxed, on the C backend."""
    return sim.run_sessions(task, start_sessions([program(name)] * nworld, "quadruped"), seed=seed)


def motion_calls(rollout: Rollout) -> list[Any]:
    return [c for c in rollout.calls if not c.skill.startswith("get_")]


QUADRUPED_TASKS = [t for t in REFERENCE if tasks.load(t).robot.type == "quadruped"]


@pytest.mark.slow  # ten worlds of a whole reference program: up to 8 s
@pytest.mark.parametrize(
    ("task", "name", "seed"),
    [(task, REFERENCE[task], 0) for task in QUADRUPED_TASKS]  # (the Warp tests run them at seed 5)
    + [("sofa_traversing", "paper_sofa_traversing", 3), ("sofa_climbing", "paper_sofa_climbing", 3)],
)
def test_reference_program_solves_nine_of_ten_perturbed_worlds(sim_scene: Any, task: str, name: str, seed: int) -> None:
    rollouts = run(sim_scene(task), name, 10, seed=seed)
    assert sum(r.success for r in rollouts) >= 9, [motion_calls(r) for r in rollouts if not r.success]


@pytest.mark.parametrize(
    ("task", "name", "skill", "key", "value"),
    [
        # the surfboard overhangs the gap by 0.10 m: walking straight over it meets the 0.30 m left beyond its end
        ("sofa_traversing", "sofa_traversing_direct", "walk_to_position", "gap", 0.30),
        ("sofa_climbing", "sofa_climbing_direct", "climb_to_position", "step", 0.34),
        ("cube_lifting", "cube_lifting_direct", "push_to_position", "mass", None),
    ],
)
def test_tool_free_program_is_refused_with_the_measured_value(
    sim_scene: Any, task: str, name: str, skill: str, key: str, value: float | None
) -> None:
    scene = sim_scene(task)
    scales = Perturbation.sample(scene, 2, 0).mass_scale  # the cube's mass is the world's, perturbed
    masses = scales[:, scene.object_index("cube")] * 10.0 if value is None else [value] * 2
    for rollout, mass in zip(run(scene, name, 2), masses, strict=True):
        assert not rollout.success
        refused = [c for c in rollout.calls if c.outcome == "refused"]
        assert [c.skill for c in refused] == [skill]
        assert refused[0].measured[key] == pytest.approx(mass, abs=0.02)
        assert "exceeds the" in refused[0].reason and f"{refused[0].measured[key]:.1f}" in refused[0].reason


@pytest.mark.parametrize(
    ("task", "name"),
    [
        ("sofa_traversing_small_gap", "sofa_traversing_direct"),
        ("sofa_climbing_low_sofa", "sofa_climbing_direct"),
    ],
)
def test_variants_are_solved_by_walking_directly(sim_scene: Any, task: str, name: str) -> None:
    rollouts = run(sim_scene(task), name, 2)
    assert all(r.success for r in rollouts), [motion_calls(r) for r in rollouts]


def test_the_cloth_is_no_bridge(sim_scene: Any) -> None:
    for rollout in run(sim_scene("sofa_traversing"), "sofa_traversing_cloth", 2):
        assert not rollout.success
        assert motion_calls(rollout)[-1].outcome == "refused"


def test_cloth_across_the_gap_sags_and_walking_onto_it_is_refused() -> None:
    data = tasks.load("sofa_traversing").model_dump(mode="json", exclude_defaults=True)
    data["objects"] = [o for o in data["objects"] if o["name"] != "surfboard"]
    cloth = next(o for o in data["objects"] if o["name"] == "strip_of_cloth")
    cloth["center"] = [0.95, 0.0, 0.342]  # spans the 0.40 m gap, 0.35 m on each sofa
    for rollout in run(parse_task(data), "sofa_traversing_direct", 2):
        (walk,) = motion_calls(rollout)
        assert walk.outcome in ("refused", "fell") and not rollout.success  # the cloth gives way under the feet


@pytest.mark.parametrize(
    ("name", "lifted"),
    [
        ("cube_lifting_chair_only", False),  # (b) the chair alone does nothing
        ("cube_lifting_lever_only", False),  # (c) the chair props the lever
    ],
)
def test_lever_needs_both_the_chair_away_and_the_robot_on_it(sim_scene: Any, name: str, lifted: bool) -> None:
    for rollout in run(sim_scene("cube_lifting"), name, 2):
        assert all(c.outcome == "done" for c in motion_calls(rollout)), motion_calls(rollout)
        assert rollout.conditions == {
            "cube_lifted": lifted,
            "robot_has_not_fallen": True,
            "robot_shoved_nothing": True,
            "nothing_passed_through": True,
        }


def test_a_light_robot_does_not_tip_the_lever() -> None:
    """A 1 kg robot that walks onto the lever's raised end leaves the cube down, every motion done, where a robot of
    the usual weight lifts it. The chair that props the lever is left out, so that only the robot's weight decides: a
    1 kg robot's feet cannot hold a push of the 3 kg chair (the grip rule refuses it)."""
    data = tasks.load("cube_lifting").model_dump(mode="json", exclude_defaults=True)
    data["objects"] = [o for o in data["objects"] if o["name"] != "chair"]
    for rollout in run(parse_task(data), "cube_lifting_lever_only", 2):  # the control: the usual weight tips it
        assert rollout.conditions["cube_lifted"], motion_calls(rollout)
    data["robot"]["limits"] = {"mass": 1.0}
    for rollout in run(parse_task(data), "cube_lifting_lever_only", 2):
        assert all(c.outcome == "done" for c in motion_calls(rollout)), motion_calls(rollout)
        assert rollout.conditions == {
            "cube_lifted": False,
            "robot_has_not_fallen": True,
            "robot_shoved_nothing": True,
            "nothing_passed_through": True,
        }


@pytest.mark.parametrize(
    ("name", "unbroken"),
    [
        ("vase_lowering", True),
        ("vase_lowering_no_cushion", False),
    ],
)
def test_the_vase_survives_only_a_fall_onto_the_cushion(sim_scene: Any, name: str, unbroken: bool) -> None:
    for rollout in run(sim_scene("vase_lowering"), name, 2):
        assert rollout.conditions == {
            "glass_vase_lowered": True,
            "glass_vase_unbroken": unbroken,
            "robot_has_not_fallen": True,
            "robot_shoved_nothing": True,
            "robot_stood_on_nothing_fragile": True,
            "nothing_passed_through": True,
        }
        assert rollout.success is unbroken
        broke = [e for e in rollout.events if e.kind == "broke"]
        assert len(broke) == (0 if unbroken else 1)
        if not unbroken:  # the failure reason gives the measured fall and what the vase landed on
            assert broke[0].object == "glass_vase" and broke[0].measured["fall"] > broke[0].measured["max_drop"]
            assert 0 < broke[0].time <= rollout.sim_time
            assert re.search(
                r"glass_vase broke: it fell \d\.\d\d m onto the ground \(a fall of more than",
                world_failure(rollout) or "",
            )


def test_queries_answer_from_the_current_state(sim_scene: Any) -> None:
    answers: list[Any] = []

    def probe(robot: Any) -> None:
        answers.extend([robot.get_size("robot"), robot.get_position("robot"), robot.get_position("box_1")])
        robot.walk_to_position([0.3, 0.0, 0.0])
        answers.append(robot.get_position("robot"))
        robot.get_position("no_such_thing")

    (rollout,) = sim.run_programs(sim_scene("sofa_climbing"), [probe], perturb=False)
    size, start, box, end = answers
    assert size == [0.65, 0.30, 0.30]
    assert start == pytest.approx([0.0, 0.0, 0.14], abs=0.015) and box == pytest.approx([1.0, 0.0, 0.06], abs=0.01)
    assert end == pytest.approx([0.3, 0.0, 0.14], abs=0.02)
    assert rollout.calls[-1].outcome == "error" and "no object named" in rollout.calls[-1].reason


def test_a_step_shorter_than_the_feet_span_is_crossed_without_catching_the_legs(run_texts: Any) -> None:
    """box_2 (0.4 m long) is shorter than the feet's span (0.59 m): when the front feet step down past it onto
    the sofa the rear feet are still over the lower box_1, and the legs keep the torso above box_2 (regression:
    it dropped onto box_2 with its torso and stalled with its rear legs against box_2's side)."""
    data = tasks.load("sofa_climbing").model_dump(mode="json", exclude_defaults=True)
    objects = {o["name"]: o for o in data["objects"]}
    objects["box_2"]["center"] = [1.4, 0.0, 0.12]  # against box_1, in line
    objects["sofa"].update(center=[2.05, 0.0, 0.042], size=[0.9, 1.5, 0.084])  # against box_2, lower than it
    for rollout in run_texts(parse_task(data), ["climb_to_position([2.05, 0.0, 0.084])"] * 2):
        assert [c.outcome for c in motion_calls(rollout)] == ["done"], motion_calls(rollout)
        assert rollout.success


def test_a_push_that_turns_the_object_off_its_line_is_corrected_until_the_object_is_there() -> None:
    """A board's raised end rests on the chair, so the robot can push it only from 0.1 m off its centre: the chair
    turns and slides 0.15-0.25 m sideways. The push pushes on and corrects from the side (walking round the chair,
    away from the board) until the chair's centre is at the target."""

    def program(robot: Any) -> None:
        robot.walk_to_position([1.22, 0.0598, 0.0])
        chair = robot.get_position("chair")
        robot.push_to_position("chair", [chair[0] - 0.975, chair[1], chair[2]])

    task = generate("cube_lifting", 1022).task  # its chair as the family drew it before light cubes got lighter chairs
    objects = [o.model_copy(update={"mass": 3.0}) if o.name == "chair" else o for o in task.objects]
    rollouts = sim.run_programs(task.model_copy(update={"objects": objects}), [program] * 3, world_seeds=[0, 1, 2])
    pushes = [r.calls[-1] for r in rollouts]
    assert all(p.skill == "push_to_position" and p.outcome == "done" for p in pushes), pushes


@pytest.mark.slow
def test_after_corrections_from_another_side_the_push_leaves_the_robot_behind_the_object_where_it_pushed_from() -> None:
    """The chair is pushed 1.075 m from 0.15 m off its centre line (the board's raised end is beside it): in these
    perturbed worlds it turned, and the push corrected it from its side. The robot then stood beside the chair, not
    behind it where the program expected it, and its next walk ran into the chair (a planner's program held in 18 of
    20 such worlds). It now walks back round to the side it pushed from, and the walk on is clear."""
    ends: list[list[float]] = []

    def program(robot: Any) -> None:
        robot.walk_to_position([2.36, 0.7217, 0.0])
        chair = robot.get_position("chair")
        robot.push_to_position("chair", [chair[0] - 1.075, chair[1], chair[2]])
        ends.append([*robot.get_position("robot")[:2], *robot.get_position("chair")[:2]])
        robot.walk_to_position([2.185, 1.126, 0.0])

    task = generate("cube_lifting", 25005).task
    rollouts = sim.run_programs(task, [program] * 2, world_seeds=[50003, 50004])
    half = task.object("chair").size[0] / 2
    for rollout, (x, _, chair_x, _) in zip(rollouts, ends, strict=True):
        assert [c.outcome for c in motion_calls(rollout)] == ["done"] * 3, motion_calls(rollout)
        assert x > chair_x + half, (x, chair_x)  # behind the chair's +x face, the side the push was made from


def test_a_push_lined_up_off_the_centre_turns_the_face_so_the_object_does_not_slide_off_it() -> None:
    """The board's raised end, 0.16 m over the chair, keeps the robot 0.08 m off the chair's centre line as it pushes
    the chair out sideways. With a flat face, a chair whose perturbed yaw turns its near face's outer end toward the
    robot met the face there first, turned and slid off it 0.3 m along the board, dragging the board round, and the
    push stalled 0.4 m short (regression: these three worlds). The face turned toward the centre line meets the chair
    at its inner end: the chair goes out straight and the board stays where it lay."""

    boards: list[list[float]] = []

    def program(robot: Any) -> None:
        robot.turn_to_heading(90)
        robot.walk_to_position([-1.3688, -0.3850, 0.0])
        robot.walk_to_position([-1.3688, -1.6350, 0.0])
        robot.walk_to_position([-1.0188, -1.8600, 0.0])
        chair = robot.get_position("chair")
        robot.push_to_position("chair", [chair[0], chair[1] + 1.228, chair[2]])
        boards.append(robot.get_position("surfboard"))

    task = generate("cube_lifting", 9610).task
    rollouts = sim.run_programs(task, [program] * 3, world_seeds=[8002, 8006, 8007])
    pushes = [r.calls[-2] for r in rollouts]
    assert all(p.skill == "push_to_position" and p.outcome == "done" for p in pushes), pushes
    lay = task.object("surfboard").center
    assert len(boards) == 3 and all(np.hypot(b[0] - lay[0], b[1] - lay[1]) < 0.05 for b in boards), boards


def test_what_lies_on_an_object_is_read_from_the_contacts_that_bear_it_up() -> None:
    """The board's raised end lies on the chair, though the board also rests on the roller, and the cube lies on the
    board: the chair, the board and the roller are loaded (a push of the chair or the board lined up off its centre
    line turns the face); the cube touches the board only from above, and nothing lies on the furniture."""
    from robotool.sim.backend_choice import make_sim
    from robotool.sim.build import embodiment_for

    task = generate("cube_lifting", 9610).task
    scene = sim.build(task)
    simulator = make_sim(scene, 1, backend="mujoco", perturbation=Perturbation.none(scene, 1))
    simulator.step(200, np.ones(1, dtype=bool))
    controller = embodiment_for(task).controller(simulator)
    controller.tick(simulator.state())
    loaded = {name: controller.referee.pushes.loaded(0, k) for k, name in enumerate(scene.object_names)}
    assert loaded == {
        "yoga_roller": True,
        "surfboard": True,
        "cube": False,
        "chair": True,
        "side_table_1": False,
        "bin_1": False,
        "side_table_2": False,
    }


@pytest.mark.slow  # 9-11 s on a 2-core machine
def test_a_fall_read_at_every_physics_step_is_the_same_physics(sim_scene: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    """The runner steps the worlds the goal watches (a fragile object falling far enough to break) one physics step at
    a time: with its world watched at every tick, the reference program's world moves exactly as in steps of a whole
    control interval, and ends the same."""
    from robotool.sim.goals import WithSceneRules
    from robotool.sim.recorder import StateRecorder

    def tracks(watch_all: bool) -> tuple[list[Rollout], list[np.ndarray]]:
        if watch_all:
            monkeypatch.setattr(WithSceneRules, "watched", lambda self, state: np.ones(len(state.time), dtype=bool))
        recorder = StateRecorder([0])
        rollouts = sim.run_sessions(
            sim_scene("vase_lowering"),
            start_sessions([program("vase_lowering")], "quadruped"),
            seed=0,
            recorder=recorder,
        )
        return rollouts, [np.array(recorder.tracks[0].qpos)]

    plain, plain_qpos = tracks(False)
    watched, watched_qpos = tracks(True)
    assert all(r.success for r in plain)
    assert [r.model_dump() for r in watched] == [r.model_dump() for r in plain]
    for a, b in zip(plain_qpos, watched_qpos, strict=True):
        assert np.array_equal(a, b)
