"""The arm embodiment: a translating two-finger gripper inside the workspace box (BENCHMARK.md section 3).

The gripper body ``robot_gripper`` rides on three slide joints whose coordinates are the gripper
centre in the world (``ref`` = home, so ``qpos`` is absolute); position servos with force limits
drive them, so a blocked motion really stalls. The joint ranges are the workspace; targets outside
it are clamped and the clamp is recorded. Fingers are visual; the palm above the centre collides.
A grasp is the weld ``robot_grasp__<object>`` (one per movable object) attached at the current pose
when ``close_gripper`` finds a graspable point within the grasp radius, and released by ``open_gripper``.
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from robotool.embodiments import ArmLimits
from robotool.scene import Task
from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.build import WELD_SOLREF, Scene
from robotool.sim.embodiment import QueryError, SkillEnd

GRIPPER_BODY = "robot_gripper"
GRASP_EQ_PREFIX = "robot_grasp__"
HOME = (0.1, 0.0, 0.3)  # m, gripper centre at the start
SPEED = 0.25  # m/s, straight-line reference speed
SERVO_KP, SERVO_KV, SERVO_FORCE = 2000.0, 80.0, 100.0  # N/m, N s/m, N
REACHED = 0.005  # m: a move is done when the centre is this close to the target
STALL_ERROR, STALL_SPEED, STALL_TIME = 0.02, 0.02, 0.3  # m, m/s, s
TIME_MARGIN = 2.0  # s a move may take beyond distance / speed
GRIPPER_TIME = 0.3  # s to open or close the fingers
FINGER_OPEN = 0.04  # m, each finger's offset from the centre when open
PALM_HALF = (0.02, 0.05, 0.01)  # m
PALM_CLEARANCE = 0.03  # m from the centre up to the palm's underside

_IDLE, _MOVE, _FINGERS = 0, 1, 2
_AXES = "xyz"


def grasp_eq_name(obj: str) -> str:
    """Name of the weld that holds ``obj`` in the gripper."""
    return f"{GRASP_EQ_PREFIX}{obj}"


class ArmEmbodiment:
    """:class:`~robotool.sim.embodiment.Embodiment` for the arm."""

    control_substeps = 50  # 10 Hz: the servos track interpolated targets, so a slower tick loses nothing

    def __init__(self, limits: ArmLimits):
        self.limits = limits

    def add_to_spec(self, spec: mujoco.MjSpec, task: Task) -> None:
        """Gripper on x/y/z slides with position servos, two visual fingers, one grasp weld per movable object."""
        lo, hi = self.limits.workspace_min, self.limits.workspace_max
        gripper = spec.worldbody.add_body(name=GRIPPER_BODY, pos=HOME, gravcomp=1.0)
        for k, axis in enumerate(_AXES):
            direction = [0.0, 0.0, 0.0]
            direction[k] = 1.0
            gripper.add_joint(name=f"robot_{axis}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=direction, ref=HOME[k],
                              range=[lo[k], hi[k]], armature=0.01)
            act = spec.add_actuator(name=f"robot_{axis}", target=f"robot_{axis}", trntype=mujoco.mjtTrn.mjTRN_JOINT)
            act.set_to_position(kp=SERVO_KP, kv=SERVO_KV)
            act.ctrlrange = [lo[k], hi[k]]
            act.forcerange = [-SERVO_FORCE, SERVO_FORCE]
            act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        gripper.add_geom(name="robot_palm", type=mujoco.mjtGeom.mjGEOM_BOX, size=PALM_HALF,
                         pos=[0, 0, PALM_CLEARANCE + PALM_HALF[2]], mass=0.5)
        for side, sign in (("left", 1.0), ("right", -1.0)):
            finger = gripper.add_body(name=f"robot_finger_{side}", pos=[0, 0, 0], gravcomp=1.0)
            finger.add_joint(name=f"robot_finger_{side}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, sign, 0],
                             range=[0, FINGER_OPEN])
            finger.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.008, 0.004, PALM_CLEARANCE / 2 + 0.008],
                            pos=[0, 0, PALM_CLEARANCE / 2 - 0.008], mass=0.02, contype=0, conaffinity=0)
            act = spec.add_actuator(name=f"robot_finger_{side}", target=f"robot_finger_{side}",
                                    trntype=mujoco.mjtTrn.mjTRN_JOINT)
            act.set_to_position(kp=50.0, kv=2.0)
            act.ctrlrange = [0, FINGER_OPEN]
        for obj in task.objects:
            if obj.movable and obj.shape != "cloth":
                spec.add_equality(name=grasp_eq_name(obj.name), type=mujoco.mjtEq.mjEQ_WELD,
                                  objtype=mujoco.mjtObj.mjOBJ_BODY, name1=GRIPPER_BODY, name2=obj.name,
                                  active=False, solref=WELD_SOLREF)

    def controller(self, sim: BatchedSim) -> ArmController:
        """Skill controller for every world of ``sim``."""
        return ArmController(sim, self.limits)


class ArmController:
    """Runs move/open/close in every world; answers the arm's queries from the batched state."""

    def __init__(self, sim: BatchedSim, limits: ArmLimits):
        self.sim, self.limits, self.scene = sim, limits, sim.scene
        model = self.scene.model
        self.gripper = model.body(GRIPPER_BODY).id
        self.xyz_act = np.array([model.actuator(f"robot_{a}").id for a in _AXES])
        self.finger_act = np.array([model.actuator(f"robot_finger_{s}").id for s in ("left", "right")])
        self.xyz_dof = np.array([model.jnt_dofadr[model.joint(f"robot_{a}").id] for a in _AXES])
        names = self.scene.object_names
        self.grasp_eq = np.array([model.equality(grasp_eq_name(n)).id if self._graspable(i) else -1
                                  for i, n in enumerate(names)])
        n = sim.nworld
        self.mode = np.full(n, _IDLE)
        self.started = np.zeros(n)
        self.origin = np.tile(HOME, (n, 1))
        self.target = np.tile(HOME, (n, 1))
        self.length = np.zeros(n)
        self.stall_since = np.full(n, np.nan)
        self.closing = np.zeros(n, dtype=bool)
        self.clamp: list[dict[str, float]] = [{} for _ in range(n)]
        sim.ctrl[:, self.xyz_act] = HOME
        sim.ctrl[:, self.finger_act] = FINGER_OPEN

    def _graspable(self, i: int) -> bool:
        obj = self.scene.task.objects[i]
        return obj.movable and obj.shape != "cloth"

    # -- motion skills -------------------------------------------------------------------------

    def start(self, state: BatchState, worlds: np.ndarray, skill: str, args: tuple[Any, ...]) -> list[SkillEnd]:
        """Begin ``move_to_position``, ``open_gripper`` or ``close_gripper`` in ``worlds``."""
        worlds = np.asarray(worlds, dtype=int)
        self.started[worlds] = state.time[worlds]
        if skill == "move_to_position":
            self._start_move(state, worlds, np.asarray(args[0], dtype=float))
        else:
            self.mode[worlds] = _FINGERS
            self.closing[worlds] = skill == "close_gripper"
            self.sim.ctrl[np.ix_(worlds, self.finger_act)] = 0.0 if skill == "close_gripper" else FINGER_OPEN
            if skill == "open_gripper":
                for eq in self.grasp_eq[self.grasp_eq >= 0]:
                    self.sim.set_weld(worlds, eq, False)
        return []

    def _start_move(self, state: BatchState, worlds: np.ndarray, target: np.ndarray) -> None:
        lo, hi = np.asarray(self.limits.workspace_min), np.asarray(self.limits.workspace_max)
        clamped = np.clip(target, lo, hi)
        clamp: dict[str, float] = {}
        if not np.allclose(clamped, target):
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

    def tick(self, state: BatchState) -> list[SkillEnd]:
        """Finish skills that reached their end, then write the servo references for the next interval."""
        ends = self._tick_moves(state) + self._tick_fingers(state)
        moving = np.flatnonzero(self.mode == _MOVE)
        if moving.size:
            elapsed = state.time[moving] - self.started[moving]
            along = np.minimum(SPEED * elapsed + SPEED * self.scene.control_dt, self.length[moving])
            direction = self.target[moving] - self.origin[moving]
            norm = np.maximum(self.length[moving], 1e-9)[:, None]
            ref = self.origin[moving] + direction / norm * along[:, None]
            self.sim.ctrl[np.ix_(moving, self.xyz_act)] = ref
        return ends

    def _tick_moves(self, state: BatchState) -> list[SkillEnd]:
        worlds = np.flatnonzero(self.mode == _MOVE)
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
            if done[k]:
                ends.append(SkillEnd(int(w), "done", reason, measured))
                continue
            here = ", ".join(f"{v:.3f}" for v in pos[k])
            why = "blocked" if stalled[k] else "out of time"
            text = f"{why} at [{here}], {remaining[k]:.3f} m short of the target"
            ends.append(SkillEnd(int(w), "stalled" if stalled[k] else "timeout",
                                 "; ".join(t for t in (text, reason) if t), measured))
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
        return (f"target [{target}] is {clamp['outside_workspace']:.3f} m outside the workspace; "
                f"clamped to [{clamped}]")

    def _tick_fingers(self, state: BatchState) -> list[SkillEnd]:
        worlds = np.flatnonzero((self.mode == _FINGERS) & (state.time - self.started >= GRIPPER_TIME - 1e-9))
        ends = []
        for w in worlds:
            self.mode[w] = _IDLE
            if not self.closing[w]:
                ends.append(SkillEnd(int(w), "done"))
                continue
            ends.append(self._grasp(state, int(w)))
        return ends

    def _grasp(self, state: BatchState, w: int) -> SkillEnd:
        held = held_objects(self.scene, state)[w]
        if held >= 0:
            return SkillEnd(w, "done", f"holding {self.scene.object_names[held]}")
        points = graspable_points(self.scene, state)[w]
        candidates = np.flatnonzero(self.grasp_eq >= 0)
        if not candidates.size:
            return SkillEnd(w, "done", "nothing graspable in the scene")
        dist = np.linalg.norm(points[candidates] - state.xpos[w, self.gripper], axis=1)
        best = int(np.argmin(dist))
        name, d = self.scene.object_names[candidates[best]], float(dist[best])
        if d > self.limits.grasp_radius:
            return SkillEnd(w, "done", f"nothing within {self.limits.grasp_radius} m of the gripper centre "
                                       f"(nearest graspable point: {name}, {d:.3f} m)", {"distance": d})
        self.sim.set_weld(np.array([w]), int(self.grasp_eq[candidates[best]]), True)
        return SkillEnd(w, "done", f"holding {name}", {"distance": d})

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
            return [float(v) for v in self.scene.task.objects[i].size]
        raise QueryError(f"{skill} is not a query skill of the arm")


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
