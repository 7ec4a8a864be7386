"""The mujoco_warp backend agrees with the C backend (Warp's CPU device; kernels compile once per run).

Kept to one model (button_pressing) and a few worlds: the first Warp kernel compile is slow on CPU.
"""

from __future__ import annotations

import importlib.util
from typing import Any

import numpy as np
import pytest
from fixtures.reference import REFERENCE, TOOL_FREE, program
from fixtures.warp_group import ON_WARP

from robotool import sim

if importlib.util.find_spec("mujoco_warp") is None:  # not imported here: collecting stays quick where deselected
    pytest.skip("mujoco_warp is not installed", allow_module_level=True)

pytestmark = [pytest.mark.slow, ON_WARP]  # Warp compiles its kernels on the CPU first

TASK = "button_pressing"
PROGRAMS = [program(REFERENCE[TASK]), program(TOOL_FREE[TASK]), program(REFERENCE[TASK])]


@pytest.fixture(scope="session")
def warp_rollouts(sim_scene: Any, run_texts: Any) -> list[Any]:
    """Reference and tool-free programs side by side in one warp batch (once: the Warp tests share one xdist worker)."""
    return run_texts(sim_scene(TASK), PROGRAMS, seed=1, backend="warp")


def test_same_outcomes_as_the_c_backend(sim_scene: Any, run_texts: Any, warp_rollouts: list[Any]) -> None:
    c_rollouts = run_texts(sim_scene(TASK), PROGRAMS, seed=1, backend="mujoco")
    assert [r.success for r in warp_rollouts] == [r.success for r in c_rollouts] == [True, False, True]
    for w, c in zip(warp_rollouts, c_rollouts, strict=True):
        assert [(k.skill, k.outcome) for k in w.calls] == [(k.skill, k.outcome) for k in c.calls]
        assert w.sim_time == pytest.approx(c.sim_time, abs=0.3)  # float32 contacts: a stall may end a tick or two apart


def test_tiny_njmax_marks_the_world_failed(sim_scene: Any, run_texts: Any, warp_rollouts: list[Any]) -> None:
    for backend in ("warp", "mujoco"):
        (r,) = run_texts(sim_scene(TASK), PROGRAMS[:1], backend=backend, njmax=8)
        assert not r.success and r.error.startswith("simulation failed")
        assert ("NEFC" in r.error) if backend == "warp" else ("over njmax 8" in r.error)


def test_rays_match_between_backends(sim_scene: Any, warp_rollouts: list[Any]) -> None:
    scene = sim_scene(TASK)
    pnt = np.array([[[0.62, -0.1, 0.5], [0.4, 0.0, 0.5], [1.5, 1.5, 0.5]]] * 2)
    vec = np.tile([0.0, 0.0, -1.0], (2, 3, 1))
    sims = [sim.make_sim(scene, 2, backend=b) for b in ("mujoco", "warp")]
    (dist_c, geom_c), (dist_w, geom_w) = (s.rays(np.arange(2), pnt, vec) for s in sims)
    np.testing.assert_allclose(dist_w, dist_c, atol=1e-4)
    np.testing.assert_array_equal(geom_w, geom_c)
    for s, (dist, geom) in zip(sims, ((dist_c, geom_c), (dist_w, geom_w)), strict=True):  # one world asked for
        one = s.rays(np.array([1]), pnt[1:], vec[1:])
        np.testing.assert_array_equal(one[0], dist[1:])
        np.testing.assert_array_equal(one[1], geom[1:])
    with pytest.raises(ValueError, match=r"worlds \[1, 1\] name a world twice"):
        sims[1].rays(np.array([1, 1]), pnt, vec)
    assert dist_c[0, 0] == pytest.approx(0.5 - 0.08) and dist_c[0, 1] == pytest.approx(0.5 - 0.03, abs=1e-3)


def test_contact_normals_match_between_backends(sim_scene: Any, warp_rollouts: list[Any]) -> None:
    """Which way touching bodies press on each other, from Warp's batched contact list as from each MjData's."""
    scene = sim_scene(TASK)
    sims = [sim.make_sim(scene, 2, backend=b) for b in ("mujoco", "warp")]
    for s in sims:
        s.step(scene.control_substeps, np.ones(2, dtype=bool))
    (c, w) = (s.contact_normals(1) for s in sims)
    touching = np.linalg.norm(c, axis=2) > 0
    assert touching.any()
    np.testing.assert_array_equal(np.linalg.norm(w, axis=2) > 0, touching)
    unit = [n[touching] / np.linalg.norm(n[touching], axis=1, keepdims=True) for n in (c, w)]
    np.testing.assert_allclose(unit[1], unit[0], atol=1e-3)


def test_contact_points_match_between_backends(sim_scene: Any, warp_rollouts: list[Any]) -> None:
    """Where the world's own bodies touch what rests on them, from Warp's batched contact list as from each MjData's
    (a fragile object's strike is read where the striker meets it)."""
    scene = sim_scene(TASK)
    sims = [sim.make_sim(scene, 2, backend=b) for b in ("mujoco", "warp")]
    ground = np.zeros(scene.model.nbody, dtype=bool)
    ground[0] = True
    for s in sims:
        s.step(scene.control_substeps, np.ones(2, dtype=bool))
    (c, cb, cn), (w, wb, wn) = (s.contact_points(1, ground) for s in sims)
    assert len(c) and sorted(cb.tolist()) == sorted(wb.tolist())
    order = [np.lexsort((p[:, 0], p[:, 1], b)) for p, b in ((c, cb), (w, wb))]
    np.testing.assert_allclose(w[order[1]], c[order[0]], atol=1e-3)
    np.testing.assert_allclose(wn[order[1]], cn[order[0]], atol=1e-3)


def test_contact_forces_match_between_backends(sim_scene: Any, warp_rollouts: list[Any]) -> None:
    """The force the world's own bodies put on what rests on them, from each backend's solver: each cube lying on the
    table is borne up by its weight, on Warp as on C (the arm's payload reads what the robot bears this way)."""
    scene = sim_scene(TASK)
    sims = [sim.make_sim(scene, 2, backend=b) for b in ("mujoco", "warp")]
    ground = np.zeros(scene.model.nbody, dtype=bool)
    ground[0] = True
    for s in sims:
        for _ in range(10):
            s.step(scene.control_substeps, np.ones(2, dtype=bool))
    c, w = (s.contact_forces(np.array([1, 0]), ground) for s in sims)
    np.testing.assert_allclose(w, c, atol=0.05)
    cubes = [int(scene.object_body[scene.object_index(f"magnetic_cube{k}")]) for k in (1, 2, 3)]
    weight = sims[0].body_mass[1, cubes] * 9.81
    np.testing.assert_allclose(c[0, cubes, 2], weight, rtol=0.02)
    np.testing.assert_allclose(c[0, cubes, :2], 0.0, atol=1e-3)
    assert not c[:, 0].any()  # none on the flagged bodies themselves


@pytest.mark.parametrize("task_name", ["can_grasping", "milk_reaching", "milk_reaching_near"])
def test_reference_programs_solve_the_other_arm_tasks(sim_scene: Any, run_texts: Any, task_name: str) -> None:
    """Grasps by contact, rigid holds and sheet carriers behave on Warp as on C (fewer worlds: Warp on CPU is slow)."""
    rollouts = run_texts(sim_scene(task_name), [program(REFERENCE[task_name])] * 2, seed=3, backend="warp")
    assert all(r.success for r in rollouts), [(r.conditions, r.error) for r in rollouts]


def test_a_world_whose_state_turns_non_finite_fails_alone(
    sim_scene: Any, run_texts: Any, warp_rollouts: list[Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Worlds share Warp's arrays (and its contact pool): one world's NaN state must not reach the others."""
    from robotool.sim.backend_warp import WarpSim

    original = WarpSim.step

    def step(self: Any, nstep: int, active: np.ndarray) -> None:
        if self.state().time[1] > 1.0 and np.isfinite(self.state().qpos[1]).all():
            qpos = self.d.qpos.numpy()
            qpos[1] = np.nan  # world 1's simulation blows up
            self.d.qpos.assign(qpos)
        original(self, nstep, active)

    monkeypatch.setattr(WarpSim, "step", step)
    rollouts = run_texts(sim_scene(TASK), PROGRAMS, seed=1, backend="warp")
    assert rollouts[0].model_dump() == warp_rollouts[0].model_dump() and rollouts[0].success
    assert rollouts[2].model_dump() == warp_rollouts[2].model_dump() and rollouts[2].success
    assert rollouts[1].error == "simulation failed: physics diverged (non-finite state)"
