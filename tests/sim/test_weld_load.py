"""The load a weld carries, read from its constraint force, agrees with statics on both backends: a hammer turned
half a radian and held in the air by its grasp weld alone puts its weight on the gripper and, about its body's origin,
the torque of its weight acting at its centre of mass (the hammer's lies off its origin)."""

from __future__ import annotations

import importlib.util

import mujoco
import numpy as np
import pytest
from fixtures.warp_group import ON_WARP

from robotool import sim, tasks
from robotool.robots.arm.arm_body import AXES, grasp_eq_name
from robotool.sim.backend import Perturbation, quat_to_mat

GRAVITY = 9.81
WARP = pytest.param(
    "warp",
    marks=[
        pytest.mark.slow,
        ON_WARP,
        pytest.mark.skipif(importlib.util.find_spec("mujoco_warp") is None, reason="mujoco_warp is not installed"),
    ],
)


@pytest.mark.parametrize("backend", ["mujoco", WARP])
def test_a_held_hammer_loads_its_weld_with_its_weight_and_the_weights_torque(backend: str) -> None:
    scene = sim.build(tasks.load("milk_reaching"))
    model, hammer = scene.model, scene.object_index("hammer")
    turn = np.zeros((1, len(scene.object_names), 3))
    turn[0, hammer, 2] = 0.5  # rad: the hammer's frame is not the world's
    perturbation = Perturbation(np.ones(1), np.ones((1, len(scene.object_names))), turn)
    batch = sim.make_sim(scene, 1, backend=backend, perturbation=perturbation)  # type: ignore[arg-type]
    eq = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_EQUALITY, grasp_eq_name("hammer"))
    assert (batch.weld_load(np.array([0]), eq) == 0).all()  # off: no load
    batch.set_weld(np.array([0]), eq, True)
    joints = [model.joint(f"robot_{a}").id for a in AXES]
    batch.ctrl[0, [model.actuator(f"robot_{a}").id for a in AXES]] = batch.state().qpos[0, model.jnt_qposadr[joints]]
    batch.ctrl[0, model.actuator("robot_z").id] += 0.2  # lifts the hammer off the table: the weld alone holds it
    for _ in range(6):  # 0.6 s: the servos settle under the hammer's weight
        batch.step(scene.control_substeps, np.ones(1, dtype=bool))
    state = batch.state()
    body = scene.object_body[hammer]
    assert state.xpos[0, body, 2] > 0.15
    weight = np.array([0.0, 0.0, -batch.body_mass[0, body] * GRAVITY])
    centre = quat_to_mat(state.xquat[:, body])[0] @ model.body_ipos[body]  # from the body's origin
    assert np.linalg.norm(centre[:2]) > 0.01  # the centre of mass lies off the origin, so the torque is not zero
    (load,) = batch.weld_load(np.array([0]), eq)
    np.testing.assert_allclose(load[:3], weight, atol=0.02 * abs(weight[2]))
    np.testing.assert_allclose(load[3:], np.cross(centre, weight), atol=0.01)
