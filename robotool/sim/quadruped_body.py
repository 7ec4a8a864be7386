"""The quadruped's physical body: a Go1-sized rigid body on three slide joints, and its actuators.

The body never rotates. Four capsule legs end in round feet at the corners of its footprint and a
torso box sits on them, so the bounding box is ``limits.body_size`` and the whole ``limits.mass``
rests on whatever the feet touch. x and y are driven by force-limited position servos. z has a
motor that can only push up (force range ``[0, LIFT_FORCE]``): it lifts the body while a step up is
being crossed and is switched off otherwise, so that standing, the full weight acts on the support.
Robot contacts are frictionless (``condim`` 1, imposed through a higher contact ``priority`` than the
scene's geoms): the servos, not the feet, carry the sideways forces, so walking does not drag the
surface underfoot and pushing does not lift what is pushed.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from robotool import geometry
from robotool.embodiments import QuadrupedLimits
from robotool.scene import Task

BODY = "robot"
LEG_HEIGHT = 0.05  # m: torso underside above the feet's bottom (its faces push objects)
FOOT_RADIUS = 0.03  # m
LEG_MASS = 0.25  # kg each; the torso carries the rest
XY_KP = 20000.0  # N/m
XY_FORCE = 300.0  # N: the most the legs push sideways
LIFT_KP = 30000.0  # N/m
LIFT_FORCE = 600.0  # N
OFF = -100.0  # lift setpoint that saturates the motor at zero force


@dataclass(frozen=True)
class BodyIds:
    """Indices of the robot's body, joints and actuators in a compiled model."""

    body: int
    qpos: np.ndarray  # (3,) qpos addresses of x, y, z (each the world coordinate of the feet's bottom centre)
    qvel: np.ndarray  # (3,)
    actuator: np.ndarray  # (3,) x servo, y servo, lift motor
    xy_kv: float  # N s/m of the x-y servos

    @classmethod
    def of(cls, model: mujoco.MjModel) -> BodyIds:
        joints = [model.joint(f"{BODY}_{a}") for a in "xyz"]
        acts = [model.actuator(f"{BODY}_{a}").id for a in ("x", "y", "lift")]
        return cls(
            body=model.body(BODY).id,
            qpos=np.array([model.jnt_qposadr[j.id] for j in joints]),
            qvel=np.array([model.jnt_dofadr[j.id] for j in joints]),
            actuator=np.array(acts),
            xy_kv=float(-model.actuator_biasprm[acts[0], 2]),
        )


def start_height(task: Task) -> float:
    """Height of the surface under the robot's start footprint (cloth does not count)."""
    limits = _limits(task)
    x, y = task.robot.position  # type: ignore[misc]
    hx, hy = limits.body_size[0] / 2 - FOOT_RADIUS, limits.body_size[1] / 2 - FOOT_RADIUS
    feet = np.array([[x + sx * hx, y + sy * hy] for sx in (-1, 1) for sy in (-1, 1)])
    solids = [geometry.object_parts(o) for o in task.objects if o.shape != "cloth"]
    return float(geometry.surface_height(feet, solids).max())


def _limits(task: Task) -> QuadrupedLimits:
    limits = task.limits
    assert isinstance(limits, QuadrupedLimits)
    return limits


def add_body(spec: mujoco.MjSpec, task: Task) -> None:
    """Add the robot body, its slide joints and its three actuators to ``spec``."""
    limits = _limits(task)
    sx, sy, sz = limits.body_size
    x0, y0 = task.robot.position  # type: ignore[misc]
    z0 = start_height(task) + 0.001
    body = spec.worldbody.add_body(name=BODY, pos=[x0, y0, z0])
    for axis, ref in zip("xyz", (x0, y0, z0), strict=True):
        body.add_joint(
            name=f"{BODY}_{axis}",
            type=mujoco.mjtJoint.mjJNT_SLIDE,
            axis=np.eye(3)["xyz".index(axis)],
            ref=ref,
        )
    contact = {"condim": 1, "priority": 1}
    torso_mass = limits.mass - 4 * LEG_MASS
    body.add_geom(
        name=f"{BODY}_torso",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[sx / 2, sy / 2, (sz - LEG_HEIGHT) / 2],
        pos=[0, 0, (sz + LEG_HEIGHT) / 2],
        mass=torso_mass,
        **contact,
    )
    hx, hy = sx / 2 - FOOT_RADIUS, sy / 2 - FOOT_RADIUS
    for i, (px, py) in enumerate((px, py) for px in (-hx, hx) for py in (-hy, hy)):
        body.add_geom(
            name=f"{BODY}_leg{i}",
            type=mujoco.mjtGeom.mjGEOM_CAPSULE,
            size=[FOOT_RADIUS, 0, 0],
            fromto=[px, py, FOOT_RADIUS, px, py, LEG_HEIGHT],
            mass=LEG_MASS,
            **contact,
        )
    kv = 2.0 * np.sqrt(XY_KP * limits.mass)
    for axis in "xy":
        act = spec.add_actuator(
            name=f"{BODY}_{axis}", target=f"{BODY}_{axis}", trntype=mujoco.mjtTrn.mjTRN_JOINT
        )
        act.set_to_position(kp=XY_KP, kv=kv)
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = [-XY_FORCE, XY_FORCE]
    lift = spec.add_actuator(name=f"{BODY}_lift", target=f"{BODY}_z", trntype=mujoco.mjtTrn.mjTRN_JOINT)
    lift.set_to_position(kp=LIFT_KP, kv=2.0 * np.sqrt(LIFT_KP * limits.mass))
    lift.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    lift.forcerange = [0.0, LIFT_FORCE]
