"""The quadruped's physical body: a Go1-sized torso on four extendable legs, free to pitch and roll, and its actuators.

The root body ``robot`` rides on slides along x, y and z and two hinges, pitch (about y) then roll (about x),
through its centre of mass; nothing holds its pitch or roll, so it tips over an edge when its centre of mass leaves
the support of its feet. The torso stands on four legs, each a child body ``robot_foot<i>`` (order
:data:`.terrain.FOOT_NAMES`) holding a capsule that ends in a round foot at a corner of the footprint, on a
slide joint ``robot_leg<i>`` along the body's up axis (0: the nominal stance; down to ``max_step_down`` plus
:data:`LEG_SLACK` below it) driven by a force-limited position servo: the legs' length keeps the body level over
uneven ground and its torso clear of what lies under it, and the legs' servos carry its weight onto whatever the
feet touch. The torso's underside rides :data:`BELLY_HEIGHT` above the feet, so that its faces push low objects. The
bounding box is ``limits.body_size``, the whole ``limits.mass`` rests on the feet's contacts, and each foot's
contacts can be read apart. x and y are driven by force-limited position servos (the legs' sideways push). z has a
lift motor that can only push up, with a force bounded by :data:`LIFT_FACTOR` times the robot's weight, and pitch
and roll have torque motors bounded by :data:`TILT_FACTOR` (weight times metres) that the controller uses only to
hold the body level while the lift carries it; it switches both on only while a foot crosses a step, a small gap or
a drop edge within the legs' limits, so that standing and walking, the full weight acts through the feet; while
they act, :mod:`.lift_load` puts their reaction on what the feet stand on, as legs would. The feet
and legs are frictionless (``condim`` 1, imposed through a higher contact ``priority`` than any scene geom's): the
servos, not the feet, carry the sideways forces, so walking does not drag the surface underfoot; :mod:`.lift_load`
puts the servos' reaction, as much of it as the feet's grip passes on, on what the feet stand on too (a stride rolls
a cart on free rollers back). The torso's faces grip what they push (:data:`TORSO_FRICTION`), so that an object
pushed off-centre turns no more than friction lets it. Robot geoms are in geom group :data:`ROBOT_GROUP`, which the
terrain rays skip.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from robotool.robots.quadruped.quadruped_skills import BELLY_HEIGHT, QuadrupedLimits
from robotool.robots.quadruped.terrain import FOOT_RADIUS, foot_offsets
from robotool.sim.build import MAX_SLIPPERY_PRIORITY
from robotool.task import geometry
from robotool.task.task_model import Task

BODY = "robot"
LEG_SHARE = 0.02  # of the robot's mass in each leg; the torso carries the rest
XY_KP = 20000.0  # N/m
XY_FORCE = 120.0  # N: the most the legs push sideways (about the weight: a blocked push cannot flip the body)
YAW_TWIST = 0.002  # rad the yaw servo gives under its whole torque (the legs' sideways push at the corners)
YAW_OMEGA = 100.0  # rad/s: the yaw's natural frequency, set by the hinge's armature (stiffer slows the solver)
LIFT_KP = 30000.0  # N/m
LIFT_FACTOR = 2.0  # the lift motor's force bound, in robot weights
TILT_FACTOR = 0.15  # m: the pitch and roll motors' torque bound, in robot weights times this lever
LEG_KP = 20000.0  # N/m of each leg's servo
LEG_FACTOR = 2.0  # each leg servo's force bound, in robot weights
LEG_SLACK = 0.05  # m a leg reaches below the deepest step down
LEG_RETRACT = 0.05  # m a leg can pull its foot up above the nominal stance
OFF = -100.0  # lift setpoint that saturates the motor at zero force
TILT_DAMPING = 3.0  # N m s/rad on pitch and roll (the legs' joint friction; it never holds the body up)
TORSO_FRICTION = 0.25  # the torso's faces grip what they push (the feet stay frictionless)
CONTACT_PRIORITY = MAX_SLIPPERY_PRIORITY + 1  # above every scene geom's: the robot's contacts keep their own rules
ROBOT_GROUP = 2  # geom group of the robot's geoms (shown by default; rays leave it out)
GRAVITY = 9.81


@dataclass(frozen=True)
class BodyIds:
    """Indices of the robot's bodies, joints and actuators in a compiled model, and its mass layout."""

    body: int
    feet: np.ndarray  # (4,) foot body ids
    qpos: np.ndarray  # (5,) qpos addresses of x, y, z, pitch, roll (x, y, z: the world coordinates of the feet's
    # bottom centre while level)
    qvel: np.ndarray  # (5,)
    actuator: np.ndarray  # (5,) x servo, y servo, lift motor, pitch motor, roll motor
    leg_qpos: np.ndarray  # (4,) qpos addresses of the legs' slides (0: nominal, negative: reaching down)
    leg_qvel: np.ndarray  # (4,)
    leg_actuator: np.ndarray  # (4,) the legs' servos
    yaw_qpos: int  # qpos address of the yaw hinge (rad, 0: the body's length along x)
    yaw_qvel: int
    yaw_actuator: int  # the yaw servo
    xy_kv: float  # N s/m of the x-y servos
    masses: np.ndarray  # (5,) the root body's mass, then the feet's
    com_offsets: np.ndarray  # (5, 3) each body's centre of mass in its own frame

    @classmethod
    def of(cls, model: mujoco.MjModel) -> BodyIds:
        joints = [model.joint(f"{BODY}_{a}") for a in ("x", "y", "z", "pitch", "roll")]
        acts = [model.actuator(f"{BODY}_{a}").id for a in ("x", "y", "lift", "pitch", "roll")]
        body = model.body(BODY).id
        feet = np.array([model.body(f"{BODY}_foot{i}").id for i in range(4)])
        bodies = np.array([body, *feet])
        return cls(
            body=body,
            feet=feet,
            qpos=np.array([model.jnt_qposadr[j.id] for j in joints]),
            qvel=np.array([model.jnt_dofadr[j.id] for j in joints]),
            actuator=np.array(acts),
            leg_qpos=np.array([model.jnt_qposadr[model.joint(f"{BODY}_leg{i}").id] for i in range(4)]),
            leg_qvel=np.array([model.jnt_dofadr[model.joint(f"{BODY}_leg{i}").id] for i in range(4)]),
            leg_actuator=np.array([model.actuator(f"{BODY}_leg{i}").id for i in range(4)]),
            yaw_qpos=int(model.jnt_qposadr[model.joint(f"{BODY}_yaw").id]),
            yaw_qvel=int(model.jnt_dofadr[model.joint(f"{BODY}_yaw").id]),
            yaw_actuator=model.actuator(f"{BODY}_yaw").id,
            xy_kv=float(-model.actuator_biasprm[acts[0], 2]),
            masses=model.body_mass[bodies].copy(),
            com_offsets=model.body_ipos[bodies].copy(),
        )


def start_height(task: Task) -> float:
    """Height of the surface under the robot's start footprint (cloth does not count)."""
    limits = _limits(task)
    feet = np.asarray(task.robot.position) + foot_offsets(limits)
    solids = [geometry.object_parts(o) for o in task.objects if o.shape != "cloth"]
    return float(geometry.surface_height(feet, solids).max())


def _limits(task: Task) -> QuadrupedLimits:
    limits = task.limits
    assert isinstance(limits, QuadrupedLimits)
    return limits


def add_body(spec: mujoco.MjSpec, task: Task) -> None:
    """Add the robot body, its joints, its four feet and its five actuators to ``spec``."""
    limits = _limits(task)
    sx, sy, sz = limits.body_size
    x0, y0 = task.robot.required_position()
    z0 = start_height(task) + 0.001
    leg_mass = LEG_SHARE * limits.mass
    torso_mass = limits.mass - 4 * leg_mass
    torso_z = (sz + BELLY_HEIGHT) / 2
    com_z = (torso_mass * torso_z + 4 * leg_mass * (FOOT_RADIUS + BELLY_HEIGHT) / 2) / limits.mass
    body = spec.worldbody.add_body(name=BODY, pos=[x0, y0, z0])
    for axis, ref in zip("xyz", (x0, y0, z0), strict=True):
        body.add_joint(
            name=f"{BODY}_{axis}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=np.eye(3)["xyz".index(axis)], ref=ref
        )
    twist = XY_FORCE * (sx + sy)  # N m: the legs' sideways push at the corners, the yaw servo's torque bound
    yaw_kp = twist / YAW_TWIST
    inertia = limits.mass * (sx**2 + sy**2) / 12 + yaw_kp / YAW_OMEGA**2  # about the vertical, armature included
    body.add_joint(
        name=f"{BODY}_yaw",
        type=mujoco.mjtJoint.mjJNT_HINGE,
        axis=[0, 0, 1],
        armature=yaw_kp / YAW_OMEGA**2,
    )
    for name, hinge in (("pitch", [0, 1, 0]), ("roll", [1, 0, 0])):
        body.add_joint(
            name=f"{BODY}_{name}",
            type=mujoco.mjtJoint.mjJNT_HINGE,
            axis=hinge,
            pos=[0, 0, com_z],
            damping=TILT_DAMPING,
            armature=0.01,
        )
    contact = {"condim": 1, "priority": CONTACT_PRIORITY, "group": ROBOT_GROUP}
    body.add_geom(
        name=f"{BODY}_torso",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[sx / 2, sy / 2, (sz - BELLY_HEIGHT) / 2],
        pos=[0, 0, torso_z],
        mass=torso_mass,
        **(contact | {"condim": 3, "friction": [TORSO_FRICTION, 0.005, 0.0001]}),
    )
    reach = limits.max_step_down + LEG_SLACK
    for i, (px, py) in enumerate(foot_offsets(limits)):
        foot = body.add_body(name=f"{BODY}_foot{i}", pos=[px, py, 0.0])
        foot.add_joint(
            name=f"{BODY}_leg{i}",
            type=mujoco.mjtJoint.mjJNT_SLIDE,
            axis=[0, 0, 1],
            range=[-reach, LEG_RETRACT],
            armature=0.05,
        )
        foot.add_geom(
            name=f"{BODY}_leg{i}",
            type=mujoco.mjtGeom.mjGEOM_CAPSULE,
            size=[FOOT_RADIUS, 0, 0],
            fromto=[0, 0, FOOT_RADIUS, 0, 0, BELLY_HEIGHT],
            mass=leg_mass,
            **contact,
        )
        leg = spec.add_actuator(name=f"{BODY}_leg{i}", target=f"{BODY}_leg{i}", trntype=mujoco.mjtTrn.mjTRN_JOINT)
        leg.set_to_position(kp=LEG_KP, kv=2.0 * np.sqrt(LEG_KP * limits.mass / 4))
        leg.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        leg.forcerange = [-LEG_FACTOR * limits.mass * GRAVITY, LEG_FACTOR * limits.mass * GRAVITY]
    kv = 2.0 * np.sqrt(XY_KP * limits.mass)
    for axis in "xy":
        act = spec.add_actuator(name=f"{BODY}_{axis}", target=f"{BODY}_{axis}", trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=XY_KP, kv=kv)
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = [-XY_FORCE, XY_FORCE]
    lift = spec.add_actuator(name=f"{BODY}_lift", target=f"{BODY}_z", trntype=mujoco.mjtTrn.mjTRN_JOINT)
    lift.set_to_position(kp=LIFT_KP, kv=2.0 * np.sqrt(LIFT_KP * limits.mass))
    lift.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    lift.forcerange = [0.0, LIFT_FACTOR * limits.mass * GRAVITY]
    for name in ("pitch", "roll"):
        tilt = spec.add_actuator(name=f"{BODY}_{name}", target=f"{BODY}_{name}", trntype=mujoco.mjtTrn.mjTRN_JOINT)
        tilt.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        tilt.ctrlrange = [-1.0, 1.0]
        tilt.gainprm[0] = TILT_FACTOR * limits.mass * GRAVITY  # torque per unit of control
    yaw = spec.add_actuator(name=f"{BODY}_yaw", target=f"{BODY}_yaw", trntype=mujoco.mjtTrn.mjTRN_JOINT)
    yaw.set_to_position(kp=yaw_kp, kv=2.0 * np.sqrt(yaw_kp * inertia))
    yaw.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    yaw.forcerange = [-twist, twist]
