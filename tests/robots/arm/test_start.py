"""The arm starts still: its x/y/z servos hold the gripper at home through the settle before a program starts.

The servos follow a low-passed reference (the actuators' activation). It started at MuJoCo's 0, not at the home the
controller writes, so during the 0.3 s settle the reference ramped up from 0 and the gripper plunged from home
(0.1, 0, 0.3) to about (0.055, 0, 0.185) at up to 3.9 m/s and back: whatever stood within about 11 cm under home was
struck before the program ran. The activation now starts at home (the model's start keyframe), on both backends.
"""

from __future__ import annotations

import importlib.util
from typing import Any

import numpy as np
import pytest
from fixtures.paths import FIXTURES
from fixtures.warp_group import ON_WARP

from robotool import tasks
from robotool.robots.arm.arm_config import ARM
from robotool.rollout import Rollout
from robotool.sim.backend import Perturbation
from robotool.sim.backend_choice import make_sim
from robotool.sim.build import embodiment_for
from robotool.sim.compiled_scene import Scene
from robotool.sim.lockstep import SETTLE_TIME
from robotool.verify import world_failure
from robotool.vocabulary import BackendName

HELD_SPEED = 0.01  # m/s: the gripper's speed through the settle, at most (3.9 m/s before)
HELD_POSITION = 1e-3  # m from home at the end of the settle, at most
BUTTON_UNDER_HOME = "arm_button_just_under_the_home"
DO_NOTHING = (FIXTURES / "cheats" / "arm_do_nothing_under_a_button.py").read_text()


def _settle(scene: Scene, backend: BackendName, chunk: int) -> tuple[np.ndarray, np.ndarray]:
    """The gripper centre (T, nworld, 3) and speed (T, nworld) every ``chunk`` physics steps through the settle, in
    two perturbed worlds whose controller has written its first controls (home), as the lockstep runner starts."""
    sim = make_sim(scene, 2, backend=backend, perturbation=Perturbation.for_seeds(scene, [3, 4]))
    embodiment_for(scene.task).controller(sim)
    model = scene.model
    joint = model.joint("robot_x").id
    qadr, vadr = model.jnt_qposadr[joint], model.jnt_dofadr[joint]
    positions, speeds = [], []
    for _ in range(round(SETTLE_TIME / model.opt.timestep) // chunk):
        sim.step(chunk, np.ones(2, dtype=bool))
        state = sim.state()
        positions.append(state.qpos[:, qadr : qadr + 3])
        speeds.append(np.linalg.norm(state.qvel[:, vadr : vadr + 3], axis=1))
    return np.array(positions), np.array(speeds)


def _assert_held(positions: np.ndarray, speeds: np.ndarray) -> None:
    assert speeds.max() < HELD_SPEED, speeds.max()
    assert np.abs(positions - np.array(ARM.home)).max() < HELD_POSITION, positions.min(axis=(0, 1))


WARP = pytest.param(
    "warp",
    5,  # every 10 ms: the plunge's speed peaked over some 50 ms
    marks=[
        pytest.mark.slow,  # Warp compiles its kernels on the CPU first (3 s once they are compiled)
        ON_WARP,
        pytest.mark.skipif(importlib.util.find_spec("mujoco_warp") is None, reason="mujoco_warp is not installed"),
    ],
)


@pytest.mark.parametrize(("backend", "chunk"), [("mujoco", 1), WARP])
def test_the_gripper_holds_home_through_the_settle(sim_scene: Any, backend: BackendName, chunk: int) -> None:
    """Through the settle (every physics step on the C backend), the gripper stays at home, still."""
    _assert_held(*_settle(sim_scene("button_pressing"), backend, chunk))


def test_the_servos_start_at_the_reference_the_controller_writes(sim_scene: Any) -> None:
    """The x/y/z servos' activations start at home, the reference the controller writes first; the fingers have
    none."""
    scene = sim_scene("button_pressing")
    model = scene.model
    adr = [model.actuator_actadr[model.actuator(f"robot_{a}").id] for a in "xyz"]
    assert model.na == 3
    np.testing.assert_array_equal(scene.initial_act[adr], ARM.home)


def _button_task() -> Any:
    return tasks.load(FIXTURES / "layouts" / f"{BUTTON_UNDER_HOME}.yaml")


def test_a_program_that_does_nothing_presses_no_button_under_the_home(run_texts: Any) -> None:
    """A soft latching button faces up 3.4 cm under the fingertips at home: struck during the settle, it stayed in,
    and a program that only prints pressed it in every world. Now nothing touches it."""
    rollouts: list[Rollout] = run_texts(_button_task(), [DO_NOTHING] * 2, seed=11)
    for rollout in rollouts:
        assert rollout.error is None and not rollout.calls, rollout.error
        assert rollout.conditions == {"button_pressed": False}, world_failure(rollout)
        assert world_failure(rollout) == "goal not reached: button_pressed"


def test_a_program_that_lowers_the_fingers_onto_it_presses_the_button_under_the_home(run_texts: Any) -> None:
    """The control: the fingers lowered 2 cm into the face press the same button and it stays in, so the failure
    above is the gripper holding still, not the scene."""
    code = "move_to_position([0.09, 0.0, 0.246])\nmove_to_position([0.09, 0.0, 0.3])\n"
    rollouts: list[Rollout] = run_texts(_button_task(), [code] * 2, seed=11)
    assert all(r.success for r in rollouts), [world_failure(r) for r in rollouts]
