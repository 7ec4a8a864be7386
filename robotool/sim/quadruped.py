"""The quadruped embodiment: its skills over batched worlds, its queries and its goal kinds.

Every motion skill is a plan of straight moves (a walk is one move; a push is the approach around the
object and one push per axis, see :mod:`robotool.sim.quadruped_push`). Each control tick, for every
world that is moving, downward rays read the terrain from the robot's rear edge to its front edge at
the move's goal (at most ``LOOKAHEAD`` ahead; :mod:`robotool.sim.quadruped_terrain`). A violated
limit moves the stopping point to just before its edge; when the robot has stopped there the skill
is refused with the measured value. The x-y setpoint advances at ``WALK_SPEED`` (waiting while the
lift motor raises the body for a step up) and the lift motor is on only while a higher accepted
surface lies under or just ahead of the body. Nothing here reads the task's category or name:
limits come from ``task.robot.limits`` and the terrain from the simulated geoms.

Hooks wanted from the simulator core (local workarounds in use):
- the per-world (perturbed) body masses in :class:`~robotool.sim.backend.BatchedSim`, for the push
  mass limit; until then the nominal ``body_subtreemass`` of the compiled model is used;
- ``rays(..., exclude_body)`` taking several bodies (or a geom group mask); until then rays exclude
  the robot and a pushed object's hits are read as the floor it rests on.
"""

from __future__ import annotations

from collections.abc import Generator
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from robotool.embodiments import QuadrupedLimits
from robotool.scene import Task
from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.build import Scene
from robotool.sim.embodiment import QueryError, SkillEnd
from robotool.sim.quadruped_body import FOOT_RADIUS, OFF, XY_KP, BodyIds, add_body
from robotool.sim.quadruped_goals import LiftedGoal, LoweredGoal, RobotOnGoal, local_corners, world_corners
from robotool.sim.quadruped_push import (
    GAP,
    Leg,
    lateral_offsets,
    legs,
    push_pose,
    route,
    rule_violation,
    sweep_points,
)
from robotool.sim.quadruped_terrain import RISE, TOLERANCE, scan
from robotool.sim.quadruped_terrain import describe as describe_violation

WALK_SPEED = 0.4  # m/s
SPACING = 0.01  # m between terrain samples along the path
LOOKAHEAD = 0.6  # m of terrain read ahead of the front edge
EDGE_SAMPLES = 2  # samples this close to the body's rear and front edges are not under its feet
LIFT_AHEAD = 0.12  # m ahead of the front edge where a higher surface starts the lift
CLEARANCE = 0.025  # m the lift carries the feet above the surface they step onto
STOP_MARGIN = 0.03  # m between the front edge and a refused edge
ARRIVED = 0.015  # m from a move's goal that counts as there
SETTLED_SPEED = 0.03  # m/s: a move ends only once the body is this still
LEASH = 0.06  # m the setpoint may run ahead of the body
STALL_TIME = 3.0  # s without 1 cm of progress is a stall
STAGING = 0.15  # m behind the push pose from where the robot lines up straight along the push
PUSH_TOLERANCE = 0.06  # m: a push is done when the object's centre is this close to the target
RAY_HEIGHT = 0.6  # m above the feet where downward rays start (things higher are overhead)

Outcome = tuple[str, str | None, dict[str, float]]


@dataclass
class _Move:
    """One straight move to ``goal`` (x-y); ``pushing`` is the object index being pushed or -1."""

    goal: np.ndarray
    pushing: int = -1


Plan = Generator[_Move, Outcome, Outcome | None]


@dataclass
class _Active:
    """A motion skill running in one world."""

    plan: Plan
    move: _Move
    started: float
    best: float = np.inf
    progress_time: float = 0.0
    refusal: Outcome | None = None


class QuadrupedEmbodiment:
    """The quadruped (Go1-sized) with the limits of one task."""

    control_substeps = 25  # 20 Hz: the lift motor must react within a step's approach

    def __init__(self, limits: QuadrupedLimits):
        self.limits = limits

    def add_to_spec(self, spec: mujoco.MjSpec, task: Task) -> None:
        """Add the robot body and its actuators (see :mod:`robotool.sim.quadruped_body`)."""
        add_body(spec, task)

    def controller(self, sim: BatchedSim) -> QuadrupedController:
        return QuadrupedController(sim, self.limits)


class QuadrupedController:
    """Runs the quadruped's skills in every world of one batched simulator."""

    def __init__(self, sim: BatchedSim, limits: QuadrupedLimits):
        self.sim, self.limits = sim, limits
        self.scene: Scene = sim.scene
        model = self.scene.model
        self.ids = BodyIds.of(model)
        self.half = np.array(limits.body_size[:2]) / 2
        self.height = limits.body_size[2]
        self.lead = self.ids.xy_kv / XY_KP  # s: setpoint lead that cancels the servo's lag at speed
        self.corners = local_corners(self.scene)
        self.geom_object = self.scene.body_object[model.geom_bodyid]
        self.cloth = np.array([o.shape == "cloth" for o in self.scene.task.objects])
        self.mass = np.array([model.body_subtreemass[b] for b in self.scene.object_body])
        self.active: list[_Active | None] = [None] * sim.nworld
        self.state: BatchState = sim.state()
        self.setpoint = self.state.qpos[:, self.ids.qpos[:2]].copy()
        self._hold(np.arange(sim.nworld))

    # -- the controller interface ----------------------------------------------------------------

    def start(
        self, state: BatchState, worlds: np.ndarray, skill: str, args: tuple[Any, ...]
    ) -> list[SkillEnd]:
        """Begin a motion skill; pushes that break a rule are refused at once."""
        self.state = state
        ends = []
        for w in np.asarray(worlds, dtype=int).reshape(-1):
            plan = self._push_plan(w, *args) if skill == "push_to_position" else self._walk_plan(args[0])
            end = self._begin(w, plan)
            if end is not None:
                ends.append(end)
        return ends

    def tick(self, state: BatchState) -> list[SkillEnd]:
        """Report finished skills and write the controls for the next interval."""
        self.state = state
        ends: list[SkillEnd] = []
        worlds = [w for w, a in enumerate(self.active) if a is not None and state.failed[w] is None]
        if worlds:
            self._drive(np.array(worlds), ends)
        return ends

    def query(self, state: BatchState, world: int, skill: str, args: tuple[Any, ...]) -> Any:
        """``get_position`` / ``get_size`` of an object or of ``robot``, from the current state."""
        name = args[0]
        if name == "robot":
            if skill == "get_size":
                return list(self.limits.body_size)
            feet = state.qpos[world, self.ids.qpos]
            return [float(feet[0]), float(feet[1]), float(feet[2] + self.height / 2)]
        try:
            index = self.scene.object_index(name)
        except KeyError as e:
            raise QueryError(str(e.args[0])) from None
        if skill == "get_size":
            return list(self.scene.task.objects[index].size)
        return [float(v) for v in self._centers(state)[world, index]]

    # -- skill plans -------------------------------------------------------------------------------

    def _walk_plan(self, target: tuple[float, float, float]) -> Plan:
        outcome = yield _Move(np.array(target[:2], dtype=float))
        return outcome

    def _push_plan(self, w: int, name: str, target: tuple[float, float, float]) -> Plan:
        try:
            index = self.scene.object_index(name)
        except KeyError as e:
            return "refused", str(e.args[0]), {}
        broken = self._push_rules(w, index)
        if broken is not None:
            return "refused", f"cannot push {name}: {broken[0]}", broken[1]
        goal = np.array(target[:2], dtype=float)
        for leg in legs(self._centers(self.state)[w, index], goal):
            lo, hi = self._bounds(w, index)
            pose = self._clear_pose(w, index, leg, lo, hi)
            if pose is None:
                return "refused", f"cannot push {name}: no clear place to stand behind it", {}
            start, end = pose
            robot = self.state.qpos[w, self.ids.qpos[:2]]
            staging = start - (end - start) / np.linalg.norm(end - start) * STAGING
            for waypoint in [
                *route(robot, staging, lo - self.half - GAP / 2, hi + self.half + GAP / 2),
                start,
            ]:
                outcome = yield _Move(waypoint)
                if outcome[0] != "done":
                    return outcome
            outcome = yield _Move(end, pushing=index)
            if outcome[0] not in ("done", "stalled"):
                return outcome
            back = (start - end) / np.linalg.norm(start - end) * GAP
            outcome = yield _Move(self.state.qpos[w, self.ids.qpos[:2]] + back)
            if outcome[0] != "done":
                return outcome
        miss = float(np.linalg.norm(self._centers(self.state)[w, index, :2] - goal))
        if miss > PUSH_TOLERANCE:
            return "stalled", f"{name} stopped {miss:.2f} m from the target", {"distance": miss}
        return None

    def _push_rules(self, w: int, index: int) -> tuple[str, dict[str, float]] | None:
        """Check the push rules in world ``w`` from rays under the robot and under the object."""
        feet_z = self.state.qpos[w, self.ids.qpos[2]]
        centre = self.state.qpos[w, self.ids.qpos[:2]]
        foot = self.half - FOOT_RADIUS
        points = np.array([centre, *(centre + foot * np.array([sx, sy]) for sx in (-1, 1) for sy in (-1, 1))])
        z, objects = self._heights(w, points, feet_z + 0.05)
        on = objects[z >= z.max() - RISE]
        on = on[on >= 0]
        carriers = [o for o in on if not self.cloth[o]]
        movable = next(
            (self.scene.object_names[o] for o in carriers if self.scene.task.objects[o].movable), None
        )
        obj_lo, obj_hi = self._bounds3(w, index)
        centre_obj = (obj_lo + obj_hi) / 2
        below, _ = self._heights(
            w, centre_obj[None, :2], obj_hi[2] + 0.01, exclude=self.scene.object_body[index]
        )
        return rule_violation(
            movable=self.scene.task.objects[index].movable,
            mass=float(self.mass[index]),
            under_robot=bool(np.isin(index, on)),
            robot_support_movable=movable,
            object_support=float(below[0]),
            robot_support=float(z.max()),
            limits=self.limits,
        )

    def _clear_pose(
        self, w: int, index: int, leg: Leg, lo: np.ndarray, hi: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """The push start and end poses nearest straight-on whose sweep meets nothing above the floor.

        Poses whose sweep is clear from the staging point (``STAGING`` behind the start, where the robot lines up)
        come first, so that the robot can line up there; failing those, a clear sweep from the start will do.
        """
        feet_z = self.state.qpos[w, self.ids.qpos[2]]
        floor = float(self._heights(w, self.state.qpos[w, self.ids.qpos[:2]][None], feet_z + 0.05)[0][0])
        width = hi[1 - leg.axis] - lo[1 - leg.axis]
        offsets = lateral_offsets(width, 2 * self.half[1 - leg.axis])
        poses = [push_pose(lo, hi, leg, self.half, float(o)) for o in offsets]
        for staging in (STAGING, 0.0):
            for start, end in poses:
                behind = start - (end - start) / np.linalg.norm(end - start) * staging
                z, objects = self._heights(w, sweep_points(behind, end, self.half), floor + RAY_HEIGHT)
                if np.all((z <= floor + RISE) | (objects == index)):
                    return start, end
        return None

    # -- running moves -----------------------------------------------------------------------------

    def _begin(self, w: int, plan: Plan) -> SkillEnd | None:
        try:
            move = next(plan)
        except StopIteration as stop:
            return self._end(w, stop.value)
        self.active[w] = _Active(plan, move, started=float(self.state.time[w]))
        self._reset_progress(w)
        return None

    def _advance(self, w: int, outcome: Outcome) -> SkillEnd | None:
        """The current move ended with ``outcome``: start the plan's next move or end the skill."""
        active = self.active[w]
        assert active is not None
        try:
            active.move = active.plan.send(outcome)
        except StopIteration as stop:
            return self._end(w, stop.value)
        active.refusal = None
        self._reset_progress(w)
        return None

    def _end(self, w: int, outcome: Outcome | None) -> SkillEnd:
        self.active[w] = None
        self._hold(np.array([w]))
        kind, reason, measured = outcome or ("done", None, {})
        return SkillEnd(world=int(w), outcome=kind, reason=reason, measured=measured)  # type: ignore[arg-type]

    def _reset_progress(self, w: int) -> None:
        active = self.active[w]
        assert active is not None
        active.best, active.progress_time = np.inf, float(self.state.time[w])

    def _hold(self, worlds: np.ndarray) -> None:
        """Stand still where the body is, lift motor off."""
        self.setpoint[worlds] = self.state.qpos[worlds][:, self.ids.qpos[:2]]
        self.sim.ctrl[worlds[:, None], self.ids.actuator[:2]] = self.setpoint[worlds]
        self.sim.ctrl[worlds, self.ids.actuator[2]] = OFF

    def _drive(self, worlds: np.ndarray, ends: list[SkillEnd]) -> None:
        """Read the terrain in every moving world, then stop, refuse, advance or lift."""
        state = self.state
        pos = state.qpos[:, self.ids.qpos]
        goals = np.array([self.active[w].move.goal for w in worlds])  # type: ignore[union-attr]
        delta = goals - pos[worlds, :2]
        dist = np.linalg.norm(delta, axis=1)
        u = np.where(dist[:, None] > 1e-9, delta / np.maximum(dist, 1e-9)[:, None], np.array([1.0, 0.0]))
        extent = self._chord(u)  # half length of the body along the direction of travel
        heights, objects = self._profiles(worlds, u, extent, dist)
        for k, w in enumerate(worlds):
            active = self.active[w]
            assert active is not None
            h = heights[k].copy()
            pushed = objects[k] == active.move.pushing
            n = int((min(dist[k], LOOKAHEAD) + 2 * extent[k]) / SPACING) + 1 - EDGE_SAMPLES
            if active.move.pushing >= 0:
                h[pushed] = h[0]
            under = min(round(2 * extent[k] / SPACING), n - 1)
            footprint = (EDGE_SAMPLES, max(EDGE_SAMPLES, under - EDGE_SAMPLES))
            result = scan(h[:n], SPACING, self.limits, footprint, feet=pos[w, 2])
            reach = dist[k]
            if result.violation is not None:
                reach = min(reach, max(0.0, result.edge - 2 * extent[k] - STOP_MARGIN))
                active.refusal = (
                    "refused",
                    describe_violation(result.violation, result.measured, self.limits),
                    {result.violation: round(float(result.measured), 3)},
                )
            else:
                active.refusal = None
            stop = pos[w, :2] + u[k] * reach
            end = self._check_arrival(w, active, reach, dist[k])
            if end is not None:
                ends.append(end)
                continue
            front = int(np.ceil((2 * extent[k] + LIFT_AHEAD) / SPACING)) + 1
            lift = float(np.nanmax(result.level[: min(front, n)]))
            rest = float(result.level[0])
            lifting = lift > rest + RISE
            belly = self._belly(h, under, pos[w, 2])
            if belly is not None and (not lifting or belly > lift):
                lift, lifting = belly, True
            self.sim.ctrl[w, self.ids.actuator[2]] = lift + CLEARANCE if lifting else OFF
            waiting = lifting and pos[w, 2] < lift + CLEARANCE / 2
            self._step_setpoint(w, stop, moving=not waiting)

    def _belly(self, h: np.ndarray, under: int, feet: float) -> float | None:
        """The height of a surface under the middle of the body that stands higher than both foot rows.

        A step shorter than the feet's span (the body straddles it, front feet past its near edge and rear
        feet not yet on it, or the other way round) carries no foot: the body is held above it by the lift
        motor until a foot row is over it again, instead of dropping onto it with its torso and catching
        its legs on its sides. Only a surface the feet could have stepped onto (within the step limit of
        the feet) counts. None when there is no such surface.
        """
        reach = int(np.ceil(2 * FOOT_RADIUS / SPACING))
        if under - EDGE_SAMPLES <= 2 * reach:
            return None
        rows = max(float(h[EDGE_SAMPLES : reach + 1].max()), float(h[under - reach : under - EDGE_SAMPLES + 1].max()))
        middle = float(h[reach + 1 : under - reach].max())
        if middle > rows + RISE and middle - feet <= self.limits.max_step_up + TOLERANCE:
            return middle
        return None

    def _check_arrival(self, w: int, active: _Active, reach: float, dist: float) -> SkillEnd | None:
        """End the move when the body reached its stopping point, stalled or ran out of time."""
        now = float(self.state.time[w])
        still = float(np.abs(self.state.qvel[w, self.ids.qvel]).max()) < SETTLED_SPEED
        if reach < ARRIVED and still:
            outcome: Outcome = active.refusal or ("done", None, {})
            if dist < ARRIVED or active.refusal is not None:
                return self._advance(w, outcome)
        if dist < active.best - 0.01:
            active.best, active.progress_time = dist, now
        elif now - active.progress_time > STALL_TIME:
            where = self.state.qpos[w, self.ids.qpos]
            return self._advance(
                w,
                (
                    "stalled",
                    f"blocked at [{where[0]:.2f}, {where[1]:.2f}], {dist:.2f} m short of the goal",
                    {"distance": round(dist, 3)},
                ),
            )
        return None

    def _step_setpoint(self, w: int, stop: np.ndarray, moving: bool) -> None:
        """Move the x-y setpoint toward ``stop`` at walking speed, leashed to the body."""
        body = self.state.qpos[w, self.ids.qpos[:2]]
        sp = self.setpoint[w]
        to_stop = stop - sp
        gap = float(np.linalg.norm(to_stop))
        velocity = np.zeros(2)
        if moving and gap > 1e-9 and np.linalg.norm(sp - body) < LEASH:
            step = min(gap, WALK_SPEED * self.scene.control_dt)
            sp += to_stop / gap * step
            if gap > step:
                velocity = to_stop / gap * WALK_SPEED
        self.sim.ctrl[w, self.ids.actuator[:2]] = sp + self.lead * velocity

    # -- sensing -----------------------------------------------------------------------------------

    def _profiles(
        self, worlds: np.ndarray, u: np.ndarray, extent: np.ndarray, dist: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Height profiles (len(worlds), n) along each world's direction, highest across the body width."""
        n = int(np.ceil((LOOKAHEAD + 2 * self.half.max()) / SPACING)) + 1
        lateral = np.stack([-u[:, 1], u[:, 0]], axis=1)
        width = self._chord(lateral) - FOOT_RADIUS
        length = np.minimum(dist, LOOKAHEAD) + 2 * extent
        s = np.minimum(np.arange(n)[None, :] * SPACING, length[:, None])  # (k, n)
        pos = self.state.qpos[worlds][:, self.ids.qpos]
        rear = pos[:, :2] - u * extent[:, None]
        across = np.array([-1.0, 0.0, 1.0])
        xy = (
            rear[:, None, None, :]
            + s[:, :, None, None] * u[:, None, None, :]
            + across[None, None, :, None] * (width[:, None, None, None] * lateral[:, None, None, :])
        )
        top = pos[:, 2] + RAY_HEIGHT
        z, objects = self._cast(worlds, xy.reshape(len(worlds), -1, 2), top)
        z, objects = z.reshape(len(worlds), n, 3), objects.reshape(len(worlds), n, 3)
        best = z.argmax(axis=2)[..., None]
        return np.take_along_axis(z, best, 2)[..., 0], np.take_along_axis(objects, best, 2)[..., 0]

    def _chord(self, u: np.ndarray) -> np.ndarray:
        """Half length of the body's footprint along directions ``u`` (k, 2) through its centre.

        Diagonal moves read the terrain over this central band; the corners outside it meet what
        is there physically.
        """
        return np.min(self.half / np.maximum(np.abs(u), 1e-9), axis=1)

    def _heights(
        self, w: int, xy: np.ndarray, top: float, exclude: int | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Surface heights and hit objects (-1: ground or nothing) under points ``xy`` in world ``w``."""
        z, objects = self._cast(np.array([w]), xy[None], np.array([top]), exclude)
        return z[0], objects[0]

    def _cast(
        self, worlds: np.ndarray, xy: np.ndarray, top: np.ndarray, exclude: int | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Downward rays from height ``top`` (per world) over ``xy`` (k, nray, 2) in ``worlds``."""
        nworld, nray = self.sim.nworld, xy.shape[1]
        pnt = np.zeros((nworld, nray, 3))
        pnt[worlds, :, :2] = xy
        pnt[worlds, :, 2] = top[:, None]
        vec = np.zeros((nworld, nray, 3))
        vec[..., 2] = -1.0
        body = self.ids.body if exclude is None else exclude
        dist, geom = self.sim.rays(pnt, vec, exclude_body=body)
        dist, geom = dist[worlds], geom[worlds]
        hit = np.isfinite(dist)
        z = np.where(hit, top[:, None] - dist, 0.0)
        objects = np.where(hit & (geom >= 0), self.geom_object[np.maximum(geom, 0)], -1)
        if exclude is not None:  # the robot is not excluded: what is under it is read as its own floor
            robot = hit & (self.scene.model.geom_bodyid[np.maximum(geom, 0)] == self.ids.body)
            z = np.where(robot, np.nan, z)
        return z, objects

    # -- object state --------------------------------------------------------------------------------

    def _centers(self, state: BatchState) -> np.ndarray:
        """Object centres (nworld, nobject, 3): body origins; a cloth's is the mean of its links."""
        out = state.xpos[:, self.scene.object_body].copy()
        for i in np.flatnonzero(self.cloth):
            out[:, i] = state.xpos[:, self.scene.body_object == i].mean(axis=1)
        return out

    def _bounds3(self, w: int, index: int) -> tuple[np.ndarray, np.ndarray]:
        """World axis-aligned bounds of an object in world ``w``."""
        if self.cloth[index]:
            center = self._centers(self.state)[w, index]
            half = np.asarray(self.scene.task.objects[index].size) / 2
            return center - half, center + half
        corners = world_corners(self.state, self.scene.object_body[index], self.corners[index])[w]
        return corners.min(axis=0), corners.max(axis=0)

    def _bounds(self, w: int, index: int) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = self._bounds3(w, index)
        return lo[:2], hi[:2]


def robot_on_goal(scene: Scene) -> RobotOnGoal:
    """Tracker for ``robot_on`` goals."""
    return RobotOnGoal(scene)


def lifted_goal(scene: Scene) -> LiftedGoal:
    """Tracker for ``lifted`` goals."""
    return LiftedGoal(scene)


def lowered_goal(scene: Scene) -> LoweredGoal:
    """Tracker for ``lowered`` goals (fragile objects must arrive unbroken)."""
    return LoweredGoal(scene)
