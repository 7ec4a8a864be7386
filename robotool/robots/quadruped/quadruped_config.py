"""The quadruped's tunables, named and documented in one place (SI units: m, s, rad, kg).

One frozen :class:`QuadrupedConfig` holds every tunable of the skill controller's components (plans, move runner,
terrain following, referee, rays), of the push geometry (:mod:`.push`) and of the planner's macros
(:mod:`.quadruped_routes`, :mod:`.quadruped_macros`); :data:`QUADRUPED` is the robot's instance, passed to each
controller component and read by the macros and by the task families that size scenes to the robot. The legs'
limits come from the task (:class:`~robotool.robots.quadruped.quadruped_skills.QuadrupedLimits`); the body's
physics (masses, servo gains) from :mod:`robotool.robots.quadruped.body`; the foot's size and the terrain sampling
shared with the planner from :mod:`robotool.robots.quadruped.terrain`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robotool.robots.quadruped.body import GRAVITY
from robotool.robots.quadruped.terrain import FOOT_RADIUS, LOOKAHEAD, RISE, SPACING


@dataclass(frozen=True)
class QuadrupedConfig:
    """The quadruped's tunables (one instance per robot: :data:`QUADRUPED`)."""

    walk_speed: float = 0.4
    """m/s the x-y setpoint moves at."""
    scan_ahead: float = 1.2
    """m of a move read at a time (plus ``terrain.LOOKAHEAD``)."""
    back: float = 0.06
    """m read behind each foot (the lift's window over an edge just passed)."""
    lift_ahead: float = 0.10
    """m ahead of a foot's centre where a higher surface starts the lift."""
    hold_behind: float = 0.03
    """m past a drop edge over which the lift holds the foot up before letting it down."""
    clearance: float = 0.025
    """m the lift carries a foot above the surface it steps onto."""
    descent_speed: float = 0.15
    """m/s at which the lift lets the body down past a drop."""
    release: float = 0.02
    """m: a lift setpoint this far below the body is off."""
    press: float = 0.01
    """m a leg's setpoint reaches below the surface under its foot."""
    leg_speed: float = 0.25
    """m/s at which a leg changes length."""
    torso_clearance: float = 0.02
    """m the legs keep the torso above what lies under it."""
    max_hover: float = 0.2
    """m of travel a foot may take to cross an edge (a step, or a stride over a gap, takes less)."""
    torso_grid: tuple[tuple[float, float], ...] = tuple((x, y) for x in (-0.9, 0.0, 0.9) for y in (-0.8, 0.0, 0.8))
    """Points under the torso where rays read what lies under it, in half sizes of the body (x, y)."""
    tilt_gain: float = 2.0
    """1/rad: tilt motor control per rad of pitch or roll while the lift carries the body."""
    tilt_damping: float = 0.15
    """s/rad: tilt motor control per rad/s of pitch or roll, likewise."""
    stop_margin: float = 0.03
    """m between a foot and a refused step's face."""
    edge_margin: float = 0.01
    """m between a foot's centre and a refused gap's or drop's edge."""
    arrived: float = 0.015
    """m from a move's stopping point that counts as there."""
    settled_speed: float = 0.03
    """m/s: a move ends only once the body is this still."""
    settled_turn: float = 0.2
    """rad/s of pitch and roll, likewise."""
    turn_speed: float = 1.0
    """rad/s the heading setpoint of a turn moves at."""
    turn_arrived: float = 0.01
    """rad from a turn's heading that counts as there."""
    leash: float = 0.06
    """m the setpoint may run ahead of the body."""
    stall_time: float = 3.0
    """s without 1 cm of progress is a stall."""
    staging: float = 0.15
    """m behind the push pose from where the robot lines up straight along the push."""
    push_tolerance: float = 0.06
    """m: a push is done when the object's centre is this close to the target."""
    follow_throughs: int = 2
    """Pushes on along a leg whose object's centre fell short of the leg's target."""
    corrections: int = 2
    """Pushes again from where the object ended when it turned or slid off the line and missed the target."""
    correction_gain: float = 0.02
    """m a push round must bring the object closer to the target for another round to follow."""
    shove: float = 0.03
    """m a movable object may move after the torso touched it, unless it is being pushed."""
    push_force_margin: float = 2.0
    """How many times the force that slides an object of the push limit (on the pushed object's support) a push may
    take (the contact forces are read at an instant: a push starts, knocks and turns what it pushes)."""
    push_strain_time: float = 0.5
    """s a push of an object may take more than that force, added up over the run, before it moves too much."""
    ray_height: float = 0.6
    """m above the feet where downward rays start (things higher are overhead)."""
    cloth_step: float = 1e-4
    """m above the point where a ray met a cloth from where it is cast again."""
    fall_tilt: float = float(np.radians(35.0))
    """rad: a body tilted further has fallen."""
    fall_ticks: int = 3
    """Control ticks with the centre of mass outside the feet's support (lift off) that make a fall..."""
    tipping: float = float(np.radians(5.0))
    """rad: ... once the body tilts this much (a level body with a foot off the ground is not falling)."""
    support_margin: float = -0.02
    """m: the support polygon grown by this much before the centre of mass counts as outside."""

    # the push geometry (:mod:`.push`), shared by the push skill and the planner's predictions
    push_gap: float = 0.03
    """m between the robot's face and the object's face when it lines up to push."""
    min_overlap: float = 0.08
    """m of the object's face the robot's face must cover."""
    offset_step: float = 0.02
    """m between candidate lateral offsets of a push pose."""
    same_surface: float = 0.04
    """m: supports closer in height than this are the same surface (the push rules, the macros' routes)."""
    min_leg: float = 0.02
    """m: shorter pushes along an axis are skipped."""
    side_margin: float = 0.01
    """m beyond the body's outline that must be clear of anything higher than its floor."""
    face_turn: float = float(np.radians(2.5))
    """rad the body turns its face toward the centre line of a pushed object that something lies on, as it pushes
    lined up off that line (more than ``face_turn_from`` of the object's half width), where the turned feet stay over
    the floor. The weight on part of the top drags on that part and turns the object; the turned face meets it first
    at its inner end, nearest the centre line, and not at the outer end, where the object would turn further away and
    slide off the face. (A flat face pushes a free object straighter: a turned one drifts it a little sideways.)"""
    face_turn_from: float = 0.25
    """the share of the pushed object's half width (across the push) beyond which the body's face is turned."""
    detour_slack: float = 0.05
    """m a way around something keeps between the body and the movable objects it passes, where it can: an object's
    perturbed pose and a walk's drift use up a bare margin."""
    detour_tight_cost: float = 1.0
    """m of walking that a stretch of a way around something counts for beyond its length when it passes a movable
    object closer than ``detour_slack``: a way with room is taken unless it is this much longer."""
    exit_margin: float = 0.005
    """m beyond the side of a box that a route starting inside it steps out to."""

    # the planner's macros (:mod:`.quadruped_routes`, :mod:`.quadruped_macros`)
    climb_approach: float = 0.1
    """m between the robot and a step when it lines up to climb it."""
    edge_inset: float = 0.06
    """m the robot keeps from the far edge of what it walks onto."""
    bridge_overlap: float = 0.15
    """m a bridge rests on each side of a gap."""
    flush_gap: float = 0.03
    """m a staircase link pushed flush beside a movable object standing by the same face keeps from its side (5 mm
    beside a fixed one): the push slides along that side, and a few centimetres of a perturbed world's drift rammed a
    3.5 kg box into the push, over the push limit together (3 fresh worlds in 9)."""
    prop_clearances: tuple[float, ...] = (1.2, 0.8, 0.5, 0.2)
    """m a prop pushed out from under a board keeps from the board's side, tried in this order: far enough to be left
    behind by the board's end when friction drags it sideways part of the way, even where the prop, pushed off its
    centre (the body keeps clear of the board), turns and slides part way off the robot's face; then nearer; else
    just clear."""
    prop_min_clearance: float = 0.05
    """m: where each of ``prop_clearances`` would push a prop into something on its way there, it is pushed only as far
    as the floor leaves room (with ``prop_room_margin`` to spare), keeping at least this much from the board's side."""
    prop_room_margin: float = 0.05
    """m a prop pushed as far as the room allows stops short of what stands beyond it."""
    prop_drag_clearance: float = 0.5
    """m beyond the board's side below which a prop's push is a less likely choice, tried after the pushes that go
    further (the other side's, and the robot's after a quarter turn, included), and thin: the board's end, resting on
    the prop, is dragged sideways with it part of the way. A push 0.2 m out dragged a lever's board 19 cm off its
    roller, or rammed the toolbox 2 mm beyond, in 6 to 8 worlds of 24, where one 1.2 m out, on the other side, held in
    all of them. A push that ends within ``prop_room_margin`` of what stands beyond is thin too."""
    board_side: float = 0.25
    """m the robot keeps from a board it walks beside."""
    tip_past: float = 0.015
    """m past an edge that an object pushed off it has its centre: it tips over the edge and falls while the robot
    stops behind it (pushed wholly past the edge, it fell with the robot still walking on behind it, and its rising
    edge met a front foot; 3 cm past, a vase lying on a sofa as low as it is thick fell to lie level with the seat,
    and a front foot stood on it in 1 fresh world in 9 of vase_lowering 1007 and 2 in 12 of 27006; 1.5 cm held in all
    of them and in every fresh world of seeds 1000-1019)."""
    max_steps: int = 3
    """Objects a staircase may use below the target."""
    entries: int = 2
    """Predicted-fine approaches kept for a direct climb."""
    landing_step: float = 0.02
    """m between the stops tried when a route's stop on its target is pulled back."""
    stance_slack: float = 0.05
    """m a staircase's climb line keeps the feet from the steps' side edges, where the steps allow it."""

    @property
    def walk_grip(self) -> float:
        """The friction the feet need under them to walk, climb or turn on level ground: the body's horizontal
        acceleration over g (on a slope add its tangent: :func:`.terrain.first_slip`). The feet are frictionless in the
        simulation and the x-y servos are anchored to the world, so nothing but this rule stops a walk on ice.

        A walk's x-y setpoint leaves at ``walk_speed`` from rest and runs at most ``leash`` ahead of the body, so a body
        that follows it reaches walking speed (and stops from it) within the leash: it accelerates at least at
        ``walk_speed ** 2 / (2 * leash)`` = 0.4 ** 2 / 0.12 = 1.33 m/s2, 0.136 g. That is the gentlest start and stop
        the gait allows (the x-y servos, 20 kN/m with up to 120 N on 12 kg, drive up to 10 m/s2), hence the least grip
        its feet need: 0.136. A turn in place moves the feet at ``turn_speed`` times their 0.36 m from the centre,
        0.36 m/s, no faster than a walk: the walk's grip is the turn's too."""
        return self.walk_speed**2 / (2 * self.leash) / GRAVITY

    @property
    def foot_radius(self) -> float:
        """m: a foot's radius; the feet's centres sit this far inside the body's outline (``terrain.FOOT_RADIUS``,
        shared with the planner's terrain checks)."""
        return FOOT_RADIUS

    @property
    def rise(self) -> float:
        """m: heights closer than this are the same surface to the legs (``terrain.RISE``, shared with the planner)."""
        return RISE

    @property
    def local(self) -> np.ndarray:
        """m: the per-tick samples along a foot's path, from its centre (behind, under, ahead)."""
        return np.array([-FOOT_RADIUS, 0.0, FOOT_RADIUS, self.lift_ahead / 2, self.lift_ahead])

    @property
    def samples(self) -> int:
        """Samples in one reading of a foot's path (``back`` + ``scan_ahead`` + ``terrain.LOOKAHEAD``)."""
        return round((self.back + self.scan_ahead + LOOKAHEAD) / SPACING) + 1

    @property
    def behind(self) -> int:
        """The sample under a foot at scan time."""
        return round(self.back / SPACING)


QUADRUPED = QuadrupedConfig()
"""The quadruped's tunables."""
