"""Writing the quadruped macros' pushes and walks into programs (:class:`Writer`): each push the way predicted best
(:func:`_push_plans`), with the walks to where it lines up and, where only the turned body fits there, a quarter
turn in place; walks and climbs anchored to the objects they go onto, queried when the program runs."""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from dataclasses import dataclass, field, replace

import numpy as np

from robotool.planner.codegen import Direction, Point, Program, Ref
from robotool.planner.layout import Layout
from robotool.robots.quadruped.predict import (
    OFF_CENTRE,
    PushBlock,
    detour,
    drift_room,
    off_centre,
    push_problem,
    push_room,
    push_route,
    push_staging,
    turn_violation,
    walk_violation,
)
from robotool.robots.quadruped.push import legs
from robotool.robots.quadruped.quadruped_config import QUADRUPED
from robotool.robots.quadruped.quadruped_routes import DIRECTIONS, Quadruped, Route
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.terrain import foot_offsets
from robotool.task.scene import MASS_NOISE


def _push_plans(
    layout: Layout, name: str, xy: np.ndarray, limits: QuadrupedLimits, floor: float, turns: bool = False
) -> Iterator[list[np.ndarray]]:
    """Ways to push ``name`` to ``xy``, as the targets of successive pushes: straight (one skill call, which pushes
    along the shorter axis first), one axis at a time in either order, then routed around what stands in the way
    (:func:`~.predict.push_route`; with ``turns``, legs the robot pushes turned a quarter too)."""
    center = layout.box(name).center
    yield [xy]
    parts = legs(center, xy)
    for first in parts if len(parts) == 2 else []:
        corner = center.copy()
        corner[first.axis] = first.target
        yield [corner, xy]
    around = push_route(layout, name, xy, limits, floor, turns)
    if around is not None and len(around) > 2:
        yield around


TURN_STEPS = (0.1, 0.2, 0.3)  # m the robot walks off along an axis, at most, to find room to turn in place
TURN_ROOM = QUADRUPED.push_tolerance  # m a turn between pushes keeps clear (a pushed object ends up to this far off)
PUSH_ROOM = QUADRUPED.push_tolerance  # m of room a push's line-up keeps, or the program is thin (for the same reason)


def turn_spots(layout: Layout, here: np.ndarray, quad: Quadruped) -> Iterator[np.ndarray]:
    """Where ``quad``, standing at ``here``, may turn a quarter in place: there, and a short straight walk off along
    each axis (:data:`TURN_STEPS`), nearest first; each walk and turn predicted fine (read as they are asked for)."""
    spots = [here, *(here + d * k for k in TURN_STEPS for d in DIRECTIONS)]
    for spot in spots:
        walks = spot is here or walk_violation(layout, here, [spot], quad.limits) is None
        if walks and _turns_at(layout, spot, quad):
            yield spot


def _turns_at(layout: Layout, spot: np.ndarray, quad: Quadruped) -> bool:
    """Whether a quarter turn in place at ``spot`` is predicted fine, :data:`TURN_ROOM` clear of what stands around
    (the sweep is the same either way round)."""
    limits = quad.task.limits
    assert isinstance(limits, QuadrupedLimits)
    return turn_violation(layout, spot, limits, 90, TURN_ROOM) is None


@dataclass
class PushStep:
    """One push of a planned sequence: the walk to where it lines up (waypoints on the floor), the heading the robot
    turns to in place at the end of that walk (None: no turn) and its walk on from there, the push's target and
    where the robot ends."""

    path: list[np.ndarray]
    target: np.ndarray
    end: np.ndarray
    heading: int | None = None
    then: list[np.ndarray] = field(default_factory=list)


class Writer:
    """Writes pushes and walks into a program, querying positions when they run."""

    def __init__(self, quad: Quadruped, prog: Program):
        self.quad, self.prog = quad, prog
        self.layout = quad.layout
        self.here = quad.start
        self.level = quad.floor
        self.surface = quad.floor_name
        self.refs: dict[str, Ref] = {}
        self.directions: dict[tuple[str, str], Direction] = {}  # (from, toward) query variables -> direction

    def position(self, name: str) -> Ref:
        """Query where ``name`` is now (once per placement)."""
        if name not in self.refs:
            box = self.layout.box(name)
            self.refs[name] = self.prog.query("get_position", name, (*box.center, 0.0))
        return self.refs[name]

    def push(
        self, name: str, xy: np.ndarray, why: str, turns: bool = False, against: tuple[str, int] | None = None
    ) -> None:
        """Push ``name`` to ``xy`` the first way (:func:`_push_plans`) predicted fine that leaves it room to drift
        (:func:`~.predict.drift_room`), lines up near its centre line (:data:`~.predict.OFF_CENTRE`) and with
        :data:`PUSH_ROOM` of room (:func:`~.predict.push_room`), else the one predicted fine that meets the most of
        these, in that order, else the straight way, its problem kept as the program's doubt: in one skill call, or
        one axis at a time, or routed around what stands in the way; before each push whose own way to where the robot
        lines up is predicted blocked, the robot walks there around what stands in the way. With ``turns``, when no
        way is predicted fine and lined up near the centre line as the body lies, the robot may also turn a quarter
        in place before a push that the turned body makes better (:meth:`_turned_push`); the writer's ``quad`` then
        lies as the body does after the last push. With ``against`` (a movable object ``name`` is placed against, and
        the axis along which it meets it), the last push's target on that axis is read from where that object is
        when the push starts, at its planned offset from it."""
        xy = np.asarray(xy, dtype=float)
        predicted, rank = None, (True, True, True, True)  # a problem, no room to drift, off the centre line, cramped
        for turning in (False, True) if turns else (False,):
            if turning and not rank[0] and not rank[2]:
                break
            for plan in _push_plans(self.layout, name, xy, self.quad.limits, self.level, turning):
                found = self._predict_pushes(name, plan, turning)
                key = (True, True, True, True)
                if found[1] is None:
                    drifts = not drift_room(self.layout, name, plan, self.level)
                    key = (False, drifts, found[2] > OFF_CENTRE, found[3])
                if predicted is None or key < rank:
                    predicted, rank = found, key
                if not any(rank):
                    break
        assert predicted is not None
        steps, problem, off, cramped = predicted
        for step in steps:
            for via in step.path:
                self.walk(via, self.surface, f"walk to where the push of {name} lines up")
            if step.heading is not None:
                self.prog.turn(step.heading, f"turn so that the body fits where the push of {name} lines up")
                self.quad = self.quad.quarter_turned().after(self.layout, self.here, [])
                for via in step.then:
                    self.walk(via, self.surface, f"walk to where the push of {name} lines up")
            ref = self.position(name)
            start = self.layout.box(name).center
            point = Point.at(ref, (*(step.target - start), 0.0))
            if against is not None and step is steps[-1]:  # where the object it meets stands, not where it should
                other, axis = against
                offset = float(step.target[axis] - self.layout.box(other).center[axis])
                point = point.with_axis(axis, self.position(other), offset)
            self.prog.motion(
                "push_to_position",
                obj=name,
                point=point,
                intent=f"push {name} {why}",
                explanation=f"centre to [{step.target[0]:.3f}, {step.target[1]:.3f}]",
            )
            self.here = step.end
            self.layout = self.layout.with_moved(name, step.target)
            self.refs.pop(name, None)
        if off > OFF_CENTRE:
            self.prog.thin.append(f"the push of {name} lines up {off:.0%} of its half width off its centre: it turns")
        if cramped and problem is None:
            self.prog.thin.append(
                f"a push of {name} lines up with under {PUSH_ROOM * 100:.0f} cm of room: an object pushed before may "
                "end up that far off its target"
            )
        self.doubt(problem)
        mass, limit = self.quad.task.object(name).effective_mass, self.quad.limits.max_push_mass
        heavy = f"{name}'s {mass:.2f} kg is within {MASS_NOISE:.0%} of the {limit:g} kg push limit"
        if mass * (1 + MASS_NOISE) > limit and heavy not in self.prog.thin:  # perturbed worlds scale masses so
            self.prog.thin.append(heavy)
        self.prog.use(name)

    def _predict_pushes(
        self, name: str, targets: list[np.ndarray], turns: bool = False
    ) -> tuple[list[PushStep], str | None, float, bool]:
        """Pushes of ``name`` through ``targets`` in turn, as predicted from where the robot is (:meth:`_lined_up`);
        with ``turns``, a push predicted to fail, or to line up well off the object's centre line, as the body lies
        is made turned a quarter where that is predicted fine and lines up nearer (:meth:`_turned_push`). The steps,
        the first problem predicted, how far off the centre line the pushes line up, at most
        (:func:`~.predict.off_centre`), and whether one lines up with less than :data:`PUSH_ROOM` of room
        (:func:`~.predict.push_room`)."""
        layout, here, quad = self.layout, self.here, self.quad
        steps: list[PushStep] = []
        first, worst, cramped = None, 0.0, False
        for xy in targets:
            step, problem = self._lined_up(layout, quad, here, name, xy)
            off = off_centre(layout, name, [xy], quad.limits, self.level)
            if turns and (problem is not None or off > OFF_CENTRE):
                turned = quad.quarter_turned()
                turned_off = off_centre(layout, name, [xy], turned.limits, self.level)
                if (problem is not None or turned_off < off) and (
                    turning := self._turned_push(layout, quad, turned, here, name, xy)
                ):
                    step, problem, quad, off = turning, None, turned, turned_off
            steps.append(step)
            first, worst = first or (str(problem) if problem else None), max(worst, off)
            cramped = cramped or not push_room(layout, name, xy, quad.limits, self.level, PUSH_ROOM)
            layout, here = layout.with_moved(name, xy), step.end
        return steps, first, worst, cramped

    def _lined_up(
        self, layout: Layout, quad: Quadruped, here: np.ndarray, name: str, xy: np.ndarray
    ) -> tuple[PushStep, PushBlock | None]:
        """A push of ``name`` to ``xy`` by ``quad`` from ``here`` as predicted, with the walk to where it lines up
        when the skill's own way there is blocked (else none), and its problem (None: predicted fine)."""
        limits = quad.limits
        problem, end = push_problem(layout, name, xy, limits, self.level, here)
        path: list[np.ndarray] = []
        staging = push_staging(layout, name, xy, limits, self.level) if problem else None
        if problem and problem.kind == "approach" and staging is not None:
            way = detour(layout, here, staging, limits)
            if walk_violation(layout, here, way, limits) is None:
                path = way
                problem, end = push_problem(layout, name, xy, limits, self.level, staging)
        return PushStep(path, xy, end), problem

    def _turned_push(
        self, layout: Layout, quad: Quadruped, turned: Quadruped, here: np.ndarray, name: str, xy: np.ndarray
    ) -> PushStep | None:
        """A push of ``name`` to ``xy`` that ``quad`` makes after turning a quarter in place: where it stands or a
        short walk off (:func:`turn_spots`), else where the turned push lines up, the first spot where the turn and
        the walks to and from it are predicted fine and so is the push (None: nowhere); ``turned`` is ``quad`` turned
        a quarter."""
        staging = push_staging(layout, name, xy, turned.limits, self.level)
        if staging is None:
            return None
        for spot, path in itertools.chain(
            ((spot, [spot] if spot is not here else []) for spot in turn_spots(layout, here, quad)),
            self._via_staging(layout, quad, here, staging),
        ):
            step, problem = self._lined_up(layout, turned, spot, name, xy)
            if problem is None:
                return PushStep(path, xy, step.end, heading=turned.heading, then=step.path)
        return None

    @staticmethod
    def _via_staging(
        layout: Layout, quad: Quadruped, here: np.ndarray, staging: np.ndarray
    ) -> Iterator[tuple[np.ndarray, list[np.ndarray]]]:
        """``staging`` and the way there from ``here`` around what stands in the way, where that walk and a quarter
        turn at ``staging`` are predicted fine (nothing where it is ``here``)."""
        if np.allclose(staging, here):
            return
        way = detour(layout, here, staging, quad.limits)
        if walk_violation(layout, here, way, quad.limits) is None and _turns_at(layout, staging, quad):
            yield staging, way

    def doubt(self, problem: str | None) -> None:
        """Keep the first predicted problem as the program's doubt."""
        if problem and not self.prog.doubt:
            self.prog.doubt = problem

    def walk(
        self, xy: np.ndarray, surface: str, intent: str, along_from: str | None = None, fixed_axis: int | None = None
    ) -> None:
        """Walk (or climb, when the surface is higher) to ``xy`` on ``surface``, anchored to it when it is an object.
        With ``along_from``, a movable surface's point is placed along the line from that object's centre through
        the surface's as they lie when the walk runs (a lever that turned about its load keeps the robot on it);
        with ``fixed_axis``, the point's coordinate on that axis is the planned number (a spot placed by something
        fixed, such as a lever's fulcrum), the others follow the surface."""
        height = 0.0 if surface == "ground" else self.layout.box(surface).top
        if surface == "ground" or not self.quad.task.object(surface).movable:
            point = Point.at(None, (*xy, height))
        elif along_from is not None:
            point = self._along(xy, surface, along_from)
        else:  # a movable surface may not be quite where it was pushed to
            point = Point.at(self.position(surface), (*(xy - self.layout.box(surface).center), 0.0))
            if fixed_axis is not None:
                point = point.with_axis(fixed_axis, None, float(xy[fixed_axis]))
        skill = "climb_to_position" if height > self.level + 0.015 else "walk_to_position"
        self.prog.motion(skill, point=point, objects=[] if surface == "ground" else [surface], intent=intent)
        self.level = max(height, self.level) if skill == "climb_to_position" else height
        self.here = np.asarray(xy, dtype=float)
        self.surface = surface

    def _along(self, xy: np.ndarray, surface: str, start: str) -> Point:
        """``xy`` on ``surface`` as a distance along the direction from ``start``'s centre to ``surface``'s, read when
        the program runs, from ``surface``'s centre (what lies off that line stays a fixed offset)."""
        ref, origin = self.position(surface), self.position(start)
        key = (origin.var, ref.var)
        if key not in self.directions:
            self.directions[key] = self.prog.direction(origin, ref)
        direction = self.directions[key]
        offset = np.asarray(xy, dtype=float) - self.layout.box(surface).center
        distance = float(offset @ np.array(direction.value))
        across = offset - distance * np.array(direction.value)
        return replace(Point.at(ref, (*across, 0.0)), along=(direction, distance))

    def around(self, xy: np.ndarray) -> None:
        """Walk on the floor around what stands between the robot and ``xy`` (:func:`detour`), up to the last turn
        before it."""
        for via in detour(self.layout, self.here, xy, self.quad.limits)[:-1]:
            self.walk(via, self.quad.floor_name, "walk around what stands in the way")

    def floor_walk(self, xy: np.ndarray, intent: str) -> None:
        """Walk on the floor to ``xy`` around what stands in the way; a walk still predicted to break a limit is
        kept as the program's doubt."""
        self.around(xy)
        self.doubt(walk_violation(self.layout, self.here, [xy], self.quad.limits))
        self.walk(xy, self.quad.floor_name, intent)

    def route(self, route: Route) -> None:
        """Write a whole route; record a predicted violation of its walk as the program's doubt."""
        self.prog.late += route.late
        self.prog.slack = min(self.prog.slack, route.slack)
        for name, role in route.uses:
            self.prog.use(name, role)
        for push in route.pushes:
            self.push(push.name, push.xy, push.why, against=push.against)
        first, surface = route.waypoints[0]
        if surface == self.quad.floor_name:
            self.around(first)
        self.doubt(walk_violation(self.layout, self.here, [xy for xy, _ in route.waypoints], self.quad.limits))
        for xy, surface in route.waypoints:
            self.walk(xy, surface, f"walk onto {surface}" if surface != "ground" else "walk into position")
        self.stance(*route.waypoints[-1])
        self.prog.say(route.words)

    def stance(self, xy: np.ndarray, surface: str) -> None:
        """Keep how far the feet standing at ``xy`` on ``surface`` are from its top's edges as the program's slack
        when it is the least yet; feet beyond them are its doubt (the body does not fit there as it is turned)."""
        if surface == "ground":
            return
        box = self.layout.box(surface)
        slack = float((box.half - np.abs(xy + foot_offsets(self.quad.limits) - box.center)).min())
        self.prog.slack = min(self.prog.slack, slack)
        if slack < 0:
            self.doubt(f"a foot would stand off {surface}'s top: the body does not fit there as it is turned")
