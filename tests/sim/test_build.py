"""Task -> MuJoCo model: every arm shape, fixed vs movable, buttons, magnets, the gripper."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from robotool import sim
from robotool.task.task_file import parse_task


def _task(objects: list[dict], goal: dict | None = None):
    return parse_task({"format": 1, "name": "t", "category": "no_tool", "instruction": "x",
                       "robot": {"type": "arm"}, "objects": objects,
                       "goal": goal or {"grasped": objects[0]["name"]}})


SHAPES = [
    {"name": "block", "shape": "box", "center": [0.3, 0.0, 0.02], "size": [0.04, 0.06, 0.04], "mass": 0.3},
    {"name": "roller", "shape": "cylinder", "axis": "x", "center": [0.2, 0.2, 0.02], "size": [0.2, 0.04, 0.04]},
    {"name": "hook", "shape": "hook", "center": [0.0, -0.3, 0.015], "size": [0.3, 0.15, 0.03], "mass": 0.4},
    {"name": "button", "shape": "button", "center": [0.6, 0.3, 0.04], "size": [0.2, 0.1, 0.08], "movable": False},
    {"name": "wall", "shape": "box", "center": [-0.2, 0.3, 0.05], "size": [0.02, 0.2, 0.1], "movable": False,
     "friction": 0.9},
]


@pytest.fixture(scope="module")
def scene() -> sim.Scene:
    return sim.build(_task(SHAPES))


def test_movable_objects_are_free_bodies_with_their_mass(scene: sim.Scene) -> None:
    m = scene.model
    for obj in scene.task.objects:
        body = m.body(obj.name)
        if obj.movable:
            assert m.jnt_type[body.jntadr[0]] == mujoco.mjtJoint.mjJNT_FREE
            assert body.mass[0] == pytest.approx(obj.effective_mass, rel=1e-6)
        else:
            assert body.jntnum[0] == 0  # static: welded to the world


def test_geoms_follow_the_object_parts(scene: sim.Scene) -> None:
    m, d = scene.model, mujoco.MjData(scene.model)
    mujoco.mj_forward(m, d)
    hook = m.body("hook").id
    assert np.count_nonzero(m.geom_bodyid == hook) == 2  # handle and head
    roller = np.flatnonzero(m.geom_bodyid == m.body("roller").id)[0]
    assert m.geom_type[roller] == mujoco.mjtGeom.mjGEOM_CYLINDER
    np.testing.assert_allclose(d.geom_xmat[roller].reshape(3, 3)[:, 2], [1, 0, 0], atol=1e-9)  # axis along x
    np.testing.assert_allclose(m.geom_size[roller][:2], [0.02, 0.1])
    wall = np.flatnonzero(m.geom_bodyid == m.body("wall").id)[0]
    assert m.geom_friction[wall][0] == pytest.approx(0.9)


def test_button_face_is_spring_loaded_with_a_travel_sensor(scene: sim.Scene) -> None:
    m, d = scene.model, mujoco.MjData(scene.model)
    joint = m.joint("button__travel")
    assert joint.stiffness[0] > 0 and m.sensor("button__travel").type[0] == mujoco.mjtSensor.mjSENS_JOINTPOS
    d.qpos[joint.qposadr[0]] = 0.02
    mujoco.mj_step(m, d, 500)
    assert d.sensordata[m.sensor("button__travel").adr[0]] < 0.002  # the spring pushes the face back out


def test_gripper_is_confined_to_the_workspace(scene: sim.Scene) -> None:
    limits = scene.task.limits
    for k, axis in enumerate("xyz"):
        np.testing.assert_allclose(scene.model.joint(f"robot_{axis}").range,
                                   [limits.workspace_min[k], limits.workspace_max[k]])
    assert scene.robot_body[scene.model.body("robot_gripper").id]
    assert scene.body_object[scene.model.body("button__face").id] == scene.object_index("button")


def test_magnetic_pairs_get_inactive_welds() -> None:
    cubes = [{"name": f"c{i}", "shape": "box", "center": [0.1 * i, 0, 0.015], "size": [0.03] * 3, "magnetic": True}
             for i in range(3)]
    m = sim.build(_task(cubes)).model
    names = [m.equality(i).name for i in range(m.neq)]
    assert sorted(n for n in names if n.startswith("magnet__")) == ["magnet__c0__c1", "magnet__c0__c2",
                                                                    "magnet__c1__c2"]
    assert not m.eq_active0.any()


def test_mujoco_warnings_go_to_logging_not_a_file(tmp_path, monkeypatch) -> None:
    """Regression: an unstable world used to leave MUJOCO_LOG.TXT in the working directory."""
    import mujoco

    import robotool.sim.backend_mujoco  # noqa: F401 - installs the warning handler

    monkeypatch.chdir(tmp_path)
    xml = "<mujoco><worldbody><body><freejoint/><geom size='.1'/></body></worldbody></mujoco>"
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.qvel[0] = float("nan")
    mujoco.mj_step(model, data)
    assert data.warning[mujoco.mjtWarning.mjWARN_BADQVEL].number == 1
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()


def test_a_non_finite_control_fails_only_its_world(sim_scene) -> None:
    """Regression: MuJoCo zeroes a NaN control and carries on; the world must be marked failed instead."""
    from robotool import sim

    simulator = sim.make_sim(sim_scene("milk_reaching_near"), 2, backend="mujoco")
    simulator.ctrl[0, 0] = float("nan")
    simulator.step(5, np.ones(2, dtype=bool))
    failed = simulator.state().failed
    assert failed[0] is not None and "non-finite control" in failed[0]
    assert failed[1] is None


@pytest.mark.parametrize(
    ("size", "mass", "sheet"),
    [
        ((0.6, 0.4, 0.0005), 0.05, True),  # the built-in strip of paper
        ((0.3, 0.3, 0.003), None, True),  # 3 mm at the default density: 0.9 kg per square metre
        ((0.3, 0.3, 0.003), 2.1, False),  # a steel plate, 23 kg per square metre: rigid
        ((0.3, 0.003, 0.3), 2.1, False),  # the same standing on edge
        ((0.3, 0.3, 0.004), 0.01, False),  # thicker than a sheet
    ],
)
def test_a_sheet_is_thin_and_light(size: tuple[float, float, float], mass: float | None, sheet: bool) -> None:
    """A rigid steel plate 3 mm thin was pinched like paper by fingertips resting on it (an adversarial run)."""
    obj = {"name": "plate", "shape": "box", "center": [0.3, 0.0, size[2] / 2], "size": list(size)}
    task = _task([obj if mass is None else {**obj, "mass": mass}])
    assert task.objects[0].is_sheet is sheet


def test_a_slippery_surface_is_slippery_against_anything() -> None:
    """Found by an adversarial run: MuJoCo takes the larger of two touching geoms' frictions, so a greased bar held
    at a rubber block's 1.0, and a rubber mat lay on ice as on rubber. The slippery geoms' contact priority ranks
    them, the most slippery highest: of two touching geoms the more slippery one's friction holds. A 1 kg block of the
    default friction on a slab of ice tilted 5 degrees slides down it; on a slab of the default friction it stays."""
    from robotool.sim.build import contact_friction

    assert contact_friction(1.0, 0.02) == 0.02 and contact_friction(1.0, 0.5) == 1.0
    assert contact_friction(0.3, 0.1) == 0.1
    slid = {}
    for friction in (0.02, 0.5):
        slab = {"name": "slab", "shape": "box", "center": [0.4, 0.0, 0.0362], "size": [0.6, 0.3, 0.02],
                "rpy": [0, 5, 0], "movable": False, "friction": friction}
        block = {"name": "block", "shape": "box", "center": [0.4026, 0.0, 0.0661], "size": [0.04, 0.04, 0.04],
                 "rpy": [0, 5, 0], "mass": 1.0}
        scene = sim.build(_task([block, slab]))
        model = scene.model
        priority = {model.geom(g).name: int(model.geom_priority[g]) for g in range(model.ngeom)}
        assert priority["slab__geom0"] == (1 if friction < 0.5 else 0) and priority["block__geom0"] == 0
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        start = data.xpos[model.body("block").id].copy()
        mujoco.mj_step(model, data, 500)
        slid[friction] = float(np.linalg.norm(data.xpos[model.body("block").id] - start))
    assert slid[0.02] > 0.05 and slid[0.5] < 0.005, slid


def test_every_slippery_friction_ranks_apart_below_the_quadrupeds_own() -> None:
    """Found by an adversarial run: slippery geoms' ranks were capped at 50, and 49 chips of distinct frictions made a
    greased puck share the top rank with a waxed chute, so MuJoCo held the pair at the wax's friction. Each distinct
    friction below the default now has its own rank, under the quadruped's geoms' (which keep their own)."""
    from robotool.robots.quadruped.body import CONTACT_PRIORITY
    from robotool.sim.build import MAX_SLIPPERY_PRIORITY

    chips = [
        {"name": f"chip{k}", "shape": "box", "center": [-0.4 + 0.04 * (k % 20), 0.4 + 0.04 * (k // 20), 0.005],
         "size": [0.02, 0.02, 0.01], "movable": False, "friction": 0.49 - 0.005 * k}
        for k in range(60)
    ]
    model = sim.build(_task([{"name": "puck", "shape": "box", "center": [0.3, 0.0, 0.01], "size": [0.02] * 3,
                              "mass": 0.02, "friction": 0.001}, *chips])).model
    names = ["puck", *(c["name"] for c in chips)]
    ranks = [int(model.geom_priority[model.geom(f"{name}__geom0").id]) for name in names]
    assert len(set(ranks)) == len(ranks) and ranks[0] == max(ranks) == 61, ranks
    assert CONTACT_PRIORITY > MAX_SLIPPERY_PRIORITY >= 201
