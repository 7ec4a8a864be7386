"""The arm's body: a translating two-finger gripper inside the workspace box (BENCHMARK.md section 3), as MuJoCo
elements, and what is read from it (the held object, the objects' graspable points).

The gripper body ``robot_gripper`` rides on three slide joints whose coordinates are the gripper
centre in the world (``ref`` = home, so ``qpos`` is absolute); position servos with force limits
drive them, so a blocked motion really stalls. The servos follow a low-passed reference (their activation), which
starts at home (the model's start keyframe, :attr:`~robotool.sim.compiled_scene.Scene.initial_act`): from MuJoCo's
0 it pulled the gripper 0.12 m down towards the origin and back at up to 3.9 m/s before a program started. The joint
ranges are the workspace. The palm above the centre and the two fingers collide; the fingers close along the world y
axis on position servos until they meet something or close fully. One weld ``robot_grasp__<object>`` per movable
object stands for a grasp (:mod:`.arm_grasp`).
"""

from __future__ import annotations

import mujoco
import numpy as np

from robotool.robots.arm.arm_config import ARM, finger_open
from robotool.robots.arm.arm_skills import ArmLimits
from robotool.sim.backend import BatchState
from robotool.sim.build import DEFAULT_BIT, SHEET_BIT, WELD_SOLIMP, WELD_SOLREF
from robotool.sim.compiled_scene import START_KEY, Scene
from robotool.task.task_model import Task

GRIPPER_BODY = "robot_gripper"
GRASP_EQ_PREFIX = "robot_grasp__"
SERVO_KP, SERVO_KV, SERVO_FORCE = 2000.0, 80.0, 100.0  # N/m, N s/m, N
SERVO_FILTER = 0.05  # s: the servo follows a low-passed reference, so the tick-wise steps do not jerk
FINGER_KP, FINGER_KV = 50.0, 2.0  # N/m, N s/m: about 1 N of squeeze on a 4 cm object
CONTACT_SOLREF, CONTACT_SOLIMP = (0.005, 1.0), (0.95, 0.99, 0.001, 0.5, 2.0)  # the gripper's hard surfaces
# Friction that holds on the table top: with MuJoCo's default pyramidal cone and soft friction, a block pressed
# from above by a held stick dragged across it crept about 7% of the drag, although the ground (more load, the
# same coefficient) must hold it still, so repeated presses dragged things in from beyond reach; elliptic cones
# with friction ten times stiffer than the normal force (impratio) bring the creep under 0.5%
# (tests/robots/arm/test_cheats.py).
FRICTION_CONE, IMPRATIO = mujoco.mjtCone.mjCONE_ELLIPTIC, 10.0
AXES = "xyz"
SIDES = ("left", "right")


def grasp_eq_name(obj: str) -> str:
    """Name of the weld that holds ``obj`` in the gripper."""
    return f"{GRASP_EQ_PREFIX}{obj}"


def add_body(spec: mujoco.MjSpec, task: Task, limits: ArmLimits) -> None:
    """Gripper on x/y/z slides with position servos, two colliding fingers, one grasp weld per movable object;
    friction that does not creep."""
    spec.option.cone, spec.option.impratio = FRICTION_CONE, IMPRATIO
    lo, hi = limits.workspace_min, limits.workspace_max
    gripper = spec.worldbody.add_body(name=GRIPPER_BODY, pos=ARM.home, gravcomp=1.0)
    for k, axis in enumerate(AXES):
        direction = [0.0, 0.0, 0.0]
        direction[k] = 1.0
        gripper.add_joint(
            name=f"robot_{axis}",
            type=mujoco.mjtJoint.mjJNT_SLIDE,
            axis=direction,
            ref=ARM.home[k],
            range=[lo[k], hi[k]],
            armature=0.01,
        )
        act = spec.add_actuator(name=f"robot_{axis}", target=f"robot_{axis}", trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=SERVO_KP, kv=SERVO_KV, timeconst=SERVO_FILTER)
        act.ctrlrange = [lo[k], hi[k]]
        act.forcerange = [-SERVO_FORCE, SERVO_FORCE]
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    gripper.add_geom(
        name="robot_palm",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=ARM.palm_half,
        pos=[0, 0, ARM.palm_clearance + ARM.palm_half[2]],
        mass=0.5,
        solref=CONTACT_SOLREF,
        solimp=CONTACT_SOLIMP,
        conaffinity=DEFAULT_BIT | SHEET_BIT,
    )
    for side, sign in zip(SIDES, (1.0, -1.0), strict=True):
        finger = gripper.add_body(name=f"robot_finger_{side}", pos=[0, 0, 0], gravcomp=1.0)
        finger.add_joint(
            name=f"robot_finger_{side}",
            type=mujoco.mjtJoint.mjJNT_SLIDE,
            axis=[0, sign, 0],
            range=[0, finger_open(limits.gripper_opening)],
        )
        finger.add_geom(
            name=f"robot_finger_{side}",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=ARM.finger_half,
            pos=[0, 0, ARM.finger_z],
            mass=0.02,
            friction=[1.0, 0.005, 0.0001],
            solref=CONTACT_SOLREF,
            solimp=CONTACT_SOLIMP,
            conaffinity=DEFAULT_BIT | SHEET_BIT,
        )
        act = spec.add_actuator(
            name=f"robot_finger_{side}", target=f"robot_finger_{side}", trntype=mujoco.mjtTrn.mjTRN_JOINT
        )
        act.set_to_position(kp=FINGER_KP, kv=FINGER_KV)
        act.ctrlrange = [0, finger_open(limits.gripper_opening)]
    spec.add_exclude(bodyname1="robot_finger_left", bodyname2="robot_finger_right")
    _add_start_key(spec)
    for obj in task.objects:
        if obj.movable and obj.shape != "cloth":
            spec.add_equality(
                name=grasp_eq_name(obj.name),
                type=mujoco.mjtEq.mjEQ_WELD,
                objtype=mujoco.mjtObj.mjOBJ_BODY,
                name1=GRIPPER_BODY,
                name2=obj.name,
                active=False,
                solref=WELD_SOLREF,
                solimp=WELD_SOLIMP,
            )


def _add_start_key(spec: mujoco.MjSpec) -> None:
    """The start keyframe: the x/y/z servos' filtered references at home, every other activation at 0 (its ``qpos``
    is left to ``qpos0``). Added after the last actuator: the keyframe lists every actuator state of the model."""
    home = {f"robot_{axis}": ARM.home[k] for k, axis in enumerate(AXES)}
    act: list[float] = []
    for actuator in spec.actuators:
        if actuator.dyntype != mujoco.mjtDyn.mjDYN_NONE:
            act += [home.get(actuator.name, 0.0)] * max(actuator.actdim, 1)
    spec.add_key(name=START_KEY, act=act)


def held_objects(scene: Scene, state: BatchState) -> np.ndarray:
    """Index of the object the gripper holds in each world, or -1, from the grasp welds (nworld,)."""
    model = scene.model
    held = np.full(state.time.shape[0], -1)
    for i, name in enumerate(scene.object_names):
        eq = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_EQUALITY, grasp_eq_name(name))
        if eq >= 0:
            held[state.eq_active[:, eq]] = i
    return held


def graspable_points(scene: Scene, state: BatchState) -> np.ndarray:
    """Every object's graspable point in every world, moved with its body (nworld, nobject, 3)."""
    out = np.zeros((state.time.shape[0], len(scene.object_names), 3))
    for i, body in enumerate(scene.object_body):
        out[:, i] = state.xpos[:, body] + np.einsum("wij,j->wi", state.xmat(body), scene.grasp_local[i])
    return out
