"""The quadruped's skill plans: each motion skill as a generator of straight moves (:data:`.move_runner.SkillPlan`).

A walk is one move, or a few around an object that stands in its way (:func:`~robotool.robots.quadruped.push.route`);
a push is the approach around the object and one push per axis (:mod:`robotool.robots.quadruped.push`), pushed on
along the axis while the object's centre falls short (it turned on the way), and, while the object ends off the
target (it turned or slid aside), pushed again from where it lies, round after round, as long as each brings it
closer and a way round it is clear; after such corrections the robot walks back round to the side the first round
pushed from, where the program expects it. Nothing here reads the task's category or name: limits come from
``task.robot.limits`` and the terrain from the simulated geoms.
"""

from __future__ import annotations

from collections.abc import Generator
from dataclasses import replace

import numpy as np

from robotool.robots.quadruped.move_runner import Move, SkillPlan, finding_measured
from robotool.robots.quadruped.push import (
    Leg,
    face_turn,
    first_clear_sweep,
    legs,
    push_tries,
    route,
    routes,
    turned_feet_drop,
)
from robotool.robots.quadruped.quadruped_config import QuadrupedConfig
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.rays import Rays
from robotool.robots.quadruped.referee import Referee
from robotool.robots.quadruped.sensing import Senses
from robotool.robots.quadruped.support import feet
from robotool.robots.quadruped.terrain import (
    FOOT_NAMES,
    FOOT_RADIUS,
    RISE,
    Finding,
    check_walk,
    quarter_turns,
    turn_sweep,
    turned,
    turned_feet,
)
from robotool.vocabulary import MoveEnd


class Plans:
    """Makes the plans of ``walk_to_position``, ``turn_to_heading`` and ``push_to_position`` in one world (no state
    of its own: a plan's progress lives in its generator, which the move runner holds)."""

    def __init__(self, senses: Senses, rays: Rays, referee: Referee, limits: QuadrupedLimits, config: QuadrupedConfig):
        self.senses, self.rays, self.referee, self.limits, self.config = senses, rays, referee, limits, config
        self.scene = senses.scene

    def _limits(self, w: int) -> QuadrupedLimits:
        """The limits with the body's outline as it is turned now in world ``w`` (x and y swapped at a quarter)."""
        return turned(self.limits, int(quarter_turns(self.senses.yaw(w))))

    def walk(self, w: int, target: tuple[float, float, float]) -> SkillPlan:
        """Straight to ``target`` when the feet's paths allow it; else along an L (one axis, then the other) that
        does; else around the object whose side is too high to climb (refused, naming it, when there is no way
        round); else straight, to be refused where the legs meet their limit."""
        goal = np.array(target[:2], dtype=float)
        here = self.senses.position(w)
        found = self._check(w, here, [goal])
        path = [goal]
        if found is not None:
            corners = [np.array([goal[0], here[1]]), np.array([here[0], goal[1]])]
            arrived = self.config.arrived
            ways = [[c, goal] for c in corners if min(np.linalg.norm(c - here), np.linalg.norm(goal - c)) > arrived]
            obstacle = found[1] if found[0].kind == "step" else -1
            if obstacle >= 0:
                lo, hi = self.senses.bounds(w, obstacle)
                if not np.all((goal >= lo) & (goal <= hi)):  # the goal is not on it: go around it
                    gap = self.config.push_gap
                    half = self.senses.half_now(w)
                    ways.append(route(here, goal, lo - half - gap, hi + half + gap))
            clear = next((way for way in ways if self._check(w, here, way) is None), None)
            if clear is not None:
                path = clear
            elif obstacle >= 0 and not np.all((goal >= lo) & (goal <= hi)):
                name = self.scene.object_names[obstacle]
                return "refused", f"the way is blocked by {name}: {found[0].describe()}", finding_measured(found[0])
        for waypoint in path:
            outcome = yield Move(waypoint)
            if outcome[0] != "done":
                return outcome
        return None

    def turn(self, w: int, heading: float) -> SkillPlan:
        """Turn in place to ``heading`` (degrees from +x, a quarter turn's multiple), the shorter way round; refused
        where a foot's arc would leave the level it stands on or the body's sweep meets anything above it."""
        asked = heading
        if abs(heading) >= 360.0:  # exactly (a float's remainder is exact): 1e20 / 90 is a whole number, 1e20 deg no
            heading = heading % 360.0  # quarter turn, and radians() of a huge heading is off by degrees (an adversary)
        quarters = heading / 90.0
        if abs(quarters - round(quarters)) > 1e-6:
            reason = f"the robot turns by quarter turns: heading {asked:g} is not 0, 90, 180 or 270"
            return "refused", reason, {}
        yaw = float(self.senses.yaw(w))
        target = yaw + float(np.angle(np.exp(1j * (np.radians(heading) - yaw))))  # the shorter way round
        if abs(target - yaw) < self.config.turn_arrived:
            return None
        problem = self._sweep_problem(w, yaw, target)
        if problem is not None:
            return "refused", f"cannot turn to {asked:g} deg: {problem}", {}
        outcome = yield Move(self.senses.position(w), turn=target)
        return None if outcome[0] == "done" else outcome

    def _sweep_problem(self, w: int, yaw: float, target: float) -> str | None:
        """What a turn in place from heading ``yaw`` to ``target`` (rad) in world ``w`` would meet: anything in the
        body's sweep (its outline and ``side_margin``) above the feet's level, a foot's arc leaving the level it
        stands on, or crossing a surface too slippery for the feet to push the body round (under ``walk_grip``, as the
        world's perturbation scales its friction); None when the way round is clear."""
        here = self.senses.position(w)
        arcs, sweep = turn_sweep(self.limits, yaw, target, self.config.side_margin)
        levels = feet(self.senses.state, self.senses.facts.ids)[w, :, 2] - FOOT_RADIUS
        top = float(levels.min()) + self.config.ray_height
        points = (here + sweep).reshape(-1, 2)
        heights, objects = self.rays.heights(w, points, top)
        standing_on = self.rays.heights(w, here + arcs[0], top)[1]
        facts = self.senses.facts
        loose = (objects >= 0) & facts.movable[objects] & ~facts.cloth[objects] & ~np.isin(objects, standing_on)
        high = (heights > levels.max() + RISE) | loose  # a loose object, however thin, would be swept along
        if high.any():
            k = int(np.argmax(high))
            name = self.scene.object_names[objects[k]] if objects[k] >= 0 else "something"
            return f"{name} stands in the body's way at [{points[k, 0]:.2f}, {points[k, 1]:.2f}]"
        world = np.array([w])
        under, _, solid, cloth = self.rays.surface(world, (here + arcs).reshape(1, -1, 2), np.array([top]))
        under, geoms = under.reshape(arcs.shape[:2]), self.rays.grip(solid, cloth).reshape(arcs.shape[:2])
        off = np.abs(under - levels) > RISE
        if off.any():
            k, foot = np.argwhere(off)[0]
            x, y = here + arcs[k, foot]
            step = under[k, foot] - levels[foot]
            edge = "step" if step > 0 else "drop"
            return f"the {FOOT_NAMES[foot]} foot would meet a {abs(step):.2f} m {edge} at [{x:.2f}, {y:.2f}]"
        friction = self.rays.friction(world, geoms[None])[0]
        slip = friction < self.config.walk_grip  # the feet push the body round: they need a walk's grip
        if slip.any():
            k, foot = np.argwhere(slip)[0]
            x, y = here + arcs[k, foot]
            return (
                f"{self.rays.surface_name(int(geoms[k, foot]))} is too slippery to turn on: its friction of "
                f"{friction[k, foot]:.4g} under the {FOOT_NAMES[foot]} foot at [{x:.2f}, {y:.2f}] is under the "
                f"{self.config.walk_grip:.3f} the feet need to grip"
            )
        return None

    def push(self, w: int, name: str, target: tuple[float, float, float]) -> SkillPlan:
        """Push object ``name`` so that its centre reaches ``target`` (x-y), within the push rules."""
        try:
            index = self.scene.object_index(name)
        except KeyError as e:
            return "refused", str(e.args[0]), {}
        senses, config = self.senses, self.config
        goal = np.array(target[:2], dtype=float)
        miss, blocked = np.inf, False
        side: tuple[np.ndarray, int, np.ndarray] | None = None  # the first round's last leg: direction, axis, end
        corrected = False
        for attempt in range(1 + config.corrections):
            broken = self.referee.pushes.push_rules(w, index)
            if broken is not None:
                if attempt:  # what it moved changed (it fell off something, something landed on it): no correction
                    break
                return "refused", f"cannot push {name}: {broken[0]}", broken[1]
            for leg in legs(senses.centers(senses.state)[w, index], goal):
                lo, hi = senses.bounds(w, index)
                pose, problem = self._clear_pose(w, index, leg, lo, hi)
                if pose is None:
                    if attempt:  # no way to correct the drift: the push stopped where it did
                        break
                    return "refused", f"cannot push {name}: no clear place to stand behind it{problem}", {}
                start, end, behind, face = pose
                robot = senses.position(w)
                staging = start - (end - start) / np.linalg.norm(end - start) * behind
                gap = config.push_gap
                half = senses.half_now(w)
                ways = routes(robot, staging, lo - half - gap / 2, hi + half + gap / 2)
                if attempt:  # a correction goes only a way round that the legs can walk, or not at all
                    way = next((way for way in ways if self._check(w, robot, [*way, start]) is None), None)
                    if way is None:
                        break
                else:
                    way = ways[0]
                for waypoint in [*way, start]:
                    outcome = yield Move(waypoint)
                    if outcome[0] != "done":
                        return outcome
                corrected |= attempt > 0
                height = senses.centers(senses.state)[w, index, 2]
                outcome = yield from self._push_move(w, index, end, face)
                if outcome[0] not in ("done", "stalled"):
                    return outcome
                blocked |= outcome[0] == "stalled"
                u = (end - start) / np.linalg.norm(end - start)
                for _ in range(config.follow_throughs):  # it turned on the way: push on until its centre gets there
                    centre = senses.centers(senses.state)[w, index]
                    short = (leg.target - centre[leg.axis]) * u[leg.axis]
                    if blocked or short < config.min_leg or abs(centre[2] - height) > RISE:  # (not after it fell off)
                        break
                    outcome = yield from self._push_move(w, index, senses.position(w) + u * short, face)
                    if outcome[0] not in ("done", "stalled"):
                        return outcome
                    blocked |= outcome[0] == "stalled"
                back = (start - end) / np.linalg.norm(start - end) * self.config.push_gap
                outcome = yield Move(senses.position(w) + back)
                if outcome[0] != "done":
                    return outcome
                if not attempt:
                    side = (u, leg.axis, senses.position(w))
            previous, miss = miss, float(np.linalg.norm(senses.centers(senses.state)[w, index, :2] - goal))
            if miss <= config.push_tolerance or blocked or miss > previous - config.correction_gain:
                break
        if corrected and side is not None:
            outcome = yield from self._back_behind(w, index, *side)
            if outcome[0] != "done":
                return outcome
        if miss > config.push_tolerance:
            return "stalled", f"{name} stopped {miss:.2f} m from the target", {"distance": miss}
        return None

    def _back_behind(
        self, w: int, index: int, u: np.ndarray, axis: int, end: np.ndarray
    ) -> Generator[Move, MoveEnd, MoveEnd]:
        """After corrections pushed object ``index`` from other sides, walk back round it to where the first round
        left the robot: behind it on the side its last leg pushed from (direction ``u`` along ``axis``), ``push_gap``
        off its face and across as it stood then (``end``), so that where a push leaves the robot does not depend on
        how the object drifted; the way round is the first the legs can walk, else the robot stays."""
        lo, hi = self.senses.bounds(w, index)
        half, gap = self.senses.half_now(w), self.config.push_gap
        spot = np.array(end, dtype=float)
        spot[axis] = (lo if u[axis] > 0 else hi)[axis] - u[axis] * (half[axis] + gap)
        robot = self.senses.position(w)
        if float(np.linalg.norm(spot - robot)) <= self.config.arrived:
            return "done", "", {}
        ways = routes(robot, spot, lo - half - gap / 2, hi + half + gap / 2)
        way = next((way for way in ways if self._check(w, robot, way) is None), None)
        for waypoint in way or []:
            outcome = yield Move(waypoint)
            if outcome[0] != "done":
                return outcome
        return "done", "", {}

    def _push_move(self, w: int, index: int, goal: np.ndarray, face: float) -> Generator[Move, MoveEnd, MoveEnd]:
        """One straight push of object ``index`` to ``goal`` in world ``w``, refused where the push rules do not hold
        from where the robot stands now (:meth:`.push_rules.PushRules.push_rules`: something came to ride on the
        object, the robot walked onto another surface); its outcome."""
        broken = self.referee.pushes.push_rules(w, index)
        if broken is not None:
            return "refused", f"cannot push {self.scene.object_names[index]}: {broken[0]}", broken[1]
        return (yield Move(goal, pushing=index, face=face))

    def _clear_pose(
        self, w: int, index: int, leg: Leg, lo: np.ndarray, hi: np.ndarray
    ) -> tuple[tuple[np.ndarray, np.ndarray, float, float] | None, str]:
        """The push start and end poses nearest straight-on whose sweep meets nothing above the floor and whose
        feet stay over the floor (no drop, no gap), with how far behind the start the robot lines up and how far it
        turns its face as it pushes (:func:`~.push.face_turn`, where something lies on the object and the turned
        feet stay over the floor from the start, else none); when there is none, what was wrong under the feet.

        Poses whose sweep is clear from the staging point (``staging`` behind the start, where the robot lines up)
        come first, so that the robot can line up there; failing those, a clear sweep from the start will do.
        """
        centres = feet(self.senses.state, self.senses.facts.ids)[w]
        floor = float(centres[:, 2].min() - FOOT_RADIUS)
        half, limits = self.senses.half_now(w), self._limits(w)
        tries = push_tries(lo, hi, leg, half, self.config.staging)

        def heights(xy: np.ndarray) -> np.ndarray:
            z, objects = self.rays.heights(w, xy, floor + self.config.ray_height)
            return np.where(objects == index, floor, z)

        clear, drop = first_clear_sweep(heights, [(behind, end) for _, end, _, behind in tries], limits, floor)
        if clear is not None:
            start, end, staging, _ = tries[clear]
            face = face_turn(start, end, lo, hi) if self.referee.pushes.loaded(w, index) else 0.0
            if face and turned_feet_drop(heights, start, end, limits, face, floor) is not None:
                face = 0.0
            return (start, end, staging, face), ""
        if drop is None:
            return None, ""
        start, end, _, _ = tries[drop[0]]  # the first drop found: under the pose nearest straight-on
        return None, f": pushing from [{start[0]:.2f}, {start[1]:.2f}] to [{end[0]:.2f}, {end[1]:.2f}], {drop[1]}"

    def _check(self, w: int, here: np.ndarray, path: list[np.ndarray]) -> tuple[Finding, int] | None:
        """The first finding on a walk through ``path`` in world ``w`` and the object there (-1: none)."""
        state, ids = self.senses.state, self.senses.facts.ids
        top = float(feet(state, ids)[w, :, 2].min()) + self.config.ray_height

        def heights(xy: np.ndarray) -> np.ndarray:
            return self.rays.heights(w, xy, top)[0]

        quarters = int(quarter_turns(self.senses.yaw(w)))
        order = turned_feet(self.limits, quarters)  # the feet in the order of the turned outline's corners
        bottom = feet(state, ids)[w, order, 2] - FOOT_RADIUS
        finding = check_walk(heights, here, path, turned(self.limits, quarters), start_levels=bottom)
        if finding is None:
            return None
        finding = replace(finding, foot=FOOT_NAMES[order[FOOT_NAMES.index(finding.foot)]])
        where = np.array(finding.where)
        ahead = path[0] - here
        probe = where + ahead / max(float(np.linalg.norm(ahead)), 1e-9) * FOOT_RADIUS
        _, objects = self.rays.heights(w, probe[None], top)
        return finding, int(objects[0])
