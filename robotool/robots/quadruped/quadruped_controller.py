"""The quadruped embodiment: its skills over batched worlds and its queries.

Every motion skill is a plan of straight moves: a walk is one move, or a few around an object that stands in its way
(:func:`~robotool.robots.quadruped.push.route`); a push is the approach around the object and one push per axis
(:mod:`robotool.robots.quadruped.push`), pushed on along the axis while the object's centre falls short (it turned
on the way), and, while the object ends off the target (it turned or slid aside), pushed again from where it lies,
round after round, as long as each brings it closer and a way round it is clear. When a move starts, and again when
the terrain under a foot changed or the stretch read runs out, downward rays read the path of each of the four feet
from just behind it to :data:`~robotool.robots.quadruped.terrain.LOOKAHEAD` past the move's end (at most
:data:`SCAN_AHEAD` at a time), and :mod:`.terrain` checks every foot's path against the legs' limits: a finding
moves the stopping point to just before it, and once the robot has stopped there the skill is refused with the
measured value, the limit and where. A cloth is no footing over a gap: the rays see through it to what carries
it. Every control tick, in all moving worlds at once, a few rays under and ahead of each foot tell whether a foot
is crossing an accepted edge: then the lift motor carries the body so that foot clears the higher surface (a step
up, a stridden gap), or lets it down slowly past a drop, and the x-y setpoint waits until the foot is clear.
Otherwise the lift is off and the robot's weight rests on its feet.

Every tick, in every world, a robot whose centre of mass has stayed outside the support of its touching feet for
:data:`FALL_TICKS` ticks with the lift off and that tips, or that tilts past :data:`FALL_TILT`, has fallen: its
skill ends with outcome ``fell`` and a reason that says where and which feet lost support,
:attr:`QuadrupedController.failures` marks its world failed, and later motion skills there are refused. A walk or a
climb is no push: a movable object that the torso has touched, other than one being pushed, and that has moved more
than :data:`SHOVE` since (what a foot's weight or a push moved it by not counted), was shoved; so were the objects
that a push rams ahead of the pushed one once together they weigh more than the push limit. The move is stopped and
refused, naming them, and the world fails. A foot or the belly that rests on a fragile object (a low glass vase
reads as a step) breaks it: the move is refused, naming it, and the world fails. Nothing here
reads the task's category or name: limits come from ``task.robot.limits`` and the terrain from the simulated geoms.
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from robotool.robots.quadruped.body import BELLY_HEIGHT, LEG_SLACK, OFF, ROBOT_GROUP, XY_KP, BodyIds, add_body
from robotool.robots.quadruped.push import (
    GAP,
    MIN_LEG,
    Leg,
    lateral_offsets,
    legs,
    push_pose,
    route,
    routes,
    rule_violation,
    sweep_problem,
)
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.support import (
    centre_of_mass,
    feet,
    feet_touching,
    pass_weight,
    resting_on,
    supported,
    tilt,
    unsupported_feet,
)
from robotool.robots.quadruped.terrain import (
    EDGE_KINDS,
    FOOT_NAMES,
    FOOT_RADIUS,
    LOOKAHEAD,
    RADIUS_SAMPLES,
    RISE,
    SPACING,
    Finding,
    TerrainKind,
    check_walk,
    finding_kind,
    limit_of,
    scan_paths,
)
from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.compiled_scene import Scene
from robotool.sim.embodiment import QueryError, SkillEnd, error_end, size_now, world_mask
from robotool.sim.object_goals import local_corners, world_corners
from robotool.task_model import Task
from robotool.vocabulary import MoveEnd

WALK_SPEED = 0.4  # m/s
SCAN_AHEAD = 1.2  # m of a move read at a time (plus LOOKAHEAD)
BACK = 0.06  # m read behind each foot (the lift's window over an edge just passed)
LIFT_AHEAD = 0.10  # m ahead of a foot's centre where a higher surface starts the lift
HOLD_BEHIND = 0.03  # m past a drop edge over which the lift holds the foot up before letting it down
CLEARANCE = 0.025  # m the lift carries a foot above the surface it steps onto
DESCENT_SPEED = 0.15  # m/s at which the lift lets the body down past a drop
RELEASE = 0.02  # m: a lift setpoint this far below the body is off
PRESS = 0.01  # m a leg's setpoint reaches below the surface under its foot
LEG_SPEED = 0.25  # m/s at which a leg changes length
TORSO_CLEARANCE = 0.02  # m the legs keep the torso above what lies under it
MAX_HOVER = 0.2  # m of travel a foot may take to cross an edge (a step, or a stride over a gap, takes less)
TORSO_GRID = np.array([[x, y] for x in (-0.9, 0.0, 0.9) for y in (-0.8, 0.0, 0.8)])  # under the torso, in half sizes
TILT_GAIN = 2.0  # 1/rad: tilt motor control per rad of pitch or roll while the lift carries the body
TILT_DAMPING = 0.15  # s/rad: tilt motor control per rad/s of pitch or roll, likewise
STOP_MARGIN = 0.03  # m between a foot and a refused step's face
EDGE_MARGIN = 0.01  # m between a foot's centre and a refused gap's or drop's edge
ARRIVED = 0.015  # m from a move's stopping point that counts as there
SETTLED_SPEED = 0.03  # m/s: a move ends only once the body is this still
SETTLED_TURN = 0.2  # rad/s of pitch and roll, likewise
LEASH = 0.06  # m the setpoint may run ahead of the body
STALL_TIME = 3.0  # s without 1 cm of progress is a stall
STAGING = 0.15  # m behind the push pose from where the robot lines up straight along the push
PUSH_TOLERANCE = 0.06  # m: a push is done when the object's centre is this close to the target
FOLLOW_THROUGHS = 2  # pushes on along a leg whose object's centre fell short of the leg's target
CORRECTIONS = 2  # pushes again from where the object ended when it turned or slid off the line and missed the target
CORRECTION_GAIN = 0.02  # m a push round must bring the object closer to the target for another round to follow
FALL_CONDITION = "robot_has_not_fallen"  # the goal condition a fall breaks
SHOVE_CONDITION = "robot_shoved_nothing"  # the goal condition a shove breaks
CRUSH_CONDITION = "robot_stood_on_nothing_fragile"  # the goal condition a foot or the belly on a fragile object breaks
SHOVE = 0.03  # m a movable object may move after the torso touched it, unless it is being pushed
RAY_HEIGHT = 0.6  # m above the feet where downward rays start (things higher are overhead)
CLOTH_STEP = 1e-4  # m above the point where a ray met a cloth from where it is cast again
FALL_TILT = np.radians(35.0)  # a body tilted further has fallen
FALL_TICKS = 3  # control ticks with the centre of mass outside the feet's support (lift off) that make a fall...
TIPPING = np.radians(5.0)  # ... once the body tilts this much (a level body with a foot off the ground is not falling)
SUPPORT_MARGIN = -0.02  # m: the support polygon grown by this much before the centre of mass counts as outside
LOCAL = np.array([-FOOT_RADIUS, 0.0, FOOT_RADIUS, LIFT_AHEAD / 2, LIFT_AHEAD])  # per-tick samples along a foot's path
SAMPLES = round((BACK + SCAN_AHEAD + LOOKAHEAD) / SPACING) + 1
BEHIND = round(BACK / SPACING)  # the sample under a foot at scan time


@dataclass
class _Move:
    """One straight move to ``goal`` (x-y); ``pushing`` is the object index being pushed or -1."""

    goal: np.ndarray
    pushing: int = -1


Plan = Generator[_Move, MoveEnd, MoveEnd | None]


class QuadrupedEmbodiment:
    """The quadruped (Go1-sized) with the limits of one task."""

    control_substeps = 25  # 20 Hz: the lift motor must react within a step's approach

    def __init__(self, limits: QuadrupedLimits):
        self.limits = limits

    def add_to_spec(self, spec: mujoco.MjSpec, task: Task) -> None:
        """Add the robot body and its actuators (see :mod:`robotool.robots.quadruped.body`)."""
        add_body(spec, task)

    def controller(self, sim: BatchedSim) -> QuadrupedController:
        return QuadrupedController(sim, self.limits)


class QuadrupedController:
    """Runs the quadruped's skills in every world of one batched simulator.

    ``failures[w]`` says why world ``w``'s robot can no longer be trusted (it fell), else None.
    """

    def __init__(self, sim: BatchedSim, limits: QuadrupedLimits):
        self.sim, self.limits = sim, limits
        self.scene: Scene = sim.scene
        model = self.scene.model
        nworld = sim.nworld
        self.ids = BodyIds.of(model)
        self.half = np.array(limits.body_size[:2]) / 2
        self.height = limits.body_size[2]
        self.lead = self.ids.xy_kv / XY_KP  # s: setpoint lead that cancels the servo's lag at speed
        self.corners = local_corners(self.scene)
        self.geom_object = self.scene.body_object[model.geom_bodyid]
        self.cloth = np.array([o.shape == "cloth" for o in self.scene.task.objects], dtype=bool)
        # the most recasts one cast needs: one per cloth link for every layer of cloth a ray can pass
        self.cloth_crossings = int(self.cloth[self.geom_object[self.geom_object >= 0]].sum()) ** 2
        self.movable = np.array([o.movable for o in self.scene.task.objects])
        self.fragile = np.array([o.fragile is not None for o in self.scene.task.objects], dtype=bool)
        self.not_robot = ~self.scene.robot_body
        self.plans: list[Plan | None] = [None] * nworld
        self.failures: list[str | None] = [None] * nworld
        self.shoves: list[str | None] = [None] * nworld  # the first object each world's robot shoved, and how far
        self.crushes: list[str | None] = [None] * nworld  # the first fragile object each world's robot stood on
        # the move running in each world
        self.moving = np.zeros(nworld, dtype=bool)
        self.origin = np.zeros((nworld, 2))  # body position where the move started
        self.u = np.tile([1.0, 0.0], (nworld, 1))  # its direction
        self.length = np.zeros(nworld)  # its length
        self.pushing = np.full(nworld, -1)
        self.stop = np.zeros(nworld)  # travel along the move where the body must stop
        self.findings: list[Finding | None] = [None] * nworld
        self.best = np.full(nworld, np.inf)
        self.progress_time = np.zeros(nworld)
        # the last reading of each world's feet paths: index k lies at travel scan_t0 - BACK + k * SPACING
        self.rescan = np.zeros(nworld, dtype=bool)
        self.scan_t0 = np.zeros(nworld)
        self.heights = np.full((nworld, 4, SAMPLES), np.nan)
        self.level = np.full((nworld, 4, SAMPLES), np.nan)
        self.lift = np.full(nworld, np.nan)  # lift setpoint (NaN: off)
        self.outside = np.zeros(nworld, dtype=int)  # ticks the centre of mass has been outside the support
        self.lost_support = np.full(nworld, None, dtype=object)  # where and how it last left its support
        self.legs = np.full((nworld, 4), -PRESS)  # the legs' setpoints: standing, each carries its share
        sim.ctrl[:, self.ids.leg_actuator] = self.legs
        self.hover_from = np.full((nworld, 4), np.nan)  # travel where each foot began to cross an edge
        self.halted = np.zeros(nworld, dtype=bool)  # the move was refused for want of footing
        # where each object's centre was when the torso first touched it (NaN: untouched, or pushed since)
        self.bumped = np.full((nworld, len(self.scene.object_names), 2), np.nan)
        # touched without a break, and without a walk, since a push of it (it may slide on after the push ended)
        self.pressed = np.zeros((nworld, len(self.scene.object_names)), dtype=bool)
        self.reach = limits.max_step_down + LEG_SLACK
        self.state: BatchState = sim.state()
        self._memo: tuple[BatchState | None, dict[Any, np.ndarray]] = (None, {})  # see _of_state
        # how far each object travelled while a push of another object rammed it, from push to push until the robot
        # pushes it itself, and where each object was at the last tick
        self.carried = np.zeros((nworld, len(self.scene.object_names)))
        self.last_centres = self._centers(self.state)[:, :, :2]
        self.setpoint = self.state.qpos[:, self.ids.qpos[:2]].copy()
        self._hold(np.arange(nworld))

    # -- the controller interface ----------------------------------------------------------------

    def start(self, state: BatchState, worlds: np.ndarray, skill: str, args: tuple[Any, ...]) -> list[SkillEnd]:
        """Begin a motion skill; pushes that break a rule, and any motion of a fallen robot, are refused at once."""
        self.state = state
        ends = []
        for w in np.asarray(worlds, dtype=int).reshape(-1):
            if self.failures[w] is not None:
                ends.append(
                    SkillEnd(world=int(w), outcome="refused", reason=f"the robot has fallen ({self.failures[w]})")
                )
                continue
            plan = self._push_plan(w, *args) if skill == "push_to_position" else self._walk_plan(w, args[0])
            end = self._begin(w, plan)
            if end is not None:
                ends.append(end)
        return ends

    def robot_conditions(self) -> dict[str, list[bool]]:
        """What every goal also needs, per world: the robot has not fallen, it shoved nothing by walking into it
        (what a shove moved, such as a vase pushed off its edge, may not count toward a goal) and, in a scene with a
        fragile object, it stood on none (its weight would break it)."""
        conditions = {
            FALL_CONDITION: [f is None for f in self.failures],
            SHOVE_CONDITION: [s is None for s in self.shoves],
        }
        if self.fragile.any():
            conditions[CRUSH_CONDITION] = [c is None for c in self.crushes]
        return conditions

    def tick(self, state: BatchState, worlds: np.ndarray | None = None) -> list[SkillEnd]:
        """Report finished skills, falls and shoves, and write the controls for the next interval (in ``worlds``,
        every world when None)."""
        self.state = state
        mask = world_mask(self.sim.nworld, worlds)
        ends = self._falls(mask)
        centres = self._centers(state)[:, :, :2]
        shift = centres - self.last_centres  # each object's travel since the last tick
        self.last_centres = np.where(mask[:, None, None], centres, self.last_centres)
        self._shoves(ends, mask, centres, shift)
        self._rams(ends, mask, centres, shift)
        if self.fragile.any():
            self._crushes(ends, mask)
        worlds = np.flatnonzero(mask & self.moving & np.array([f is None for f in state.failed]))
        if worlds.size:
            self._drive(worlds, ends)
        return ends

    def query(self, state: BatchState, world: int, skill: str, args: tuple[Any, ...]) -> Any:
        """``get_position`` / ``get_size`` of an object or of ``robot``, from the current state."""
        name = args[0]
        if name == "robot":
            if skill == "get_size":
                return list(self.limits.body_size)
            centres = feet(state, self.ids)[world]
            x, y = centres[:, :2].mean(axis=0)
            return [float(x), float(y), float(centres[:, 2].mean() - FOOT_RADIUS + self.height / 2)]
        try:
            index = self.scene.object_index(name)
        except KeyError as e:
            raise QueryError(str(e.args[0])) from None
        if skill == "get_size":
            return size_now(self.scene, state, world, index)
        return [float(v) for v in self._centers(state)[world, index]]

    # -- skill plans -------------------------------------------------------------------------------

    def _walk_plan(self, w: int, target: tuple[float, float, float]) -> Plan:
        """Straight to ``target`` when the feet's paths allow it; else along an L (one axis, then the other) that
        does; else around the object whose side is too high to climb (refused, naming it, when there is no way
        round); else straight, to be refused where the legs meet their limit."""
        goal = np.array(target[:2], dtype=float)
        here = self._position(w)
        found = self._check(w, here, [goal])
        path = [goal]
        if found is not None:
            corners = [np.array([goal[0], here[1]]), np.array([here[0], goal[1]])]
            ways = [[c, goal] for c in corners if min(np.linalg.norm(c - here), np.linalg.norm(goal - c)) > ARRIVED]
            obstacle = found[1] if found[0].kind == "step" else -1
            if obstacle >= 0:
                lo, hi = self._bounds(w, obstacle)
                if not np.all((goal >= lo) & (goal <= hi)):  # the goal is not on it: go around it
                    ways.append(route(here, goal, lo - self.half - GAP, hi + self.half + GAP))
            clear = next((way for way in ways if self._check(w, here, way) is None), None)
            if clear is not None:
                path = clear
            elif obstacle >= 0 and not np.all((goal >= lo) & (goal <= hi)):
                name = self.scene.object_names[obstacle]
                return "refused", f"the way is blocked by {name}: {found[0].describe()}", _measured(found[0])
        for waypoint in path:
            outcome = yield _Move(waypoint)
            if outcome[0] != "done":
                return outcome
        return None

    def _push_plan(self, w: int, name: str, target: tuple[float, float, float]) -> Plan:
        try:
            index = self.scene.object_index(name)
        except KeyError as e:
            return "refused", str(e.args[0]), {}
        goal = np.array(target[:2], dtype=float)
        miss, blocked = np.inf, False
        for attempt in range(1 + CORRECTIONS):
            broken = self._push_rules(w, index)
            if broken is not None:
                if attempt:  # what it moved changed (it fell off something, something landed on it): no correction
                    break
                return "refused", f"cannot push {name}: {broken[0]}", broken[1]
            for leg in legs(self._centers(self.state)[w, index], goal):
                lo, hi = self._bounds(w, index)
                pose, problem = self._clear_pose(w, index, leg, lo, hi)
                if pose is None:
                    if attempt:  # no way to correct the drift: the push stopped where it did
                        break
                    return "refused", f"cannot push {name}: no clear place to stand behind it{problem}", {}
                start, end, behind = pose
                robot = self._position(w)
                staging = start - (end - start) / np.linalg.norm(end - start) * behind
                ways = routes(robot, staging, lo - self.half - GAP / 2, hi + self.half + GAP / 2)
                if attempt:  # a correction goes only a way round that the legs can walk, or not at all
                    way = next((way for way in ways if self._check(w, robot, [*way, start]) is None), None)
                    if way is None:
                        break
                else:
                    way = ways[0]
                for waypoint in [*way, start]:
                    outcome = yield _Move(waypoint)
                    if outcome[0] != "done":
                        return outcome
                height = self._centers(self.state)[w, index, 2]
                outcome = yield _Move(end, pushing=index)
                if outcome[0] not in ("done", "stalled"):
                    return outcome
                blocked |= outcome[0] == "stalled"
                u = (end - start) / np.linalg.norm(end - start)
                for _ in range(FOLLOW_THROUGHS):  # it turned on the way: push on until its centre gets there
                    centre = self._centers(self.state)[w, index]
                    short = (leg.target - centre[leg.axis]) * u[leg.axis]
                    if blocked or short < MIN_LEG or abs(centre[2] - height) > RISE:  # (not after it fell off)
                        break
                    outcome = yield _Move(self._position(w) + u * short, pushing=index)
                    if outcome[0] not in ("done", "stalled"):
                        return outcome
                    blocked |= outcome[0] == "stalled"
                back = (start - end) / np.linalg.norm(start - end) * GAP
                outcome = yield _Move(self._position(w) + back)
                if outcome[0] != "done":
                    return outcome
            previous, miss = miss, float(np.linalg.norm(self._centers(self.state)[w, index, :2] - goal))
            if miss <= PUSH_TOLERANCE or blocked or miss > previous - CORRECTION_GAIN:
                break
        if miss > PUSH_TOLERANCE:
            return "stalled", f"{name} stopped {miss:.2f} m from the target", {"distance": miss}
        return None

    def _push_rules(self, w: int, index: int) -> tuple[str, dict[str, float]] | None:
        """Check the push rules in world ``w`` from rays under the feet and the object, and the masses it moves."""
        centres = feet(self.state, self.ids)[w]
        z, objects = self._heights(w, centres[:, :2], float(centres[:, 2].max()) + 0.05)
        on = objects[z >= z.max() - RISE]
        on = on[on >= 0]
        movable = next((self.scene.object_names[o] for o in on if self.movable[o]), None)
        obj_lo, obj_hi = self._bounds3(w, index)
        centre_obj = (obj_lo + obj_hi) / 2
        below, _ = self._heights(w, centre_obj[None, :2], obj_hi[2] + 0.01, exclude=self.scene.object_body[index])
        riders = self._riders(w, index)
        mass = float(sum(self._mass(w, o) for o in [index, *riders]))
        return rule_violation(
            movable=bool(self.movable[index]),
            mass=round(mass, 3),
            riders=[self.scene.object_names[o] for o in riders],
            under_robot=bool(np.isin(index, on)),
            robot_support_movable=movable,
            object_support=float(below[0]),
            robot_support=float(z.max()),
            limits=self.limits,
        )

    def _riders(self, w: int, index: int) -> list[int]:
        """Movable objects that ride on object ``index`` in world ``w``, recursively: higher than what carries them
        and touching nothing else (but the robot)."""
        state, owner = self.state, self.scene.body_object
        centres = self._centers(state)[w]
        carried = [index]
        riders: list[int] = []
        robot = self.scene.robot_body
        while carried:
            base = carried.pop()
            touching = state.touching[w][owner == base].any(axis=0)
            for other in np.unique(owner[touching & (owner >= 0)]):
                if (
                    other == index
                    or other in riders
                    or not self.movable[other]
                    or centres[other, 2] <= centres[base, 2]
                ):
                    continue
                supports = state.touching[w][owner == other].any(axis=0) & ~robot & (owner != other)
                if np.all(np.isin(owner[supports], [index, *riders])):  # it rests on what the push moves only
                    riders.append(int(other))
                    carried.append(int(other))
        return riders

    def _mass(self, w: int, index: int) -> float:
        """World ``w``'s (perturbed) mass of object ``index``, all its bodies."""
        return float(self.sim.body_mass[w, self.scene.body_object == index].sum())

    def _clear_pose(
        self, w: int, index: int, leg: Leg, lo: np.ndarray, hi: np.ndarray
    ) -> tuple[tuple[np.ndarray, np.ndarray, float] | None, str]:
        """The push start and end poses nearest straight-on whose sweep meets nothing above the floor and whose
        feet stay over the floor (no drop, no gap), with how far behind the start the robot lines up; when there
        is none, what was wrong under the feet.

        Poses whose sweep is clear from the staging point (``STAGING`` behind the start, where the robot lines up)
        come first, so that the robot can line up there; failing those, a clear sweep from the start will do.
        """
        centres = feet(self.state, self.ids)[w]
        floor = float(centres[:, 2].min() - FOOT_RADIUS)
        width = hi[1 - leg.axis] - lo[1 - leg.axis]
        offsets = lateral_offsets(width, 2 * self.half[1 - leg.axis])
        poses = [push_pose(lo, hi, leg, self.half, float(o)) for o in offsets]

        def heights(xy: np.ndarray) -> np.ndarray:
            z, objects = self._heights(w, xy, floor + RAY_HEIGHT)
            return np.where(objects == index, floor, z)

        problem = ""  # the first drop found: under the pose nearest straight-on, where the robot would push from
        for staging in (STAGING, 0.0):
            for start, end in poses:
                behind = start - (end - start) / np.linalg.norm(end - start) * staging
                found = sweep_problem(heights, behind, end, self.limits, floor)
                if found is None:
                    return (start, end, staging), ""
                if found.kind == "drop" and not problem:
                    where = f"[{start[0]:.2f}, {start[1]:.2f}] to [{end[0]:.2f}, {end[1]:.2f}]"
                    problem = f": pushing from {where}, {found}"
        return None, problem

    # -- running moves -----------------------------------------------------------------------------

    def _begin(self, w: int, plan: Plan) -> SkillEnd | None:
        self.plans[w] = plan
        try:
            move = next(plan)
        except StopIteration as stop:
            return self._end(w, stop.value)
        self._start_move(w, move)
        return None

    def _advance(self, w: int, outcome: MoveEnd) -> SkillEnd | None:
        """The current move ended with ``outcome``: start the plan's next move or end the skill (with outcome
        ``error`` when the plan raises: an advanced plan cannot be rolled back, so this world's error is its own)."""
        plan = self.plans[w]
        assert plan is not None
        try:
            move = plan.send(outcome)
            self._start_move(w, move)
        except StopIteration as stop:
            return self._end(w, stop.value)
        except Exception as e:  # any error in this world's plan ends this world's skill only
            self._end(w, None)
            return error_end(w, e)
        return None

    def _start_move(self, w: int, move: _Move) -> None:
        here = self._position(w)
        delta = move.goal - here
        length = float(np.linalg.norm(delta))
        self.moving[w] = True
        self.origin[w] = here
        self.u[w] = delta / length if length > 1e-9 else np.array([1.0, 0.0])
        self.length[w] = length
        self.pushing[w] = move.pushing
        self.stop[w] = 0.0
        self.findings[w] = None
        self.rescan[w] = True
        self.level[w] = np.nan
        self.hover_from[w] = np.nan
        self.halted[w] = False
        if move.pushing >= 0:
            self.bumped[w, move.pushing] = np.nan
            self.carried[w, move.pushing] = 0.0
        self.best[w], self.progress_time[w] = np.inf, float(self.state.time[w])

    def _end(self, w: int, outcome: MoveEnd | None) -> SkillEnd:
        self.plans[w] = None
        self.moving[w] = False
        self._hold(np.array([w]))
        kind, reason, measured = outcome or ("done", None, {})
        return SkillEnd(world=int(w), outcome=kind, reason=reason, measured=measured)

    def _hold(self, worlds: np.ndarray) -> None:
        """Stand still where the body is, lift motor off."""
        self.setpoint[worlds] = self.state.qpos[worlds][:, self.ids.qpos[:2]]
        self.sim.ctrl[worlds[:, None], self.ids.actuator[:2]] = self.setpoint[worlds]
        self.sim.ctrl[worlds, self.ids.actuator[2]] = OFF
        self.sim.ctrl[worlds[:, None], self.ids.actuator[3:]] = 0.0
        self.lift[worlds] = np.nan

    def _drive(self, worlds: np.ndarray, ends: list[SkillEnd]) -> None:
        """Read the terrain where needed, then lift, stop, refuse or advance, in all moving worlds at once."""
        state = self.state
        q = state.qpos[worlds][:, self.ids.qpos]
        travel = np.einsum("ki,ki->k", q[:, :2] - self.origin[worlds], self.u[worlds])
        centres = feet(state, self.ids)[worlds]
        local, local_objects, under_torso = self._local(worlds, centres)
        index = self._indices(worlds, travel)
        stale = self.rescan[worlds] | np.any((index < 0) | (index >= SAMPLES), axis=1)
        stale |= (travel > self.scan_t0[worlds] + SCAN_AHEAD / 2) & (
            self.length[worlds] > self.scan_t0[worlds] + SCAN_AHEAD
        )
        stored = self._gather(self.heights[worlds], index)
        pushed = (local_objects == self.pushing[worlds][:, None, None]) & (local_objects >= 0)
        stale |= np.any(~pushed & (np.abs(local - stored) > RISE), axis=(1, 2))
        if stale.any():
            self._scan(worlds[stale], travel[stale], centres[stale])
            index = self._indices(worlds, travel)
        local = np.where(pushed, self._gather(self.heights[worlds], index), local)
        waiting = self._lift(worlds, q, travel, centres, local, under_torso, index)
        self._steer(worlds, q, travel, waiting)
        self._check_arrival(worlds, q, travel, ends)

    def _shoves(self, ends: list[SkillEnd], mask: np.ndarray, centres: np.ndarray, shift: np.ndarray) -> None:
        """Find the objects the robot shoved, in the worlds in ``mask``: a movable object (not a cloth) that the
        torso touches outside a push of it or of something it touches (and the contact that lasts on from the push
        until the next walk), and that no foot stands on (a lever tips under the robot), is remembered where it is;
        while a push presses it or a foot stands on it, that place moves along with it (so shoves add up, however
        they are split between steps onto it); once it lies more than :data:`SHOVE` from that place, it was shoved
        (a walk or a climb is no push: it would move
        things the push rules refuse, such as objects over the push limit, and what it moved may slide or tip on
        after the robot stops). The world fails (:meth:`robot_conditions`) and a move in progress there is stopped
        and refused, naming the object."""
        state = self.state
        touched = state.touching[:, self.ids.body][:, self.scene.object_body] & self.movable & ~self.cloth
        touched &= mask[:, None]
        pushed = (np.arange(len(self.scene.object_names))[None, :] == self.pushing[:, None]) & self.moving[:, None]
        pushed &= mask[:, None]
        for w in np.flatnonzero(pushed.any(axis=1)):  # what the pushed object moves by touching it moves with it
            pushed[w] |= state.touching[w, self.scene.object_body[self.pushing[w]]][self.scene.object_body]
        walking = (self.moving & (self.pushing < 0))[:, None]
        self.pressed = np.where(mask[:, None], pushed | (self.pressed & touched & ~walking), self.pressed)
        stood_on = state.touching[:, self.ids.feet][:, :, self.scene.object_body].any(axis=1)  # it carries a foot
        excused = (self.pressed | stood_on) & mask[:, None]
        self.bumped = np.where(excused[:, :, None], self.bumped + shift, self.bumped)
        first = touched & ~self.pressed & ~stood_on & np.isnan(self.bumped[:, :, 0])
        self.bumped[first] = centres[first]
        moved = np.nan_to_num(np.linalg.norm(centres - self.bumped, axis=2), nan=0.0)
        for w in np.flatnonzero(mask & (moved > SHOVE).any(axis=1)):
            if self.shoves[w] is not None or state.failed[w] is not None:
                continue
            index = int(np.argmax(moved[w]))
            self.shoves[w] = reason = (
                f"the robot ran into {self.scene.object_names[index]} and moved it {moved[w, index]:.2f} m "
                "(a walk or a climb does not push things: push_to_position does, within the push rules)"
            )
            self._refuse_move(int(w), reason, {"moved": round(float(moved[w, index]), 3)}, ends)

    def _crushes(self, ends: list[SkillEnd], mask: np.ndarray) -> None:
        """Find the fragile objects the robot stands on, in the worlds in ``mask``: a foot that touches one with its
        centre above the object's centre, or a belly that touches one whose centre lies under the torso, rests the
        robot's weight on it, which breaks it (a low vase read as a step is no footing); so does standing on a
        movable object that rests on it (:meth:`_loaded`: a board lying on a vase). The world fails
        (:meth:`robot_conditions`) and a move in progress there is stopped and refused, naming the object."""
        state = self.state
        bodies = self.scene.object_body[self.fragile]
        centres = state.xpos[:, bodies]  # (nworld, nfragile, 3)
        foot_z = feet(state, self.ids)[:, :, 2]
        by_foot = state.touching[:, self.ids.feet][:, :, bodies] & (foot_z[:, :, None] > centres[:, None, :, 2])
        torso = state.xpos[:, self.ids.body]
        under = np.all(np.abs(centres[:, :, :2] - torso[:, None, :2]) < self.half, axis=2)
        by_belly = state.touching[:, self.ids.body][:, bodies] & under
        stood_on = (by_foot.any(axis=1) | by_belly) & mask[:, None]
        loaded, via = self._loaded(mask)
        for w in np.flatnonzero((stood_on | loaded[:, self.fragile]).any(axis=1)):
            if self.crushes[w] is not None or state.failed[w] is not None:
                continue
            index = int(np.flatnonzero(self.fragile)[np.argmax(stood_on[w] | loaded[w, self.fragile])])
            name = self.scene.object_names[index]
            what = name if stood_on[w].any() else f"{self.scene.object_names[via[w, index]]}, which rests on {name}"
            self.crushes[w] = reason = f"the robot stood on {what}, which is fragile: the robot's weight would break it"
            self._refuse_move(int(w), reason, {}, ends)

    def _loaded(self, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(nworld, nobject) the objects that carry the robot's weight through movable objects, in the worlds in
        ``mask``: a movable object (not fragile) under a foot carries it, and passes it on to each object it rests
        on (touching it, that object's centre below its underside along its own up axis: under a board lying flat or
        leaning on it from the floor); a fixed object passes it to the ground.
        Also (nworld, nobject) the object that passed the weight on to each one."""
        state, owner = self.state, self.scene.body_object
        nobject = len(self.scene.object_names)
        loaded, via = np.zeros((self.sim.nworld, nobject), dtype=bool), np.zeros((self.sim.nworld, nobject), dtype=int)
        member = (owner[None, :] == np.arange(nobject)[:, None]).astype(float)  # (nobject, nbody)
        carrier = self.movable & ~self.fragile
        under_feet = (state.touching[:, self.ids.feet].any(axis=1).astype(float) @ member.T > 0) & carrier
        worlds = np.flatnonzero(mask & under_feet.any(axis=1))
        if worlds.size == 0:
            return loaded, via
        rests = resting_on(state, self.scene, self.corners, worlds)
        loaded[worlds], via[worlds] = pass_weight(rests, under_feet[worlds], carrier)
        return loaded, via

    def _rams(self, ends: list[SkillEnd], mask: np.ndarray, centres: np.ndarray, shift: np.ndarray) -> None:
        """Find the pushes that ram more than the robot may push, in the worlds in ``mask``. A push rams the movable
        objects that the pushed object presses, directly or through others, and whose centres lie beyond its front
        face (what rides on it is checked when the push starts; what it drags by friction is not rammed); the travel
        of each rammed object adds up from push to push until the robot pushes it itself. Once the pushed object and
        the rammed objects that travelled more than :data:`SHOVE` weigh more than the push limit, the robot shoved
        them (a light object used as a ram moves no more than the robot may push): the world fails
        (:meth:`robot_conditions`) and the push is stopped and refused, naming them."""
        step = np.linalg.norm(shift, axis=2)
        for w in np.flatnonzero(mask & self.moving & (self.pushing >= 0)):
            index = int(self.pushing[w])
            lo, hi = self._bounds(w, index)
            front = float(np.abs(self.u[w]) @ (hi - lo)) / 2  # from the pushed object's centre to its front face
            ahead = (centres[w] - centres[w, index]) @ self.u[w] > front  # centres beyond that face
            rammed = self._pressed_by(w, index) & ahead
            self.carried[w] += np.where(rammed, step[w], 0.0)
            moved = np.flatnonzero(rammed & (self.carried[w] > SHOVE))
            mass = self._mass(w, index) + sum(self._mass(w, int(o)) for o in moved)
            if mass <= self.limits.max_push_mass or self.shoves[w] is not None or self.state.failed[w] is not None:
                continue
            self.shoves[w] = reason = (
                f"pushing {self.scene.object_names[index]} rammed "
                f"{', '.join(self.scene.object_names[o] for o in moved)}: {mass:.1f} kg in all, over the "
                f"push limit of {self.limits.max_push_mass:.1f} kg (a push moves only what the robot may push)"
            )
            measured = {"mass": round(mass, 3), "limit": self.limits.max_push_mass}
            self._refuse_move(int(w), reason, measured, ends)

    def _refuse_move(self, w: int, reason: str, measured: dict[str, float], ends: list[SkillEnd]) -> None:
        """Stop the move in progress in world ``w``, if any: its skill is refused with ``reason``."""
        if self.moving[w] and self.plans[w] is not None:
            end = self._advance(w, ("refused", reason, measured))
            if end is not None:
                ends.append(end)

    def _pressed_by(self, w: int, index: int) -> np.ndarray:
        """(nobject,) the movable objects that object ``index`` touches in world ``w``, directly or through other
        movable objects (itself left out)."""
        owner = self.scene.body_object
        touching = self.state.touching[w]
        group = np.zeros(len(self.scene.object_names), dtype=bool)
        group[index] = True
        frontier = [index]
        while frontier:
            near = touching[owner == frontier.pop()].any(axis=0) & (owner >= 0)
            for other in np.unique(owner[near]):
                if self.movable[other] and not group[other]:
                    group[other] = True
                    frontier.append(int(other))
        group[index] = False
        return group

    def _indices(self, worlds: np.ndarray, travel: np.ndarray) -> np.ndarray:
        """Sample indices (k, 5) of the :data:`LOCAL` offsets ahead of the feet in each world's last reading."""
        t = travel - self.scan_t0[worlds] + BACK
        return np.round((t[:, None] + LOCAL[None, :]) / SPACING).astype(int)

    @staticmethod
    def _gather(table: np.ndarray, index: np.ndarray) -> np.ndarray:
        """``table`` (k, 4, SAMPLES) at ``index`` (k, 5) for every foot -> (k, 4, 5) (NaN out of range)."""
        ok = (index >= 0) & (index < SAMPLES)
        out = np.take_along_axis(table, np.clip(index, 0, SAMPLES - 1)[:, None, :].repeat(4, axis=1), axis=2)
        return np.where(ok[:, None, :], out, np.nan)

    def _local(self, worlds: np.ndarray, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Heights and objects (k, 4, 5) at the :data:`LOCAL` offsets along each foot's path, and the highest
        surface under the torso (k,) (the pushed object left out)."""
        k = len(worlds)
        points = centres[:, :, None, :2] + LOCAL[None, None, :, None] * self.u[worlds][:, None, None, :]
        torso = self.state.qpos[worlds][:, None, self.ids.qpos[:2]] + TORSO_GRID * self.half
        top = centres[:, :, 2].min(axis=1) + RAY_HEIGHT
        z, objects = self._cast(worlds, np.concatenate([points.reshape(k, -1, 2), torso], axis=1), top)
        pushed = (objects == self.pushing[worlds][:, None]) & (objects >= 0)
        under_torso = np.where(pushed, -np.inf, z)[:, 4 * len(LOCAL) :].max(axis=1)
        return (z[:, : 4 * len(LOCAL)].reshape(k, 4, -1), objects[:, : 4 * len(LOCAL)].reshape(k, 4, -1), under_torso)

    def _scan(self, worlds: np.ndarray, travel: np.ndarray, centres: np.ndarray) -> None:
        """Read and check the feet's paths ahead in ``worlds``; set where each must stop and why."""
        u = self.u[worlds]
        bottom = centres[:, :, 2] - FOOT_RADIUS
        ahead = np.clip(self.length[worlds] - travel, 0.0, SCAN_AHEAD) + LOOKAHEAD
        s = np.minimum(-BACK + np.arange(SAMPLES) * SPACING, ahead[:, None])  # (k, SAMPLES)
        points = centres[:, :, None, :2] + s[:, None, :, None] * u[:, None, None, :]
        z, objects = self._cast(worlds, points.reshape(len(worlds), -1, 2), bottom.min(axis=1) + RAY_HEIGHT)
        z, objects = z.reshape(points.shape[:3]), objects.reshape(points.shape[:3])
        under = z[:, :, BEHIND - RADIUS_SAMPLES : BEHIND + RADIUS_SAMPLES + 1]
        actual = np.minimum(bottom + RISE, np.nanmax(under, axis=2))
        now = self._indices(worlds, travel)[:, 1]
        before = self._gather(self.level[worlds], now[:, None])[:, :, 0]
        over_gap = np.nan_to_num(before - actual, nan=0.0) > self.limits.max_step_up  # striding a gap: keep its level
        start = np.where(over_gap, before, actual)
        into_gap = np.zeros(over_gap.shape)
        for k, f in zip(*np.nonzero(over_gap), strict=True):  # how far into it, from the last reading
            w, i = worlds[k], int(now[k])
            low = self.heights[w, f, : i + 1] < self.level[w, f, : i + 1] - self.limits.max_step_up
            edge = np.flatnonzero(~low)
            into_gap[k, f] = (i - (edge[-1] if edge.size else -1)) * SPACING
        pushed = (objects == self.pushing[worlds][:, None, None]) & (objects >= 0)
        z = np.where(pushed, start[:, :, None], z)
        result = scan_paths(
            z[:, :, BEHIND:].reshape(-1, SAMPLES - BEHIND), start.reshape(-1), self.limits, into_gap.reshape(-1)
        )
        level = np.concatenate(
            [np.repeat(start[:, :, None], BEHIND, axis=2), result.level.reshape(len(worlds), 4, -1)], axis=2
        )
        self.heights[worlds], self.level[worlds] = z, level
        self.scan_t0[worlds] = travel
        self.rescan[worlds] = False
        index = result.index.reshape(len(worlds), 4) + BEHIND
        kind = result.kind.reshape(len(worlds), 4)
        measured = result.measured.reshape(len(worlds), 4)
        meets = travel[:, None] + np.take_along_axis(s, np.minimum(index, SAMPLES - 1), axis=1)
        edges = np.isin(kind, EDGE_KINDS)
        past = np.where(edges, FOOT_RADIUS, 0.0)  # a gap or a drop: the foot's centre passes its edge
        relevant = (kind != TerrainKind.NONE) & (meets - past <= self.length[worlds][:, None])
        margin = np.where(edges, FOOT_RADIUS + EDGE_MARGIN, STOP_MARGIN)  # centre before an edge, foot a face
        stop_at = np.where(relevant, meets - margin, np.inf).min(axis=1)
        limit = np.where(self.length[worlds] > travel + SCAN_AHEAD, travel + SCAN_AHEAD, self.length[worlds])
        halted = self.halted[worlds]
        self.stop[worlds] = np.where(halted, self.stop[worlds], np.minimum(limit, stop_at))
        for k, w in enumerate(worlds):
            hits = np.flatnonzero(relevant[k])
            if halted[k]:  # refused already: the move ends where it stopped
                continue
            if not hits.size:
                self.findings[w] = None
                continue
            foot = int(hits[np.argmin(meets[k, hits])])
            where = points[k, foot, index[k, foot]]
            kind_name = finding_kind(int(kind[k, foot]))
            self.findings[w] = Finding(
                kind_name,
                round(float(measured[k, foot]), 3),
                limit_of(kind_name, self.limits),
                (float(where[0]), float(where[1])),
                FOOT_NAMES[foot],
            )

    def _lift(
        self,
        worlds: np.ndarray,
        q: np.ndarray,
        travel: np.ndarray,
        centres: np.ndarray,
        local: np.ndarray,
        under_torso: np.ndarray,
        index: np.ndarray,
    ) -> np.ndarray:
        """Set the legs and the lift; return the worlds (k,) that must wait for a foot to clear an edge.

        Each leg reaches down to the surface under its foot, a little further (``PRESS``) so that it carries its
        share, the body level over the highest one and its torso :data:`TORSO_CLEARANCE` above what lies under it;
        legs change length at :data:`LEG_SPEED`. A foot crosses up
        while the level accepted from just behind it to :data:`LIFT_AHEAD` ahead stands higher than the surface
        under it (a step up ahead, a stridden gap under it): the lift raises the body until that foot is
        ``CLEARANCE`` above that level. It crosses down from when the surface under its centre drops below the
        level it stood at (it bears weight up to the edge) until :data:`HOLD_BEHIND` past it: the lift holds the
        body. While the lift
        carries the body the legs keep their length and the tilt motors hold it level; once no foot crosses, the
        lift lets the body down onto its legs at :data:`DESCENT_SPEED` and switches off once they stand as they
        should and carry it.
        """
        hold_len = round(HOLD_BEHIND / SPACING)
        span = np.arange(-hold_len - RADIUS_SAMPLES, round(LIFT_AHEAD / SPACING) + 1)
        window = index[:, 1, None] + span[None, :]  # around each foot's centre
        values = np.take_along_axis(
            self.level[worlds], np.clip(window, 0, SAMPLES - 1)[:, None, :].repeat(4, axis=1), axis=2
        )
        last = np.round((self.stop[worlds] - self.scan_t0[worlds] + BACK) / SPACING)  # the move's end (the foot's)
        values = np.where(((window >= 0) & (window < SAMPLES) & (window <= last[:, None]))[:, None, :], values, np.nan)
        values = np.where(np.isnan(values), -np.inf, values)
        ahead = values[:, :, hold_len:].max(axis=2)
        behind = values[:, :, : hold_len + RADIUS_SAMPLES + 1].max(axis=2)  # up to the foot's centre
        under = local[:, :, :3].max(axis=2)
        below = local[:, :, 1]  # under the foot's centre: it bears weight up to the edge
        bottom = centres[:, :, 2] - FOOT_RADIUS
        up = ahead - under > RISE
        hold = ~up & (behind - below > RISE)
        crossing = (up | hold).any(axis=1)
        standing = self._gather(self.level[worlds], index[:, 1:2])[:, :, 0]  # the level accepted under each foot
        footing = np.abs(below - standing) <= RISE  # a surface the foot could stand on lies under it
        crossing &= ~self._no_footing(worlds, travel, up | hold, footing, centres)
        up &= crossing[:, None]
        clear = under_torso - BELLY_HEIGHT + TORSO_CLEARANCE  # the lowest the feet's level may be under the torso
        stance = np.clip(under - np.maximum(under.max(axis=1), clear)[:, None] - PRESS, -self.reach, 0.0)
        legs = self.legs[worlds]
        step = np.clip(stance - legs, -LEG_SPEED * self.scene.control_dt, LEG_SPEED * self.scene.control_dt)
        self.legs[worlds] = np.where(crossing[:, None], legs, legs + step)  # held while the lift carries the body
        self.sim.ctrl[worlds[:, None], self.ids.leg_actuator] = self.legs[worlds]
        need = np.where(up, ahead + CLEARANCE, np.where(hold, behind, -np.inf)) - bottom
        wanted = np.where(crossing, np.maximum(q[:, 2] + need.max(axis=1), clear), np.nan)
        previous = np.minimum(self.lift[worlds], q[:, 2]) - DESCENT_SPEED * self.scene.control_dt  # NaN: was off
        target = np.where(np.isnan(wanted), previous, np.fmax(wanted, previous))
        settled = np.all(np.abs(self.legs[worlds] - stance) < 1e-3, axis=1)  # the legs stand where they should
        target = np.where(~crossing & settled & (target < q[:, 2] - RELEASE), np.nan, target)  # resting on its legs
        self.lift[worlds] = target
        self.sim.ctrl[worlds, self.ids.actuator[2]] = np.where(np.isnan(target), OFF, target)
        angle, rate = q[:, 3:], self.state.qvel[worlds][:, self.ids.qvel[3:]]
        level = np.clip(-angle * TILT_GAIN - rate * TILT_DAMPING, -1.0, 1.0) * ~np.isnan(target)[:, None]
        self.sim.ctrl[worlds[:, None], self.ids.actuator[3:]] = level
        return np.any(up & (bottom < ahead + CLEARANCE / 2), axis=1)

    def _no_footing(
        self, worlds: np.ndarray, travel: np.ndarray, crossing: np.ndarray, footing: np.ndarray, centres: np.ndarray
    ) -> np.ndarray:
        """Worlds (k,) where a foot has been carried further than any edge needs (``crossing``: (k, 4) the feet
        crossing now) since it last passed over footing (``footing``: (k, 4) the surface under the foot's centre
        is the level it stands at, such as the tread between two steps): it found no footing. The move stops
        there, refused, and the lift lets go: what the feet stand on then carries the robot, or not."""
        start = self.hover_from[worlds]
        fresh = np.isnan(start) | footing
        start = np.where(crossing & fresh, travel[:, None], np.where(crossing, start, np.nan))
        self.hover_from[worlds] = start
        carried = np.where(crossing, travel[:, None] - start, 0.0)
        too_far = (carried > MAX_HOVER).any(axis=1) | self.halted[worlds]
        for k in np.flatnonzero(too_far & ~self.halted[worlds]):
            w, foot = int(worlds[k]), int(np.argmax(carried[k]))
            where = centres[k, foot, :2]
            self.findings[w] = Finding(
                "gap",
                round(float(carried[k, foot]), 3),
                self.limits.max_gap,
                (float(where[0]), float(where[1])),
                FOOT_NAMES[foot],
            )
            self.stop[w] = float(travel[k])
            self.hover_from[w] = np.nan
            self.halted[w] = True
        return too_far

    def _steer(self, worlds: np.ndarray, q: np.ndarray, travel: np.ndarray, waiting: np.ndarray) -> None:
        """Move the x-y setpoints toward the stopping points at walking speed, leashed to the bodies."""
        body = q[:, :2]
        sp = self.setpoint[worlds]
        stop = self.origin[worlds] + self.u[worlds] * self.stop[worlds][:, None]
        to_stop = stop - sp
        gap = np.linalg.norm(to_stop, axis=1)
        go = ~waiting & (gap > 1e-9) & (np.linalg.norm(sp - body, axis=1) < LEASH)
        step = np.minimum(gap, WALK_SPEED * self.scene.control_dt)
        direction = to_stop / np.maximum(gap, 1e-9)[:, None]
        sp = sp + np.where(go[:, None], direction * step[:, None], 0.0)
        velocity = np.where((go & (gap > step))[:, None], direction * WALK_SPEED, 0.0)
        self.setpoint[worlds] = sp
        self.sim.ctrl[worlds[:, None], self.ids.actuator[:2]] = sp + self.lead * velocity

    def _check_arrival(self, worlds: np.ndarray, q: np.ndarray, travel: np.ndarray, ends: list[SkillEnd]) -> None:
        """End the moves whose body reached its stopping point (done or refused), stalled or ran out of time."""
        state = self.state
        now = state.time[worlds]
        qvel = state.qvel[worlds][:, self.ids.qvel]
        still = (np.abs(qvel[:, :3]).max(axis=1) < SETTLED_SPEED) & (np.abs(qvel[:, 3:]).max(axis=1) < SETTLED_TURN)
        stop = self.origin[worlds] + self.u[worlds] * self.stop[worlds][:, None]
        there = (np.linalg.norm(q[:, :2] - stop, axis=1) < ARRIVED) & still
        remaining = np.abs(self.length[worlds] - travel)
        finished = there & (
            (self.stop[worlds] >= self.length[worlds] - 1e-9) | np.array([self.findings[w] is not None for w in worlds])
        )
        better = remaining < self.best[worlds] - 0.01
        self.best[worlds] = np.where(better, remaining, self.best[worlds])
        self.progress_time[worlds] = np.where(better, now, self.progress_time[worlds])
        stalled = ~finished & (now - self.progress_time[worlds] > STALL_TIME)
        for k in np.flatnonzero(finished | stalled):
            w = int(worlds[k])
            finding = self.findings[w]
            if stalled[k]:
                outcome: MoveEnd = (
                    "stalled",
                    f"blocked at [{q[k, 0]:.2f}, {q[k, 1]:.2f}], {remaining[k]:.2f} m short of the goal",
                    {"distance": round(float(remaining[k]), 3)},
                )
            elif finding is not None:
                outcome = ("refused", finding.describe(), _measured(finding))
            else:
                outcome = ("done", None, {})
            end = self._advance(w, outcome)
            if end is not None:
                ends.append(end)

    # -- falls ---------------------------------------------------------------------------------------

    def _falls(self, mask: np.ndarray) -> list[SkillEnd]:
        """Find the robots in ``mask`` that fell since the last tick: end their skills and mark their worlds failed."""
        state = self.state
        com = centre_of_mass(state, self.ids)
        centres = feet(state, self.ids)
        touching = feet_touching(state, self.ids, self.not_robot)
        held = supported(com, centres, touching, SUPPORT_MARGIN)
        self.outside = np.where(mask, np.where(~held & np.isnan(self.lift), self.outside + 1, 0), self.outside)
        self.lost_support[held & mask] = None
        for w in np.flatnonzero(mask & (self.outside == 1)):  # where it left its support, and which feet had none
            x, y = com[w, :2]
            self.lost_support[w] = f"fell at [{x:.2f}, {y:.2f}]: no support under {unsupported_feet(touching[w])}"
        angle = tilt(state, self.ids)
        fell = ((self.outside >= FALL_TICKS) & (angle > TIPPING)) | (angle > FALL_TILT)
        ends = []
        for w in np.flatnonzero(fell & mask):
            if self.failures[w] is not None or state.failed[w] is not None:
                continue
            x, y = com[w, :2]
            reason = (
                self.lost_support[w] or f"fell at [{x:.2f}, {y:.2f}]: tipped over ({np.degrees(angle[w]):.0f} degrees)"
            )
            self.failures[w] = reason
            if self.plans[w] is not None:
                self.plans[w] = None
                ends.append(
                    SkillEnd(
                        world=int(w),
                        outcome="fell",
                        reason=reason,
                        measured={
                            "x": round(float(x), 3),
                            "y": round(float(y), 3),
                            "tilt": round(float(np.degrees(angle[w])), 1),
                        },
                    )
                )
            self.moving[w] = False
            self._hold(np.array([w]))
        return ends

    # -- sensing -----------------------------------------------------------------------------------

    def _check(self, w: int, here: np.ndarray, path: list[np.ndarray]) -> tuple[Finding, int] | None:
        """The first finding on a walk through ``path`` in world ``w`` and the object there (-1: none)."""
        top = float(feet(self.state, self.ids)[w, :, 2].min()) + RAY_HEIGHT

        def heights(xy: np.ndarray) -> np.ndarray:
            return self._heights(w, xy, top)[0]

        bottom = feet(self.state, self.ids)[w, :, 2] - FOOT_RADIUS
        finding = check_walk(heights, here, path, self.limits, start_levels=bottom)
        if finding is None:
            return None
        where = np.array(finding.where)
        ahead = path[0] - here
        probe = where + ahead / max(float(np.linalg.norm(ahead)), 1e-9) * FOOT_RADIUS
        _, objects = self._heights(w, probe[None], top)
        return finding, int(objects[0])

    def _heights(self, w: int, xy: np.ndarray, top: float, exclude: int = -1) -> tuple[np.ndarray, np.ndarray]:
        """Surface heights and hit objects (-1: ground or nothing) under points ``xy`` in world ``w``."""
        z, objects = self._cast(np.array([w]), xy[None], np.array([top]), exclude)
        return z[0], objects[0]

    def _cast(
        self, worlds: np.ndarray, xy: np.ndarray, top: np.ndarray, exclude: int = -1
    ) -> tuple[np.ndarray, np.ndarray]:
        """Downward rays from height ``top`` (per world) over ``xy`` (k, nray, 2) in ``worlds``: surface heights
        and the objects that carry them (-1: ground or nothing); the robot is never hit.

        A cloth is limp: it carries no load over a gap, whichever way it lies. A ray that meets a cloth's link is
        cast again from just above the point it met, that link left out, until it meets something solid, which is
        the object returned; the height is the cloth's where that solid lies no deeper under it than a step the
        legs climb (a cloth lying on a surface, or bunched up on it, is stepped onto), else the solid's (over a gap
        the feet would sink to it)."""
        start = np.repeat(np.asarray(top, dtype=float)[:, None], xy.shape[1], axis=1)
        z, geom = self._cast_from(worlds, xy, start, exclude)
        through = self._on_cloth(geom)
        cloth_top = np.where(through, z, np.nan)
        for _ in range(self.cloth_crossings):
            if not through.any():
                break
            link = self.scene.model.geom_bodyid[geom[through][0]]
            again = through & (self.scene.model.geom_bodyid[np.maximum(geom, 0)] == link)
            rows = np.flatnonzero(again.any(axis=1))
            count = again[rows].sum(axis=1)
            first = np.argsort(~again[rows], axis=1, kind="stable")[:, : count.max()]  # each row's rays to redo first
            redo = np.where(np.arange(first.shape[1])[None, :] < count[:, None], first, first[:, :1])  # padded
            z_again, geom_again = self._cast_from(
                worlds[rows],
                np.take_along_axis(xy[rows], redo[:, :, None], axis=1),
                np.take_along_axis(z[rows], redo, axis=1) + CLOTH_STEP,
                int(link),
            )
            z[rows[:, None], redo], geom[rows[:, None], redo] = z_again, geom_again
            through = self._on_cloth(geom)
        objects = np.where(geom >= 0, self.geom_object[np.maximum(geom, 0)], -1)
        lying = cloth_top - z <= self.limits.max_step_up  # False where no cloth was met (NaN)
        return np.where(lying, cloth_top, z), objects

    def _on_cloth(self, geom: np.ndarray) -> np.ndarray:
        """Whether each ray's hit geom (-1: none) belongs to a cloth."""
        objects = np.where(geom >= 0, self.geom_object[np.maximum(geom, 0)], -1)
        return (objects >= 0) & self.cloth[np.maximum(objects, 0)]

    def _cast_from(
        self, worlds: np.ndarray, xy: np.ndarray, start: np.ndarray, exclude: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """Downward rays from heights ``start`` (k, nray) over ``xy`` (k, nray, 2) in ``worlds``, the robot and body
        ``exclude`` left out: surface heights (0 where nothing is hit) and the geoms hit (-1: none)."""
        nworld, nray = self.sim.nworld, xy.shape[1]
        pnt = np.full((nworld, nray, 3), np.nan)
        pnt[worlds, :, :2] = xy
        pnt[worlds, :, 2] = start
        vec = np.zeros((nworld, nray, 3))
        vec[..., 2] = -1.0
        dist, geom = self.sim.rays(pnt, vec, exclude_body=exclude, skip_group=ROBOT_GROUP)
        dist, geom = dist[worlds], geom[worlds]
        return np.where(np.isfinite(dist), start - dist, 0.0), geom

    # -- state ---------------------------------------------------------------------------------------

    def _position(self, w: int) -> np.ndarray:
        """The x-y of the body's slides (the servos' coordinates) in world ``w``."""
        return self.state.qpos[w, self.ids.qpos[:2]].copy()

    def _centers(self, state: BatchState) -> np.ndarray:
        """Object centres (nworld, nobject, 3), read-only: body origins; a cloth's is the mean of its links."""

        def compute() -> np.ndarray:
            out = state.xpos[:, self.scene.object_body].copy()
            for i in np.flatnonzero(self.cloth):
                out[:, i] = state.xpos[:, self.scene.body_object == i].mean(axis=1)
            return out

        return self._of_state(state, "centres", compute)

    def _of_state(self, state: BatchState, key: Any, compute: Callable[[], np.ndarray]) -> np.ndarray:
        """``compute()`` once per state (a tick and the skill starts that follow read the same one), read-only."""
        if self._memo[0] is not state:
            self._memo = (state, {})
        found = self._memo[1].get(key)
        if found is None:
            found = self._memo[1][key] = compute()
            found.flags.writeable = False
        return found

    def _bounds3(self, w: int, index: int) -> tuple[np.ndarray, np.ndarray]:
        """World axis-aligned bounds of an object in world ``w``."""
        if self.cloth[index]:
            center = self._centers(self.state)[w, index]
            half = np.asarray(self.scene.task.objects[index].size) / 2
            return center - half, center + half
        state, body = self.state, self.scene.object_body[index]
        corners = self._of_state(state, ("corners", index), lambda: world_corners(state, body, self.corners[index]))[w]
        return corners.min(axis=0), corners.max(axis=0)

    def _bounds(self, w: int, index: int) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = self._bounds3(w, index)
        return lo[:2], hi[:2]


def _measured(finding: Finding) -> dict[str, float]:
    return {
        finding.kind: finding.measured,
        "limit": finding.limit,
        "x": round(finding.where[0], 3),
        "y": round(finding.where[1], 3),
    }
