"""The quadruped's walks and pushes predicted on the planner's layout, before anything is simulated.

Everything here reads only the task file (objects, limits) through :mod:`robotool.task.geometry` and a
:class:`~robotool.planner.layout.Layout`, which can move objects to hypothetical x-y placements, so macros can
predict a walk (:func:`walk_violation`) or a push (:func:`push_problem`) on a planned placement.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Literal, TypeVar, cast

import numpy as np

from robotool.planner.layout import CONTACT, Box, Layout
from robotool.robots.quadruped.footing import footing, fragile_footing, straddle
from robotool.robots.quadruped.push import (
    GAP,
    SIDE_MARGIN,
    Leg,
    crosses,
    first_clear_sweep,
    lateral_offsets,
    legs,
    push_tries,
    route,
    sweep_points,
)
from robotool.robots.quadruped.quadruped_config import QUADRUPED
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.terrain import (
    FOOT_RADIUS,
    RISE,
    check_walk,
    foot_offsets,
    turn_sweep,
)

SAMPLE = 0.02  # m between terrain samples along a walk
BRUSH = 0.03  # m: something this much higher than the surface under the feet, at the flanks or between the feet,
# is in the way (the torso's underside rides 0.05 m above the feet)
BELLY_LINES = 5  # lines between the feet's paths along which the surface under the torso is read
LANE = 0.05  # m a pushed object keeps from the side of another that it is pushed past
DETOUR_CHECKS = 150  # walks predicted at most when looking for a way around
ON_LEVEL = QUADRUPED.same_surface  # m from the level it starts on that a way around's turns keep every foot
LEG_COST = 0.3  # m: what one more push leg counts for, against distance, when a push is routed around something
OFF_CENTRE = 0.5  # a push lined up further off the object's centre line (share of its half width) turns it
OFF_CENTRE_COST = 1.0  # m: what a routed push leg lined up further off than that counts for, beyond its length
REMEMBERED = 20_000  # predictions kept of each kind (the same walks and pushes recur across a task's programs)
Pose = tuple[np.ndarray, np.ndarray, np.ndarray]  # a push leg's start and end poses and its staging point
_walks: dict[tuple[object, ...], tuple[object, str | None]] = {}  # key -> (the task it was read on, the prediction)
_poses: dict[tuple[object, ...], tuple[object, Pose | None]] = {}
_routes: dict[tuple[object, ...], tuple[object, list[np.ndarray] | None]] = {}
T = TypeVar("T")


def _remembered(
    memo: dict[tuple[object, ...], tuple[object, T]], key: tuple[object, ...], layout: Layout, compute: Callable[[], T]
) -> T:
    """``compute()`` once per ``key`` (which starts with the id of the layout's task, and says how the layout moved
    its objects) while ``memo`` holds it: the entry holds its task, so an id is never reused while it is
    remembered."""
    task, known = memo.get(key, (None, None))
    if task is layout.task:
        return cast(T, known)
    if len(memo) >= REMEMBERED:
        memo.clear()
    memo[key] = (layout.task, found := compute())
    return found


def _moved(layout: Layout) -> tuple[tuple[str, bytes], ...]:
    """Where ``layout`` moved its objects, as a key."""
    return tuple(sorted((name, xy.tobytes()) for name, xy in layout.moved.items()))


def turn_violation(
    layout: Layout, start: np.ndarray, limits: QuadrupedLimits, heading: float, margin: float = QUADRUPED.side_margin
) -> str | None:
    """Predict whether a turn in place at ``start`` from heading 0 to ``heading`` (degrees) breaks a rule, as the
    simulator checks it (:meth:`.plans.Plans.turn`): a foot's arc leaving the level under the feet, or anything in
    the body's sweep (grown by ``margin``) above it; the problem in words, or None."""
    here = np.asarray(start, dtype=float)
    arcs, sweep = turn_sweep(limits, 0.0, float(np.radians(heading)), margin)
    levels = layout.heights(here + foot_offsets(limits))
    if np.any(layout.heights((here + sweep).reshape(-1, 2)) > levels.max() + RISE):
        return "something stands in the body's way as the robot turns"
    under = layout.heights((here + arcs).reshape(-1, 2)).reshape(arcs.shape[:2])
    if np.any(np.abs(under - levels) > RISE):
        return "a foot would cross an edge as the robot turns"
    return None


def walk_violation(
    layout: Layout,
    start: np.ndarray,
    waypoints: Iterable[np.ndarray],
    limits: QuadrupedLimits,
    exclude: Iterable[str] = (),
) -> str | None:
    """Predict whether walking through ``waypoints`` breaks a limit: the first violation in words, or None.

    The feet's paths are checked as the simulator checks them (:func:`.terrain.check_walk`). Between the
    feet's paths (under the torso) and just outside the body's flanks (on a slanted move, the band its corners sweep)
    nothing may stand higher than what its feet are on, or the body would run into it.
    """
    skip = list(exclude)
    goals = [np.asarray(g, dtype=float) for g in waypoints]
    path = (np.asarray(start, dtype=float).tobytes(), *(g.tobytes() for g in goals))
    key = (id(layout.task), _moved(layout), path, tuple(skip), limits)
    return _remembered(_walks, key, layout, lambda: _walk_violation(layout, start, goals, limits, skip))


def _walk_violation(
    layout: Layout, start: np.ndarray, goals: list[np.ndarray], limits: QuadrupedLimits, skip: list[str]
) -> str | None:
    finding = check_walk(lambda xy: layout.heights(xy, skip), np.asarray(start, dtype=float), goals, limits)
    if finding is not None:
        return finding.describe()
    if (fragile := fragile_footing(layout, start, goals, limits, skip)) is not None:
        return fragile
    if (apart := straddle(layout, start, goals, limits, skip)) is not None:
        return apart
    half = np.asarray(limits.body_size[:2]) / 2
    here = np.asarray(start, dtype=float)
    for goal in goals:
        delta = goal - here
        length = float(np.linalg.norm(delta))
        if length < 1e-6:
            continue
        u = delta / length
        extent = float(np.abs(u) @ half)
        lateral = np.array([-u[1], u[0]])
        s = np.arange(0.0, length + 2 * extent + 1e-9, SAMPLE)
        points = here - u * extent + s[:, None] * u
        width = float(np.abs(lateral) @ half) - FOOT_RADIUS  # the feet's centres (:func:`.terrain.foot_offsets`)
        flank = float(np.abs(lateral) @ half) + SIDE_MARGIN
        offsets = (-width, width, *np.linspace(-width, width, BELLY_LINES + 2)[1:-1], -flank, flank)
        across = np.stack([points + k * lateral for k in offsets])
        heights = layout.heights(across.reshape(-1, 2), skip).reshape(len(offsets), -1)
        body = heights[2:]  # under the torso and at its flanks: read only where the body passes (a slanted band reaches
        body[~_swept(across[2:], here, delta, half + SIDE_MARGIN)] = -np.inf  # past the body's start and end)
        feet, under, sides = heights[:2].max(axis=0), heights[2:-2].max(axis=0), heights[-2:].max(axis=0)
        if (rise := under - feet).max() > BRUSH:
            return (
                f"the body runs into something {float(rise.max()):.2f} m higher than its feet, between them, on the "
                f"way to [{goal[0]:.2f}, {goal[1]:.2f}]"
            )
        if (rub := sides - np.maximum(feet, under)).max() > BRUSH:
            return (
                f"the body brushes against something {float(rub.max()):.2f} m higher at its side on the way to "
                f"[{goal[0]:.2f}, {goal[1]:.2f}]"
            )
        here = goal
    return None


def _swept(points: np.ndarray, start: np.ndarray, delta: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Which of ``points`` (..., 2) an axis-aligned box of half size ``half`` covers as its centre moves from
    ``start`` by ``delta``: those within ``half`` of the centre on both axes at some point of the move."""
    rel = points - start
    lo, hi = np.zeros(rel.shape[:-1]), np.ones(rel.shape[:-1])
    for k in (0, 1):
        if abs(delta[k]) < 1e-12:
            inside = np.abs(rel[..., k]) <= half[k] + 1e-9
            lo, hi = np.where(inside, lo, 1.0), np.where(inside, hi, 0.0)
            continue
        a, b = (rel[..., k] - half[k] - 1e-9) / delta[k], (rel[..., k] + half[k] + 1e-9) / delta[k]
        lo, hi = np.maximum(lo, np.minimum(a, b)), np.minimum(hi, np.maximum(a, b))
    return lo <= hi


def detour(
    layout: Layout, start: np.ndarray, goal: np.ndarray, limits: QuadrupedLimits, exclude: Iterable[str] = ()
) -> list[np.ndarray]:
    """Waypoints from ``start`` to ``goal``: straight when the walk is predicted fine, else the shortest way found
    through the L-corners and the corners of the objects (grown by the body and a margin) where all four feet stand
    on the start's level (a way round never stops half on a step), each stretch predicted fine (a lazy A* search: a
    stretch is predicted only when it is the best way left); ``[goal]`` when none is found within
    :data:`DETOUR_CHECKS` predictions. A stretch whose body passes a movable object closer than
    ``QUADRUPED.detour_slack`` (but one it starts or ends that close to) counts ``QUADRUPED.detour_tight_cost``
    longer than it is, so a way with room is taken unless it is much longer."""
    skip = list(exclude)
    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    offsets = foot_offsets(limits)
    movable = {o.name for o in layout.task.objects if o.movable and o.shape != "cloth"}
    loose = [  # movable objects not under the feet where the walk starts or ends: no footing on the way
        name
        for name in sorted(movable)
        if name not in skip and all(np.isnan(layout.top_of(name, end + offsets)).all() for end in (start, goal))
    ]

    def fine(a: np.ndarray, b: np.ndarray) -> bool:
        return (
            walk_violation(layout, a, [b], limits, skip) is None
            and footing(layout, a, [b], limits, skip, loose) is None
        )

    if fine(start, goal):
        return [goal]
    half = np.asarray(limits.body_size[:2]) / 2
    boxes = layout.boxes(skip)
    points = [start, goal, np.array([goal[0], start[1]]), np.array([start[0], goal[1]])]
    for box in boxes:
        lo, hi = box.lo - half - 0.1, box.hi + half + 0.1
        points += [np.array([x, y]) for x in (lo[0], hi[0]) for y in (lo[1], hi[1])]
    level = float(layout.heights(start + offsets, skip).max())
    feet = layout.heights((np.array(points[2:])[:, None, :] + offsets).reshape(-1, 2), skip).reshape(-1, len(offsets))
    points = points[:2] + [p for p, f in zip(points[2:], feet, strict=True) if np.all(np.abs(f - level) <= ON_LEVEL)]
    room = half + QUADRUPED.detour_slack
    passed = [
        box
        for box in boxes
        if box.name in movable and not any(np.all(np.abs(end - box.center) < box.half + room) for end in (start, goal))
    ]

    def extra_cost(a: np.ndarray, b: np.ndarray) -> float | None:
        """None where the stretch from ``a`` to ``b`` is predicted to break a limit, else what it costs beyond its
        length."""
        if not fine(a, b):
            return None
        tight = any(crosses(a, b, box.lo - room, box.hi + room) for box in passed)
        return QUADRUPED.detour_tight_cost if tight else 0.0

    frontier = [(float(np.linalg.norm(goal - start)), 0.0, 0, -1, False)]
    parent: dict[int, int] = {}
    checks = 0
    while frontier and checks < DETOUR_CHECKS:
        estimate, cost, node, frm, charged = heapq.heappop(frontier)
        if node in parent:
            continue
        if frm >= 0 and not charged:
            checks += 1
            extra = extra_cost(points[frm], points[node])
            if extra is None:
                continue
            if extra > 0:  # back in line at its true cost: a way with room may yet come first
                heapq.heappush(frontier, (estimate + extra, cost + extra, node, frm, True))
                continue
        parent[node] = frm
        if node == 1:
            path = []
            while node != 0:
                path.append(points[node])
                node = parent[node]
            return path[::-1]
        for k, p in enumerate(points):
            if k not in parent and k != node:
                g = cost + float(np.linalg.norm(p - points[node]))
                heapq.heappush(frontier, (g + float(np.linalg.norm(goal - p)), g, k, node, False))
    return [goal]


@dataclass(frozen=True)
class PushBlock:
    """What blocks a predicted push of ``object``: it would run into ``blocker`` (``collides``), there is no clear
    place to stand behind it (``no_stance``), or the walk to where the push lines up breaks a limit (``approach``,
    the walk's problem in ``walk``). ``str()`` renders it for people."""

    kind: Literal["collides", "no_stance", "approach"]
    object: str
    blocker: str | None = None
    walk: str | None = None

    def __str__(self) -> str:
        if self.kind == "collides":
            return f"{self.object} would run into {self.blocker}"
        if self.kind == "no_stance":
            return f"no clear place to stand behind {self.object}"
        return f"the way to push {self.object}: {self.walk}"


def push_problem(
    layout: Layout, name: str, dest: np.ndarray, limits: QuadrupedLimits, floor: float, here: np.ndarray | None = None
) -> tuple[PushBlock | None, np.ndarray]:
    """Predict a push of ``name`` to ``dest`` (x-y) as the skill makes it (:mod:`robotool.robots.quadruped.push`): one
    straight leg per axis, the shorter first, the robot's face against the object's, slid along the face to the
    nearest offset whose sweep (from where it lines up, else from the start pose, to the end of the push plus the
    gap) meets nothing above its floor and keeps its feet over the floor. With the robot's position ``here``, the walk
    around the object to where it lines up is predicted too. Returns what blocks it (or None) and where the robot
    ends."""
    box = layout.box(name)
    half = np.asarray(limits.body_size[:2]) / 2
    robot = np.asarray(here, dtype=float) if here is not None else box.center.copy()
    for leg in legs(box.center, np.asarray(dest, dtype=float)):
        axis = leg.axis
        end_center = box.center.copy()
        end_center[axis] = leg.target
        steps = max(2, int(abs(end_center[axis] - box.center[axis]) / 0.05) + 1)
        hit = next(
            (
                h
                for f in np.linspace(0.0, 1.0, steps)
                if (h := layout.collides(box.moved_to(box.center + f * (end_center - box.center)), ignore=[name]))
            ),
            None,
        )
        if hit:
            return PushBlock("collides", name, blocker=hit), robot
        pose = _push_pose(layout, name, box, leg, limits, floor)
        if pose is None:
            return PushBlock("no_stance", name), robot
        start, end, staging = pose
        if here is not None:
            around = route(robot, staging, box.lo - half - GAP / 2, box.hi + half + GAP / 2)
            problem = walk_violation(layout, robot, [*around, start], limits, exclude=[name])
            if problem:
                return PushBlock("approach", name, walk=problem), robot
        robot = end - (end - start) / np.linalg.norm(end - start) * GAP
        layout, box = _after_leg(layout, name, box, leg)
    return None, robot


def _after_leg(layout: Layout, name: str, box: Box, leg: Leg) -> tuple[Layout, Box]:
    """The layout and ``name``'s box once a push leg has taken it to the leg's target."""
    end_center = box.center.copy()
    end_center[leg.axis] = leg.target
    return layout.with_moved(name, end_center), box.moved_to(end_center)


def off_centre(
    layout: Layout, name: str, targets: Sequence[np.ndarray], limits: QuadrupedLimits, floor: float
) -> float:
    """How far from ``name``'s centre line the robot lines up for the pushes through ``targets`` (as the skill lines
    up, :func:`_push_pose`), at most, as a share of the object's half width across the push: over about a half, the
    push turns the object as much as it moves it; over 1, the robot's centre passes beside it."""
    worst = 0.0
    for xy in targets:
        box = layout.box(name)
        for leg in legs(box.center, np.asarray(xy, dtype=float)):
            across = 1 - leg.axis
            pose = _push_pose(layout, name, box, leg, limits, floor)
            if pose is not None:
                worst = max(worst, abs(float(pose[0][across] - box.center[across])) / float(box.half[across]))
            layout, box = _after_leg(layout, name, box, leg)
    return worst


def push_room(layout: Layout, name: str, xy: np.ndarray, limits: QuadrupedLimits, floor: float, margin: float) -> bool:
    """Whether each leg of a push of ``name`` to ``xy``, lined up as the skill lines up (:func:`_push_pose`), keeps
    ``margin`` beyond the body's outline clear of what stands above the floor, from where it lines up to where it
    ends (True where no leg lines up: that is the push's problem, not its room). What lies over the object (a board
    that rests on it) goes with it, not counted."""
    box = layout.box(name)
    over = [b.name for b in layout.boxes([name]) if b.overlap(box) > 0 and b.top > box.top]
    grown = np.asarray(limits.body_size[:2]) / 2 + margin
    for leg in legs(box.center, np.asarray(xy, dtype=float)):
        pose = _push_pose(layout, name, box, leg, limits, floor)
        swept = sweep_points(pose[2], pose[1], grown) if pose is not None else None
        if swept is not None and np.any(layout.heights(swept, [name, *over]) > floor + RISE):
            return False
        layout, box = _after_leg(layout, name, box, leg)
    return True


def push_staging(
    layout: Layout, name: str, dest: np.ndarray, limits: QuadrupedLimits, floor: float
) -> np.ndarray | None:
    """Where the push skill lines the robot up for the first leg of a push of ``name`` to ``dest`` (None: no leg, or
    nowhere clear to stand)."""
    box = layout.box(name)
    first = legs(box.center, np.asarray(dest, dtype=float))
    pose = _push_pose(layout, name, box, first[0], limits, floor) if first else None
    return None if pose is None else pose[2]


def _push_pose(layout: Layout, name: str, box: Box, leg: Leg, limits: QuadrupedLimits, floor: float) -> Pose | None:
    """The skill's choice of start and end poses for one leg, and its staging point (None: nowhere clear); read-only
    arrays, remembered (the same pushes recur across a task's programs)."""
    key = (id(layout.task), _moved(layout), name, box.lo.tobytes(), box.hi.tobytes(), leg.axis, leg.target, limits)
    return _remembered(
        _poses, (*key, floor), layout, lambda: _read_only(_choose_push_pose(layout, name, box, leg, limits, floor))
    )


def _read_only(pose: Pose | None) -> Pose | None:
    for a in pose or ():
        a.flags.writeable = False
    return pose


def _choose_push_pose(
    layout: Layout, name: str, box: Box, leg: Leg, limits: QuadrupedLimits, floor: float
) -> Pose | None:
    """:func:`_push_pose`, read from the layout."""
    tries = push_tries(box.lo, box.hi, leg, np.asarray(limits.body_size[:2]) / 2, QUADRUPED.staging)

    def heights(xy: np.ndarray) -> np.ndarray:
        return layout.heights(xy, exclude=[name])

    clear, _ = first_clear_sweep(heights, [(behind, end) for _, end, _, behind in tries], limits, floor)
    if clear is None:
        return None
    start, end, _, behind = tries[clear]
    return start, end, behind


def _obstacles(layout: Layout, name: str, floor: float) -> tuple[np.ndarray, np.ndarray]:
    """The x-y bounds (k, 2), (k, 2) of the objects a push of ``name`` on a floor at ``floor`` could run into: those
    standing above the floor and reaching below the top of ``name``."""
    top = layout.box(name).top
    blocks = [b for b in layout.boxes(exclude=[name]) if b.top > floor + RISE and b.bottom < top]
    return np.array([b.lo for b in blocks]).reshape(-1, 2), np.array([b.hi for b in blocks]).reshape(-1, 2)


def _gaps(rect_lo: np.ndarray, rect_hi: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(k,) how far each box (``lo``, ``hi``) lies from the rectangle (negative: how deep they overlap); with
    rectangles (n, 1, 2), (n, k) for each of them."""
    return np.max(np.maximum(lo - rect_hi, rect_lo - hi), axis=-1)


def _drift_room(
    half: np.ndarray, frm: np.ndarray, to: np.ndarray, lo: np.ndarray, hi: np.ndarray, from_start: bool, to_goal: bool
) -> bool:
    """Whether an object of half size ``half`` pushed straight from ``frm`` to ``to`` passes the boxes (``lo``,
    ``hi``) with half a :data:`LANE` to spare (a long push drifts sideways a little). Within a lane of where it starts
    (``from_start``) and of its goal (``to_goal``) it may meet them: it may start against one, and end against one
    it comes straight at, but not slide along one on its way there."""
    length = float(np.linalg.norm(to - frm))
    near, far = (LANE if from_start else 0.0), length - (LANE if to_goal else 0.0)
    if far <= near:
        return True
    u = (to - frm) / length
    a, b = frm + near * u, frm + far * u
    return not np.any(_gaps(np.minimum(a, b) - half, np.maximum(a, b) + half, lo, hi) < LANE / 2)


def drift_room(layout: Layout, name: str, targets: Sequence[np.ndarray], floor: float) -> bool:
    """Whether pushing ``name`` through ``targets`` in turn (each as the push skill makes it: the shorter axis first)
    passes everything above the floor at ``floor`` with room to drift (:func:`_drift_room`)."""
    lo, hi = _obstacles(layout, name, floor)
    box, goal = layout.box(name), np.asarray(targets[-1], dtype=float)
    here, first = box.center, True
    for xy in targets:
        for leg in legs(here, np.asarray(xy, dtype=float)):
            to = here.copy()
            to[leg.axis] = leg.target
            if not _drift_room(box.half, here, to, lo, hi, first, bool(np.allclose(to, goal))):
                return False
            here, first = to, False
    return True


def push_route(
    layout: Layout, name: str, goal: np.ndarray, limits: QuadrupedLimits, floor: float, turns: bool = False
) -> list[np.ndarray] | None:
    """Targets of successive one-axis pushes that bring ``name`` to ``goal`` (x-y) around what stands in the way,
    the shortest found (each extra leg counts :data:`LEG_COST`, and one the robot can only push lined up well off the
    object's centre line, which turns it, :data:`OFF_CENTRE_COST`), or None.

    The object's centre moves on lanes clear of the other objects' sides (their boxes grown by the object's half size
    and :data:`LANE`); a leg is kept when the object's swept footprint meets no other object and passes them with
    room to drift (:func:`_drift_room`: so a goal beside something is come at across its side), and the robot's, from
    where it lines up behind the object to the end of the push, meets nothing above the floor at one of the
    offsets along the face that the push skill may take. With ``turns``, the robot may push each leg with its body
    turned a quarter either way (it turns in place between legs). Boxes only: the prediction of each push
    (:func:`push_problem`) is the judge of the route found.
    """
    goal = np.asarray(goal, dtype=float)
    key = (id(layout.task), _moved(layout), name, goal.tobytes(), limits, floor, turns)
    route = _remembered(_routes, key, layout, lambda: _push_route(layout, name, goal, limits, floor, turns))
    return None if route is None else [xy.copy() for xy in route]


def _push_route(
    layout: Layout, name: str, goal: np.ndarray, limits: QuadrupedLimits, floor: float, turns: bool
) -> list[np.ndarray] | None:
    box = layout.box(name)
    body = np.asarray(limits.body_size[:2]) / 2
    bodies = (body, body[::-1]) if turns else (body,)
    lo, hi = _obstacles(layout, name, floor)
    lanes = [
        sorted(
            {float(box.center[a]), float(goal[a]), *(lo[:, a] - box.half[a] - LANE), *(hi[:, a] + box.half[a] + LANE)}
        )
        for a in (0, 1)
    ]

    def clear(rect_lo: np.ndarray, rect_hi: np.ndarray) -> bool:
        return not np.any(_gaps(rect_lo, rect_hi, lo, hi) < -CONTACT / 4)

    def leg_cost(a: int, frm: np.ndarray, to: np.ndarray) -> float | None:
        """None where the leg is not kept, else what it counts for beyond its length (:data:`OFF_CENTRE_COST` where
        the robot must line up further off the object's centre line than :data:`OFF_CENTRE`)."""
        if not clear(np.minimum(frm, to) - box.half, np.maximum(frm, to) + box.half):
            return None
        if not _drift_room(box.half, frm, to, lo, hi, np.array_equal(frm, box.center), np.array_equal(to, goal)):
            return None
        sign = np.sign(to[a] - frm[a])
        least = np.inf  # the least offset a clear line-up takes, as a share of the object's half width across
        for robot in bodies:
            back = box.half[a] + GAP + robot[a]
            offsets = lateral_offsets(2 * float(box.half[1 - a]), 2 * float(robot[1 - a]))
            start, end = np.tile(frm, (len(offsets), 1)), np.tile(to, (len(offsets), 1))
            start[:, a] -= sign * (back + QUADRUPED.staging)
            end[:, a] -= sign * back
            start[:, 1 - a] += offsets
            end[:, 1 - a] += offsets
            rect_lo, rect_hi = np.minimum(start, end) - robot, np.maximum(start, end) + robot
            gaps = _gaps(rect_lo[:, None], rect_hi[:, None], lo, hi)
            fits = np.flatnonzero(~np.any(gaps < -CONTACT / 4, axis=1))  # as clear() reads each line-up
            if fits.size:  # (the offsets come nearest the centre line first)
                least = min(least, abs(float(offsets[fits[0]])) / float(box.half[1 - a]))
        if least == np.inf:
            return None
        return OFF_CENTRE_COST if least > OFF_CENTRE else 0.0

    nodes = [(i, j) for i in range(len(lanes[0])) for j in range(len(lanes[1]))]
    at = {n: np.array([lanes[0][n[0]], lanes[1][n[1]]]) for n in nodes}
    source = (lanes[0].index(float(box.center[0])), lanes[1].index(float(box.center[1])))
    target = (lanes[0].index(float(goal[0])), lanes[1].index(float(goal[1])))
    best = {source: 0.0}
    previous: dict[tuple[int, int], tuple[int, int]] = {}
    frontier = [(0.0, source)]
    while frontier:
        cost, node = heapq.heappop(frontier)
        if node == target:
            path = [at[node]]
            while node in previous:
                node = previous[node]
                path.append(at[node])
            return path[::-1][1:]
        if cost > best.get(node, np.inf):
            continue
        for a in (0, 1):
            for k in range(len(lanes[a])):
                nxt = (k, node[1]) if a == 0 else (node[0], k)
                if nxt == node:
                    continue
                step = cost + abs(lanes[a][k] - lanes[a][node[a]]) + LEG_COST
                if step >= best.get(nxt, np.inf) or (extra := leg_cost(a, at[node], at[nxt])) is None:
                    continue
                step += extra
                if step < best.get(nxt, np.inf):
                    best[nxt] = step
                    previous[nxt] = node
                    heapq.heappush(frontier, (step, nxt))
    return None
