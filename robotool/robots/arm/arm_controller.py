"""The arm embodiment: a translating two-finger gripper inside the workspace box (BENCHMARK.md section 3).

The gripper body ``robot_gripper`` rides on three slide joints whose coordinates are the gripper
centre in the world (``ref`` = home, so ``qpos`` is absolute); position servos with force limits
drive them, so a blocked motion really stalls. The joint ranges are the workspace; targets outside
it are clamped and the clamp is recorded. The palm above the centre and the two fingers collide; the
fingers close along the world y axis on position servos until they meet something or close fully.

``close_gripper`` holds an object only when both fingers touch it from its sides (not resting on top
of it, nor pressing their fronts on a face of it), it lies between them (beside the fingers none of it
reaches past their inner faces), and it is no wider across them than the opening (a sheet is pinched
when both fingertips press on it: they gather a fold of it); it is then attached
rigidly by the weld ``robot_grasp__<object>`` (one per movable object) at the current pose, as
grasp-assisted simulators do, and released by ``open_gripper``. Otherwise the call reports what the
fingers met and why nothing is held, as a typed ``grasp_failed`` event with the measured values.

The weld stands for a friction grip, so it holds only what that grip can (:class:`_Hold`): the pads must
cover at least half of what they could of the object across their width (a pinch of its last millimetres
at an edge is no grip), and the squeeze of :data:`GRIP_FORCE` per pad must carry the load, the weight of
the held object and of everything joined to it, and its torque about the pads (the weight's lever along
the pads against the grip's depth across them, its lever along the closing axis against the width between
them). A grip that cannot is refused at ``close_gripper``; one that stops holding when more is joined to
it (a magnetic chain grown from it) lets go at once and the skill reports it.
Each motion skill also reports objects it pushed further out of the workspace (``pushed_out``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from itertools import combinations
from typing import Any

import mujoco
import numpy as np

from robotool.robots.arm.arm_skills import ArmLimits
from robotool.rollout import Event, GraspFailure
from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.build import DEFAULT_BIT, SHEET_BIT, WELD_SOLIMP, WELD_SOLREF, is_sheet
from robotool.sim.compiled_scene import Scene
from robotool.sim.embodiment import QueryError, SkillEnd, size_now, world_mask
from robotool.task.task_model import Task

GRIPPER_BODY = "robot_gripper"
GRASP_EQ_PREFIX = "robot_grasp__"
HOME = (0.1, 0.0, 0.3)  # m, gripper centre at the start
SPEED = 0.25  # m/s, straight-line reference speed
SERVO_KP, SERVO_KV, SERVO_FORCE = 2000.0, 80.0, 100.0  # N/m, N s/m, N
SERVO_FILTER = 0.05  # s: the servo follows a low-passed reference, so the tick-wise steps do not jerk
REACHED = 0.005  # m: a move is done when the centre is this close to the target
STALL_ERROR, STALL_SPEED, STALL_TIME = 0.01, 0.02, 0.3  # m, m/s, s
TIME_MARGIN = 2.0  # s a move may take beyond distance / speed
GRIPPER_TIME = 0.3  # s to open or close the fingers
FINGER_HALF = (0.008, 0.004, 0.023)  # m, half sizes of a finger (x, y across the closing axis, z)
FINGER_Z = 0.007  # m, a finger's centre above the gripper centre: the tips reach 0.016 m below it
FINGER_KP, FINGER_KV = 50.0, 2.0  # N/m, N s/m: about 1 N of squeeze on a 4 cm object
GRIP_TOLERANCE = 0.003  # m: geometry within this of a finger counts as next to it
ON_TOP = 0.002  # m: fingertips less than this below an object's top rest on it
OPENING_GIVE = 1e-4  # m the open fingers' stops may give before what is between them counts as too wide
SIDE_SLACK = 0.001  # m: beside the fingers, an object they grip may reach this far into them (contact give)
CLAMP_TOLERANCE = 1e-4  # m: a target this close to the workspace counts as inside (no clamp is reported)
ON_SHEET = 0.003  # m: a fingertip this close above a top face (or a sheet) it overlaps rests on it
PUSHED_OUT = 0.02  # m an object must be pushed further out of the workspace to be reported
CONTACT_SOLREF, CONTACT_SOLIMP = (0.005, 1.0), (0.95, 0.99, 0.001, 0.5, 2.0)  # the gripper's hard surfaces
PALM_HALF = (0.02, 0.05, 0.01)  # m
PALM_CLEARANCE = 0.03  # m from the centre up to the palm's underside
# Friction that holds on the table top: with MuJoCo's default pyramidal cone and soft friction, a block pressed
# from above by a held stick dragged across it crept about 7% of the drag, although the ground (more load, the
# same coefficient) must hold it still, so repeated presses dragged things in from beyond reach; elliptic cones
# with friction ten times stiffer than the normal force (impratio) bring the creep under 0.5%
# (tests/robots/arm/test_cheats.py).
FRICTION_CONE, IMPRATIO = mujoco.mjtCone.mjCONE_ELLIPTIC, 10.0
# The grip a grasp weld stands for (module docstring): each pad squeezes with GRIP_FORCE and holds by friction
# GRIP_FRICTION times that; a frictional couple across the depth the pads engage resists a torque about them.
# GRIP_FORCE is the continuous squeeze of a parallel gripper of this size (a Franka hand's is 70 N); the largest
# load an honest tool puts on it, the hammer held by its handle end with its head 0.17 m away, needs 0.71 N m
# across the pads' 16 mm, 45 N. EDGE_SHARE of what the pads could cover of an object across their width is the
# least that is a grip rather than a pinch at its edge.
GRIP_FORCE, GRIP_FRICTION, EDGE_SHARE = 60.0, 1.0, 0.5  # N, -, -
GRAVITY = 9.81  # m/s^2

_IDLE, _MOVE, _FINGERS = 0, 1, 2
_AXES = "xyz"
_SIDES = ("left", "right")


def finger_open(limits: ArmLimits) -> float:
    """Each finger's offset from the gripper centre when open (0 when fully closed), m."""
    return limits.gripper_opening / 2 + FINGER_HALF[1]


def grasp_eq_name(obj: str) -> str:
    """Name of the weld that holds ``obj`` in the gripper."""
    return f"{GRASP_EQ_PREFIX}{obj}"


class ArmEmbodiment:
    """:class:`~robotool.sim.embodiment.Embodiment` for the arm."""

    control_substeps = 50  # 10 Hz: the servos track interpolated targets, so a slower tick loses nothing

    def __init__(self, limits: ArmLimits):
        self.limits = limits

    def add_to_spec(self, spec: mujoco.MjSpec, task: Task) -> None:
        """Gripper on x/y/z slides with position servos, two colliding fingers, one grasp weld per movable object;
        friction that does not creep."""
        spec.option.cone, spec.option.impratio = FRICTION_CONE, IMPRATIO
        lo, hi = self.limits.workspace_min, self.limits.workspace_max
        gripper = spec.worldbody.add_body(name=GRIPPER_BODY, pos=HOME, gravcomp=1.0)
        for k, axis in enumerate(_AXES):
            direction = [0.0, 0.0, 0.0]
            direction[k] = 1.0
            gripper.add_joint(
                name=f"robot_{axis}",
                type=mujoco.mjtJoint.mjJNT_SLIDE,
                axis=direction,
                ref=HOME[k],
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
            size=PALM_HALF,
            pos=[0, 0, PALM_CLEARANCE + PALM_HALF[2]],
            mass=0.5,
            solref=CONTACT_SOLREF,
            solimp=CONTACT_SOLIMP,
            conaffinity=DEFAULT_BIT | SHEET_BIT,
        )
        for side, sign in zip(_SIDES, (1.0, -1.0), strict=True):
            finger = gripper.add_body(name=f"robot_finger_{side}", pos=[0, 0, 0], gravcomp=1.0)
            finger.add_joint(
                name=f"robot_finger_{side}",
                type=mujoco.mjtJoint.mjJNT_SLIDE,
                axis=[0, sign, 0],
                range=[0, finger_open(self.limits)],
            )
            finger.add_geom(
                name=f"robot_finger_{side}",
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=FINGER_HALF,
                pos=[0, 0, FINGER_Z],
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
            act.ctrlrange = [0, finger_open(self.limits)]
        spec.add_exclude(bodyname1="robot_finger_left", bodyname2="robot_finger_right")
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

    def controller(self, sim: BatchedSim) -> ArmController:
        """Skill controller for every world of ``sim``."""
        return ArmController(sim, self.limits)


@dataclass(frozen=True)
class _Hold:
    """How the pads engage a held object: depth across the pads (world x) and the least that is a grip there,
    width between them (world y), and the engaged patch's centre relative to the gripper centre."""

    depth: float
    edge_need: float
    width: float
    centre: np.ndarray

    def need(self, weight: float, lever: np.ndarray) -> tuple[float, float]:
        """The depth across the pads and the width between them that hold ``weight`` (N) whose centre lies
        ``lever`` (x, y) from the patch: the weight's torque over the grip's friction couple."""
        grip = GRIP_FRICTION * GRIP_FORCE
        return max(self.edge_need, weight * abs(float(lever[0])) / grip), weight * abs(float(lever[1])) / grip


@dataclass(frozen=True)
class _Grip:
    """Where the fingers are in one world: the inner faces across the closing axis (world y), their x and z spans."""

    left: float
    right: float
    x: tuple[float, float]
    z: tuple[float, float]

    @property
    def gap(self) -> float:
        return self.left - self.right


class ArmController:
    """Runs move/open/close in every world; answers the arm's queries from the batched state."""

    def __init__(self, sim: BatchedSim, limits: ArmLimits):
        self.sim, self.limits, self.scene = sim, limits, sim.scene
        model = self.scene.model
        self.gripper = model.body(GRIPPER_BODY).id
        self.xyz_act = np.array([model.actuator(f"robot_{a}").id for a in _AXES])
        self.finger_act = np.array([model.actuator(f"robot_finger_{s}").id for s in _SIDES])
        self.finger_body = np.array([model.body(f"robot_finger_{s}").id for s in _SIDES])
        self.finger_qpos = np.array([model.jnt_qposadr[model.joint(f"robot_finger_{s}").id] for s in _SIDES])
        self.xyz_dof = np.array([model.jnt_dofadr[model.joint(f"robot_{a}").id] for a in _AXES])
        names = self.scene.object_names
        self.grasp_eq = np.array(
            [model.equality(grasp_eq_name(n)).id if self._graspable(i) else -1 for i, n in enumerate(names)]
        )
        self.object_geoms = [np.flatnonzero(self.scene.body_object[model.geom_bodyid] == i) for i in range(len(names))]
        self.movable = np.array([o.movable for o in self.scene.task.objects])
        self.sheet = np.array([is_sheet(o) for o in self.scene.task.objects])
        n = sim.nworld
        self.mode = np.full(n, _IDLE)
        self.started = np.zeros(n)
        self.origin = np.tile(HOME, (n, 1))
        self.target = np.tile(HOME, (n, 1))
        self.length = np.zeros(n)
        self.stall_since = np.full(n, np.nan)
        self.closing = np.zeros(n, dtype=bool)
        self.clamp: list[dict[str, float]] = [{} for _ in range(n)]
        self.start_points = np.zeros((n, len(names), 3))
        sim.ctrl[:, self.xyz_act] = HOME
        self.finger_open = finger_open(limits)
        sim.ctrl[:, self.finger_act] = self.finger_open
        self.hold_depth = np.zeros(n)  # the held object's _Hold, per world (valid while its grasp weld is on)
        self.hold_edge = np.zeros(n)
        self.hold_width = np.zeros(n)
        self.hold_centre = np.zeros((n, 3))
        self.let_go: list[list[Event]] = [[] for _ in range(n)]  # grips that gave way, told at the next skill end

    def _graspable(self, i: int) -> bool:
        obj = self.scene.task.objects[i]
        return obj.movable and obj.shape != "cloth"

    # -- motion skills -------------------------------------------------------------------------

    def start(self, state: BatchState, worlds: np.ndarray, skill: str, args: tuple[Any, ...]) -> list[SkillEnd]:
        """Begin ``move_to_position``, ``open_gripper`` or ``close_gripper`` in ``worlds``."""
        worlds = np.asarray(worlds, dtype=int)
        self.started[worlds] = state.time[worlds]
        self.start_points[worlds] = graspable_points(self.scene, state)[worlds]
        if skill == "move_to_position":
            self._start_move(state, worlds, np.asarray(args[0], dtype=float))
        else:
            self.mode[worlds] = _FINGERS
            self.closing[worlds] = skill == "close_gripper"
            self.sim.ctrl[np.ix_(worlds, self.finger_act)] = 0.0 if skill == "close_gripper" else self.finger_open
            if skill == "open_gripper":
                for eq in self.grasp_eq[self.grasp_eq >= 0]:
                    self.sim.set_weld(worlds, eq, False)
        return []

    def _start_move(self, state: BatchState, worlds: np.ndarray, target: np.ndarray) -> None:
        lo, hi = np.asarray(self.limits.workspace_min), np.asarray(self.limits.workspace_max)
        clamped = np.clip(target, lo, hi)
        clamp: dict[str, float] = {}
        if np.linalg.norm(clamped - target) > CLAMP_TOLERANCE:
            clamp = {f"target_{a}": float(t) for a, t in zip(_AXES, target, strict=True)}
            clamp |= {f"clamped_{a}": float(c) for a, c in zip(_AXES, clamped, strict=True)}
            clamp["outside_workspace"] = float(np.linalg.norm(target - clamped))
        pos = state.xpos[worlds, self.gripper]
        self.mode[worlds] = _MOVE
        self.origin[worlds] = pos
        self.target[worlds] = clamped
        self.length[worlds] = np.linalg.norm(clamped - pos, axis=1)
        self.stall_since[worlds] = np.nan
        for w in worlds:
            self.clamp[w] = clamp

    def tick(self, state: BatchState, worlds: np.ndarray | None = None) -> list[SkillEnd]:
        """Finish skills that reached their end, then write the servo references for the next interval (in
        ``worlds``, every world when None)."""
        mask = world_mask(self.sim.nworld, worlds)
        self._check_holds(state, mask)
        ends = self._tick_moves(state, mask) + self._tick_fingers(state, mask)
        if ends:
            ends = self._with_pushed_out(state, ends)
        moving = np.flatnonzero((self.mode == _MOVE) & mask)
        if moving.size:
            elapsed = state.time[moving] - self.started[moving]
            along = np.minimum(SPEED * elapsed + SPEED * self.scene.control_dt, self.length[moving])
            direction = self.target[moving] - self.origin[moving]
            norm = np.maximum(self.length[moving], 1e-9)[:, None]
            ref = self.origin[moving] + direction / norm * along[:, None]
            self.sim.ctrl[np.ix_(moving, self.xyz_act)] = ref
        return ends

    def _tick_moves(self, state: BatchState, mask: np.ndarray) -> list[SkillEnd]:
        worlds = np.flatnonzero((self.mode == _MOVE) & mask)
        if not worlds.size:
            return []
        pos = state.xpos[worlds, self.gripper]
        speed = np.linalg.norm(state.qvel[worlds][:, self.xyz_dof], axis=1)
        remaining = np.linalg.norm(self.target[worlds] - pos, axis=1)
        elapsed = state.time[worlds] - self.started[worlds]
        ref_done = SPEED * elapsed >= self.length[worlds]
        lag = np.linalg.norm(self.sim.ctrl[np.ix_(worlds, self.xyz_act)] - pos, axis=1)
        slow = (lag > STALL_ERROR) & (speed < STALL_SPEED)
        since = self.stall_since[worlds]
        self.stall_since[worlds] = np.where(slow, np.where(np.isnan(since), state.time[worlds], since), np.nan)
        stalled = slow & (state.time[worlds] - self.stall_since[worlds] >= STALL_TIME)
        timeout = elapsed > self.length[worlds] / SPEED + TIME_MARGIN
        done = ref_done & (remaining < REACHED)
        ends = []
        for k, w in enumerate(worlds):
            if not (done[k] or stalled[k] or timeout[k]):
                continue
            measured = dict(self.clamp[w]) | {"remaining": float(remaining[k])}
            reason = self._clamp_reason(w)
            events = (Event(kind="clamped", limit="workspace", measured=dict(self.clamp[w])),) if self.clamp[w] else ()
            if done[k]:
                ends.append(SkillEnd(int(w), "done", reason, measured, events=events))
                continue
            here = ", ".join(f"{v:.3f}" for v in pos[k])
            why = "blocked" if stalled[k] else "out of time"
            text = f"{why} at [{here}], {remaining[k]:.3f} m short of the target"
            ends.append(
                SkillEnd(
                    int(w),
                    "stalled" if stalled[k] else "timeout",
                    "; ".join(t for t in (text, reason) if t),
                    measured,
                    events=events,
                )
            )
            self.sim.ctrl[w, self.xyz_act] = pos[k]
        for end in ends:
            self.mode[end.world] = _IDLE
        return ends

    def _clamp_reason(self, w: int) -> str | None:
        clamp = self.clamp[w]
        if not clamp:
            return None
        target = ", ".join(f"{clamp[f'target_{a}']:.3f}" for a in _AXES)
        clamped = ", ".join(f"{clamp[f'clamped_{a}']:.3f}" for a in _AXES)
        return f"target [{target}] is {clamp['outside_workspace']:.3f} m outside the workspace; clamped to [{clamped}]"

    def _with_pushed_out(self, state: BatchState, ends: list[SkillEnd]) -> list[SkillEnd]:
        """Add a ``pushed_out`` event for each loose object pushed further out of the workspace during the skill."""
        lo, hi = np.asarray(self.limits.workspace_min), np.asarray(self.limits.workspace_max)
        points = graspable_points(self.scene, state)
        out = []
        for end in ends:
            w = end.world
            carried = self._carried(state, w)
            before = np.linalg.norm(self.start_points[w] - np.clip(self.start_points[w], lo, hi), axis=1)
            after = np.linalg.norm(points[w] - np.clip(points[w], lo, hi), axis=1)
            pushed = np.linalg.norm(points[w] - self.start_points[w], axis=1)
            events = list(end.events) + self.let_go[w]
            self.let_go[w] = []
            for i in np.flatnonzero(self.movable & (after - before > PUSHED_OUT) & ~carried):
                centre = state.xpos[w, self.scene.object_body[i]]
                events.append(
                    Event(
                        kind="pushed_out",
                        object=self.scene.object_names[i],
                        limit="workspace",
                        measured={
                            "pushed": float(pushed[i]),
                            "outside": float(after[i]),
                            **{a: float(v) for a, v in zip(_AXES, centre, strict=True)},
                        },
                    )
                )
            out.append(replace(end, events=tuple(events)))
        return out

    def _carried(self, state: BatchState, w: int) -> np.ndarray:
        """Objects the gripper carries in world ``w``: held, or joined to what it carries by an active weld."""
        return self._joined(state, w, self.gripper)

    def _joined(self, state: BatchState, w: int, start: int) -> np.ndarray:
        """Objects joined to body ``start`` in world ``w`` by a chain of active welds (its own object too)."""
        model, owner = self.scene.model, self.scene.body_object
        carried = np.zeros(len(self.scene.object_names), dtype=bool)
        reach = {start}
        grown = True
        while grown:
            grown = False
            for eq in np.flatnonzero(state.eq_active[w]):
                a, b = int(model.eq_obj1id[eq]), int(model.eq_obj2id[eq])
                for x, y in ((a, b), (b, a)):
                    if x in reach and y not in reach:
                        reach.add(y)
                        grown = True
        for body in reach:
            if owner[body] >= 0:
                carried[owner[body]] = True
        return carried

    def _tick_fingers(self, state: BatchState, mask: np.ndarray) -> list[SkillEnd]:
        worlds = np.flatnonzero(mask & (self.mode == _FINGERS) & (state.time - self.started >= GRIPPER_TIME - 1e-9))
        ends = []
        for w in worlds:
            self.mode[w] = _IDLE
            if not self.closing[w]:
                ends.append(SkillEnd(int(w), "done"))
                continue
            ends.append(self._grasp(state, int(w)))
        return ends

    def _grip(self, state: BatchState, w: int) -> _Grip:
        c = state.xpos[w, self.gripper]
        q_left, q_right = state.qpos[w, self.finger_qpos]
        return _Grip(
            left=float(c[1] + q_left - FINGER_HALF[1]),
            right=float(c[1] - q_right + FINGER_HALF[1]),
            x=(float(c[0] - FINGER_HALF[0]), float(c[0] + FINGER_HALF[0])),
            z=(float(c[2] + FINGER_Z - FINGER_HALF[2]), float(c[2] + FINGER_Z + FINGER_HALF[2])),
        )

    def _grasp(self, state: BatchState, w: int) -> SkillEnd:
        """Hold the object both fingers grip from its sides, if it fits the opening; else say why nothing is held."""
        names = self.scene.object_names
        held = held_objects(self.scene, state)[w]
        if held >= 0:
            return SkillEnd(w, "done", f"holding {names[held]}", events=(Event(kind="grasped", object=names[held]),))
        grip = self._grip(state, w)
        owner = self.scene.body_object
        touch = state.touching[w][self.finger_body]  # (2, nbody)
        by_finger = [set(owner[np.flatnonzero(t)]) - {-1} for t in touch]
        for finger, under in zip(by_finger, self._resting_under(state, w, grip), strict=True):
            finger |= under
        both = sorted(i for i in by_finger[0] & by_finger[1] if self.grasp_eq[i] >= 0)
        failures: list[tuple[GraspFailure, int, dict[str, float]]] = []
        for i in both:
            cause, measured = self._fit(state, w, i, grip)
            if cause is None:
                hold = self._hold(state, w, i, grip)
                weak = self._weak(state, w, i, hold)
                if weak:
                    failures.append(("weak_grip", i, weak))
                    continue
                self.hold_depth[w], self.hold_edge[w], self.hold_width[w] = hold.depth, hold.edge_need, hold.width
                self.hold_centre[w] = hold.centre
                self.sim.set_weld(np.array([w]), int(self.grasp_eq[i]), True)
                return SkillEnd(
                    w,
                    "done",
                    f"holding {names[i]}",
                    measured,
                    events=(Event(kind="grasped", object=names[i], measured=measured),),
                )
            failures.append((cause, i, measured))
        if not failures:
            one = sorted(i for i in by_finger[0] ^ by_finger[1] if self.grasp_eq[i] >= 0)
            if one:
                failures.append(("one_finger", one[0], {}))
            else:
                failures.append(("nothing_between", *self._nearest(state, w)))
        cause, i, measured = failures[0]
        event = Event(
            kind="grasp_failed", object=names[i] if i >= 0 else None, limit="grasp", cause=cause, measured=measured
        )
        return SkillEnd(w, "done", event.describe([]), measured, events=(event,))

    def _hold(self, state: BatchState, w: int, i: int, grip: _Grip) -> _Hold:
        """How the closed fingers engage object ``i``: across the pads, the longest x overlap of one of its parts
        (beside the fingers) with the pads, and the least that is a grip there (EDGE_SHARE of what the pads could
        cover of that part); the width between the fingers; the patch's centre from the gripper centre."""
        c = state.xpos[w, self.gripper]
        lo, hi = _geom_extents(self.scene, state, w, self.object_geoms[i])
        pad = 2 * FINGER_HALF[0]
        best = (0.0, 0.0, float(c[0]), float(c[2]))
        for k, g in enumerate(self.object_geoms[i]):
            if self.sheet[i] or _y_span_in_slab(self.scene, state, w, int(g), grip.x, grip.z) is None:
                continue
            x0, x1 = max(lo[k, 0], grip.x[0]), min(hi[k, 0], grip.x[1])
            z0, z1 = max(lo[k, 2], grip.z[0]), min(hi[k, 2], grip.z[1])
            if x1 - x0 > best[0]:
                best = (x1 - x0, EDGE_SHARE * min(pad, hi[k, 0] - lo[k, 0]), (x0 + x1) / 2, (z0 + z1) / 2)
        depth, edge, x, z = best
        width = max(grip.gap, 0.0)
        if self.sheet[i]:  # a fold of a sheet gathered between the pads fills them
            depth, edge, width = pad, 0.0, pad
        centre = np.array([x, (grip.left + grip.right) / 2, z]) - c
        return _Hold(depth=float(depth), edge_need=float(edge), width=float(width), centre=centre)

    def _weak(self, state: BatchState, w: int, i: int, hold: _Hold) -> dict[str, float]:
        """The measures of a grip on object ``i`` that cannot hold it and what is joined to it (empty if it can)."""
        carried = self._joined(state, w, int(self.scene.object_body[i]))
        bodies = np.asarray(self.scene.object_body)[carried]
        mass = self.sim.body_mass[w, bodies]
        model = self.scene.model
        com = [state.xpos[w, b] + _rotation(state.xquat[w, b]) @ model.body_ipos[b] for b in bodies]
        centre = np.average(np.array(com), axis=0, weights=mass) if mass.sum() > 0 else state.xpos[w, bodies[0]]
        weight = float(mass.sum()) * GRAVITY
        lever = centre[:2] - (state.xpos[w, self.gripper] + hold.centre)[:2]
        need_depth, need_width = hold.need(weight, lever)
        most = 2 * GRIP_FRICTION * GRIP_FORCE
        if hold.depth >= need_depth - 1e-9 and hold.width >= need_width - 1e-9 and weight <= most:
            return {}
        return {
            "depth": hold.depth,
            "need_depth": need_depth,
            "edge_depth": hold.edge_need,
            "width": hold.width,
            "need_width": need_width,
            "weight": weight,
            "most_weight": most,
            "lever": float(np.linalg.norm(lever)),
            "joined": float(carried.sum() - 1),
        }

    def _check_holds(self, state: BatchState, mask: np.ndarray) -> None:
        """Let go of a held object whose grip can no longer carry its load (more was joined to it)."""
        eqs = self.grasp_eq[self.grasp_eq >= 0]
        if not eqs.size:
            return
        objects = np.flatnonzero(self.grasp_eq >= 0)
        active = state.eq_active[:, eqs]
        for w in np.flatnonzero(mask & active.any(axis=1)):
            i = int(objects[np.argmax(active[w])])
            hold = _Hold(self.hold_depth[w], self.hold_edge[w], self.hold_width[w], self.hold_centre[w])
            weak = self._weak(state, w, i, hold)
            if weak:
                self.sim.set_weld(np.array([w]), int(self.grasp_eq[i]), False)
                name = self.scene.object_names[i]
                self.let_go[w].append(
                    Event(kind="grasp_failed", object=name, limit="grasp", cause="weak_grip", measured=weak)
                )

    def _resting_under(self, state: BatchState, w: int, grip: _Grip) -> list[set[int]]:
        """For each finger, the graspable objects its tip rests on (under its footprint, just below it).

        Contacts report only what the tips press into; a tip resting on a top face, or on a sheet, may sit a
        hair above it, so this reads the geometry: a tip corner over the object's top, within ON_SHEET.
        """
        out: list[set[int]] = [set(), set()]
        tips = [
            np.array([[x, y] for x in grip.x for y in ys])
            for ys in ((grip.left, grip.left + 2 * FINGER_HALF[1]), (grip.right - 2 * FINGER_HALF[1], grip.right))
        ]
        for i in np.flatnonzero(self.grasp_eq >= 0):
            geoms = self.object_geoms[i]
            _, hi = _geom_extents(self.scene, state, w, geoms)
            for g, top in zip(geoms, hi[:, 2], strict=True):
                if not -ON_TOP <= grip.z[0] - top <= ON_SHEET:
                    continue
                for f, corners in enumerate(tips):
                    if _over_geom(self.scene, state, w, int(g), corners):
                        out[f].add(int(i))
        return out

    def _fit(self, state: BatchState, w: int, i: int, grip: _Grip) -> tuple[GraspFailure | None, dict[str, float]]:
        """Whether both fingers, touching object ``i``, grip it from its sides (else why not).

        Fingers that touch an object below its top and stopped apart grip it between them, if beside the
        fingers (in the slab their x and z spans make) it lies within the gap, give or take the contacts'
        give: the gap is then its width there. Beside the fingers an object that reaches further past a
        finger's inner face lies in front of, behind or under it, or (turned) across their span wider than
        their opening: pressed against its face, friction may keep the open fingers from closing, but they
        hold nothing. Fingertips at or above its
        top rest on it: it is too wide to get between the fingers, or the gripper is off to one side.
        """
        lo, hi = _geom_extents(self.scene, state, w, self.object_geoms[i])
        near = (lo[:, 0] < grip.x[1] + GRIP_TOLERANCE) & (hi[:, 0] > grip.x[0] - GRIP_TOLERANCE)
        if not near.any():
            return "not_between", {}
        lo, hi = lo[near], hi[near]
        if self.sheet[i]:  # fingertips pressed on a sheet pinch a fold of it
            return None, {"width": 2 * min(self.scene.task.objects[i].size), "opening": self.limits.gripper_opening}
        if grip.z[0] > hi[:, 2].max() - ON_TOP:
            width = float((hi[:, 1] - lo[:, 1]).min())
            return ("too_wide" if width > self.limits.gripper_opening else "on_top"), {
                "width": width,
                "opening": self.limits.gripper_opening,
            }
        spans = [_y_span_in_slab(self.scene, state, w, int(g), grip.x, grip.z) for g in self.object_geoms[i]]
        inside = np.array([s for s in spans if s is not None]).reshape(-1, 2)  # its y spans beside the fingers
        between = (inside[:, 0] < grip.left) & (inside[:, 1] > grip.right)  # some of it lies between the fingers
        if grip.gap <= 0.0 or not between.any():
            return "not_between", {}
        if grip.gap > self.limits.gripper_opening + OPENING_GIVE:  # wedged in, it pushed the open fingers apart
            return "too_wide", {"width": grip.gap, "opening": self.limits.gripper_opening}
        low, high = float(inside[:, 0].min()), float(inside[:, 1].max())
        if low < grip.right - SIDE_SLACK or high > grip.left + SIDE_SLACK:
            # beside the fingers it reaches past one of them: they pressed on a face in front of (or behind or
            # under) them, not on its sides
            return "not_between", {"span": high - low, "gap": grip.gap}
        return None, {"width": grip.gap, "opening": self.limits.gripper_opening}

    def _nearest(self, state: BatchState, w: int) -> tuple[int, dict[str, float]]:
        """The graspable object whose graspable point is nearest to the gripper centre, and that distance."""
        candidates = np.flatnonzero(self.grasp_eq >= 0)
        if not candidates.size:
            return -1, {}
        points = graspable_points(self.scene, state)[w, candidates]
        dist = np.linalg.norm(points - state.xpos[w, self.gripper], axis=1)
        return int(candidates[np.argmin(dist)]), {"nearest": float(dist.min())}

    # -- state and queries ---------------------------------------------------------------------

    def query(self, state: BatchState, world: int, skill: str, args: tuple[Any, ...]) -> Any:
        """Answer get_center, get_graspable_point, get_size or get_workspace_range."""
        if skill == "get_workspace_range":
            lo, hi = self.limits.workspace_min, self.limits.workspace_max
            return [[float(lo[k]), float(hi[k])] for k in range(3)]
        try:
            i = self.scene.object_index(args[0])
        except KeyError as e:
            raise QueryError(str(e.args[0])) from None
        if skill == "get_center":
            return [float(v) for v in state.xpos[world, self.scene.object_body[i]]]
        if skill == "get_graspable_point":
            return [float(v) for v in graspable_points(self.scene, state)[world, i]]
        if skill == "get_size":
            return size_now(self.scene, state, world, i)
        raise QueryError(f"{skill} is not a query skill of the arm")


def _geom_pose(scene: Scene, state: BatchState, w: int, geom: int) -> tuple[np.ndarray, np.ndarray]:
    """World rotation (3, 3) and centre (3,) of a geom in world ``w``, from its body's pose in the state."""
    model = scene.model
    body = model.geom_bodyid[geom]
    body_rot = _rotation(state.xquat[w, body])
    return body_rot @ _rotation(model.geom_quat[geom]), state.xpos[w, body] + body_rot @ model.geom_pos[geom]


def _rotation(quat: np.ndarray) -> np.ndarray:
    """The rotation matrix (3, 3) of a unit quaternion (w, x, y, z)."""
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, np.asarray(quat, dtype=float))
    return rot.reshape(3, 3)


def _over_geom(scene: Scene, state: BatchState, w: int, geom: int, points: np.ndarray) -> bool:
    """Whether any of the x-y ``points`` lies over the footprint of a box or upright cylinder geom in world ``w``."""
    model = scene.model
    rot, centre = _geom_pose(scene, state, w, geom)
    local = (np.column_stack([points, np.full(len(points), centre[2])]) - centre) @ rot
    size = model.geom_size[geom]
    if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return bool(np.any(np.hypot(local[:, 0], local[:, 1]) <= size[0]))
    return bool(np.any(np.all(np.abs(local[:, :2]) <= size[:2], axis=1)))


SLAB_CYLINDER_SIDES = 32  # a cylinder counts as the prism of this many sides around it (0.5% wider at most)


def _y_span_in_slab(
    scene: Scene, state: BatchState, w: int, geom: int, x: tuple[float, float], z: tuple[float, float]
) -> tuple[float, float] | None:
    """Lowest and highest world y of a box or cylinder geom's volume within ``x`` and ``z`` (any y) in world
    ``w``, or None where it misses that slab: the extremes of a convex polytope, found among its vertices."""
    model = scene.model
    rot, centre = _geom_pose(scene, state, w, geom)
    size = model.geom_size[geom]
    if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_CYLINDER:
        turn = np.linspace(0.0, 2 * np.pi, SLAB_CYLINDER_SIDES, endpoint=False)
        local = np.column_stack([np.cos(turn), np.sin(turn), np.zeros_like(turn)])
        local = np.vstack([local, [[0, 0, 1], [0, 0, -1]]])
        reach = np.concatenate([np.full(SLAB_CYLINDER_SIDES, size[0]), [size[1], size[1]]])
    else:
        local = np.vstack([np.eye(3), -np.eye(3)])
        reach = np.concatenate([size[:3], size[:3]])
    normals = local @ rot.T  # outward face normals in the world: normal . p <= normal . centre + reach
    offsets = normals @ centre + reach
    slab = np.array([[-1.0, 0, 0], [1, 0, 0], [0, 0, -1], [0, 0, 1]])
    normals = np.vstack([normals, slab])
    offsets = np.concatenate([offsets, [-x[0], x[1], -z[0], z[1]]])
    triples = np.array(list(combinations(range(len(normals)), 3)))
    planes = normals[triples]
    solvable = np.abs(np.linalg.det(planes)) > 1e-12
    corners = np.linalg.solve(planes[solvable], offsets[triples[solvable]][..., None])[..., 0]
    corners = corners[np.all(corners @ normals.T <= offsets + 1e-9, axis=1)]
    if not len(corners):
        return None
    return float(corners[:, 1].min()), float(corners[:, 1].max())


def _geom_extents(scene: Scene, state: BatchState, w: int, geoms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World axis-aligned bounds (low, high), (ngeom, 3) each, of box and cylinder geoms in world ``w``."""
    model = scene.model
    lo, hi = np.zeros((len(geoms), 3)), np.zeros((len(geoms), 3))
    for k, g in enumerate(geoms):
        rot, centre = _geom_pose(scene, state, w, g)
        size = model.geom_size[g]
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_CYLINDER:
            axis = np.abs(rot[:, 2])
            half = axis * size[1] + size[0] * np.sqrt(np.clip(1 - axis**2, 0, 1))
        else:
            half = np.abs(rot) @ size
        lo[k], hi[k] = centre - half, centre + half
    return lo, hi


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
