"""Quadruped routes onto a surface, for the macros (:mod:`.quadruped_macros`): directly, over a pushed bridge, up
pushed steps; the quadruped's view of a task (:class:`Quadruped`) and the route record (:class:`Route`).

Each route is predicted with :func:`robotool.robots.quadruped.predict.walk_violation` on the planned layout; a
program whose walk is predicted to break a limit keeps that as its ``doubt`` and is tried late.
"""

from __future__ import annotations

import copy
import itertools
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np

from robotool.planner.codegen import Program
from robotool.planner.layout import CONTACT, Box, Layout
from robotool.robots.quadruped.predict import detour, walk_violation
from robotool.robots.quadruped.push import sweep_points
from robotool.robots.quadruped.quadruped_concepts import start_surface
from robotool.robots.quadruped.quadruped_config import QUADRUPED
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.terrain import RISE, foot_offsets, turned
from robotool.task.scene import SceneObject
from robotool.task.task_model import Task

# the macros' tunables, documented in QuadrupedConfig
LEVEL = QUADRUPED.same_surface
APPROACH = QUADRUPED.climb_approach
INSET = QUADRUPED.edge_inset
OVERLAP = QUADRUPED.bridge_overlap
CLEARANCES = QUADRUPED.prop_clearances
MIN_CLEARANCE = QUADRUPED.prop_min_clearance
ROOM_MARGIN = QUADRUPED.prop_room_margin
DRAG_CLEARANCE = QUADRUPED.prop_drag_clearance
SIDE = QUADRUPED.board_side
TIP_PAST = QUADRUPED.tip_past
MAX_STEPS = QUADRUPED.max_steps
FLUSH_GAP = QUADRUPED.flush_gap
MOVED_AWAY = 0.02  # m: a placement nearer than this to where a link stands is where it stands
STEP_GAP = 0.01  # m a staircase link is placed short of the next (pushed flush, a perturbed overrun rams the next)
Placement = tuple[np.ndarray, np.ndarray | None]  # a staircase link's climb direction (to the next) and new centre


class RoutePush(NamedTuple):
    """A push a route makes: the object, its new x-y centre, why; and the movable object it is placed against, if
    any, with the axis along which it meets it: the push's target on that axis then follows where that object is
    measured to stand (a staircase link stops its gap short of the link it meets, however far a perturbed world's
    push left that one from its plan; across the climb it keeps its own line)."""

    name: str
    xy: np.ndarray
    why: str
    against: tuple[str, int] | None = None


@dataclass
class Route:
    """Pushes that rearrange the scene, then waypoints the robot walks through (each on a named surface)."""

    pushes: list[RoutePush] = field(default_factory=list)
    waypoints: list[tuple[np.ndarray, str]] = field(default_factory=list)  # x-y, surface ("ground" or object)
    uses: list[tuple[str, str]] = field(default_factory=list)  # object, role
    words: str = ""
    late: int = 0  # less likely choices it makes (a step down onto the target: the body rides on a higher step)
    slack: float = float("inf")  # m the feet keep, at the tightest stance, from the side edges of what they stand on

    def layout(self, base: Layout) -> Layout:
        """``base`` with the route's pushes made."""
        out = base
        for push in self.pushes:
            out = out.with_moved(push.name, push.xy)
        return out


class Quadruped:
    """The quadruped's view of one task: its limits, body, start and the objects' boxes."""

    def __init__(self, task: Task, heading: int = 0):
        self.task = task
        self.heading = heading  # degrees: the quarter turn its programs open with (0: none; then the body lies so)
        limits = task.limits
        assert isinstance(limits, QuadrupedLimits)
        self.limits = turned(limits, heading // 90)
        self.half = np.asarray(self.limits.body_size[:2]) / 2  # as the body lies after the turn
        self.start = np.asarray(task.robot.position, dtype=float)
        self.floor_name, self.floor = start_surface(task)
        self.layout = Layout(task)
        self.placed: frozenset[str] = frozenset()  # objects already pushed where the program needs them
        self.opening: Program | None = None  # what its programs open with, made before (a push out of the way)

    def program(self) -> Program:
        """A new program, opening with the robot's turn when it has one, or with a copy of its ``opening``."""
        if self.opening is not None:
            return copy.deepcopy(self.opening)
        prog = Program()
        if self.heading:
            prog.turn(self.heading, f"turn so that the body's length lies along {'xy'[self.heading // 90 % 2]}")
        return prog

    def quarter_turned(self) -> Quadruped:
        """The same robot where it stands, in the same scene, once it has turned in place a quarter (to heading 90
        from 0, back to 0 from 90)."""
        return Quadruped(self.task, heading=90 - self.heading).after(self.layout, self.start, self.placed)

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

    def moved_to(
        self, surface: str, level: float, here: np.ndarray, opening: Program, layout: Layout, placed: Iterable[str]
    ) -> Quadruped:
        """The same robot once ``opening`` has brought it to ``here`` on ``surface`` (the ground, or a top ``level``
        high) and rearranged the scene to ``layout``, the ``placed`` objects to stay: its programs open with it."""
        out = self.after(layout, here, placed)
        out.floor_name, out.floor, out.opening = surface, level, opening
        return out

    def extent(self, u: np.ndarray) -> float:
        """Half length of the body along direction ``u``."""
        return float(np.abs(u) @ self.half)

    def stands_clear(self, layout: Layout, xy: np.ndarray) -> bool:
        """Whether the body standing at ``xy`` on the robot's floor has nothing higher than the floor under its
        outline (and its side margin)."""
        return _highest_under(self, layout, xy) <= self.floor + RISE

    def room(self, box: Box) -> np.ndarray:
        """How far (x, y) the body's centre may stand off ``box``'s centre with the body on its top, ``INSET`` from
        its edges (0 where it does not fit)."""
        return np.maximum(box.half - self.half - INSET, 0.0)

    def top_point(self, box: Box, toward: np.ndarray, frm: np.ndarray) -> np.ndarray:
        """A point well on ``box``'s top for a robot arriving from ``frm``: its centre, or, for a long box,
        the point along the arrival direction that leaves room for the body."""
        room = self.room(box)
        along = np.clip(frm - box.center, -room, room)
        return np.where(np.abs(toward) > 0.5, box.center, box.center + along)


# --- routes onto a surface ----------------------------------------------------------------------------

DIRECTIONS = tuple(np.array(v, dtype=float) for v in ((1, 0), (-1, 0), (0, 1), (0, -1)))
FOOT = QUADRUPED.foot_radius  # m the feet sit inside the body's outline: they must be over what it stands on
ENTRIES = QUADRUPED.entries
LANDING_STEP = QUADRUPED.landing_step
STANCE_SLACK = QUADRUPED.stance_slack
LANE_TOLERANCE = 0.02  # m: lanes closer than this are one
LINE_UP_REACH = 2.0  # m a line-up point is moved back, at most, to stand on the floor
LINE_UP_STEP = 0.05  # m between the line-up points tried
MIN_APPROACH = 0.01  # m before a step the robot lines up, at least, where something stands behind
APPROACH_STEP = 0.01  # m between the line-up distances tried


def routes_onto(quad: Quadruped, name: str, tools: bool) -> Iterator[Route]:
    """Ways onto ``name``'s top: walk there, bridge a gap with a pushed board, or climb pushed steps; each stops
    short of what stands on the top (:func:`_landing`)."""
    found = itertools.chain(_direct(quad, name), *((_bridges(quad, name), _staircases(quad, name)) if tools else ()))
    for route in found:
        yield _landing(quad, name, route)


def _landing(quad: Quadruped, name: str, route: Route) -> Route:
    """``route`` with its stop on ``name`` pulled back along the way it arrives, when the walk to the stop is predicted
    to run into something standing on the top (an object lying ahead of the steps): to the farthest point with every
    foot on the top (over ``name`` itself: a surface as high beside it, such as the platform the walk starts on, is
    not its top), the body's outline (and its side margin) clear of what stands there, and the walk there
    predicted fine; unchanged when the walk is fine, or when no point is."""
    last, surface = route.waypoints[-1]
    if surface != name:
        return route
    previous = route.waypoints[-2][0] if len(route.waypoints) > 1 else quad.start
    if walk_violation(route.layout(quad.layout), previous, [last], quad.limits) is None:
        return route
    return pulled_back(quad, name, route) or route


def pulled_back(quad: Quadruped, name: str, route: Route) -> Route | None:
    """``route`` with its last stop, on ``name``, moved back along the way it arrives to the farthest point with every
    foot on the top (over ``name`` itself), the body's outline (and its side margin) clear of what stands there and
    the walk there predicted fine; None when no point is."""
    last, _ = route.waypoints[-1]
    previous = route.waypoints[-2][0] if len(route.waypoints) > 1 else quad.start
    layout = route.layout(quad.layout)
    top, length = layout.box(name).top, float(np.linalg.norm(last - previous))
    for s in np.arange(length - LANDING_STEP, 0.0, -LANDING_STEP):
        stop = previous + (last - previous) * s / length
        feet = stop + foot_offsets(quad.limits)
        if (
            np.all(np.abs(layout.heights(feet) - top) <= LEVEL / 2)
            and not np.isnan(layout.top_of(name, feet)).any()  # over the top itself, not one as high beside it
            and _highest_under(quad, layout, stop) <= top + RISE
            and walk_violation(layout, previous, [stop], quad.limits) is None
        ):
            return replace(route, waypoints=[*route.waypoints[:-1], (stop, name)])
    return None


def _direct(quad: Quadruped, name: str) -> Iterator[Route]:
    """Walk onto ``name``: straight when that is predicted fine, else lined up along an axis with one of its
    sides (reached around what stands in the way), in the first lane predicted fine from each side
    (:func:`_entries`), the shortest predicted-fine approaches first."""
    box = quad.layout.box(name)
    words = f"Walk onto {name}."
    straight = Route(waypoints=[(box.center, name)], words=words)
    if walk_violation(quad.layout, quad.start, [box.center], quad.limits) is None:
        yield straight
        return
    found = []
    for d in DIRECTIONS:
        for approach, inside in _entries(quad, box, d, quad.start):
            route = Route(
                waypoints=[(approach, quad.floor_name), (inside, name)], words=f"Line up beside {name}; " + words
            )
            route = _landing(quad, name, route)  # short of what stands on the top
            path = [*detour(quad.layout, quad.start, approach, quad.limits)[:-1], approach, route.waypoints[-1][0]]
            if walk_violation(quad.layout, quad.start, path, quad.limits) is None:
                found.append((_length(quad.start, path), route))
                break  # the first lane predicted fine from this side
    found.sort(key=lambda f: f[0])
    yield from (route for _, route in found[:ENTRIES])
    if not found:
        yield straight


def _length(start: np.ndarray, path: list[np.ndarray]) -> float:
    points = [start, *path]
    return sum(float(np.linalg.norm(b - a)) for a, b in itertools.pairwise(points))


def _entries(quad: Quadruped, box: Box, d: np.ndarray, frm: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Where to line up (outside ``box``, facing ``d``, on the robot's floor) and where to stop on its top, one pair
    for each lane across ``d`` worth trying: the one toward ``frm`` and, for each object standing before the face it
    climbs (a step up to it, which the feet must stay on), the lanes along its middle and along each side; none when
    the box is too narrow across ``d`` for the feet."""
    axis = int(np.argmax(np.abs(d)))
    lat = 1 - axis
    if box.half[lat] < quad.half[lat] - FOOT:
        return []
    inside = quad.top_point(box, d, frm)
    room = quad.room(box)[lat]
    face = box.center[axis] - d[axis] * box.half[axis]
    reach = 2 * quad.half[axis] + APPROACH  # objects this near before the face lie in the climb's lane
    lanes = [inside[lat]]
    for other in quad.layout.boxes([box.name]):
        before = (face - other.center[axis]) * d[axis]  # how far before the face its centre lies
        if -CONTACT <= before - other.half[axis] < reach and abs(other.center[lat] - box.center[lat]) < box.half[lat]:
            spare = quad.room(other)[lat]  # the feet stay on it across this
            for lane in other.center[lat] + np.array([0.0, -spare, spare]):
                lanes.append(box.center[lat] + float(np.clip(lane - box.center[lat], -room, room)))
    out: list[tuple[np.ndarray, np.ndarray]] = []
    for lane in lanes:
        if any(abs(lane - stop[lat]) < LANE_TOLERANCE for _, stop in out):
            continue
        stop = inside.copy()
        stop[lat] = lane
        approach = stop.copy()
        approach[axis] = face - d[axis] * (quad.half[axis] + APPROACH)
        out.append((_on_floor(quad, approach, -d), stop))
    return out


def _line_up(quad: Quadruped, layout: Layout, xy: np.ndarray, face: float, d: np.ndarray) -> np.ndarray:
    """Where the robot lines up in ``xy``'s lane to climb the first step of a staircase, whose face is at ``face``,
    along ``d``: :data:`APPROACH` before it, or nearer, down to :data:`MIN_APPROACH`, where something stands behind
    that spot and the nearer one is clear of it (a heavy object left just before the step)."""
    axis = int(np.argmax(np.abs(d)))
    out = np.array(xy, dtype=float)
    for gap in np.arange(APPROACH, MIN_APPROACH - 1e-9, -APPROACH_STEP):
        out[axis] = face - d[axis] * (quad.half[axis] + gap)
        if _highest_under(quad, layout, out) <= quad.floor + RISE:
            return out
    out[axis] = face - d[axis] * (quad.half[axis] + APPROACH)
    return out


def _on_floor(quad: Quadruped, xy: np.ndarray, away: np.ndarray) -> np.ndarray:
    """``xy``, or the first point from it along ``away`` where the body stands clear on the robot's floor (steps
    before a face are climbed from there, not lined up on); ``xy`` when none is within :data:`LINE_UP_REACH`."""
    for back in np.arange(0.0, LINE_UP_REACH, LINE_UP_STEP):
        point = xy + away * back
        if _highest_under(quad, quad.layout, point) <= quad.floor + RISE:
            return point
    return xy


def _highest_under(quad: Quadruped, layout: Layout, xy: np.ndarray) -> float:
    """The highest surface of ``layout`` under the body's outline (and its side margin) standing at ``xy``."""
    return float(layout.heights(sweep_points(xy, xy, quad.half)).max())


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
                    pushes=[RoutePush(obj.name, xy, f"across the {far - near:.2f} m gap")],
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
    do not already stand against the next; those that do are also pushed along it when every staircase left as it
    stands keeps the feet under :data:`STANCE_SLACK` from an edge."""
    target = quad.task.object(name)
    rise = quad.limits.max_step_up + 0.005
    top = {o.name: o.top for o in quad.task.objects}
    highest = top[name] + quad.limits.max_step_up
    steps = [
        o
        for o in quad.task.objects
        if o.name != name and o.shape != "cloth" and quad.floor + 0.02 < top[o.name] < highest
    ]
    for count in range(1, MAX_STEPS + 1):
        for chain in itertools.permutations(steps, count):
            tops = [quad.floor, *(top[o.name] for o in chain), top[name]]
            if any(
                b - a > rise or a - b > quad.limits.max_step_down or (abs(b - a) < 0.02 and k < count)
                for k, (a, b) in enumerate(itertools.pairwise(tops))
            ):  # the last link may be level with the target
                continue
            routes = list(_place_chain(quad, [*chain, target], move_standing=False))
            if max((r.slack for r in routes), default=-np.inf) < STANCE_SLACK:  # only thin stances as they stand
                routes += _place_chain(quad, [*chain, target], move_standing=True)
            for route in routes:
                route.late = int(tops[-1] < tops[-2])
                yield route


def _place_chain(quad: Quadruped, chain: list[SceneObject], move_standing: bool) -> list[Route]:
    """Placements of the chain's movable links against the next one's sides (centred or flush with either end),
    each placed against where the next link will stand, nearest the target first; placements that would overlap
    something, or whose steps cannot carry the feet, are left out. A link that already stands against the next is
    left there, or with ``move_standing`` pushed elsewhere along it (where the one before it finds room to continue
    the climb straight on: only such placements then). A link placed against a link that is itself pushed into place
    continues that link's climb in a straight line."""

    def place(k: int, layout: Layout, combo: list[Placement], moved: bool) -> Iterator[list[Placement]]:
        if k < 0:
            if moved or not move_standing:
                yield combo
            return
        obj, nxt = chain[k], chain[k + 1]
        box, nxt_box = layout.box(obj.name), layout.box(nxt.name)
        standing = box.touches(nxt_box)
        if standing:
            yield from place(k - 1, layout, [(_axis_direction(nxt_box.center - box.center), None), *combo], moved)
        if not quad.pushable(obj, quad.floor) or (standing and not move_standing):
            return
        straight = [combo[0][0]] if combo and combo[0][1] is not None else list(DIRECTIONS)
        for direction, xy in _sides(quad, layout, obj, nxt, straight):
            if standing and float(np.abs(xy - box.center).max()) < MOVED_AWAY:
                continue  # where it stands already
            if layout.collides(box.moved_to(xy)) is None:
                yield from place(k - 1, layout.with_moved(obj.name, xy), [(direction, xy), *combo], moved or standing)

    combos = place(len(chain) - 2, quad.layout, [], False)
    routes = [r for combo in combos if (r := _chain_route(quad, chain, combo))]
    return sorted(routes, key=lambda r: _pushed_distance(quad.layout, r))


def _pushed_distance(layout: Layout, route: Route) -> float:
    """How far a route's pushes move objects in all."""
    total = 0.0
    for push in route.pushes:
        total += float(np.linalg.norm(push.xy - layout.box(push.name).center))
        layout = layout.with_moved(push.name, push.xy)
    return total


def _sides(
    quad: Quadruped, layout: Layout, obj: SceneObject, nxt: SceneObject, directions: list[np.ndarray]
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Centres for ``obj`` against ``nxt``'s side facing each of ``directions`` (the climb's direction; :data:`STEP_GAP`
    short of it): centred, flush with either end, or flush with something else standing by the same face, as long as
    the feet can stand across both; none nearer than :data:`FLUSH_GAP` beside a movable object."""
    box, nxt_box = layout.box(obj.name), layout.box(nxt.name)
    beside = [o for o in quad.task.objects if o.shape != "cloth" and o.name not in (obj.name, nxt.name)]
    others = [(layout.box(o.name), FLUSH_GAP if o.movable else 0.005) for o in beside]  # 5 mm from a fixed one
    for direction in directions:
        axis = int(np.argmax(np.abs(direction)))
        lat = 1 - axis
        slide = max(0.0, float(nxt_box.half[lat] - box.half[lat]))
        along = nxt_box.center[axis] - direction[axis] * (nxt_box.half[axis] + box.half[axis] + STEP_GAP)
        offsets = [0.0, slide, -slide]
        for other, gap in others:  # flush against something else that stands by the same face
            if other.lo[axis] < along + box.half[axis] and other.hi[axis] > along - box.half[axis]:
                offsets += [
                    float(other.hi[lat] + box.half[lat] + gap - nxt_box.center[lat]),
                    float(other.lo[lat] - box.half[lat] - gap - nxt_box.center[lat]),
                ]
        reach = float(nxt_box.half[lat] + box.half[lat]) - 2 * (quad.half[lat] - FOOT)
        for offset in dict.fromkeys(round(o, 4) for o in offsets if abs(o) <= reach):
            xy = nxt_box.center.copy()
            xy[axis] = along
            xy[lat] += offset
            if all(box.moved_to(xy).overlap(o) <= 1e-3 - gap for o, gap in others if gap == FLUSH_GAP):
                yield direction, xy


def _chain_route(quad: Quadruped, chain: list[SceneObject], combo: list[Placement]) -> Route | None:
    route = Route()
    layout = quad.layout
    for k in range(len(combo) - 1, -1, -1):  # placements nearest the target first
        d, xy = combo[k]
        obj = chain[k]
        if xy is not None:
            box = layout.box(obj.name)
            lined = _lined_up(box.center, xy, d)
            if lined is not None and layout.collides(box.moved_to(lined), ignore=[obj.name]) is None:  # a free spot
                route.pushes.append(RoutePush(obj.name, lined, f"in line with {chain[k + 1].name}'s side"))
            layout = layout.with_moved(obj.name, xy)
            against = (chain[k + 1].name, int(np.argmax(np.abs(d)))) if chain[k + 1].movable else None
            route.pushes.append(RoutePush(obj.name, xy, f"against {chain[k + 1].name}'s side", against))
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
        lo, hi = _clear_of_neighbours(quad, layout, chain, k, lat, lo, hi, d if k == 0 else None)
        keep = min(STANCE_SLACK, (hi - lo) / 2)  # as far from both edges as the steps allow, up to STANCE_SLACK
        lines.append(float(np.clip(here[lat], lo + keep, hi - keep)))
        route.slack = min(route.slack, lines[-1] - lo, hi - lines[-1])
    d0, lat0 = combo[0][0], 1 - int(np.argmax(np.abs(combo[0][0])))
    axis0 = 1 - lat0
    approach = np.zeros(2)
    approach[lat0] = lines[0]
    approach = _line_up(quad, layout, approach, boxes[0].center[axis0] - d0[axis0] * boxes[0].half[axis0], d0)
    route.waypoints.append((approach, quad.floor_name))
    previous = approach
    for k in range(len(chain)):
        d = combo[min(k, len(combo) - 1)][0]
        axis = int(np.argmax(np.abs(d)))
        stance = np.zeros(2)
        stance[axis] = boxes[k].center[axis]
        stance[1 - axis] = lines[min(k, len(lines) - 1)]
        if k < len(chain) - 1 and _walked_over(quad, boxes[k], combo[max(k - 1, 0)][0], d, previous, stance):
            route.uses.append((chain[k].name, f"tool: a step up to {chain[k + 1].name}"))
            continue
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
        + (" by pushing " + ", ".join(p.name for p in route.pushes) + " into place" if route.pushes else "")
        + f", then climb it onto {chain[-1].name}."
    )
    return route


def _walked_over(
    quad: Quadruped, link: Box, came: np.ndarray, goes: np.ndarray, here: np.ndarray, stance: np.ndarray
) -> bool:
    """Whether the robot climbs on over ``link`` without stopping on it: the climb onto it (along ``came``) and the
    next (along ``goes``) run straight on in one lane, and the link is shorter along them than the body, whose feet
    would stand on its edges if it stopped there (a perturbed pose then leaves a pair of them over the edge)."""
    axis = int(np.argmax(np.abs(goes)))
    straight = bool(np.allclose(came, goes)) and abs(here[1 - axis] - stance[1 - axis]) < LANE_TOLERANCE
    return straight and link.half[axis] < quad.half[axis] + FOOT


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
    quad: Quadruped,
    layout: Layout,
    chain: list[SceneObject],
    k: int,
    lat: int,
    lo: float,
    hi: float,
    lined_up: np.ndarray | None = None,
) -> tuple[float, float]:
    """Narrow the climb line's range ``lo``-``hi`` (across the climb from link ``k`` onto link ``k + 1``) so that the
    body's flanks keep clear of other objects standing beside the two steps, and, with ``lined_up`` (the first climb's
    direction), of those standing where the robot lines up before the first step; unchanged when no line is clear."""
    axis = 1 - lat
    a, b = layout.box(chain[k].name), layout.box(chain[k + 1].name)
    span = (min(a.lo[axis], b.lo[axis]) - quad.half[axis], max(a.hi[axis], b.hi[axis]) + quad.half[axis])
    if lined_up is not None:  # the whole body stands APPROACH before the first step's face as it lines up
        reach = float(quad.half[axis]) + APPROACH
        span = (span[0] - reach, span[1]) if lined_up[axis] > 0 else (span[0], span[1] + reach)
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
