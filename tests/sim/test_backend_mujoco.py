"""The C MuJoCo backend: subtree masses follow a perturbed mass, a spinning object keeps its energy, and the batched
rays (:mod:`robotool.sim.ray_cast`) answer as mj_ray, bit for bit."""

from __future__ import annotations

import copy
from typing import Any

import mujoco
import numpy as np
import pytest
from fixtures.paths import FIXTURES

from robotool.sim import backend, backend_mujoco, ray_cast
from robotool.sim.backend import Perturbation
from robotool.sim.backend_mujoco import MujocoSim, subtree_masses
from robotool.sim.warp_runtime import launch_on_cpu

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


def _mj_ray_one_by_one(
    models: list[mujoco.MjModel],
    datas: list[mujoco.MjData],
    pnt: np.ndarray,
    vec: np.ndarray,
    exclude: int | np.ndarray,
    skip: int,
) -> tuple[np.ndarray, np.ndarray]:
    """The binding's mj_ray, ray by ray: (distance, inf where missed), (geom, -1), each (nworld, nray); ``exclude``
    is one body for every ray or each ray's own (nworld, nray)."""
    groups = np.ones(6, dtype=np.uint8)
    if skip >= 0:
        groups[skip] = 0
    dist, geom = np.full(pnt.shape[:2], np.inf), np.full(pnt.shape[:2], -1)
    hit = np.zeros(1, dtype=np.int32)
    excluded = np.broadcast_to(exclude, pnt.shape[:2])
    for w, r in np.ndindex(*pnt.shape[:2]):
        x = mujoco.mj_ray(models[w], datas[w], pnt[w, r], vec[w, r], groups, 1, int(excluded[w, r]), hit)
        if x >= 0:
            dist[w, r], geom[w, r] = x, hit[0]
    return dist, geom


@pytest.mark.parametrize("direction", ["down", "any"])
def test_rays_answer_as_the_binding_s_mj_ray_one_by_one(sim_scene: Any, direction: str) -> None:
    """The batched rays (numpy, :mod:`robotool.sim.ray_cast`) give exactly what the binding's mj_ray gives ray by
    ray, bit for bit: hits on objects and on the floor, misses, the robot skipped, a body left out, and the worlds
    asked for only (in any order); downward rays (the quadruped's) and rays in any direction; each ray leaving out a
    body of its own."""
    scene = sim_scene("sofa_climbing")
    sim, nworld = MujocoSim(scene, 3, Perturbation.sample(scene, 3, 0), njmax=scene.njmax, nconmax=scene.nconmax), 3
    try:
        sim.step(100, np.ones(nworld, dtype=bool))  # the boxes settle: tilted a little, off their start poses
        rng = np.random.default_rng(0)
        xy = rng.uniform(-1.0, 4.0, (nworld, 40, 2))
        pnt = np.concatenate([xy, np.full((nworld, 40, 1), 0.8)], axis=2)
        pnt[:, 35:, 2] = -1.0  # under the floor: nothing is hit going down
        vec = np.tile([0.0, 0.0, -1.0], (nworld, 40, 1)) if direction == "down" else rng.normal(size=(nworld, 40, 3))
        box = scene.object_body[scene.object_index("box_1")]
        own = rng.choice([-1, box, scene.object_body[scene.object_index("box_2")]], size=(nworld, 40))
        for exclude, skip in ((-1, -1), (box, 2), (own, 2)):  # group 2: the robot's geoms
            worlds = np.array([2, 0])  # world 1 casts no rays
            mine = exclude[worlds] if np.ndim(exclude) else exclude
            dist, geom = sim.rays(worlds, pnt[worlds], vec[worlds], exclude_body=mine, skip_group=skip)
            models, datas = [sim.models[w] for w in worlds], [sim.datas[w] for w in worlds]
            want_dist, want_geom = _mj_ray_one_by_one(models, datas, pnt[worlds], vec[worlds], mine, skip)
            np.testing.assert_array_equal(dist, want_dist)
            np.testing.assert_array_equal(geom, want_geom)
            assert {-1, 0} < set(geom.ravel().tolist())  # misses, the floor and objects were all met
    finally:
        sim.close()


def _every_shape() -> mujoco.MjModel:
    """A bounded plane and tilted, offset spheres, capsules, ellipsoids, cylinders and boxes, one invisible, one with
    an invisible material, a few sharing a pose (ties) and one in group 3."""
    spec = mujoco.MjSpec()
    spec.add_material(name="clear", rgba=[1, 1, 1, 0])
    world = spec.worldbody
    world.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[2.0, 1.5, 0.1], quat=[0.99, 0.1, 0.0, 0.05])
    rng = np.random.default_rng(3)
    kinds = [
        mujoco.mjtGeom.mjGEOM_SPHERE,
        mujoco.mjtGeom.mjGEOM_CAPSULE,
        mujoco.mjtGeom.mjGEOM_ELLIPSOID,
        mujoco.mjtGeom.mjGEOM_CYLINDER,
        mujoco.mjtGeom.mjGEOM_BOX,
    ]
    for n in range(20):
        quat = rng.normal(size=4)
        body = world.add_body(pos=rng.uniform(-1.0, 1.0, 3), quat=quat / np.linalg.norm(quat))
        body.add_freejoint()
        geom = body.add_geom(type=kinds[n % len(kinds)], size=rng.uniform(0.05, 0.3, 3))
        if n == 7:
            geom.rgba = [1, 0, 0, 0]
        if n == 8:
            geom.material = "clear"
        if n == 9:
            geom.group = 3
    twin = world.add_body(pos=[0.2, 0.2, 0.3])
    twin.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.1, 0.1, 0.1])
    twin.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.1, 0.1, 0.1])  # the same box again: mj_ray keeps the first
    return spec.compile()


@pytest.mark.parametrize(("exclude", "skip"), [(-1, -1), (3, 3)])
def test_every_primitive_shape_answers_as_mj_ray(exclude: int, skip: int) -> None:
    """Each primitive geom type, posed anywhere, hit from outside, from inside and edge-on, gives mj_ray's answer bit
    for bit; invisible geoms (their own alpha or their material's) are not hit, nor a left-out group or body."""
    model = _every_shape()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    rng = np.random.default_rng(4)
    pnt = rng.uniform(-1.5, 1.5, (1, 3000, 3))
    vec = rng.normal(size=(1, 3000, 3))
    vec[0, :500] = [0.0, 0.0, -1.0]
    vec[0, 500:600, :2] = 0.0  # along z, either way
    geoms = ray_cast.RayGeoms.of(model)
    index = geoms.eligible(backend.geom_groups(skip), exclude)
    x, hit = ray_cast.cast(geoms, index, data.geom_xpos[None, index], data.geom_xmat[None, index], pnt, vec)
    want_dist, want_geom = _mj_ray_one_by_one([model], [data], pnt, vec, exclude, skip)
    np.testing.assert_array_equal(np.where(x >= 0, x, np.inf), want_dist)
    np.testing.assert_array_equal(hit, want_geom)
    assert len(set(hit.ravel().tolist())) > 15  # most shapes were met


def test_a_mesh_is_refused_with_its_type_named() -> None:
    spec = mujoco.MjSpec()
    spec.add_mesh(name="tetra", uservert=[0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1])
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="tetra")
    geoms = ray_cast.RayGeoms.of(spec.compile())
    with pytest.raises(ray_cast.UnsupportedGeom, match="mjGEOM_MESH"):
        geoms.eligible(backend.geom_groups(-1), -1)


def test_contact_normals_say_which_way_touching_bodies_press(sim_scene: Any) -> None:
    """A box resting on the floor: the normals between the floor's body and the box's point up from the floor (and
    down from the box); bodies that do not touch have none."""
    scene = sim_scene("sofa_climbing")
    sim = MujocoSim(scene, 1, Perturbation.none(scene, 1), njmax=scene.njmax, nconmax=scene.nconmax)
    try:
        sim.step(50, np.ones(1, dtype=bool))
        normals = sim.contact_normals(0)
        box_1, box_2 = (scene.object_body[scene.object_index(n)] for n in ("box_1", "box_2"))
        up = normals[0, box_1]
        assert up[2] > 0.5 and np.allclose(up[:2], 0.0, atol=1e-3), up
        np.testing.assert_array_equal(normals, -normals.transpose(1, 0, 2))
        assert not sim.state().touching[0, box_1, box_2] and not normals[box_1, box_2].any()
    finally:
        sim.close()


def test_contact_points_say_where_flagged_bodies_touch_the_others(sim_scene: Any) -> None:
    """A box resting on the floor touches it on its underside: the points where the floor's body touches it lie on
    the floor's top, under the box's footprint, each naming the box's body."""
    scene = sim_scene("sofa_climbing")
    sim = MujocoSim(scene, 1, Perturbation.none(scene, 1), njmax=scene.njmax, nconmax=scene.nconmax)
    try:
        sim.step(50, np.ones(1, dtype=bool))
        floor = np.zeros(scene.model.nbody, dtype=bool)
        floor[0] = True
        box = scene.object_body[scene.object_index("box_1")]
        points, bodies, normals = sim.contact_points(0, floor)
        under = points[bodies == box]
        centre, half = sim.state().xpos[0, box], np.asarray(scene.task.object("box_1").size) / 2
        assert len(under) and np.allclose(under[:, 2], 0.0, atol=2e-3), under
        assert np.all(np.abs(under[:, :2] - centre[:2]) <= half[:2] + 1e-3), (under, centre)
        assert not np.isin(bodies, np.flatnonzero(floor)).any()
        assert np.allclose(np.abs(normals[bodies == box][:, 2]), 1.0, atol=1e-3)  # the floor's normal: vertical
    finally:
        sim.close()


def test_inside_tells_points_inside_each_primitive_shape_from_points_just_outside() -> None:
    """Points 10 % inside a geom's surface lie in it, points 10 % outside do not, for every primitive shape posed
    anywhere (a ray that starts inside a geom meets it where it leaves it, so its readers ask this)."""
    model = _every_shape()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    geoms = ray_cast.RayGeoms.of(model)
    rng = np.random.default_rng(5)
    solid = np.flatnonzero(geoms.type != mujoco.mjtGeom.mjGEOM_PLANE)
    box, sphere, capsule, ellipsoid = (
        int(t)
        for t in (
            mujoco.mjtGeom.mjGEOM_BOX,
            mujoco.mjtGeom.mjGEOM_SPHERE,
            mujoco.mjtGeom.mjGEOM_CAPSULE,
            mujoco.mjtGeom.mjGEOM_ELLIPSOID,
        )
    )
    for g in solid:
        size, kind = model.geom_size[g], int(geoms.type[g])
        u = rng.normal(size=(200, 3))
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        if kind == box:
            surface, centre = size * u / np.abs(u).max(axis=1, keepdims=True), np.zeros((200, 3))
        elif kind in (sphere, capsule):
            centre = np.zeros((200, 3))
            if kind == capsule:  # on its side, from a point of its segment, or on a cap, from the segment's end
                centre[:100, 2], u[:100, 2] = rng.uniform(-size[1], size[1], 100), 0.0
                u[:100] /= np.linalg.norm(u[:100], axis=1, keepdims=True)
                centre[100:, 2] = size[1] * np.sign(u[100:, 2])
            surface = size[0] * u
        elif kind == ellipsoid:
            surface, centre = size * u, np.zeros((200, 3))
        else:  # a cylinder: on its side or a cap
            side = np.stack([u[:, 0], u[:, 1]], axis=1) / np.linalg.norm(u[:, :2], axis=1, keepdims=True)
            t = rng.uniform(-1.0, 1.0, 200)
            surface = np.column_stack([size[0] * side, size[1] * t])
            surface[:100, :2] *= rng.uniform(0, 1, (100, 1))  # on a cap
            surface[:100, 2] = size[1] * np.sign(t[:100])
            centre = np.zeros((200, 3))
        mat = data.geom_xmat[g].reshape(3, 3)
        for scale, expected in ((0.9, True), (1.1, False)):
            local = centre + scale * surface
            pnt = data.geom_xpos[g] + local @ mat.T
            found = ray_cast.inside(
                geoms, np.array([g]), data.geom_xpos[None, [g]], data.geom_xmat[None, [g]], pnt[None]
            )
            got = found[0] == g
            assert got.all() == expected and got.any() == expected, (mujoco.mjtGeom(kind).name, scale)


def test_a_point_inside_two_geoms_reads_the_later_one_unless_their_body_is_left_out() -> None:
    """The twin boxes share one pose: a point in both reads the later geom (as the rays' readers expect); left out by
    its body, neither holds it; a point in no geom reads -1."""
    model = _every_shape()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    geoms = ray_cast.RayGeoms.of(model)
    solid = np.flatnonzero(geoms.type != mujoco.mjtGeom.mjGEOM_PLANE)
    twin = np.flatnonzero(model.geom_bodyid == model.geom_bodyid[-1])
    pnt = np.array([[data.geom_xpos[twin[0]], [5.0, 5.0, 5.0]]])
    xpos, xmat = data.geom_xpos[None, solid], data.geom_xmat[None, solid]
    assert ray_cast.inside(geoms, solid, xpos, xmat, pnt).tolist() == [[twin[1], -1]]
    left_out = np.full((1, 2), model.geom_bodyid[-1])
    assert ray_cast.inside(geoms, solid, xpos, xmat, pnt, left_out).tolist() == [[-1, -1]]


def test_a_ray_cast_from_inside_reads_the_geom_its_start_lies_in_and_mj_ray_s_answer_elsewhere() -> None:
    """With ``from_inside``, a ray whose start lies in a geom meets the last such geom (as :func:`ray_cast.inside`
    finds it) at distance 0, its body left out or not as the ray's own; every other ray reads what the plain cast
    reads (``mj_ray``'s answer), in every world at once."""
    model = _every_shape()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    geoms = ray_cast.RayGeoms.of(model)
    index = geoms.eligible(np.ones(ray_cast.NGROUP), -1)
    rng = np.random.default_rng(7)
    starts = data.geom_xpos[rng.integers(0, model.ngeom, (2, 60))] + rng.normal(0.0, 0.15, (2, 60, 3))
    vec = rng.normal(size=(2, 60, 3))
    exclude = np.where(rng.random((2, 60)) < 0.3, model.geom_bodyid[rng.integers(0, model.ngeom, (2, 60))], -1)
    xpos, xmat = np.stack([data.geom_xpos[index]] * 2), np.stack([data.geom_xmat[index]] * 2)
    plain = ray_cast.cast(geoms, index, xpos, xmat, starts, vec, exclude)
    fused = ray_cast.cast(geoms, index, xpos, xmat, starts, vec, exclude, from_inside=True)
    within = ray_cast.inside(geoms, index, xpos, xmat, starts, exclude)
    assert 10 < (within >= 0).sum() < within.size - 10  # both kinds of ray are tried
    np.testing.assert_array_equal(fused[0], np.where(within >= 0, 0.0, plain[0]))
    np.testing.assert_array_equal(fused[1], np.where(within >= 0, within, plain[1]))


def test_the_compiled_ray_tests_refuse_arrays_they_would_read_past() -> None:
    """The kernels index their arrays unchecked: a per-ray array shaped for fewer rays, or a view that is not
    contiguous, is refused before the launch instead of being read past its end."""
    from robotool.sim import ray_kernel
    from robotool.sim.warp_runtime import cpu_view

    geoms = (np.array([6]), np.ones((1, 3)), np.ones(1), np.zeros(1))
    poses, rays = (np.zeros((2, 1, 3)), np.zeros((2, 1, 9))), (np.zeros((2, 5, 3)), np.zeros((2, 5, 3)))
    with pytest.raises(ValueError, match=r"exclude has shape \(2, 1\), not \(2, 5\)"):
        ray_kernel.cast(*geoms, *poses, *rays, np.zeros((2, 1)))
    with pytest.raises(ValueError, match="C-contiguous"):
        cpu_view(np.zeros((4, 4))[:, 1])


def test_which_bodies_touch_is_read_from_each_world_s_own_contacts_after_its_last_step(sim_scene: Any) -> None:
    """The touching table (built for all worlds at once) holds, in each world, the body pairs of that world's contacts
    within touching distance after its last step: a world left out of a step keeps its own, and pairs that no
    longer touch are gone."""
    scene = sim_scene("sofa_climbing")
    sim = MujocoSim(scene, 3, Perturbation.sample(scene, 3, 2), njmax=scene.njmax, nconmax=scene.nconmax)
    try:
        for active in ([True, True, True], [True, False, True], [False, True, False]):
            sim.step(40, np.array(active))
            touching = sim.state().touching
            for w, d in enumerate(sim.datas):
                want = np.zeros_like(touching[w])
                for con in d.contact[: d.ncon] if d.ncon else []:
                    if con.dist <= backend.TOUCH_DISTANCE:
                        a, b = scene.model.geom_bodyid[con.geom]
                        want[a, b] = want[b, a] = True
                np.testing.assert_array_equal(touching[w], want)
            assert touching.any(axis=(1, 2)).all()
    finally:
        sim.close()


def test_a_replayed_launch_reads_its_own_arrays_and_refuses_the_wrong_kind() -> None:
    """A kernel's later launches replay its first with their own arrays (sizes, values and outputs of their own), and
    an array of the wrong dimension or type is refused before the launch, as Warp's own packing would refuse it."""
    from robotool.sim import ray_kernel

    rng = np.random.default_rng(1)
    half = rng.uniform(0.1, 0.3, (2, 3))
    geoms = (np.full(2, int(mujoco.mjtGeom.mjGEOM_BOX)), half, (half**2).sum(axis=1), np.arange(2))
    for nworld, nray in ((2, 5), (3, 11), (2, 5)):  # recorded, replayed larger, replayed as the first
        poses = rng.uniform(-0.2, 0.2, (nworld, 2, 3)), np.tile(np.eye(3).ravel(), (nworld, 2, 1))
        pnt = np.concatenate([rng.uniform(-0.3, 0.3, (nworld, nray, 2)), np.ones((nworld, nray, 1))], axis=2)
        vec = np.tile([0.0, 0.0, -1.0], (nworld, nray, 1))
        dist, hit = ray_kernel.cast(*geoms, *poses, pnt, vec, np.full((nworld, nray), -1))
        top = pnt[..., 2:3] - (poses[0][:, None, :, 2] + half[None, None, :, 2])  # down to each box's top
        over = np.all(np.abs(pnt[:, :, None, :2] - poses[0][:, None, :, :2]) <= half[None, None, :, :2], axis=3)
        np.testing.assert_allclose(np.where(hit >= 0, dist, np.inf), np.where(over, top, np.inf).min(axis=2))
        assert (hit >= 0).any() and (hit < 0).any()
    ints, floats = np.zeros(1, dtype=np.int32), np.zeros(1)
    geom_args = (ints, np.zeros((1, 3)), floats, ints)
    rays = (np.zeros((1, 1, 3)), np.zeros((1, 1, 3)), ints, 0, floats, ints)
    with pytest.raises(ValueError, match="argument 4 must be a 3-d float64 array, not 2-d float64"):
        launch_on_cpu(ray_kernel._cast, 1, *geom_args, np.zeros((1, 3)), floats, *rays)
    with pytest.raises(ValueError, match="argument 0 must be a 1-d int32 array, not 1-d int64"):
        launch_on_cpu(ray_kernel._cast, 1, np.zeros(1, dtype=int), *geom_args[1:], np.zeros((1, 1, 3)), floats, *rays)


def test_a_process_that_shares_the_cores_steps_its_worlds_on_its_share(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(backend_mujoco, "cores", lambda: 4)
    monkeypatch.setattr(backend_mujoco, "_sharing", 1)
    assert [backend_mujoco._threads(n) for n in (1, 3, 8)] == [1, 3, 4]  # alone: every core, one a world at most
    backend_mujoco.share_cores(2)
    assert [backend_mujoco._threads(n) for n in (1, 3, 8)] == [1, 2, 2]
    backend_mujoco.share_cores(8)  # more processes than cores: still one thread each
    assert [backend_mujoco._threads(n) for n in (1, 3, 8)] == [1, 1, 1]


def test_the_share_of_cores_changes_no_rollout(monkeypatch: pytest.MonkeyPatch) -> None:
    """Threads only split the worlds between them: every world steps alone, so one thread or two give the same
    rollouts."""
    from robotool import tasks
    from robotool.verify import run_codes

    task = tasks.load("sofa_climbing")
    code = (FIXTURES / "programs" / "sofa_climbing_direct.py").read_text()
    monkeypatch.setattr(backend_mujoco, "cores", lambda: 2)
    monkeypatch.setattr(backend_mujoco, "_sharing", 1)  # put back after the test
    two = run_codes(task, [code], worlds=3, seed=5)[0]
    backend_mujoco.share_cores(2)
    one = run_codes(task, [code], worlds=3, seed=5)[0]
    assert [r.model_dump() for r in one] == [r.model_dump() for r in two]
