"""Bad skill arguments fail one call and a controller exception ends one world as an internal error, never the
batch."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fixtures.reference import REFERENCE, program

from robotool import robots, sandbox, sim, tasks, verify
from robotool.cli import main
from robotool.eval.failure_classes import TaskFacts, classify
from robotool.robots.arm.arm_controller import ArmController
from robotool.robots.quadruped.move_runner import MoveRunner
from robotool.robots.quadruped.quadruped_controller import QuadrupedController
from robotool.robots.skills import MAX_DISTANCE_FROM_SCENE, SceneBox, SkillArgumentError
from robotool.rollout import Rollout
from robotool.sim.backend_mujoco import MujocoSim
from robotool.sim.lockstep import scene_box


@pytest.mark.parametrize(
    ("position", "reason"),
    [
        ([1e155, 0.0, 0.0], "outside the scene"),
        ([0.2, 40.0, 0.0], "outside the scene"),
        ([10**400, 0, 0], "must be [x, y, z] in metres"),
        ([[0.1], [0.2], [0.3]], "must be [x, y, z] in metres"),
        ([0.1, 0.2, 0.3, 0.4], "must be [x, y, z] in metres"),
        ([float("nan"), 0, 0], "must be finite"),
    ],
)
def test_positions_are_checked_against_the_scene(position: list[Any], reason: str) -> None:
    box = scene_box(tasks.load("sofa_traversing"))
    with pytest.raises(SkillArgumentError, match=reason.replace("[", r"\[").replace("]", r"\]")):
        robots.get("quadruped").check_call("walk_to_position", (position,), box)


def test_the_scene_box_covers_objects_robot_and_workspace() -> None:
    box = scene_box(tasks.load("milk_reaching"))
    assert box.lo[0] <= -0.30 and box.hi[0] >= 0.59 and box.hi[2] >= 0.50  # workspace and the milk carton
    assert SceneBox(lo=(0, 0, 0), hi=(1, 1, 1)).distance((1 + MAX_DISTANCE_FROM_SCENE, 0.5, 0.5)) == pytest.approx(
        MAX_DISTANCE_FROM_SCENE
    )
    near = (box.hi[0] + MAX_DISTANCE_FROM_SCENE - 0.1, 0.0, 0.1)
    assert robots.get("arm").check_call("move_to_position", (near,), box) == (near,)  # far but sane: clamped by physics


def test_huge_target_is_refused_in_its_world_only(sim_scene: Any) -> None:
    scene = sim_scene("sofa_traversing")
    codes = ["walk_to_position([1e155, 0, 0])\n", "p = get_position('robot')\nwalk_to_position([p[0] + 0.1, p[1]])\n"]
    huge, fine = sim.run_sessions(scene, sandbox.start_sessions(codes, "quadruped"), perturb=False)
    assert huge.calls[0].outcome == "error" and "outside the scene" in (huge.calls[0].reason or "")
    assert huge.error is not None and "outside the scene" in huge.error
    assert fine.error is None and [c.outcome for c in fine.calls] == ["done", "done"]


def test_huge_target_through_robotool_run_is_a_report_not_a_traceback(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "huge.py"
    path.write_text("walk_to_position([1e155, 0, 0])\n")
    assert main(["run", "sofa_traversing", str(path), "--backend", "mujoco"]) == 1
    captured = capsys.readouterr()
    assert "Traceback" not in captured.out + captured.err and "outside the scene" in captured.out


def test_a_controller_exception_fails_only_its_world(
    sim_scene: Any, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """A controller that raises (a fault injected into the arm's start) is a bug in robotool: its world ends as an
    internal error, kept apart from the program's failures, and the traceback is logged and recorded."""
    original = ArmController.start

    def breaks_in_world_1(self: ArmController, state: Any, worlds: np.ndarray, skill: str, args: Any) -> Any:
        if 1 in np.asarray(worlds):
            raise FloatingPointError("overflow encountered in the servo reference")
        return original(self, state, worlds, skill, args)

    monkeypatch.setattr(ArmController, "start", breaks_in_world_1)
    code = program(REFERENCE["milk_reaching_near"])
    with caplog.at_level(logging.ERROR, logger="robotool.sim.lockstep"):
        rollouts = sim.run_sessions(sim_scene("milk_reaching_near"), sandbox.start_sessions([code] * 3, "arm"))
    assert rollouts[0].success and rollouts[2].success
    assert rollouts[0].internal_error is None and rollouts[2].internal_error is None
    broken = rollouts[1]
    assert not broken.success and broken.error is not None
    assert broken.error.startswith("internal error: controller error in ") and "FloatingPointError: overflow" in (
        broken.error
    )
    assert broken.calls[-1].outcome == "internal_error"
    found = broken.internal_error
    assert found is not None and found.where.startswith("the arm controller, in ") and found.where.endswith("world 1")
    assert found.reason == "FloatingPointError: overflow encountered in the servo reference"
    assert "Traceback" in found.traceback and "breaks_in_world_1" in found.traceback
    assert classify(broken, TaskFacts.of(sim_scene("milk_reaching_near").task, needs_tool=False)) is None
    logged = [r.getMessage() for r in caplog.records]  # one line: the traceback is the rollout's, not the console's
    assert len(logged) == 1 and "world 1" in logged[0] and "FloatingPointError" in logged[0] and "\n" not in logged[0]


def _tick_raising_in(controller: type, world: int, after: float) -> Any:
    """``controller.tick`` that does its work and then raises when it ticked ``world`` after ``after`` s: the runner
    has to undo that work and find the world."""
    original = controller.tick

    def tick(self: Any, state: Any, worlds: np.ndarray | None = None) -> Any:
        ends = original(self, state, worlds)
        ticked = np.arange(self.sim.nworld) if worlds is None else np.asarray(worlds)
        if world in ticked and state.time[world] > after:
            raise FloatingPointError(f"overflow in world {world}")
        return ends

    return tick


def _same(a: Rollout, b: Rollout) -> bool:
    return a.model_dump() == b.model_dump()


@pytest.mark.parametrize(
    ("task", "controller", "after"),
    [("milk_reaching_near", ArmController, 1.0), ("sofa_traversing", QuadrupedController, 3.0)],
)
def test_an_exception_in_the_batched_tick_fails_only_its_world(
    sim_scene: Any, run_texts: Any, monkeypatch: pytest.MonkeyPatch, task: str, controller: type, after: float
) -> None:
    scene, code = sim_scene(task), program(REFERENCE[task])
    undisturbed = run_texts(scene, [code] * 3)
    monkeypatch.setattr(controller, "tick", _tick_raising_in(controller, 1, after))
    rollouts = run_texts(scene, [code] * 3)
    assert _same(rollouts[0], undisturbed[0]) and _same(rollouts[2], undisturbed[2])
    assert undisturbed[0].success and undisturbed[2].success
    broken = rollouts[1]
    skill = broken.calls[-1].skill
    assert broken.error == f"internal error: controller error in {skill}: FloatingPointError: overflow in world 1"
    assert not broken.success and broken.calls[-1].outcome == "internal_error"
    assert broken.calls[-1].reason == broken.error and broken.internal_error is not None
    assert broken.sim_time < undisturbed[1].sim_time


def test_an_exception_in_the_batched_tick_spares_the_other_candidates(monkeypatch: pytest.MonkeyPatch) -> None:
    task = tasks.load("milk_reaching_near")
    codes = [program(REFERENCE["milk_reaching_near"]), program("milk_reaching")]
    undisturbed = verify.run_codes(task, codes, worlds=2, backend="mujoco")
    monkeypatch.setattr(ArmController, "tick", _tick_raising_in(ArmController, 1, 1.0))
    (first, broken), other = verify.run_codes(task, codes, worlds=2, backend="mujoco")
    assert _same(first, undisturbed[0][0]) and all(map(_same, other, undisturbed[1]))
    assert broken.error is not None and broken.error.endswith("FloatingPointError: overflow in world 1")


def test_an_exception_in_a_settling_world_fails_it_after_its_program(
    sim_scene: Any, run_texts: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(ArmController, "tick", _tick_raising_in(ArmController, 1, 0.0))
    codes = [program(REFERENCE["milk_reaching_near"]), "p = get_center('milk')\n"]
    moving, querying = run_texts(sim_scene("milk_reaching_near"), codes)
    assert moving.success and moving.error is None
    assert querying.error == (
        "internal error: controller error after the program ended: FloatingPointError: overflow in world 1"
    )
    assert querying.internal_error is not None and "after the program ended" in querying.internal_error.where
    assert [c.outcome for c in querying.calls] == ["done"] and not querying.success


def test_a_plan_that_raises_in_one_world_ends_that_skill_only(
    sim_scene: Any, run_texts: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    scene, code = sim_scene("sofa_traversing"), program(REFERENCE["sofa_traversing"])
    undisturbed = run_texts(scene, [code] * 2)
    original = MoveRunner._start_move

    def start_move(self: MoveRunner, w: int, move: Any) -> None:
        if w == 1 and move.pushing >= 0:  # the push itself, started by the plan after the approach
            raise ZeroDivisionError("the push's plan broke")
        original(self, w, move)

    monkeypatch.setattr(MoveRunner, "_start_move", start_move)
    fine, broken = run_texts(scene, [code] * 2)
    assert _same(fine, undisturbed[0]) and fine.success
    assert broken.error == (
        "internal error: controller error in push_to_position: ZeroDivisionError: the push's plan broke"
    )
    assert broken.calls[-1].outcome == "internal_error"
    assert broken.internal_error is not None and "start_move" in broken.internal_error.traceback


def test_a_world_whose_physics_blows_up_fails_alone(
    sim_scene: Any, run_texts: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    scene, code = sim_scene("milk_reaching_near"), program(REFERENCE["milk_reaching_near"])
    undisturbed = run_texts(scene, [code] * 3)
    original = MujocoSim._run

    def run(self: MujocoSim, worlds: np.ndarray, nstep: int) -> None:
        if 1 in worlds and self.datas[1].time > 1.0:
            self.datas[1].qvel[:] = np.nan  # world 1's simulation blows up
        original(self, worlds, nstep)

    monkeypatch.setattr(MujocoSim, "_run", run)
    rollouts = run_texts(scene, [code] * 3)
    assert _same(rollouts[0], undisturbed[0]) and _same(rollouts[2], undisturbed[2])
    broken = rollouts[1]
    assert broken.error == "simulation failed: physics diverged (bad velocity)" and not broken.success
    assert broken.calls[-1].outcome == "error" and broken.calls[-1].reason == broken.error


def test_a_worlds_rollout_does_not_depend_on_the_others_in_its_batch() -> None:
    """Worlds perturbed from given seeds: a program run alone and the same program run beside others (a longer walk
    that keeps the batch stepping after it ends, a walk into the gap that is refused) meet the same world and
    end the same, call by call, to the simulated second (the planner compares candidates batched together)."""
    scene = sim.build(tasks.load("sofa_traversing"))
    short = "walk_to_position([0.3, 0.0, 0.0])\n"
    others = ["walk_to_position([-3.0, 0.0, 0.0])\n", "walk_to_position([1.5, 0.0, 0.0])\n"]
    (alone,) = sim.run_sessions(scene, sandbox.start_sessions([short], "quadruped"), world_seeds=[12])
    batched = sim.run_sessions(scene, sandbox.start_sessions([*others, short], "quadruped"), world_seeds=[11, 13, 12])
    assert batched[2].model_dump(exclude={"world"}) == alone.model_dump(exclude={"world"})
    assert batched[0].sim_time > alone.sim_time and batched[1].calls[0].outcome != "done", batched[1].calls
