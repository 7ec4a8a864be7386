"""Task -> ``mujoco.MjModel`` through ``mujoco.MjSpec``, and the id tables the simulator needs.

Every task object becomes a body named after it whose frame is the object's centre and rotation;
its geoms are :func:`robotool.task.geometry.object_parts`. Fixed objects are static bodies (welded to the
world); movable ones have a free joint, their mass and friction. A button is a fixed housing with a
face on its -x side, on a slide joint with the button's spring (``stiffness``, N/m, over ``travel``, m;
defaults in :mod:`robotool.task.scene`), whose travel is the sensor ``<name>__travel``; it counts as pressed
after :data:`PRESS_TRAVEL`.
Magnetic objects get an inactive weld ``magnet__<a>__<b>`` per pair (see :mod:`robotool.sim.magnets`).
A sheet (a thin, light box, like paper: :attr:`~robotool.task.scene.SceneObject.is_sheet`) collides with the ground
and the robot only; it meets each other movable object through a carrier geom of its own, in place only while the
object rests on the sheet (see :mod:`robotool.sim.sheets`), so its edge never shoves an object; a weld holds it to the
table while a load pins it down. A task file lays a sheet on the ground, never magnetic
(:mod:`robotool.task.task_file`).
Cloth is built as hinged links (:func:`robotool.sim.cloth.add_cloth`).
The robot is added by its embodiment (:mod:`robotool.sim.embodiment`).
"""

from __future__ import annotations

from itertools import combinations

import mujoco
import numpy as np

from robotool import robots
from robotool.sim.cloth import add_cloth
from robotool.sim.compiled_scene import Scene
from robotool.sim.embodiment import Embodiment
from robotool.task import geometry
from robotool.task.scene import SceneObject
from robotool.task.task_model import MAX_OBJECTS, Task

TIMESTEP = 0.002  # s, physics step
GROUND_FRICTION = 0.5
DEFAULT_FRICTION = 0.5
# Welds (grasps, magnetic joins) are nearly hard. MuJoCo scales a constraint's stiffness with the
# bodies' effective mass, so under a given force a light object's weld gives way in proportion to
# 1 / mass; the shortest stable time constant (2 steps) and an impedance of 0.999 keep a chain of 50 g
# cubes within about a degree when the servo shoves it sideways with ~40 N (tests/robots/arm/test_grasp.py).
WELD_SOLREF = (2 * TIMESTEP, 1.0)
WELD_SOLIMP = (0.999, 0.9995, 0.001, 0.5, 2.0)
SHEET_RESTING = 0.003  # m: an object whose bottom is this close to a sheet's top rests on it
SHEET_CARRIER_DROP = 10.0  # m a sheet's carrier geom is dropped below it while its object is not on it
SHEET_CARRIER_LIFT = 0.002  # m a carrier stands above its sheet, so what rests on it rests on it alone
MAX_SLIPPERY_PRIORITY = MAX_OBJECTS + 1  # a contact priority per friction below the default, and no more than a task
# declares (its objects' and the ground's): each its own, so no two slippery geoms share one (found by an adversarial
# run: a cap of 50 ranks, filled by 49 chips of distinct frictions, held a greased puck on a waxed chute at the wax's)
DEFAULT_BIT, SHEET_BIT, GROUND_BIT = 1, 2, 4  # contype/conaffinity bits: sheets touch the ground and the robot
BUTTON_FACE_DEPTH = 0.015  # m
BUTTON_DAMPING = 2.0  # N s/m
BUTTON_GUIDE_FRICTION = 1.0  # N: the face's guide resists sliding, so a sideways shove does not press it


def _quat(rot: np.ndarray) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(rot).reshape(-1))
    return q


def _add_part(
    body: mujoco.MjsBody, part: geometry.Part, frame_pos: np.ndarray, frame_rot: np.ndarray, name: str, **attrs: object
) -> mujoco.MjsGeom:
    """Add one convex part, given in the world, to a body whose frame is (frame_pos, frame_rot)."""
    pos = frame_rot.T @ (part.center - frame_pos)
    quat = _quat(frame_rot.T @ part.rot)
    if part.kind == "box":
        geom = body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, size=part.half, pos=pos, quat=quat)
    else:
        geom = body.add_geom(
            name=name, type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[part.half[0], part.half[2], 0], pos=pos, quat=quat
        )
    for key, value in attrs.items():
        setattr(geom, key, value)
    return geom


def _part_volume(part: geometry.Part) -> float:
    if part.kind == "box":
        return float(8 * np.prod(part.half))
    return float(np.pi * part.half[0] ** 2 * 2 * part.half[2])


def _add_object(spec: mujoco.MjSpec, obj: SceneObject) -> None:
    center = np.asarray(obj.center, dtype=float)
    rot = geometry.rotation_matrix(obj.rpy)
    body = spec.worldbody.add_body(name=obj.name, pos=center, quat=_quat(rot))
    friction = [obj.friction or DEFAULT_FRICTION, 0.005, 0.0001]
    parts = geometry.object_parts(obj)
    if obj.shape == "button":
        _add_button(body, obj, friction)
        return
    attrs: dict[str, object] = {"friction": friction}
    if obj.movable:
        body.add_freejoint(name=f"{obj.name}__free")
        attrs["density"] = obj.effective_mass / sum(_part_volume(p) for p in parts)
    if obj.is_sheet:  # touches the ground and the robot; other objects only through its carriers
        attrs |= {"contype": SHEET_BIT, "conaffinity": GROUND_BIT}
    for k, part in enumerate(parts):
        _add_part(body, part, center, rot, name=object_geom_name(obj.name, k), **attrs)


def _add_button(body: mujoco.MjsBody, obj: SceneObject, friction: list[float]) -> None:
    """A fixed housing with a spring-loaded face on its -x side (in the button's own frame)."""
    sx, sy, sz = obj.size
    depth = min(BUTTON_FACE_DEPTH, 0.2 * sx)
    travel = obj.button_travel
    housing_x0 = -sx / 2 + depth + travel
    body.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[(sx / 2 - housing_x0) / 2, sy / 2, sz / 2],
        pos=[(housing_x0 + sx / 2) / 2, 0, 0],
        friction=friction,
    )
    face = body.add_body(name=f"{obj.name}__face", pos=[-sx / 2 + depth / 2, 0, 0])
    face.add_joint(
        name=f"{obj.name}__travel",
        type=mujoco.mjtJoint.mjJNT_SLIDE,
        axis=[1, 0, 0],
        stiffness=obj.button_stiffness,
        damping=BUTTON_DAMPING,
        frictionloss=BUTTON_GUIDE_FRICTION,
        range=[0, travel],
        limited=mujoco.mjtLimited.mjLIMITED_TRUE,
    )
    face.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[depth / 2, 0.4 * sy, 0.4 * sz],
        mass=0.02,
        friction=friction,
        rgba=[0.8, 0.1, 0.1, 1],
    )


def make_spec(task: Task, embodiment: Embodiment) -> mujoco.MjSpec:
    """The task's ``MjSpec``: ground, objects, magnet welds, button sensors and the robot."""
    spec = mujoco.MjSpec()
    spec.option.timestep = TIMESTEP
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.worldbody.add_geom(
        name="ground",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[5, 5, 0.1],
        friction=[GROUND_FRICTION, 0.005, 0.0001],
        contype=DEFAULT_BIT | GROUND_BIT,
        conaffinity=DEFAULT_BIT | GROUND_BIT,
    )
    for obj in task.objects:
        if obj.shape == "cloth":
            add_cloth(spec, obj)
        else:
            _add_object(spec, obj)
        if obj.shape == "button":
            spec.add_sensor(
                name=f"{obj.name}__travel",
                type=mujoco.mjtSensor.mjSENS_JOINTPOS,
                objtype=mujoco.mjtObj.mjOBJ_JOINT,
                objname=f"{obj.name}__travel",
            )
    magnets = [o.name for o in task.objects if o.magnetic]
    for a, b in combinations(magnets, 2):
        spec.add_equality(
            name=f"magnet__{a}__{b}",
            type=mujoco.mjtEq.mjEQ_WELD,
            objtype=mujoco.mjtObj.mjOBJ_BODY,
            name1=a,
            name2=b,
            active=False,
            solref=WELD_SOLREF,
            solimp=WELD_SOLIMP,
        )
    _add_sheet_pairs(spec, task)
    _rank_slippery(spec)
    embodiment.add_to_spec(spec, task)
    return spec


def contact_friction(a: float | np.ndarray, b: float | np.ndarray) -> float | np.ndarray:
    """The sliding friction two touching surfaces of frictions ``a`` and ``b`` hold at: the larger of the two's, unless
    one is more slippery than the default (:data:`DEFAULT_FRICTION`): then the more slippery one's (a greased face is
    slippery against rubber too). MuJoCo takes the larger of two geoms' frictions; :func:`make_spec` ranks the
    slippery geoms' contact ``priority`` so that it takes this instead."""
    low, high = np.minimum(a, b), np.maximum(a, b)
    out = np.where(low < DEFAULT_FRICTION, low, high)
    return float(out) if np.ndim(out) == 0 else out


def _rank_slippery(spec: mujoco.MjSpec) -> None:
    """Give the scene's geoms more slippery than the default a contact priority, the more slippery the higher: of two
    touching geoms MuJoCo takes the higher priority's friction (:func:`contact_friction`). Geoms added after this
    (the robot's) keep their own rules; a robot whose contacts must set their own parameters ranks above
    :data:`MAX_SLIPPERY_PRIORITY`."""
    slippery = sorted({float(g.friction[0]) for g in spec.geoms if g.friction[0] < DEFAULT_FRICTION}, reverse=True)
    if len(slippery) > MAX_SLIPPERY_PRIORITY:
        raise ValueError(f"{len(slippery)} frictions below the default: a task has {MAX_SLIPPERY_PRIORITY} at most")
    rank = {mu: k + 1 for k, mu in enumerate(slippery)}
    for geom in spec.geoms:
        if geom.friction[0] < DEFAULT_FRICTION:
            geom.priority = rank[float(geom.friction[0])]


def object_geom_name(obj: str, part: int) -> str:
    """Name of the geom of part ``part`` of object ``obj``."""
    return f"{obj}__geom{part}"


def sheet_carrier_name(sheet: str, obj: str) -> str:
    """Name of the geom through which sheet ``sheet`` carries object ``obj``."""
    return f"{sheet}__carries__{obj}"


def sheet_pin_name(sheet: str) -> str:
    """Name of the weld that holds sheet ``sheet`` to the table while a load pins it down."""
    return f"{sheet}__pinned"


def _add_sheet_pairs(spec: mujoco.MjSpec, task: Task) -> None:
    """For every sheet and every other movable object: a carrier geom on the sheet that only that object meets;
    and per sheet an inactive weld to the world, :func:`sheet_pin_name`, on while a load pins the sheet down.

    The carrier is a copy of the sheet's box :data:`SHEET_CARRIER_LIFT` higher (so the object rests on
    it alone, not half on the table), without mass, invisible and without automatic collisions, in an
    explicit contact pair with each part of the object. It is in place for objects that rest on
    the sheet at the start and dropped :data:`SHEET_CARRIER_DROP` below it otherwise;
    :mod:`robotool.sim.sheets` moves it and switches the weld while the world runs.
    """
    for sheet in (o for o in task.objects if o.is_sheet and o.movable):
        spec.add_equality(
            name=sheet_pin_name(sheet.name),
            type=mujoco.mjtEq.mjEQ_WELD,
            objtype=mujoco.mjtObj.mjOBJ_BODY,
            name1=sheet.name,
            name2="world",
            active=False,
            solref=WELD_SOLREF,
            solimp=WELD_SOLIMP,
        )
        body = spec.body(sheet.name)
        (part,) = geometry.object_parts(sheet)
        centre, rot = np.asarray(sheet.center, dtype=float), geometry.rotation_matrix(sheet.rpy)
        for obj in (o for o in task.objects if o.movable and not o.is_sheet and o.shape != "cloth"):
            mu = sheet_friction(sheet, obj)
            carrier = _add_part(
                body,
                part,
                centre,
                rot,
                name=sheet_carrier_name(sheet.name, obj.name),
                contype=0,
                conaffinity=0,
                mass=0.0,
                rgba=[0, 0, 0, 0],
            )
            drop = 0.0 if rests_on_sheet(obj, sheet) else SHEET_CARRIER_DROP
            carrier.pos = np.asarray(carrier.pos) + np.array([0.0, 0.0, SHEET_CARRIER_LIFT - drop])
            for k in range(len(geometry.object_parts(obj))):
                spec.add_pair(
                    geomname1=sheet_carrier_name(sheet.name, obj.name),
                    geomname2=object_geom_name(obj.name, k),
                    condim=3,
                    friction=[mu, mu, 0.005, 0.0001, 0.0001],
                )


def sheet_friction(sheet: SceneObject, obj: SceneObject) -> float:
    """The friction between a sheet and an object on it (its carrier's contact pair, :func:`contact_friction`)."""
    return float(contact_friction(sheet.friction or DEFAULT_FRICTION, obj.friction or DEFAULT_FRICTION))


def rests_on_sheet(obj: SceneObject, sheet: SceneObject) -> bool:
    """Whether ``obj`` stands on ``sheet`` in the task file: its bottom on the sheet's top, its centre over it."""
    local = geometry.rotation_matrix(sheet.rpy).T @ (np.asarray(obj.center) - np.asarray(sheet.center))
    over = abs(local[0]) <= sheet.size[0] / 2 and abs(local[1]) <= sheet.size[1] / 2
    return over and abs(obj.bottom - sheet.top) <= SHEET_RESTING


def embodiment_for(task: Task) -> Embodiment:
    """The simulator embodiment of ``task.robot.type`` (from the robot registry), with the task's limits."""
    return robots.get(task.robot.type).sim.embodiment(task.limits)


def build(task: Task) -> Scene:
    """Compile a task into a :class:`Scene` (model, object/body tables, buffer sizes)."""
    embodiment = embodiment_for(task)
    model = make_spec(task, embodiment).compile()
    names = tuple(o.name for o in task.objects)
    object_body = np.array([model.body(n).id for n in names], dtype=int)
    body_object = np.full(model.nbody, -1, dtype=int)
    robot_body = np.zeros(model.nbody, dtype=bool)
    for b in range(model.nbody):
        root = b
        while model.body_parentid[root] != 0:
            root = model.body_parentid[root]
        hits = np.flatnonzero(object_body == root)
        if hits.size:
            body_object[b] = hits[0]
        elif b != 0:
            robot_body[b] = model.body(root).name.startswith("robot")
    grasp_local = np.zeros((len(names), 3))
    for i, obj in enumerate(task.objects):
        rot = geometry.rotation_matrix(obj.rpy)
        grasp_local[i] = rot.T @ (np.asarray(obj.grasp_point) - np.asarray(obj.center))
    nconmax = max(32, 8 * model.ngeom)
    njmax = 4 * nconmax + 6 * model.neq + 2 * model.njnt
    return Scene(
        task=task,
        model=model,
        object_names=names,
        object_body=object_body,
        body_object=body_object,
        robot_body=robot_body,
        grasp_local=grasp_local,
        control_substeps=embodiment.control_substeps,
        nconmax=nconmax,
        njmax=njmax,
    )
