"""The arm embodiment: a translating two-finger gripper inside the workspace box (BENCHMARK.md section 3).

:class:`ArmController` implements the :class:`~robotool.sim.embodiment.SkillController` contract: it runs
``move_to_position`` (a straight-line reference at ``speed``, which never runs more than ``max_lead`` ahead of the
gripper on an axis, so a blocked servo builds up no pull to fling it with; targets outside the workspace are clamped
and the clamp is recorded) and opens and closes the fingers (:class:`MotionState`), and leaves what the closed fingers
hold to :mod:`.arm_grasp` (:class:`~.arm_grasp.GraspState`). The body is built by :mod:`.arm_body`; the tunables are
in :mod:`.arm_config`. Each motion skill also reports objects it pushed further out of the workspace (``pushed_out``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import mujoco
import numpy as np

from robotool.robots.arm.arm_body import AXES, add_body, graspable_points
from robotool.robots.arm.arm_config import ARM, ArmConfig, finger_open
from robotool.robots.arm.arm_grasp import ArmParts, Grasp
from robotool.robots.arm.arm_payload import Payload
from robotool.robots.arm.arm_skills import ArmLimits
from robotool.rollout import Event
from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.embodiment import QueryError, SkillController, SkillEnd, size_now, world_mask
from robotool.task.task_model import Task

IDLE, MOVE, FINGERS = 0, 1, 2  # what each world's gripper is doing (MotionState.mode)


class ArmEmbodiment:
    """:class:`~robotool.sim.embodiment.Embodiment` for the arm."""

    control_substeps = 50  # 10 Hz: the servos track interpolated targets, so a slower tick loses nothing

    def __init__(self, limits: ArmLimits, config: ArmConfig = ARM):
        self.limits, self.config = limits, config

    def add_to_spec(self, spec: mujoco.MjSpec, task: Task) -> None:
        """Gripper on x/y/z slides with position servos, two colliding fingers, one grasp weld per movable object;
        friction that does not creep (:func:`~.arm_body.add_body`)."""
        add_body(spec, task, self.limits)

    def controller(self, sim: BatchedSim) -> ArmController:
        """Skill controller for every world of ``sim``."""
        return ArmController(sim, self.limits, self.config)


@dataclass
class MotionState:
    """Per world (index first): the skill in progress and where it started."""

    mode: np.ndarray  # (nworld,) IDLE, MOVE or FINGERS
    started: np.ndarray  # (nworld,) s: when the skill started
    origin: np.ndarray  # (nworld, 3) m: the gripper centre where a move started
    target: np.ndarray  # (nworld, 3) m: its (clamped) target
    length: np.ndarray  # (nworld,) m: its length
    stall_since: np.ndarray  # (nworld,) s: since when it has lagged and crept (NaN: it has not)
    ref: np.ndarray  # (nworld, 3) m: the servo reference the move wrote last (its origin before the first tick)
    ref_time: np.ndarray  # (nworld,) s: when the reference was that (a tick before the start at the start)
    closing: np.ndarray  # (nworld,) bool: the fingers close (else open)
    clamp: list[dict[str, float]]  # the move's target clamped to the workspace, measured (empty: not clamped)
    start_points: np.ndarray  # (nworld, nobject, 3) m: the objects' graspable points when the skill started

    @classmethod
    def empty(cls, nworld: int, nobject: int, home: tuple[float, float, float]) -> MotionState:
        return cls(
            mode=np.full(nworld, IDLE),
            started=np.zeros(nworld),
            origin=np.tile(home, (nworld, 1)),
            target=np.tile(home, (nworld, 1)),
            length=np.zeros(nworld),
            stall_since=np.full(nworld, np.nan),
            ref=np.tile(home, (nworld, 1)),
            ref_time=np.zeros(nworld),
            closing=np.zeros(nworld, dtype=bool),
            clamp=[{} for _ in range(nworld)],
            start_points=np.zeros((nworld, nobject, 3)),
        )


class ArmController(SkillController):
    """Runs move/open/close in every world; answers the arm's queries from the batched state."""

    def __init__(self, sim: BatchedSim, limits: ArmLimits, config: ArmConfig = ARM):
        self.sim, self.limits, self.config, self.scene = sim, limits, config, sim.scene
        self.parts = ArmParts.of(self.scene)
        self.grasp = Grasp(sim, self.parts, limits, config)
        self.payload = Payload(sim, self.parts, self.grasp, limits, config)
        self.state = MotionState.empty(sim.nworld, len(self.scene.object_names), config.home)
        sim.ctrl[:, self.parts.xyz_act] = config.home
        self.finger_open = finger_open(limits.gripper_opening)
        sim.ctrl[:, self.parts.finger_act] = self.finger_open

    def world_states(self) -> tuple[Any, ...]:
        """The motion's, the grasp's and the payload's per-world state."""
        return (self.state, self.grasp.state, self.payload.state)

    def overloaded(self, state: BatchState) -> np.ndarray:
        """The worlds where a held object loads the grip past what it holds (:meth:`Grasp.past_capacity`), or where
        the arm carried more than its payload at the last tick (:class:`~.arm_payload.Payload`)."""
        return self.grasp.past_capacity(state) | self.payload.state.over_now

    def robot_conditions(self, state: BatchState, worlds: list[int]) -> dict[str, list[bool]]:
        """The arm carried no more than ``max_payload`` (in scenes whose movable objects could weigh more)."""
        return self.payload.conditions()

    # -- motion skills -------------------------------------------------------------------------

    def start(self, state: BatchState, worlds: np.ndarray, skill: str, args: tuple[Any, ...]) -> list[SkillEnd]:
        """Begin ``move_to_position``, ``open_gripper`` or ``close_gripper`` in ``worlds``."""
        worlds = np.asarray(worlds, dtype=int)
        self.state.started[worlds] = state.time[worlds]
        self.state.start_points[worlds] = graspable_points(self.scene, state)[worlds]
        if skill == "move_to_position":
            self._start_move(state, worlds, np.asarray(args[0], dtype=float))
        else:
            self.state.mode[worlds] = FINGERS
            self.state.closing[worlds] = skill == "close_gripper"
            self.sim.ctrl[np.ix_(worlds, self.parts.finger_act)] = 0.0 if skill == "close_gripper" else self.finger_open
            if skill == "open_gripper":
                for eq in self.parts.grasp_eq[self.parts.grasp_eq >= 0]:
                    self.sim.set_weld(worlds, eq, False)
        return []

    def _start_move(self, state: BatchState, worlds: np.ndarray, target: np.ndarray) -> None:
        lo, hi = np.asarray(self.limits.workspace_min), np.asarray(self.limits.workspace_max)
        clamped = np.clip(target, lo, hi)
        clamp: dict[str, float] = {}
        if np.linalg.norm(clamped - target) > self.config.clamp_tolerance:
            clamp = {f"target_{a}": float(t) for a, t in zip(AXES, target, strict=True)}
            clamp |= {f"clamped_{a}": float(c) for a, c in zip(AXES, clamped, strict=True)}
            clamp["outside_workspace"] = float(np.linalg.norm(target - clamped))
        pos = state.xpos[worlds, self.parts.gripper]
        self.state.mode[worlds] = MOVE
        self.state.origin[worlds] = pos
        self.state.target[worlds] = clamped
        self.state.length[worlds] = np.linalg.norm(clamped - pos, axis=1)
        self.state.stall_since[worlds] = np.nan
        self.state.ref[worlds] = pos
        self.state.ref_time[worlds] = state.time[worlds] - self.scene.control_dt
        for w in worlds:
            self.state.clamp[w] = clamp

    def tick(self, state: BatchState, worlds: np.ndarray | None = None) -> list[SkillEnd]:
        """Finish skills that reached their end, then write the servo references for the next interval (in
        ``worlds``, every world when None)."""
        mask = world_mask(self.sim.nworld, worlds)
        self.grasp.check_holds(state, mask)
        ends = self._overweight(state, mask)
        ends += self._tick_moves(state, mask) + self._tick_fingers(state, mask)
        if ends:
            ends = self._with_pushed_out(state, ends)
        moving = np.flatnonzero((self.state.mode == MOVE) & mask)
        if moving.size:
            self._write_references(state, moving)
        return ends

    def _write_references(self, state: BatchState, moving: np.ndarray) -> None:
        """Write the servo references of the ``moving`` worlds for the next interval: the straight line from the
        origin at ``speed`` (reached a tick ahead), followed at ``speed`` at most and kept within ``max_lead`` of the
        gripper on each axis (anti-windup). Unblocked, the reference is the line's; blocked, it waits near the gripper,
        so when the obstruction gives way the gripper lurches ``max_lead`` at most and goes on at ``speed``."""
        speed, now = self.config.speed, state.time[moving]
        elapsed = now - self.state.started[moving]
        along = np.minimum(speed * elapsed + speed * self.scene.control_dt, self.state.length[moving])
        direction = self.state.target[moving] - self.state.origin[moving]
        norm = np.maximum(self.state.length[moving], 1e-9)[:, None]
        pos, lead = state.xpos[moving, self.parts.gripper], self.config.max_lead
        goal = np.clip(self.state.origin[moving] + direction / norm * along[:, None], pos - lead, pos + lead)
        last = self.state.ref[moving]
        gap = np.linalg.norm(goal - last, axis=1)
        step = speed * np.maximum(now - self.state.ref_time[moving], 0.0)
        within = gap <= step * (1 + 1e-6) + 1e-9  # the line advanced at speed: take it exactly
        chased = last + (goal - last) * (step / np.maximum(gap, 1e-12))[:, None]
        ref = np.clip(np.where(within[:, None], goal, chased), pos - lead, pos + lead)
        self.state.ref[moving], self.state.ref_time[moving] = ref, now
        self.sim.ctrl[np.ix_(moving, self.parts.xyz_act)] = ref

    def _tick_moves(self, state: BatchState, mask: np.ndarray) -> list[SkillEnd]:
        worlds = np.flatnonzero((self.state.mode == MOVE) & mask)
        if not worlds.size:
            return []
        pos = state.xpos[worlds, self.parts.gripper]
        speed = np.linalg.norm(state.qvel[worlds][:, self.parts.xyz_dof], axis=1)
        remaining = np.linalg.norm(self.state.target[worlds] - pos, axis=1)
        elapsed = state.time[worlds] - self.state.started[worlds]
        ref_done = self.config.speed * elapsed >= self.state.length[worlds]
        lag = np.linalg.norm(self.sim.ctrl[np.ix_(worlds, self.parts.xyz_act)] - pos, axis=1)
        slow = (lag > self.config.stall_error) & (speed < self.config.stall_speed)
        since = self.state.stall_since[worlds]
        self.state.stall_since[worlds] = np.where(slow, np.where(np.isnan(since), state.time[worlds], since), np.nan)
        stalled = slow & (state.time[worlds] - self.state.stall_since[worlds] >= self.config.stall_time)
        timeout = elapsed > self.state.length[worlds] / self.config.speed + self.config.time_margin
        done = ref_done & (remaining < self.config.reached)
        ends = []
        for k, w in enumerate(worlds.tolist()):
            if not (done[k] or stalled[k] or timeout[k]):
                continue
            measured = dict(self.state.clamp[w]) | {"remaining": float(remaining[k])}
            reason = self._clamp_reason(int(w))
            events = (
                (Event(kind="clamped", limit="workspace", measured=dict(self.state.clamp[w])),)
                if self.state.clamp[w]
                else ()
            )
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
            self.sim.ctrl[w, self.parts.xyz_act] = pos[k]
        for end in ends:
            self.state.mode[end.world] = IDLE
        return ends

    def _overweight(self, state: BatchState, mask: np.ndarray) -> list[SkillEnd]:
        """Let go where the arm has carried more than its payload for too long (:class:`~.arm_payload.Payload`): the
        move in progress is refused with the reason and the gripper stops; otherwise the next skill end tells it."""
        ends = []
        for w, load, reason, measured in self.payload.check(state, mask):
            if load.held >= 0:
                self.sim.set_weld(np.array([w]), int(self.parts.grasp_eq[load.held]), False)
            name = self.scene.object_names[load.named]
            event = Event(kind="refused", object=name, limit="max_payload", measured=measured, detail=reason)
            if self.state.mode[w] != MOVE:
                self.grasp.state.let_go[w].append(event)
                continue
            self.state.mode[w] = IDLE
            self.sim.ctrl[w, self.parts.xyz_act] = state.xpos[w, self.parts.gripper]
            ends.append(SkillEnd(w, "refused", reason, measured, events=(event,)))
        return ends

    def _clamp_reason(self, w: int) -> str | None:
        clamp = self.state.clamp[w]
        if not clamp:
            return None
        target = ", ".join(f"{clamp[f'target_{a}']:.3f}" for a in AXES)
        clamped = ", ".join(f"{clamp[f'clamped_{a}']:.3f}" for a in AXES)
        return f"target [{target}] is {clamp['outside_workspace']:.3f} m outside the workspace; clamped to [{clamped}]"

    def _with_pushed_out(self, state: BatchState, ends: list[SkillEnd]) -> list[SkillEnd]:
        """Add a ``pushed_out`` event for each loose object pushed further out of the workspace during the skill."""
        lo, hi = np.asarray(self.limits.workspace_min), np.asarray(self.limits.workspace_max)
        points = graspable_points(self.scene, state)
        out = []
        for end in ends:
            w = end.world
            carried = self.grasp.carried(state, w)
            before = np.linalg.norm(self.state.start_points[w] - np.clip(self.state.start_points[w], lo, hi), axis=1)
            after = np.linalg.norm(points[w] - np.clip(points[w], lo, hi), axis=1)
            pushed = np.linalg.norm(points[w] - self.state.start_points[w], axis=1)
            events = list(end.events) + self.grasp.state.let_go[w]
            self.grasp.state.let_go[w] = []
            for i in np.flatnonzero(self.parts.movable & (after - before > self.config.pushed_out) & ~carried):
                centre = state.xpos[w, self.scene.object_body[i]]
                events.append(
                    Event(
                        kind="pushed_out",
                        object=self.scene.object_names[i],
                        limit="workspace",
                        measured={
                            "pushed": float(pushed[i]),
                            "outside": float(after[i]),
                            **{a: float(v) for a, v in zip(AXES, centre, strict=True)},
                        },
                    )
                )
            out.append(replace(end, events=tuple(events)))
        return out

    def _tick_fingers(self, state: BatchState, mask: np.ndarray) -> list[SkillEnd]:
        worlds = np.flatnonzero(
            mask & (self.state.mode == FINGERS) & (state.time - self.state.started >= self.config.gripper_time - 1e-9)
        )
        ends = []
        for w in worlds:
            self.state.mode[w] = IDLE
            if not self.state.closing[w]:
                ends.append(SkillEnd(int(w), "done"))
                continue
            ends.append(self.grasp.grasp(state, int(w)))
        return ends

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
