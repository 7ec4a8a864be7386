"""Quadruped macros: walk or climb onto a surface (directly, over a pushed bridge, up pushed steps), push an
object to a placement (against another object's side, across a gap, out of the way, beside an edge),
stand on a lever's far end, push an object off an edge onto a soft landing.

Each route is predicted with :func:`robotool.robots.quadruped.predict.walk_violation` on the planned layout; a
program whose walk is predicted to break a limit keeps that as its ``doubt`` and is tried late.
"""

from __future__ import annotations

import copy
import itertools
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field, replace

import numpy as np

from robotool.concepts import surface_under
from robotool.planner.codegen import Point, Program, Ref
from robotool.planner.layout import Box, Layout
from robotool.robots.quadruped.predict import detour, push_problem, push_route, push_staging, walk_violation
from robotool.robots.quadruped.push import lateral_offsets, legs, sweep_points
from robotool.robots.quadruped.quadruped_concepts import start_surface
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.terrain import RISE, foot_offsets
from robotool.scene import SceneObject
from robotool.task_model import Task

LEVEL = 0.04  # m: supports closer in height than this are the same surface
APPROACH = 0.1  # m between the robot and a step when it lines up to climb it
INSET = 0.06  # m the robot keeps from the far edge of what it walks onto
OVERLAP = 0.15  # m a bridge rests on each side of a gap
CLEARANCES = (0.5, 0.2)  # m a prop pushed out from under a board keeps from the board's side: far enough to be left
# behind by the board's end when friction drags it sideways part of the way, else just clear
SIDE = 0.25  # m the robot keeps from a board it walks beside
FALL_OFF = 0.01  # m an object pushed off an edge goes past it (beyond its own half size): the feet stay on
MAX_STEPS = 3  # objects a staircase may use below the target
Placement = tuple[np.ndarray, np.ndarray | None]  # a staircase link's climb direction (to the next) and new centre
PushStep = tuple[list[np.ndarray], np.ndarray, np.ndarray]  # walk to where a push lines up, its target, where it ends


@dataclass
class Route:
    """Pushes that rearrange the scene, then waypoints the robot walks through (each on a named surface)."""

    pushes: list[tuple[str, np.ndarray, str]] = field(default_factory=list)  # object, x-y centre, why
    waypoints: list[tuple[np.ndarray, str]] = field(default_factory=list)  # x-y, surface ("ground" or object)
    uses: list[tuple[str, str]] = field(default_factory=list)  # object, role
    words: str = ""
    late: int = 0  # less likely choices it makes (a step down onto the target: the body rides on a higher step)
    slack: float = float("inf")  # m the feet keep, at the tightest stance, from the side edges of what they stand on

    def layout(self, base: Layout) -> Layout:
        """``base`` with the route's pushes made."""
        out = base
        for name, xy, _ in self.pushes:
            out = out.with_moved(name, xy)
        return out


class Quadruped:
    """The quadruped's view of one task: its limits, body, start and the objects' boxes."""

    def __init__(self, task: Task):
        self.task = task
        limits = task.limits
        assert isinstance(limits, QuadrupedLimits)
        self.limits = limits
        self.half = np.asarray(limits.body_size[:2]) / 2
        self.start = np.asarray(task.robot.position, dtype=float)
        self.floor_name, self.floor = start_surface(task)
        self.layout = Layout(task)
        self.placed: frozenset[str] = frozenset()  # objects already pushed where the program needs them

    def pushable(self, obj: SceneObject, level: float) -> bool:
        """Whether the robot may push ``obj`` from a surface at height ``level``."""
        return (
            obj.movable
            and obj.name not in self.placed
            and obj.shape != "cloth"
            and obj.effective_mass <= self.limits.max_push_mass
            and abs(obj.bottom - level) < LEVEL
        )

    def after(self, layout: Layout, here: np.ndarray, placed: Iterable[str]) -> Quadruped:
        """The same robot on the same floor once the scene is rearranged to ``layout`` and it stands at ``here``;
        the ``placed`` objects are to stay where they are (no route pushes them)."""
        out = copy.copy(self)
        out.layout, out.start = layout, np.asarray(here, dtype=float)
        out.placed = self.placed | frozenset(placed)
        return out

    def extent(self, u: np.ndarray) -> float:
        """Half length of the body along direction ``u``."""
        return float(np.abs(u) @ self.half)

    def top_point(self, box: Box, toward: np.ndarray, frm: np.ndarray) -> np.ndarray:
        """A point well on ``box``'s top for a robot arriving from ``frm``: its centre, or, for a long box,
        the point along the arrival direction that leaves room for the body."""
        room = np.maximum(box.half - self.half - INSET, 0.0)
        along = np.clip(frm - box.center, -room, room)
        return np.where(np.abs(toward) > 0.5, box.center, box.center + along)


# --- routes onto a surface ----------------------------------------------------------------------------

DIRECTIONS = tuple(np.array(v, dtype=float) for v in ((1, 0), (-1, 0), (0, 1), (0, -1)))
FOOT = 0.03  # m the feet sit inside the body's outline: they must be over what the robot stands on
ENTRIES = 2  # predicted-fine approaches kept for a direct climb
LANDING_STEP = 0.02  # m between the stops tried when a route's stop on its target is pulled back
STANCE_SLACK = 0.05  # m a staircase's climb line keeps the feet from the steps' side edges, where they allow it


def routes_onto(quad: Quadruped, name: str, tools: bool) -> Iterator[Route]:
    """Ways onto ``name``'s top: walk there, bridge a gap with a pushed board, or climb pushed steps; each stops
    short of what stands on the top (:func:`_landing`)."""
    found = itertools.chain(_direct(quad, name), *((_bridges(quad, name), _staircases(quad, name)) if tools else ()))
    for route in found:
        yield _landing(quad, name, route)


def _landing(quad: Quadruped, name: str, route: Route) -> Route:
    """``route`` with its stop on ``name`` pulled back along the way it arrives, when the walk to the stop is predicted
    to run into something standing on the top (an object lying ahead of the steps): to the farthest point with every
    foot on the top, the body's outline (and its side margin) clear of what stands there, and the walk there
    predicted fine; unchanged when the walk is fine, or when no point is."""
    last, surface = route.waypoints[-1]
    if surface != name:
        return route
    previous = route.waypoints[-2][0] if len(route.waypoints) > 1 else quad.start
    layout = route.layout(quad.layout)
    if walk_violation(layout, previous, [last], quad.limits) is None:
        return route
    top, length = layout.box(name).top, float(np.linalg.norm(last - previous))
    for s in np.arange(length - LANDING_STEP, 0.0, -LANDING_STEP):
        stop = previous + (last - previous) * s / length
        feet = layout.heights(stop + foot_offsets(quad.limits))
        body = layout.heights(sweep_points(stop, stop, quad.half))
        if (
            np.all(np.abs(feet - top) <= LEVEL / 2)
            and body.max() <= top + RISE
            and walk_violation(layout, previous, [stop], quad.limits) is None
        ):
            return replace(route, waypoints=[*route.waypoints[:-1], (stop, name)])
    return route


def _direct(quad: Quadruped, name: str) -> Iterator[Route]:
    """Walk onto ``name``: straight when that is predicted fine, else lined up along an axis with one of its
    sides (reached around what stands in the way), the shortest predicted-fine approaches first."""
    box = quad.layout.box(name)
    words = f"Walk onto {name}."
    straight = Route(waypoints=[(box.center, name)], words=words)
    if walk_violation(quad.layout, quad.start, [box.center], quad.limits) is None:
        yield straight
        return
    found = []
    for d in DIRECTIONS:
        entry = _entry(quad, box, d, quad.start)
        if entry is None:
            continue
        approach, inside = entry
        path = [*detour(quad.layout, quad.start, approach, quad.limits)[:-1], approach, inside]
        if walk_violation(quad.layout, quad.start, path, quad.limits) is None:
            found.append((_length(quad.start, path), approach, inside, d))
    found.sort(key=lambda f: f[0])
    for _, approach, inside, _ in found[:ENTRIES]:
        yield Route(waypoints=[(approach, quad.floor_name), (inside, name)], words=f"Line up beside {name}; " + words)
    if not found:
        yield straight


def _length(start: np.ndarray, path: list[np.ndarray]) -> float:
    points = [start, *path]
    return sum(float(np.linalg.norm(b - a)) for a, b in itertools.pairwise(points))


def _entry(quad: Quadruped, box: Box, d: np.ndarray, frm: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Where to line up (outside ``box``, facing ``d``) and where to stop on its top, or None when the box is too
    narrow across ``d`` for the feet."""
    axis = int(np.argmax(np.abs(d)))
    lat = 1 - axis
    if box.half[lat] < quad.half[lat] - FOOT:
        return None
    inside = quad.top_point(box, d, frm)
    approach = inside.copy()
    approach[axis] = box.center[axis] - d[axis] * (box.half[axis] + quad.half[axis] + APPROACH)
    return approach, inside


def _bridges(quad: Quadruped, name: str) -> Iterator[Route]:
    """Push a board that rests on the robot's surface across the gap on the axis-aligned way to ``name``,
    keeping the board's own line across the gap when it can (one push leg), else the start's or the target's."""
    target = quad.layout.box(name)
    d = _axis_direction(target.center - quad.start)
    axis, lat = int(np.argmax(np.abs(d))), 1 - int(np.argmax(np.abs(d)))
    for obj in quad.task.objects:
        if obj.name == name or not quad.pushable(obj, quad.floor) or obj.top - obj.bottom > quad.limits.max_step_up:
            continue
        board = quad.layout.box(obj.name)
        length = 2 * float(board.half[axis])
        lines = [board.center[lat], quad.start[lat], target.center[lat]]
        for line in (v for k, v in enumerate(lines) if all(abs(v - w) > 0.02 for w in lines[:k])):
            gap = _gap(quad, d, line, target)
            if gap is None:
                continue
            near, far = gap
            if length < (far - near) + 2 * OVERLAP - 0.05:
                continue
            for shift in (far + OVERLAP - length / 2, (near + far) / 2):
                xy = np.zeros(2)
                xy[axis] = quad.start[axis] + d[axis] * shift
                xy[lat] = line
                lined = quad.start.copy()
                lined[lat] = line
                inside = quad.top_point(target, d, lined)
                inside[lat] = np.clip(line, target.lo[lat] + quad.half[lat], target.hi[lat] - quad.half[lat])
                waypoints = [(lined, quad.floor_name)] if abs(line - quad.start[lat]) > 0.01 else []
                yield Route(
                    pushes=[(obj.name, xy, f"across the {far - near:.2f} m gap")],
                    waypoints=[*waypoints, (inside, name)],
                    uses=[(obj.name, "tool: a rigid board to bridge the gap")],
                    words=f"Push {obj.name} across the gap as a bridge, then walk over it onto {name}.",
                )


def _gap(quad: Quadruped, d: np.ndarray, line: float, target: Box) -> tuple[float, float] | None:
    """The first stretch too low to step in along ``d`` from the start to ``target`` on the line ``line`` across
    (distances from the start along ``d``), ignoring movable objects."""
    axis, lat = int(np.argmax(np.abs(d))), 1 - int(np.argmax(np.abs(d)))
    length = float(abs(target.center[axis] - quad.start[axis]))
    s = np.arange(0.0, length, 0.01)
    points = np.zeros((len(s), 2))
    points[:, axis] = quad.start[axis] + d[axis] * s
    points[:, lat] = line
    movable = [o.name for o in quad.task.objects if o.movable]
    h = quad.layout.heights(points, exclude=movable)
    low = np.flatnonzero(h < quad.floor - quad.limits.max_step_up)
    if not low.size:
        return None
    end = low[0]
    while end + 1 < len(s) and h[end + 1] < quad.floor - quad.limits.max_step_up:
        end += 1
    return float(s[low[0]]), float(s[end])


def _staircases(quad: Quadruped, name: str) -> Iterator[Route]:
    """Climb objects onto ``name`` (each rise within the limit, a step down onto it allowed), pushing those that
    do not already stand against the next."""
    target = quad.task.object(name)
    rise = quad.limits.max_step_up + 0.005
    steps = [
        o
        for o in quad.task.objects
        if o.name != name and o.shape != "cloth" and quad.floor + 0.02 < o.top < target.top + quad.limits.max_step_up
    ]
    for count in range(1, MAX_STEPS + 1):
        for chain in itertools.permutations(steps, count):
            tops = [quad.floor, *(o.top for o in chain), target.top]
            if any(
                b - a > rise or a - b > quad.limits.max_step_down or (abs(b - a) < 0.02 and k < count)
                for k, (a, b) in enumerate(itertools.pairwise(tops))
            ):  # the last link may be level with the target
                continue
            for route in _place_chain(quad, [*chain, target]):
                route.late = int(tops[-1] < tops[-2])
                yield route


def _place_chain(quad: Quadruped, chain: list[SceneObject]) -> Iterator[Route]:
    """Placements of the chain's movable links against the next one's sides (centred or flush with either end),
    each placed against where the next link will stand, nearest the target first; placements that would overlap
    something, or whose steps cannot carry the feet, are left out. A link placed against a link that is itself
    pushed into place continues that link's climb in a straight line."""

    def place(k: int, layout: Layout, combo: list[Placement]) -> Iterator[list[Placement]]:
        if k < 0:
            yield combo
            return
        obj, nxt = chain[k], chain[k + 1]
        box, nxt_box = layout.box(obj.name), layout.box(nxt.name)
        if box.touches(nxt_box):
            yield from place(k - 1, layout, [(_axis_direction(nxt_box.center - box.center), None), *combo])
            return
        if not quad.pushable(obj, quad.floor):
            return
        straight = [combo[0][0]] if combo and combo[0][1] is not None else list(DIRECTIONS)
        for direction, xy in _sides(quad, layout, obj, nxt, straight):
            if layout.collides(box.moved_to(xy)) is None:
                yield from place(k - 1, layout.with_moved(obj.name, xy), [(direction, xy), *combo])

    routes = [r for combo in place(len(chain) - 2, quad.layout, []) if (r := _chain_route(quad, chain, combo))]
    yield from sorted(routes, key=lambda r: _pushed_distance(quad.layout, r))


def _pushed_distance(layout: Layout, route: Route) -> float:
    """How far a route's pushes move objects in all."""
    total = 0.0
    for name, xy, _ in route.pushes:
        total += float(np.linalg.norm(xy - layout.box(name).center))
        layout = layout.with_moved(name, xy)
    return total


def _sides(
    quad: Quadruped, layout: Layout, obj: SceneObject, nxt: SceneObject, directions: list[np.ndarray]
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Centres for ``obj`` against ``nxt``'s side facing each of ``directions`` (the climb's direction): centred,
    flush with either end, or flush with something else standing by the same face, as long as the feet can stand
    across both."""
    box, nxt_box = layout.box(obj.name), layout.box(nxt.name)
    others = [
        layout.box(o.name) for o in quad.task.objects if o.shape != "cloth" and o.name not in (obj.name, nxt.name)
    ]
    for direction in directions:
        axis = int(np.argmax(np.abs(direction)))
        lat = 1 - axis
        slide = max(0.0, float(nxt_box.half[lat] - box.half[lat]))
        along = nxt_box.center[axis] - direction[axis] * (nxt_box.half[axis] + box.half[axis] + 0.002)
        offsets = [0.0, slide, -slide]
        for other in others:  # flush against something else that stands by the same face
            if other.lo[axis] < along + box.half[axis] and other.hi[axis] > along - box.half[axis]:
                offsets += [
                    float(other.hi[lat] + box.half[lat] + 0.005 - nxt_box.center[lat]),
                    float(other.lo[lat] - box.half[lat] - 0.005 - nxt_box.center[lat]),
                ]
        reach = float(nxt_box.half[lat] + box.half[lat]) - 2 * (quad.half[lat] - FOOT)
        for offset in dict.fromkeys(round(o, 4) for o in offsets if abs(o) <= reach):
            xy = nxt_box.center.copy()
            xy[axis] = along
            xy[lat] += offset
            yield direction, xy


def _chain_route(quad: Quadruped, chain: list[SceneObject], combo: list[Placement]) -> Route | None:
    route = Route()
    layout = quad.layout
    for k in range(len(combo) - 1, -1, -1):  # placements nearest the target first
        d, xy = combo[k]
        obj = chain[k]
        if xy is not None:
            lined = _lined_up(layout.box(obj.name).center, xy, d)
            if lined is not None:
                route.pushes.append((obj.name, lined, f"in line with {chain[k + 1].name}'s side"))
            layout = layout.with_moved(obj.name, xy)
            route.pushes.append((obj.name, xy, f"against {chain[k + 1].name}'s side"))
    boxes = [layout.box(o.name) for o in chain]
    here = quad.start
    lines = []
    for k, (d, _) in enumerate(combo):  # the line across each climb on which every foot is over both steps
        lat = 1 - int(np.argmax(np.abs(d)))
        foot = quad.half[lat] - FOOT
        lo = max(boxes[k].lo[lat], boxes[k + 1].lo[lat]) + foot
        hi = min(boxes[k].hi[lat], boxes[k + 1].hi[lat]) - foot
        if hi < lo - 0.004:
            return None
        lo, hi = _clear_of_neighbours(quad, layout, chain, k, lat, lo, hi)
        keep = min(STANCE_SLACK, (hi - lo) / 2)  # as far from both edges as the steps allow, up to STANCE_SLACK
        lines.append(float(np.clip(here[lat], lo + keep, hi - keep)))
        route.slack = min(route.slack, lines[-1] - lo, hi - lines[-1])
    d0, lat0 = combo[0][0], 1 - int(np.argmax(np.abs(combo[0][0])))
    axis0 = 1 - lat0
    approach = np.zeros(2)
    approach[axis0] = boxes[0].center[axis0] - d0[axis0] * (boxes[0].half[axis0] + quad.half[axis0] + APPROACH)
    approach[lat0] = lines[0]
    route.waypoints.append((approach, quad.floor_name))
    previous = approach
    for k in range(len(chain)):
        d = combo[min(k, len(combo) - 1)][0]
        axis = int(np.argmax(np.abs(d)))
        stance = np.zeros(2)
        stance[axis] = boxes[k].center[axis]
        stance[1 - axis] = lines[min(k, len(lines) - 1)]
        if k:  # straight onto this step along the last climb, then over to this climb's line
            prev_d = combo[k - 1][0]
            prev_axis = int(np.argmax(np.abs(prev_d)))
            onto = previous.copy()
            onto[prev_axis] = boxes[k].center[prev_axis] if k < len(chain) - 1 else stance[prev_axis]
            if k == len(chain) - 1:
                onto = quad.top_point(boxes[k], prev_d, previous)
                onto[1 - prev_axis] = previous[1 - prev_axis]
            route.waypoints.append((onto, chain[k].name))
            if k == len(chain) - 1:
                break
            if float(np.linalg.norm(stance - onto)) > 0.01:
                route.waypoints.append((stance, chain[k].name))
        else:
            route.waypoints.append((stance, chain[k].name))
        previous = stance
        route.uses.append((chain[k].name, f"tool: a step up to {chain[k + 1].name}"))
    names = ", ".join(o.name for o in chain[:-1])
    route.words = (
        f"Make a staircase of {names} against {chain[-1].name}"
        + (" by pushing " + ", ".join(p[0] for p in route.pushes) + " into place" if route.pushes else "")
        + f", then climb it onto {chain[-1].name}."
    )
    return route


def _lined_up(center: np.ndarray, xy: np.ndarray, d: np.ndarray) -> np.ndarray | None:
    """Where to push an object first so that its last push toward ``xy`` runs along ``d`` (into the face it is
    to stand against) rather than sliding along that face: the push skill moves along the shorter axis first,
    so when the move across ``d`` is the longer one the object is first lined up across ``d``; None when the
    push already ends along ``d``, or when the object starts past ``xy`` along ``d`` (its last push would run away
    from the face, and lined up it would stand where the next link does)."""
    axis = int(np.argmax(np.abs(d)))
    delta = np.asarray(xy) - center
    if abs(delta[1 - axis]) < 0.02 or abs(delta[1 - axis]) <= abs(delta[axis]) or delta[axis] * d[axis] < 0:
        return None
    out = np.array(center, dtype=float)
    out[1 - axis] = xy[1 - axis]
    return out


def _clear_of_neighbours(
    quad: Quadruped, layout: Layout, chain: list[SceneObject], k: int, lat: int, lo: float, hi: float
) -> tuple[float, float]:
    """Narrow the climb line's range ``lo``-``hi`` (across the climb from link ``k`` onto link ``k + 1``) so that the
    body's flanks keep clear of other objects standing beside the two steps; unchanged when no line is clear."""
    axis = 1 - lat
    a, b = layout.box(chain[k].name), layout.box(chain[k + 1].name)
    span = (min(a.lo[axis], b.lo[axis]) - quad.half[axis], max(a.hi[axis], b.hi[axis]) + quad.half[axis])
    names = {o.name for o in chain}
    new_lo, new_hi = lo, hi
    for obj in quad.task.objects:
        if obj.name in names or obj.shape == "cloth" or obj.top < quad.floor + 0.03:
            continue
        other = layout.box(obj.name)
        if other.hi[axis] <= span[0] or other.lo[axis] >= span[1]:
            continue
        middle = (lo + hi) / 2
        if other.hi[lat] <= middle:
            new_lo = max(new_lo, float(other.hi[lat]) + quad.half[lat] + 0.02)
        elif other.lo[lat] >= middle:
            new_hi = min(new_hi, float(other.lo[lat]) - quad.half[lat] - 0.02)
    return (new_lo, new_hi) if new_hi >= new_lo else (lo, hi)


def _axis_direction(v: np.ndarray) -> np.ndarray:
    axis = int(np.argmax(np.abs(v)))
    out = np.zeros(2)
    out[axis] = np.sign(v[axis]) or 1.0
    return out


# --- writing routes into programs ---------------------------------------------------------------------


def _push_plans(
    layout: Layout, name: str, xy: np.ndarray, limits: QuadrupedLimits, floor: float
) -> Iterator[list[np.ndarray]]:
    """Ways to push ``name`` to ``xy``, as the targets of successive pushes: straight (one skill call, which pushes
    along the shorter axis first), one axis at a time in either order, then routed around what stands in the way
    (:func:`robotool.planner.layout.push_route`), a push along one axis too."""
    center = layout.box(name).center
    yield [xy]
    parts = legs(center, xy)
    for first in parts if len(parts) == 2 else []:
        corner = center.copy()
        corner[first.axis] = first.target
        yield [corner, xy]
    around = push_route(layout, name, xy, limits, floor)
    if around is not None and len(around) > 2:
        yield around


class Writer:
    """Writes pushes and walks into a program, querying positions when they run."""

    def __init__(self, quad: Quadruped, prog: Program):
        self.quad, self.prog = quad, prog
        self.layout = quad.layout
        self.here = quad.start
        self.level = quad.floor
        self.surface = quad.floor_name
        self.refs: dict[str, Ref] = {}

    def position(self, name: str) -> Ref:
        """Query where ``name`` is now (once per placement)."""
        if name not in self.refs:
            box = self.layout.box(name)
            self.refs[name] = self.prog.query("get_position", name, (*box.center, 0.0))
        return self.refs[name]

    def push(self, name: str, xy: np.ndarray, why: str) -> None:
        """Push ``name`` to ``xy`` the first way (:func:`_push_plans`) predicted fine (else the straight way, its
        problem kept as the program's doubt): in one skill call, or one axis at a time, or routed around what stands
        in the way; before each push whose own way to where the robot lines up is predicted blocked, the robot walks
        there around what stands in the way."""
        xy = np.asarray(xy, dtype=float)
        predicted = None
        for plan in _push_plans(self.layout, name, xy, self.quad.limits, self.level):
            found = self._predict_pushes(name, plan)
            predicted = predicted or found
            if found[1] is None:
                predicted = found
                break
        assert predicted is not None
        steps, problem = predicted
        for path, target, end in steps:
            for via in path:
                self.walk(via, self.surface, f"walk to where the push of {name} lines up")
            ref = self.position(name)
            start = self.layout.box(name).center
            self.prog.motion(
                "push_to_position",
                obj=name,
                point=Point.at(ref, (*(target - start), 0.0)),
                intent=f"push {name} {why}",
                explanation=f"centre to [{target[0]:.3f}, {target[1]:.3f}]",
            )
            self.here = end
            self.layout = self.layout.with_moved(name, target)
            self.refs.pop(name, None)
        self.doubt(problem)
        self.prog.use(name)

    def _predict_pushes(self, name: str, targets: list[np.ndarray]) -> tuple[list[PushStep], str | None]:
        """Pushes of ``name`` through ``targets`` in turn, as predicted from where the robot is: for each, the walk
        to where it lines up when the skill's own way there is blocked (else none), the target and where the robot
        ends; and the first problem predicted."""
        layout, here, limits = self.layout, self.here, self.quad.limits
        steps: list[PushStep] = []
        first = None
        for xy in targets:
            problem, end = push_problem(layout, name, xy, limits, self.level, here)
            path: list[np.ndarray] = []
            staging = push_staging(layout, name, xy, limits, self.level) if problem else None
            if problem and problem.kind == "approach" and staging is not None:
                way = detour(layout, here, staging, limits)
                if walk_violation(layout, here, way, limits) is None:
                    path = way
                    problem, end = push_problem(layout, name, xy, limits, self.level, staging)
            steps.append((path, xy, end))
            first = first or (str(problem) if problem else None)
            layout, here = layout.with_moved(name, xy), end
        return steps, first

    def doubt(self, problem: str | None) -> None:
        """Keep the first predicted problem as the program's doubt."""
        if problem and not self.prog.doubt:
            self.prog.doubt = problem

    def walk(self, xy: np.ndarray, surface: str, intent: str) -> None:
        """Walk (or climb, when the surface is higher) to ``xy`` on ``surface``, anchored to it when it is an object."""
        height = 0.0 if surface == "ground" else self.layout.box(surface).top
        if surface == "ground" or not self.quad.task.object(surface).movable:
            point = Point.at(None, (*xy, height))
        else:  # a movable surface may not be quite where it was pushed to
            point = Point.at(self.position(surface), (*(xy - self.layout.box(surface).center), 0.0))
        skill = "climb_to_position" if height > self.level + 0.015 else "walk_to_position"
        self.prog.motion(skill, point=point, objects=[] if surface == "ground" else [surface], intent=intent)
        self.level = max(height, self.level) if skill == "climb_to_position" else height
        self.here = np.asarray(xy, dtype=float)
        self.surface = surface

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
        for name, xy, why in route.pushes:
            self.push(name, xy, why)
        first, surface = route.waypoints[0]
        if surface == self.quad.floor_name:
            self.around(first)
        self.doubt(walk_violation(self.layout, self.here, [xy for xy, _ in route.waypoints], self.quad.limits))
        for xy, surface in route.waypoints:
            self.walk(xy, surface, f"walk onto {surface}" if surface != "ground" else "walk into position")
        self.prog.say(route.words)


# --- goals ----------------------------------------------------------------------------------------------


def candidates(task: Task, tools: bool) -> Iterator[Program]:
    """Every program the macros make for the task (unordered; the search orders them)."""
    quad = Quadruped(task)
    goal = task.goal
    target = task.object(goal.object)
    if goal.kind == "robot_on":
        for route in routes_onto(quad, target.name, tools):
            prog = Program()
            prog.use(target.name, "target")
            Writer(quad, prog).route(route)
            yield prog
    elif goal.kind == "lifted":
        if tools:
            yield from _levers(quad, target)
    else:
        yield from _lowerings(quad, target, tools)


def _levers(quad: Quadruped, target: SceneObject) -> Iterator[Program]:
    """Lift ``target`` by standing on the far end of the board it rests on, after pushing away what props it."""
    task = quad.task
    board_name, _ = surface_under(task, np.asarray(target.center[:2]), exclude=target.name)
    if board_name == "ground":
        return
    board = task.object(board_name)
    bbox = quad.layout.box(board_name)
    under = [
        o
        for o in task.objects
        if o.name not in (board_name, target.name)
        and o.shape != "cloth"
        and quad.layout.box(o.name).overlap(bbox) > 0.01
        and o.top <= board.top
    ]
    fulcrums = [o for o in under if not o.movable]
    props = [o for o in under if o.movable]
    if not fulcrums:
        return
    axis = int(np.argmax(bbox.half))
    a = np.zeros(2)
    a[axis] = -np.sign(target.center[axis] - bbox.center[axis]) or 1.0  # toward the far end
    lat = np.array([-a[1], a[0]])
    fulcrum = quad.layout.box(fulcrums[0].name)
    near = np.sign((quad.start - bbox.center) @ lat) or 1.0
    for side, clearance in itertools.product((near, -near), CLEARANCES):
        prog = Program()
        prog.use(target.name, "target")
        prog.use(board_name, f"tool: a lever over {fulcrums[0].name}, {target.name} on one end")
        prog.use(fulcrums[0].name, "tool: the fulcrum")
        w = Writer(quad, prog)
        beside = float(np.abs(lat) @ bbox.half) + quad.extent(lat) + SIDE
        for prop in props:
            p = quad.layout.box(prop.name)
            out = p.center.copy()
            away = float(np.abs(lat) @ (bbox.half + p.half)) + clearance + abs((p.center - bbox.center) @ lat)
            out -= side * lat * away
            prog.use(prop.name, f"obstacle: props up {board_name}'s far end; push it out of the way")
            along = (p.center - bbox.center) @ a + quad.extent(a)  # beside it, toward the end, clear of the board
            w.floor_walk(bbox.center + lat * side * beside + a * along, f"walk beside {prop.name}")
            w.push(prop.name, out, "out from under the board")
        step_on = fulcrum.center - a * (quad.extent(a) + 0.01)
        step_on = step_on - lat * ((step_on - bbox.center) @ lat)
        end = bbox.center + a * (float(np.abs(a) @ bbox.half) - quad.extent(a) - INSET)
        for xy in (w.here + lat * (side * beside - (w.here - bbox.center) @ lat), step_on + lat * side * beside):
            w.floor_walk(xy, "walk beside the board")
        w.walk(step_on, board_name, f"step onto {board_name} next to the fulcrum")
        w.walk(end, board_name, f"walk to {board_name}'s far end so it tips and lifts {target.name}")
        prog.say(
            (f"Push {', '.join(p.name for p in props)} out from under {board_name}. " if props else "")
            + f"Step onto {board_name} by {fulcrums[0].name} and walk to its far end: "
            + f"the lever lifts {target.name}."
        )
        yield prog


def _lowerings(quad: Quadruped, target: SceneObject, tools: bool) -> Iterator[Program]:
    """Get onto the surface ``target`` rests on and push it off an edge, onto a soft object when the fall is high."""
    task = quad.task
    goal = task.goal.lowered
    assert goal is not None
    support_name, _ = surface_under(task, np.asarray(target.center[:2]), exclude=target.name)
    if support_name == "ground":
        return
    support = quad.layout.box(support_name)
    tbox = quad.layout.box(target.name)
    fall = target.bottom
    cushions = [None]
    if tools:
        cushions += [
            o
            for o in task.objects
            if o.soft
            and quad.pushable(o, quad.floor)
            and o.top <= goal.height
            and (target.fragile is None or target.bottom - o.top <= target.fragile.max_drop)
        ]
    for direction in (np.array(v, dtype=float) for v in ((1, 0), (-1, 0), (0, 1), (0, -1))):
        axis = int(np.argmax(np.abs(direction)))
        edge = support.center[axis] + direction[axis] * support.half[axis]
        dest = tbox.center.copy()
        dest[axis] = edge + direction[axis] * (tbox.half[axis] + FALL_OFF)
        for cushion in cushions:
            if cushion is None and target.fragile is not None and fall > target.fragile.max_drop:
                continue
            pushes = []
            if cushion is not None:
                cbox = quad.layout.box(cushion.name)
                spot = dest.copy()
                spot[axis] = edge + direction[axis] * (cbox.half[axis] + 0.005)
                if quad.layout.collides(cbox.moved_to(spot), ignore=[target.name]) is not None:
                    continue
                pushes.append((cushion.name, spot))
            for route in routes_onto(_after_pushes(quad, pushes), support_name, tools):
                prog = Program()
                prog.use(target.name, "target")
                w = Writer(quad, prog)
                for name, spot in pushes:
                    prog.use(name, f"tool: a soft landing for {target.name}")
                    w.push(name, spot, f"beside {support_name}'s edge, under where {target.name} will fall")
                w.route(route)
                behind = _stance_behind(quad, w.layout, target.name, direction, support.top)
                if behind is None:
                    behind = tbox.center - direction * (tbox.half[axis] + quad.extent(direction) + 0.05)
                    w.doubt(f"no room for the feet on {support_name} behind {target.name}")
                for via in detour(w.layout, w.here, behind, quad.limits)[:-1]:
                    w.walk(via, support_name, f"walk around what stands on {support_name}")
                w.walk(behind, support_name, f"walk behind {target.name}")
                ref = w.position(target.name)
                prog.motion(
                    "push_to_position",
                    obj=target.name,
                    point=Point.at(ref, (*(dest - tbox.center), 0.0)),
                    intent=f"push {target.name} off {support_name}'s edge",
                    explanation=f"its centre {tbox.half[axis] + FALL_OFF:.2f} m past the edge",
                )
                prog.say(
                    (f"Push {pushes[0][0]} beside {support_name}; " if pushes else "")
                    + f"push {target.name} off {support_name}"
                    + (f" onto {pushes[0][0]}." if pushes else ".")
                )
                yield prog


def _after_pushes(quad: Quadruped, pushes: list[tuple[str, np.ndarray]]) -> Quadruped:
    """``quad`` as the scene will be after ``pushes`` (object, x-y centre) are made, the robot where the last ends:
    the way onto a surface is planned around what they moved (a cushion pushed beside a sofa stands in the way)."""
    if not pushes:
        return quad
    w = Writer(quad, Program())
    for name, spot in pushes:
        w.push(name, spot, "")
    return quad.after(w.layout, w.here, [name for name, _ in pushes])


def _stance_behind(
    quad: Quadruped, layout: Layout, name: str, direction: np.ndarray, level: float
) -> np.ndarray | None:
    """Where to stand behind ``name`` to push it along ``direction``: straight behind it, else slid along its face to
    the nearest offset the push skill may take (:func:`robotool.robots.quadruped.push.lateral_offsets`) with every
    foot on the surface at ``level`` it stands on; None when there is no such place."""
    box = layout.box(name)
    axis = int(np.argmax(np.abs(direction)))
    lat = 1 - axis
    straight = box.center - direction * (box.half[axis] + quad.extent(direction) + 0.05)
    for offset in lateral_offsets(2 * float(box.half[lat]), 2 * float(quad.half[lat])):
        stance = straight.copy()
        stance[lat] += offset
        feet = layout.heights(stance + foot_offsets(quad.limits), exclude=[name])
        if np.all(np.abs(feet - level) <= LEVEL / 2):
            return stance
    return None
