"""Quadruped macros: walk or climb onto a surface (directly, over a pushed bridge, up pushed steps: the routes are
in :mod:`.quadruped_routes`), push an object to a placement (against another object's side, across a gap, out of the
way, beside an edge), stand on a lever's far end, push an object off an edge onto a soft landing; written into
programs by :mod:`.quadruped_writer`.

Each route is predicted with :func:`robotool.robots.quadruped.predict.walk_violation` on the planned layout; a
program whose walk is predicted to break a limit keeps that as its ``doubt`` and is tried late.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from robotool.planner.codegen import Point, Program
from robotool.planner.layout import Box, Layout
from robotool.planner.search import precedence, tight
from robotool.robots.quadruped.predict import (
    detour,
    push_staging,
    turn_violation,
    walk_violation,
)
from robotool.robots.quadruped.quadruped_routes import (
    CLEARANCES,
    DIRECTIONS,
    DRAG_CLEARANCE,
    INSET,
    MIN_CLEARANCE,
    ROOM_MARGIN,
    SIDE,
    TIP_PAST,
    Quadruped,
    Route,
    pulled_back,
    routes_onto,
)
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.quadruped_writer import Writer, turn_spots
from robotool.robots.quadruped.terrain import RISE
from robotool.task.concepts import surface_under
from robotool.task.scene import SceneObject
from robotool.task.task_model import Task

STEP_ON_NEAR = 0.01  # m the feet step onto a lever at least this far short of its fulcrum's centre line
FULCRUM_CLEARANCE = 0.02  # m the feet keep from a lever's fulcrum as they step on, where the load leaves room
LOAD_CLEARANCE = 0.03  # m the body's rear keeps from the load on the lever's other end as the feet step on
LEVER_STRIDE = 0.1  # m between stops walking out a lever past its fulcrum: it tips under planted feet, not mid-stride


# --- goals ----------------------------------------------------------------------------------------------


def candidates(task: Task, tools: bool) -> Iterator[Program]:
    """Every program the macros make for the task (unordered; the search orders them). When the programs the robot
    can make facing as it starts that the search would try first (:func:`_leading`) leave a thin margin
    (:func:`.search.tight`), or every one is predicted to fail, the programs it can make after a quarter turn in place
    (its x and y sizes swapped) are made too; when every one is predicted to fail, those it can make after pushing
    an object out of the way first (:func:`_cleared`), or, with none of those, after stepping down off the top it
    starts on (:func:`_stepped_down`) or going onto another top first (:func:`_via_another_top`)."""
    quads = [Quadruped(task)]
    made = list(_programs(quads[0], tools))
    yield from made
    limits = task.limits
    assert isinstance(limits, QuadrupedLimits)
    if all(tight(p) for p in _leading(made)) and limits.body_size[0] != limits.body_size[1]:
        quad = Quadruped(task, heading=90)
        if turn_violation(quad.layout, quad.start, limits, quad.heading) is None:
            quads.append(quad)
            turned = list(_programs(quad, tools))
            yield from turned
            made += turned
    if tools and all(p.doubt is not None for p in made):
        cleared = [p for quad in quads for p in _cleared(quad, tools)]
        yield from cleared
        if not cleared:
            yield from _stepped_down(quads[0], tools)
            yield from _via_another_top(quads[0], tools)


def _leading(programs: list[Program]) -> list[Program]:
    """The programs not predicted to fail that the search tries first, before it weighs margins (their
    :func:`robotool.planner.search.precedence`). A program that needs a third box for its staircase comes after a
    tight one with two, so a tight two-box staircase walked flank first (its feet 5 mm inside the boxes' sides) is
    tried before the one the robot walks turned a quarter, unless that one is made too."""
    fine = [p for p in programs if p.doubt is None]
    first = min(map(precedence, fine), default=None)
    return [p for p in fine if precedence(p) == first]


def _cleared(quad: Quadruped, tools: bool) -> Iterator[Program]:
    """For a task whose every program is predicted to break a limit (a cushion standing where the climb lines up):
    the programs made after first pushing one object on the robot's floor out of the way, those not predicted to
    break one. Each object the robot may push there (not the goal's) goes, along an axis, to where its footprint is
    clear of where it stood by the body's length, the first such spot free and its push predicted fine."""
    goal = quad.task.goal.object
    for obj in quad.task.objects:
        if obj.name == goal or not quad.pushable(obj, quad.floor):
            continue
        box = quad.layout.box(obj.name)
        for d in DIRECTIONS:
            spot = box.center + d * (2 * float(np.abs(d) @ box.half) + 2 * float(quad.half.max()))
            if quad.layout.collides(box.moved_to(spot)) is not None:
                continue
            opening = quad.program()
            opening.use(obj.name, "obstacle: it stands in the way; push it aside first")
            w = Writer(quad, opening)
            w.push(obj.name, spot, "out of the way", turns=True)
            if opening.doubt is not None:
                continue
            opening.say(f"Push {obj.name} out of the way.")
            after = w.quad.after(w.layout, w.here, [obj.name])
            after.opening = opening
            fine = [p for p in _programs(after, tools) if p.doubt is None]
            yield from fine
            if fine:
                break


def _stepped_down(quad: Quadruped, tools: bool) -> Iterator[Program]:
    """For a robot that starts on an object's top (a sofa, a stage) from where every program is predicted to fail, or
    none is made (the macros plan a staircase, a push or a lever from the ground): the programs made after it first
    walks straight off one side of that top onto the ground, as low a drop as it may step down, to where its body stands
    clear of what is there, the walk predicted fine; those not predicted to fail, from the first side that leaves any
    (found by a held-out layout: a vase_lowering robot that started on the sofa beside the vase got no program)."""
    if quad.floor_name == "ground" or quad.floor > quad.limits.max_step_down:
        return
    top = quad.layout.box(quad.floor_name)
    for d in DIRECTIONS:
        axis = int(np.argmax(np.abs(d)))
        spot = quad.start.copy()
        spot[axis] = top.center[axis] + d[axis] * (top.half[axis] + quad.extent(d) + SIDE)
        opening = quad.program()
        ground = quad.moved_to("ground", 0.0, spot, opening, quad.layout, ())
        if not ground.stands_clear(quad.layout, spot) or walk_violation(quad.layout, quad.start, [spot], quad.limits):
            continue
        Writer(quad, opening).walk(spot, "ground", f"step down off {quad.floor_name} onto the ground")
        opening.say(f"Step down off {quad.floor_name}.")
        fine = [p for p in _programs(ground, tools) if p.doubt is None]
        yield from fine
        if fine:
            return


def _via_another_top(quad: Quadruped, tools: bool) -> Iterator[Program]:
    """For a robot from where every program is predicted to fail: the programs made after it first goes onto another
    fixed object's top by a route predicted fine (from the floor, a step then the sofa a board lying there bridges
    from; from a sofa, the middle sofa of three over the first gap, the second bridged from there), to where its body
    stands clear of what lies on that top, those not predicted to fail; the tops nearest the goal's object first, from
    the first route that leaves any (found by held-out layouts: a robot on the floor before a sofa_traversing scene only
    tried to climb onto the far sofa; two gaps in a row were bridged one only)."""
    goal = quad.layout.box(quad.task.goal.object)
    tops = [
        o
        for o in quad.task.objects
        if not o.movable and o.shape != "cloth" and o.name not in (goal.name, quad.floor_name) and o.top > RISE
    ]
    tops.sort(key=lambda o: float(np.linalg.norm(quad.layout.box(o.name).center - goal.center)))
    for top in tops:
        for onto in routes_onto(quad, top.name, tools):
            layout, level = onto.layout(quad.layout), quad.layout.box(top.name).top
            arrived = quad.moved_to(top.name, level, onto.waypoints[-1][0], Program(), layout, ())  # where it lands
            # standing on what lies on that top, the robot could not push it: stop short of it
            route = onto if arrived.stands_clear(layout, arrived.start) else pulled_back(quad, top.name, onto)
            if route is None:
                continue
            opening = quad.program()
            w = Writer(quad, opening)
            w.route(route)
            if opening.doubt is not None:
                continue
            placed = [push.name for push in route.pushes]
            up = quad.moved_to(top.name, level, w.here, opening, w.layout, placed)
            fine = [p for p in _programs(up, tools) if p.doubt is None]
            yield from fine
            if fine:
                return


def _programs(quad: Quadruped, tools: bool) -> Iterator[Program]:
    """The programs of the macros for ``quad`` (see :func:`candidates`)."""
    task = quad.task
    goal = task.goal
    target = task.object(goal.object)
    if goal.kind == "robot_on":
        for route in routes_onto(quad, target.name, tools):
            prog = quad.program()
            prog.use(target.name, "target")
            Writer(quad, prog).route(route)
            yield prog
    elif goal.kind == "lifted":
        if tools:
            yield from _levers(quad, target)
    else:
        yield from _lowerings(quad, target, tools)


def _levers(quad: Quadruped, target: SceneObject) -> Iterator[Program]:
    """Lift ``target`` by standing on the far end of the board it rests on, after pushing away what props it. The
    robot pushes facing as ``quad`` is turned; it walks the lever lengthwise, so when its body lies across the board
    it first walks clear of the board's end and turns a quarter (or, where that turn is predicted blocked, walks it
    sideways, which is thin)."""
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
    across = quad.extent(a) < quad.extent(lat)  # the body lies across the board as it pushes
    sides = [(side, c) for side in (near, -near) for c in _prop_clearances(quad, props, bbox, -side * lat)]
    for side, clearance in sides:
        prog = quad.program()
        prog.use(target.name, "target")
        prog.use(board_name, f"tool: a lever over {fulcrums[0].name}, {target.name} on one end")
        prog.use(fulcrums[0].name, "tool: the fulcrum")
        w = Writer(quad, prog)
        beside = float(np.abs(lat) @ bbox.half) + quad.extent(lat) + SIDE
        for prop in props:
            p = quad.layout.box(prop.name)
            out = _prop_spot(p, bbox, -side * lat, clearance)
            prog.use(prop.name, f"obstacle: props up {board_name}'s far end; push it out of the way")
            along = (p.center - bbox.center) @ a + quad.extent(a)  # beside it, toward the end, clear of the board
            near_prop = bbox.center + lat * side * beside + a * along
            if w.quad.stands_clear(w.layout, near_prop):  # (else the push routes to where it lines up by itself)
                w.floor_walk(near_prop, f"walk beside {prop.name}")
            w.push(prop.name, out, "out from under the board")
            if prop.effective_mass > quad.limits.max_push_mass:  # refused in every world
                limit = quad.limits.max_push_mass
                w.doubt(f"{prop.name} weighs {prop.effective_mass:.3g} kg, over the {limit:g} kg push limit")
            thin = _thin_prop_push(quad.layout, p, bbox, -side * lat, clearance)
            if thin is not None:
                prog.thin.append(thin)
            prog.late += int(clearance < DRAG_CLEARANCE)  # for when the far spots, on either side, are taken
        if across:
            w = _turned_lengthwise(w, bbox, a, lat * side, board_name)
        walker = w.quad
        beside = float(np.abs(lat) @ bbox.half) + walker.extent(lat) + SIDE
        step_on = fulcrum.center - a * _step_on_distance(walker.extent(a), fulcrum, quad.layout.box(target.name), a)
        step_on = step_on - lat * ((step_on - bbox.center) @ lat)
        end = bbox.center + a * (float(np.abs(a) @ bbox.half) - walker.extent(a) - INSET)
        w.doubt(_outweighed(quad, board, fulcrum, target, a, end))
        into_lane = w.here + lat * (side * beside - (w.here - bbox.center) @ lat)
        lane_end = step_on + lat * side * beside
        # (after a turn the robot stands in that lane already; where something stands there, the walk to the lane's
        # end goes around it)
        if np.linalg.norm(into_lane - w.here) > 1e-6 and w.quad.stands_clear(w.layout, into_lane):
            w.floor_walk(into_lane, "walk beside the board")
        if np.linalg.norm(lane_end - w.here) > 1e-6:
            w.floor_walk(lane_end, "walk beside the board")
        # beside the fulcrum, which stays where it is, though the prop's push may have dragged the board along: the
        # climb runs straight on from the lane, clear of the fulcrum's end sticking out beside a dragged board
        w.walk(step_on, board_name, f"step onto {board_name} next to the fulcrum", fixed_axis=axis)
        w.stance(step_on, board_name)
        lift = f"walk to {board_name}'s far end so it tips and lifts {target.name}"
        for xy in _strides(step_on, fulcrum.center, end):
            w.walk(xy, board_name, f"{lift}: a stop, every foot down, where it may tip", along_from=target.name)
        w.walk(end, board_name, lift, along_from=target.name)
        w.stance(end, board_name)
        prog.say(
            (f"Push {', '.join(p.name for p in props)} out from under {board_name}. " if props else "")
            + f"Step onto {board_name} by {fulcrums[0].name} and walk to its far end: "
            + f"the lever lifts {target.name}."
        )
        yield prog


def _outweighed(
    quad: Quadruped, board: SceneObject, fulcrum: Box, load: SceneObject, a: np.ndarray, end: np.ndarray
) -> str | None:
    """Why the robot standing at ``end`` on ``board`` (its far end along ``a``) cannot tip the lever over ``fulcrum``
    and lift ``load`` on its other end, or None: the moments of the weights about the pivot, taken at the fulcrum's
    edge toward the load (the most the robot's weight can gain: a board lying on a box tips about its other edge), the
    board's own weight counted where its centre lies. A load too heavy for the robot's weight there is not lifted in
    any world (a cube of 28 kg on a 2.4 m board over a roller, against the 12 kg robot, held the board down in every
    world; the search tried every lever before it gave up)."""
    limits = quad.task.limits
    assert isinstance(limits, QuadrupedLimits)
    pivot = float(fulcrum.center @ a) - float(np.abs(a) @ fulcrum.half)
    board_centre = float(quad.layout.box(board.name).center @ a)
    tips = limits.mass * (float(end @ a) - pivot) + board.effective_mass * (board_centre - pivot)
    holds = load.effective_mass * (pivot - float(np.asarray(load.center[:2]) @ a))
    if tips > holds:
        return None
    return (
        f"the robot's {limits.mass:g} kg at {board.name}'s far end cannot outweigh {load.name}'s "
        f"{load.effective_mass:.3g} kg on its other end: the lever would not tip"
    )


def _strides(start: np.ndarray, fulcrum: np.ndarray, end: np.ndarray) -> list[np.ndarray]:
    """The stops on the walk from ``start`` to ``end`` along a lever: level with ``fulcrum``'s centre, where the lever
    may start to tip, and then evenly, at most :data:`LEVER_STRIDE` apart, up to ``end`` (not included)."""
    length = float(np.linalg.norm(end - start))
    if length < 1e-9:
        return []
    u = (end - start) / length
    first = min(max(float((fulcrum - start) @ u), 0.0), length)
    count = int(np.ceil((length - first) / LEVER_STRIDE - 1e-9))
    stops = first + np.arange(count) * ((length - first) / max(count, 1))
    return [start + u * d for d in stops if d > 1e-6]


def _step_on_distance(extent: float, fulcrum: Box, load: Box, a: np.ndarray) -> float:
    """How far before the fulcrum's centre (toward the ``load``, against ``a``) the body's centre stands as it steps
    onto the lever: where the load leaves room, with the feet (``extent``, the body's half length along the lever,
    reaches their outer edge) :data:`FULCRUM_CLEARANCE` clear of the fulcrum's footprint, else as far as the body's
    rear stays :data:`LOAD_CLEARANCE` short of the load; never nearer than :data:`STEP_ON_NEAR` short of the fulcrum's
    centre line. (Stepped on with the feet over the fulcrum's top, the robot fell walking out to the far end in some
    worlds where it held a few millimetres further back.)"""
    near = extent + STEP_ON_NEAR
    clear = extent + float(np.abs(a) @ fulcrum.half) + FULCRUM_CLEARANCE
    room = float((fulcrum.center - load.center) @ a) - float(np.abs(a) @ load.half) - extent - LOAD_CLEARANCE
    return max(near, min(clear, room))


def _prop_spot(prop: Box, board: Box, direction: np.ndarray, clearance: float) -> np.ndarray:
    """Where ``prop`` is pushed along ``direction`` (a unit axis across ``board``) out from under the board: its near
    side ``clearance`` beyond the board's side (counting its offset from the board's centre line as if against the
    push)."""
    offset = abs(float((prop.center - board.center) @ direction))
    away = float(np.abs(direction) @ (board.half + prop.half)) + clearance + offset
    return prop.center + direction * away


def _prop_clearances(quad: Quadruped, props: list[SceneObject], board: Box, direction: np.ndarray) -> list[float]:
    """How far beyond ``board``'s side the props are pushed along ``direction``: :data:`CLEARANCES`, and where each of
    them would push a prop into something on its way (:func:`_push_blocked`), the most the floor leaves room for (on a
    2.5 cm grid, keeping :data:`ROOM_MARGIN` from what stands beyond), down to :data:`MIN_CLEARANCE`."""
    clearances = list(CLEARANCES)
    for prop in props:
        p = quad.layout.box(prop.name)
        if all(_push_blocked(quad.layout, p, board, direction, c) for c in CLEARANCES):
            for c in np.arange(min(CLEARANCES), MIN_CLEARANCE - 1e-9, -0.025):
                if not _push_blocked(quad.layout, p, board, direction, float(c), ROOM_MARGIN):
                    clearances.append(round(float(c), 3))
                    break
    return clearances


def _thin_prop_push(layout: Layout, prop: Box, board: Box, direction: np.ndarray, clearance: float) -> str | None:
    """Why pushing ``prop`` out to ``clearance`` beyond ``board``'s side along ``direction`` may fail in some perturbed
    worlds (None: it leaves room): too near the board, which it may drag along (:data:`DRAG_CLEARANCE`), or ending
    within :data:`ROOM_MARGIN` of what stands beyond."""
    if clearance < DRAG_CLEARANCE:
        return f"{prop.name} is pushed out only {clearance:.2f} m beyond {board.name}'s side: it may drag the board"
    if _push_blocked(layout, prop, board, direction, clearance, ROOM_MARGIN):
        return f"{prop.name}, pushed out from under {board.name}, ends within {ROOM_MARGIN:.2f} m of something"
    return None


def _push_blocked(
    layout: Layout, prop: Box, board: Box, direction: np.ndarray, clearance: float, margin: float = 0.0
) -> bool:
    """Whether something other than ``board`` stands in the footprint that ``prop`` sweeps as it is pushed out to
    ``clearance`` beyond the board's side (:func:`_prop_spot`), not only where it ends (a far push may carry it past
    what it runs into on the way), or within ``margin`` of where it ends."""
    spot = prop.moved_to(_prop_spot(prop, board, direction, clearance))
    swept = Box(prop.name, np.minimum(prop.lo, spot.lo), np.maximum(prop.hi, spot.hi), prop.bottom, prop.top)
    room = Box(prop.name, spot.lo - margin, spot.hi + margin, prop.bottom, prop.top)
    return any(layout.collides(box, ignore=[board.name]) is not None for box in ((swept, room) if margin else (swept,)))


def _turned_lengthwise(w: Writer, bbox: Box, a: np.ndarray, out: np.ndarray, board: str) -> Writer:
    """Walk past the board's far end (``a`` points to it), into the lane beside it on its ``out`` side, and make a
    quarter turn there, so that the body lies along the board: a writer for the rest of the program, as the body
    then lies. Where that walk or turn is predicted blocked, no turn: the same writer, the program noted thin (the
    lever is walked sideways)."""
    quad, limits = w.quad, w.quad.task.limits
    assert isinstance(limits, QuadrupedLimits)
    sweep = float(np.linalg.norm(quad.half)) + SIDE  # how far the turn reaches, with the side margin
    lane = float(np.abs(out) @ bbox.half) + quad.extent(a) + SIDE  # beside the board once turned
    spot = bbox.center + out * lane + a * (float(np.abs(a) @ bbox.half) + sweep)
    problem = walk_violation(w.layout, w.here, detour(w.layout, w.here, spot, quad.limits), quad.limits)
    problem = problem or turn_violation(w.layout, spot, limits, 90)
    if problem is not None:
        w.prog.thin.append(f"the body lies across {board}: it would walk the lever sideways ({problem})")
        return w
    w.floor_walk(spot, f"walk clear of {board}'s end to turn")
    heading = 90 - quad.heading
    w.prog.turn(heading, f"turn so that the body's length lies along {board}")
    return Writer(Quadruped(quad.task, heading=heading).after(w.layout, spot, quad.placed), w.prog)


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
    cushions: list[SceneObject | None] = [None]
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
        dest[axis] = edge + direction[axis] * TIP_PAST
        for cushion in cushions:
            if cushion is None and target.fragile is not None and fall > target.fragile.max_drop:
                continue
            pushes: list[tuple[str, np.ndarray]] = []
            if cushion is not None:
                cbox = quad.layout.box(cushion.name)
                spot = dest.copy()
                spot[axis] = edge + direction[axis] * (cbox.half[axis] + 0.005)
                if quad.layout.collides(cbox.moved_to(spot), ignore=[target.name]) is not None:
                    continue
                pushes.append((cushion.name, spot))
            for walker, route in _ways_after_pushes(quad, pushes, support_name, tools):
                prog = quad.program()
                prog.use(target.name, "target")
                w = Writer(quad, prog)
                for name, spot in pushes:
                    prog.use(name, f"tool: a soft landing for {target.name}")
                    w.push(name, spot, f"beside {support_name}'s edge, under where {target.name} will fall", turns=True)
                if walker.heading != w.quad.heading:
                    if not np.allclose(walker.start, w.here):
                        w.walk(walker.start, w.surface, "walk off to where there is room to turn")
                    prog.turn(walker.heading, f"turn so that the body fits the way onto {support_name}")
                    w.quad = walker
                w.route(route)
                behind = push_staging(w.layout, target.name, dest, w.quad.limits, support.top)
                if behind is None:
                    behind = tbox.center - direction * (tbox.half[axis] + w.quad.extent(direction) + 0.05)
                    w.doubt(f"no clear place on {support_name} to push {target.name} from")
                for via in detour(w.layout, w.here, behind, w.quad.limits)[:-1]:
                    w.walk(via, support_name, f"walk around what stands on {support_name}")
                w.walk(behind, support_name, f"walk behind {target.name}")
                ref = w.position(target.name)
                prog.motion(
                    "push_to_position",
                    obj=target.name,
                    point=Point.at(ref, (*(dest - tbox.center), 0.0)),
                    intent=f"push {target.name} off {support_name}'s edge",
                    explanation=f"its centre {TIP_PAST:.2f} m past the edge: it tips off",
                )
                prog.say(
                    (f"Push {pushes[0][0]} beside {support_name}; " if pushes else "")
                    + f"push {target.name} off {support_name}"
                    + (f" onto {pushes[0][0]}." if pushes else ".")
                )
                yield prog


def _ways_after_pushes(
    quad: Quadruped, pushes: list[tuple[str, np.ndarray]], name: str, tools: bool
) -> Iterator[tuple[Quadruped, Route]]:
    """The routes onto ``name`` once ``pushes`` are made (:func:`_after_pushes`), each with the robot as it walks the
    route: as it lies after the pushes, and, where every such route is predicted to break a limit, turned a quarter
    in place where the pushes leave it (where that turn is predicted fine): a cushion pushed into place by the turned
    body, the steps climbed as the body started."""
    after = _after_pushes(quad, pushes)
    fine = False
    for route in routes_onto(after, name, tools):
        trial = Writer(after, Program())  # only its doubt is read
        trial.route(route)
        fine |= trial.prog.doubt is None
        yield after, route
    spot = None if fine else next(turn_spots(after.layout, after.start, after), None)
    if spot is not None:
        turned = after.quarter_turned().after(after.layout, spot, [])
        for route in routes_onto(turned, name, tools):
            yield turned, route


def _after_pushes(quad: Quadruped, pushes: list[tuple[str, np.ndarray]]) -> Quadruped:
    """``quad`` as the scene will be after ``pushes`` (object, x-y centre) are made, the robot where the last ends
    and lying as it then does: the way onto a surface is planned around what they moved (a cushion pushed beside a
    sofa stands in the way)."""
    if not pushes:
        return quad
    w = Writer(quad, Program())  # only its layout, end and body are read
    for name, spot in pushes:
        w.push(name, spot, "", turns=True)
    return w.quad.after(w.layout, w.here, [name for name, _ in pushes])
