"""The C MuJoCo backend: subtree masses follow a perturbed mass, a spinning object keeps its energy, and the batched
rays answer as mj_ray."""

from __future__ import annotations

import copy
import sys
from typing import Any

import mujoco
import numpy as np
import pytest

from robotool.sim import backend_mujoco
from robotool.sim.backend import Perturbation
from robotool.sim.backend_mujoco import MujocoSim, subtree_masses

SPINS = [(5.0, 25.0, 5.0), (-3.0, 30.0, 2.0), (4.0, -20.0, -6.0), (1.0, 28.0, -4.0)]  # rad/s, in the vase's frame


def _heavier_vase(scene: Any, nworld: int) -> tuple[MujocoSim, int]:
    """Worlds of the vase_lowering scene in which the glass vase is 20 % heavier than in the task file."""
    index = scene.object_index("glass_vase")
    mass = np.ones((nworld, len(scene.object_names)))
    mass[:, index] = 1.2
    perturbation = Perturbation(np.ones(nworld), mass, np.zeros((nworld, len(scene.object_names), 3)))
    return MujocoSim(scene, nworld, perturbation, njmax=scene.njmax, nconmax=scene.nconmax), index


def test_subtree_masses_follow_the_perturbed_mass(sim_scene: Any) -> None:
    sim, index = _heavier_vase(sim_scene("vase_lowering"), 1)
    try:
        model = sim.models[0]
        body = sim.scene.object_body[index]
        assert model.body_mass[body] == pytest.approx(1.2 * sim.scene.model.body_mass[body])
        derived = copy.copy(model)
        mujoco.mj_setConst(derived, mujoco.MjData(derived))
        np.testing.assert_allclose(model.body_subtreemass, derived.body_subtreemass, rtol=1e-12)
        assert model.body_subtreemass[body] == pytest.approx(model.body_mass[body])
    finally:
        sim.close()


def test_subtree_masses_sum_each_body_and_its_descendants() -> None:
    # world <- a <- b, world <- c
    assert subtree_masses(np.array([0.0, 1.0, 2.0, 4.0]), np.array([0, 0, 1, 0])).tolist() == [7.0, 3.0, 2.0, 4.0]


def test_a_spinning_vase_on_the_floor_gains_no_energy(sim_scene: Any) -> None:
    """A heavier-than-nominal vase tumbling on the floor, spinning fast about its long axis (as after a push off a
    sofa), keeps its energy: with the subtree masses left at the nominal mass, the integrator lost its implicit
    treatment of the vase's gyroscopic forces and the tumbling vase gained energy until the world diverged."""
    sim, index = _heavier_vase(sim_scene("vase_lowering"), len(SPINS))
    try:
        model = sim.scene.model
        joint = model.body_jntadr[sim.scene.object_body[index]]
        q, v = model.jnt_qposadr[joint], model.jnt_dofadr[joint]
        body = sim.scene.object_body[index]
        rng = np.random.default_rng(0)
        for w, spin in enumerate(SPINS):
            d = sim.datas[w]
            quat = rng.normal(size=4)
            d.qpos[q : q + 7] = [1.0, -1.5, 0.17, *(quat / np.linalg.norm(quat))]  # clear of everything
            d.qvel[v : v + 6] = [0.5, -0.3, 0.0, *spin]
            mujoco.mj_forward(sim.models[w], d)

        def energy() -> np.ndarray:
            out = []
            for m, d in zip(sim.models, sim.datas, strict=True):
                mass, inertia = m.body_mass[body], m.body_inertia[body]
                lin, ang = d.qvel[v : v + 3], d.qvel[v + 3 : v + 6]
                out.append(0.5 * mass * lin @ lin + 0.5 * inertia @ ang**2 + mass * 9.81 * d.qpos[q + 2])
            return np.array(out)

        start, most = energy(), energy()
        for _ in range(40):  # 2 s
            sim.step(25, np.ones(len(SPINS), dtype=bool))
            most = np.maximum(most, energy())
        assert sim.state().failed == [None] * len(SPINS)
        assert np.all(most <= start * 1.05), most / start
    finally:
        sim.close()


@pytest.mark.parametrize("platform", [sys.platform, "elsewhere"])
def test_rays_answer_as_the_binding_s_mj_ray_one_by_one(
    sim_scene: Any, platform: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The batched rays (the library's mj_ray through ctypes, or the binding where the library is not found; a
    repeated ray answered once) give exactly what the binding's mj_ray gives ray by ray: hits on objects and on the
    floor, misses, the robot skipped, a body left out, and worlds without rays (NaN)."""
    monkeypatch.setattr(sys, "platform", platform)
    backend_mujoco._ray_caster.cache_clear()
    scene = sim_scene("sofa_climbing")
    sim, nworld = MujocoSim(scene, 3, Perturbation.sample(scene, 3, 0), njmax=scene.njmax, nconmax=scene.nconmax), 3
    try:
        rng = np.random.default_rng(0)
        xy = rng.uniform(-1.0, 4.0, (nworld, 40, 2))
        xy[:, 20:30] = xy[:, 19:20]  # a path read past its end: the same ray again
        pnt = np.concatenate([xy, np.full((nworld, 40, 1), 0.8)], axis=2)
        pnt[:, 35:, 2] = -1.0  # under the floor, pointing down: nothing is hit
        pnt[2] = np.nan  # no rays in this world
        vec = np.tile([0.0, 0.0, -1.0], (nworld, 40, 1))
        box = scene.object_body[scene.object_index("box_1")]
        for exclude, skip in ((-1, -1), (box, 2)):  # group 2: the robot's geoms
            dist, geom = sim.rays(pnt, vec, exclude_body=exclude, skip_group=skip)
            groups = np.ones(6, dtype=np.uint8)
            if skip >= 0:
                groups[skip] = 0
            hit = np.zeros(1, dtype=np.int32)
            for w in range(2):
                for r in range(40):
                    x = mujoco.mj_ray(sim.models[w], sim.datas[w], pnt[w, r], vec[w, r], groups, 1, exclude, hit)
                    assert (dist[w, r], geom[w, r]) == ((x, hit[0]) if x >= 0 else (np.inf, -1))
            assert np.isinf(dist[2]).all() and (geom[2] == -1).all()
            assert {-1, 0} < set(geom[:2].ravel().tolist())  # misses, the floor and objects were all met
    finally:
        sim.close()
        backend_mujoco._ray_caster.cache_clear()
