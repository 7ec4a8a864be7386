"""The quadruped's referee: the judge rules that physics alone would let a program break, checked every tick in every
world, and the push rules checked when a push starts (and the push limit as each push leg starts).

Every tick, in every world, a robot whose centre of mass has stayed outside the support of its touching feet for
``fall_ticks`` ticks with the lift off and that tips, or that tilts past ``fall_tilt``, has fallen: its skill ends with
outcome ``fell`` and a reason that says where and which feet lost support, :attr:`RefereeState.failures` marks its world
failed, and later motion skills there are refused. A walk or a climb is no push: a movable object (a cloth too) that the
torso has touched, other than one being pushed, and that has moved more than ``shove`` since (what a foot's weight or a
push moved it by not counted), was shoved; so were the objects that a push rams ahead of the pushed one, or drags along
under it or stuck to it, or carries on it a while, once together they weigh more than the push limit, and so was what a
push moves that takes more force than pushing what the robot may push takes (:mod:`.push_force`: a chair pushed out from
under a heavily loaded lever; and what a walk or a climb ran into and moved, however little, while it bore up another
object, with more sliding than a push of it may take), and so was what the stride of a walk or a climb carried under the
feet, and what went along with it, once they weigh more than the push limit, ramming something or not
(:mod:`.stride_loads`: a 15 kg cart on free rollers, walked off, rolled off them onto the floor). The move is stopped
and refused, naming them, and the world fails. A foot or the belly that rests on a fragile object (a low glass vase
reads as a step) breaks it, and so does standing on a movable object that rests on it: the move is refused, naming it,
and the world fails. (The tunables are in :class:`~robotool.robots.quadruped.quadruped_config.QuadrupedConfig`.)
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from robotool.robots.quadruped.crushes import Crushes
from robotool.robots.quadruped.move_runner import MoveRunner
from robotool.robots.quadruped.push_force import PushForce
from robotool.robots.quadruped.push_rules import PushRules
from robotool.robots.quadruped.quadruped_config import QuadrupedConfig
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.rams import borne_along, pressed_along, pressed_by, side_swings, stuck_to, turns
from robotool.robots.quadruped.rays import Rays
from robotool.robots.quadruped.sensing import Senses
from robotool.robots.quadruped.stride_loads import StrideLoads
from robotool.robots.quadruped.support import (
    FOOTING_ANGLE,
    bears_up,
    centre_of_mass,
    feet,
    feet_touching,
    known_lengths,
    supported,
    tilt,
    unsupported_feet,
)
from robotool.rollout import Event
from robotool.sim.embodiment import SkillEnd
from robotool.sim.magnets import Magnets

FALL_CONDITION = "robot_has_not_fallen"  # the goal condition a fall breaks
SHOVE_CONDITION = "robot_shoved_nothing"  # the goal condition a shove breaks
STILL = 1e-5  # m an object may move in a tick and count as still: whether a foot stands on it matters not (a shove
# of 3 cm at this pace would take 150 s)
RIDE_TIME = 0.5  # s a push may carry more than the push limit before it counts (what tips against it leans a while)
REST_TIME = 0.5  # s an object must stay still (in 3-D) to have come to rest: a wedged box tipping free pauses a tick
CREEP = 1e-4  # m an object may creep in a tick (2 mm/s), no faster than its slowest since, and be done with a push that
# rammed it: the soft contacts let a heavy cube resting on a tilted board creep down it at 1.3 mm/s for good, and a
# chair push that dragged both a few millimetres weighed them when the robot's weight tipped the board, 20 s later (a
# planner's program, 1 world in 7); one speeding up from rest is not done (an adversarial run: a 15 kg drum tapped off
# a kerb by a pushed bar rolled away slowly at first)
WAKE = 5 * CREEP  # m in a tick (1 cm/s): what crept out of a ram and then speeds up past this on its own, untouched by
# the robot, however long it lay still, is that ram's again (adversarial runs: a 15 kg drum tapped off a kerb by a
# pushed bar sped up from rest more slowly than the creep rule could tell from soft creep, and rolled off unweighed;
# one stopped by a light chock rolled off once the chock was pushed away)
CRUSH_CONDITION = "robot_stood_on_nothing_fragile"  # the goal condition a foot or the belly on a fragile object breaks


@dataclass
class RefereeState:
    """Per world (index first): the rules broken so far and what the rules remember between ticks."""

    failures: list[str | None]  # why the robot can no longer be trusted (it fell), else None
    shoves: list[str | None]  # the first object the robot shoved, and how far
    crushes: list[str | None]  # the first fragile object the robot stood on
    untold: list[Event | None]  # a rule broken while no move ran (between calls, or once the program ended)
    outside: np.ndarray  # (nworld,) ticks the centre of mass has been outside the support
    lost_support: np.ndarray  # (nworld,) object: where and how it last left its support
    bumped: np.ndarray  # (nworld, nobject, 3) where each object's centre was when the torso first touched it (NaN:
    # untouched, or pushed since)
    pressed: np.ndarray  # (nworld, nobject) touched without a break, and without a walk, since a push of it (it may
    # slide on after the push ended)
    carried: np.ndarray  # (nworld, nobject) m each object travelled while a push of another rammed it, or after,
    # until it came to rest, from push to push until the robot pushes it itself
    rammed_by: np.ndarray  # (nworld, nobject) the object whose push rammed each object, until it comes to rest (-1)
    dormant_by: np.ndarray  # (nworld, nobject) the object whose push each object crept out of (:data:`WAKE`; -1)
    coasting: np.ndarray  # (nworld, nobject) bool: pushed, and not at rest since (it may roll on after the push)
    drift: np.ndarray  # (nworld, nobject) m each object travelled across under the feet of a walk or climb, since rest
    still: np.ndarray  # (nworld, nobject) s each object has stayed still (in 3-D) on end
    crept: np.ndarray  # (nworld, nobject) s each object has moved no more than :data:`CREEP` a tick (in 3-D) on end
    slowest: np.ndarray  # (nworld, nobject) m the least it moved in a tick meanwhile (inf: it moved faster last tick)
    overloaded: np.ndarray  # (nworld,) s: since when a push has carried more than the push limit (NaN: it has not)
    strained: np.ndarray  # (nworld, nobject) s the pushes of each object took more force than they may, over the run
    bump_force: np.ndarray  # (nworld, nobject) N the most a walk or a climb took to slide each object it ran into
    bump_travel: np.ndarray  # (nworld, nobject) m each object travelled across meanwhile (:mod:`.push_force`)
    force_limit: np.ndarray  # (nworld, 2) N the push leg under way may take: the push limit's, what the feet hold
    # (NaN: not read yet; :mod:`.push_force`)
    last_centres: np.ndarray  # (nworld, nobject, 3) where each object was at the last tick
    last_frames: np.ndarray  # (nworld, nobject, 4) each object's orientation at the last tick (a unit quaternion)
    ride_start: np.ndarray  # (nworld, nobject, 3) where each object was when the stride first carried something
    # under the feet since the object was last pushed (NaN: not yet; :mod:`.stride_loads`)
    ride_top: np.ndarray  # (nworld, nobject) m the highest each object has been since then (NaN: not yet)
    ride_frames: np.ndarray  # (nworld, nobject, 4) each object's orientation then (a unit quaternion)
    ride_touched: np.ndarray  # (nworld, nobject) bool: touched what the stride carried since then
    ride_carried: np.ndarray  # (nworld, nobject) bool: carried by the stride since then

    @classmethod
    def empty(cls, nworld: int, centres: np.ndarray, frames: np.ndarray) -> RefereeState:
        nobject = centres.shape[1]
        return cls(
            failures=[None] * nworld,
            shoves=[None] * nworld,
            crushes=[None] * nworld,
            untold=[None] * nworld,
            outside=np.zeros(nworld, dtype=int),
            lost_support=np.full(nworld, None, dtype=object),
            bumped=np.full((nworld, nobject, 3), np.nan),
            pressed=np.zeros((nworld, nobject), dtype=bool),
            carried=np.zeros((nworld, nobject)),
            rammed_by=np.full((nworld, nobject), -1),
            dormant_by=np.full((nworld, nobject), -1),
            coasting=np.zeros((nworld, nobject), dtype=bool),
            drift=np.zeros((nworld, nobject)),
            still=np.zeros((nworld, nobject)),
            crept=np.zeros((nworld, nobject)),
            slowest=np.full((nworld, nobject), np.inf),
            overloaded=np.full(nworld, np.nan),
            strained=np.zeros((nworld, nobject)),
            bump_force=np.zeros((nworld, nobject)),
            bump_travel=np.zeros((nworld, nobject)),
            force_limit=np.full((nworld, 2), np.nan),
            last_centres=centres,
            last_frames=frames,
            ride_start=np.full((nworld, nobject, 3), np.nan),
            ride_top=np.full((nworld, nobject), np.nan),
            ride_frames=frames.copy(),
            ride_touched=np.zeros((nworld, nobject), dtype=bool),
            ride_carried=np.zeros((nworld, nobject), dtype=bool),
        )

    def doze(
        self, settled: np.ndarray, here: np.ndarray, travel: np.ndarray, touched: np.ndarray, borne: np.ndarray
    ) -> None:
        """What a ram set moving (or a push left coasting) and that has just ``settled`` by the creep rule lies dormant
        until the robot touches it (``touched``: its own rules judge it then); what lies dormant and moves more than
        :data:`WAKE` in a tick, untouched and not ``borne`` along by a moving carrier (a lever's board tipping under
        the robot lifts the cube a chair push dragged), is that ram's again (or coasts again), however long it lay
        still: a drum a tap got past its kerb and that a light chock stopped dead rolls on, the ram's, once the chock
        is pushed away. In the worlds ``here`` (nworld, 1)."""
        touched = touched & here
        woke = here & (self.dormant_by >= 0) & (travel > WAKE) & ~touched & ~borne
        own = np.arange(self.dormant_by.shape[1])[None, :] == self.dormant_by
        self.coasting |= woke & own
        self.rammed_by = np.where(woke & ~own, self.dormant_by, self.rammed_by)
        self.dormant_by[woke | touched] = -1
        objects = np.arange(own.shape[1])[None, :]
        source = np.where(self.rammed_by >= 0, self.rammed_by, np.where(self.coasting, objects, -1))
        self.dormant_by = np.where(settled & (source >= 0), source, self.dormant_by)


class Referee:
    """Judges falls, shoves, rams, crushes and pushes (state: :class:`RefereeState`)."""

    def __init__(self, senses: Senses, rays: Rays, limits: QuadrupedLimits, config: QuadrupedConfig):
        self.senses, self.rays, self.limits, self.config = senses, rays, limits, config
        self.facts, self.scene = senses.facts, senses.scene
        self.state = RefereeState.empty(senses.sim.nworld, senses.centers(senses.state), senses.frames())
        self.magnets = Magnets(self.scene)
        self.pushes = PushRules(senses, rays, limits, self.magnets)
        self.forces = PushForce(senses, self.pushes, limits, config)
        self.crushes = Crushes(senses)
        self.strides = StrideLoads(senses, limits, config)  # (its state: the ride_ fields of RefereeState)
        self.grouped = functools.partial(pressed_by, senses)  # what touches what, directly or through others

    def conditions(self) -> dict[str, list[bool]]:
        """What every goal also needs, per world: the robot has not fallen, it shoved nothing by walking into it
        (what a shove moved, such as a vase pushed off its edge, may not count toward a goal) and, in a scene with a
        fragile object, it stood on none (its weight would break it)."""
        s = self.state
        conditions = {
            FALL_CONDITION: [f is None for f in s.failures],
            SHOVE_CONDITION: [shove is None for shove in s.shoves],
        }
        if self.facts.fragile.any():
            conditions[CRUSH_CONDITION] = [c is None for c in s.crushes]
        return conditions

    def push_started(self, w: int, index: int) -> None:
        """A push of object ``index`` starts in world ``w``: it is no longer shoved, rammed or moved by the stride (what
        the stride does to it counts from the next ride on)."""
        s = self.state
        s.bumped[w, index], s.ride_start[w, index], s.ride_top[w, index] = np.nan, np.nan, np.nan
        s.carried[w, index], s.drift[w, index], s.rammed_by[w, index] = 0.0, 0.0, -1
        s.bump_force[w, index] = s.bump_travel[w, index] = 0.0
        s.ride_touched[w, index] = s.ride_carried[w, index] = False
        s.force_limit[w] = np.nan  # read anew: it may push from another surface

    def judge(self, mask: np.ndarray, moves: MoveRunner) -> list[SkillEnd]:
        """Check the rules in the worlds in ``mask`` after a tick: end the skills of robots that fell, stop and
        refuse the moves that shoved, rammed or crushed something."""
        ends = self._falls(mask, moves)
        centres = self.senses.centers(self.senses.state)
        shift = centres - self.state.last_centres  # each object's travel since the last tick
        self.state.last_centres = np.where(mask[:, None, None], centres, self.state.last_centres)
        stood_on = self._shoves(ends, mask, centres, shift, moves)  # in 3-D: a torso lifting what lies on it shoves
        travel = np.linalg.norm(shift, axis=2)  # each object's, in 3-D
        self._bump_strains(ends, mask, shift, moves, stood_on)
        self._rams(ends, mask, centres[:, :, :2], shift, travel, moves, stood_on)
        self._stride_loads(ends, mask, centres, moves)
        self._riders(ends, mask, moves)
        self._push_footing(ends, mask, moves)
        self._strains(ends, mask, travel, moves)
        if self.facts.fragile.any():
            self._crushes(ends, mask, moves)
        return ends

    # -- rules checked every tick ----------------------------------------------------------------------

    def _falls(self, mask: np.ndarray, moves: MoveRunner) -> list[SkillEnd]:
        """Find the robots in ``mask`` that fell since the last tick: end their skills and mark their worlds failed."""
        s, state, ids, config = self.state, self.senses.state, self.facts.ids, self.config
        com = centre_of_mass(state, ids)
        centres = feet(state, ids)
        touching = feet_touching(state, ids, self.facts.not_robot)
        held = supported(com, centres, touching, config.support_margin)
        s.outside = np.where(mask, np.where(~held & np.isnan(moves.terrain.state.lift), s.outside + 1, 0), s.outside)
        s.lost_support[held & mask] = None
        for w in np.flatnonzero(mask & (s.outside == 1)):  # where it left its support, and which feet had none
            x, y = com[w, :2]
            s.lost_support[w] = f"fell at [{x:.2f}, {y:.2f}]: no support under {unsupported_feet(touching[w])}"
        angle = tilt(state, ids)
        fell = ((s.outside >= config.fall_ticks) & (angle > config.tipping)) | (angle > config.fall_tilt)
        ends = []
        for w in np.flatnonzero(fell & mask):
            if s.failures[w] is not None or state.failed[w] is not None:
                continue
            x, y = com[w, :2]
            reason = (
                s.lost_support[w] or f"fell at [{x:.2f}, {y:.2f}]: tipped over ({np.degrees(angle[w]):.0f} degrees)"
            )
            s.failures[w] = reason
            measured = {"x": round(float(x), 3), "y": round(float(y), 3), "tilt": round(float(np.degrees(angle[w])), 1)}
            end = moves.fell(int(w), reason, measured)
            if end is not None:
                ends.append(end)
        return ends

    def _shoves(
        self, ends: list[SkillEnd], mask: np.ndarray, centres: np.ndarray, shift: np.ndarray, moves: MoveRunner
    ) -> np.ndarray:
        """Find the objects the robot shoved, in the worlds in ``mask``: a movable object (a cloth too, read as a
        whole: a heavy chain on a platform, which the rays see through, was driven off it by the torso) that the
        torso or a leg touches outside a push of it or of something it touches (and the contact that lasts on from the
        push until the next walk), and that no foot stands on (:meth:`_stood_on`: a lever tips under the robot; a leg
        pressing on its side stands on nothing) or that the torso touches too (a sled stood on and walked into by its
        wall is driven, not stood on), is remembered where it is;
        while a push presses it or a foot stands on it, that place moves along with it (so shoves add up, however
        they are split between steps onto it); once it lies more than ``shove`` from that place, in any direction (a
        torso that rises under what lies on its back lifts it), it was shoved (a walk or a climb is no push: it would
        move things the push rules refuse, such as objects over the push limit, and what it moved may slide or tip on
        after the robot stops). The world fails (:meth:`conditions`) and a move in progress there is stopped and
        refused, naming the object. Returns which of the objects that moved this tick a foot stands on."""
        s, state, facts, scene, m = self.state, self.senses.state, self.facts, self.scene, moves.state
        touched = self._owned(state.touching[:, scene.robot_body].any(axis=1))  # by the torso or a leg
        touched &= facts.movable & mask[:, None]
        pushed = (np.arange(len(scene.object_names))[None, :] == m.pushing[:, None]) & m.moving[:, None]
        pushed &= mask[:, None]
        rows = np.flatnonzero(pushed.any(axis=1))  # what the pushed object moves by touching it moves with it
        if rows.size:
            mine = facts.bodies[m.pushing[rows]] > 0  # (k, nbody) the pushed object's bodies
            pushed[rows] |= self._owned(np.einsum("kb,kbc->kc", mine, state.touching[rows]))
        walking = (m.moving & (m.pushing < 0))[:, None]
        s.pressed = np.where(mask[:, None], pushed | (s.pressed & touched & ~walking), s.pressed)
        moved_now = (np.abs(shift) > STILL).any(axis=2) & facts.movable & ~s.pressed
        by_torso = self._owned(state.touching[:, facts.ids.body])  # the torso drives what it presses on
        stood_on = self._stood_on(mask[:, None] & moved_now & ~by_torso)
        excused = (s.pressed | stood_on) & mask[:, None]
        s.bumped = np.where(excused[:, :, None], s.bumped + shift, s.bumped)
        first = touched & ~s.pressed & ~stood_on & np.isnan(s.bumped[:, :, 0])
        s.bumped[first] = centres[first]
        moved = known_lengths(np.linalg.norm(centres - s.bumped, axis=2))
        for w in np.flatnonzero(mask & (moved > self.config.shove).any(axis=1)):
            index = int(np.argmax(moved[w]))
            reason = (
                f"the robot ran into {scene.object_names[index]} and moved it {moved[w, index]:.2f} m "
                "(a walk or a climb does not push things: push_to_position does, within the push rules)"
            )
            self._shoved(int(w), reason, {"moved": round(float(moved[w, index]), 3)}, ends, moves)
        return stood_on

    def _owned(self, bodies: npt.ArrayLike) -> np.ndarray:
        """(..., nobject) the objects that own any of ``bodies`` (..., nbody, bool) (a cloth: any of its links)."""
        return (np.asarray(bodies, dtype=float) @ self.facts.bodies.T) > 0

    def _stood_on(self, asked: np.ndarray) -> np.ndarray:
        """(nworld, nobject) which of the objects ``asked`` (nworld, nobject) a foot stands on: its contacts press the
        foot up within :data:`~.support.FOOTING_ANGLE` of up, and no other part of the robot presses on it otherwise
        (on a side or a rim). A leg pressing on an object's side, or a foot on the rim of a plate too thin for the legs
        to notice, does not stand on it (it may drive it along, as a walk must not); nor do the front feet standing on
        a plate while the rear feet plow it along by its rim (what the robot drives is no ride). Only what moved this
        tick needs asking (:meth:`_shoves`): what a foot stands on without moving is shoved nowhere. A cloth's links
        are read together: a foot stands on it where their contacts summed press it up."""
        state, robot, foot = self.senses.state, self.facts.robot_parts, self.facts.foot_parts
        out = np.zeros(asked.shape, dtype=bool)
        if not asked.any():
            return out
        touch = self._owned(state.touching[:, robot]) & asked[:, None, :]  # (nworld, nrobot, nobject)
        for w in np.flatnonzero(touch[:, foot].any(axis=(1, 2))):
            normals = self.facts.sums.rows(self.senses.sim.contact_normals(int(w))[:, robot])  # from each object (a
            # cloth: all its links together) onto each part
            on = touch[w].T  # (nobject, nrobot)
            up = bears_up(normals, FOOTING_ANGLE) & on
            out[w] = up[:, foot].any(axis=1) & ~(on & ~up).any(axis=1)
        return out

    def _shoved(self, w: int, reason: str, measured: dict[str, float], ends: list[SkillEnd], moves: MoveRunner) -> None:
        """The robot moved what it may not in world ``w`` (a shove, a ram, a load over the push limit): the first such
        rule broken fails the world (:meth:`conditions`) and refuses the move in progress."""
        if self.state.shoves[w] is None and self.senses.state.failed[w] is None:
            self.state.shoves[w] = reason
            self._refuse(w, reason, measured, ends, moves)

    def _refuse(self, w: int, reason: str, measured: dict[str, float], ends: list[SkillEnd], moves: MoveRunner) -> None:
        """Refuse the move in progress in world ``w`` for a broken rule; with none (the program over), an event."""
        if not moves.refuse(w, reason, measured, ends) and self.state.untold[w] is None:
            now = float(self.senses.state.time[w])
            self.state.untold[w] = Event(kind="refused", time=now, measured=measured, detail=reason)

    def _crushes(self, ends: list[SkillEnd], mask: np.ndarray, moves: MoveRunner) -> None:
        """Stop and refuse the moves, in the worlds in ``mask``, whose robot stands on a fragile object, or on a
        movable object that rests on one (:class:`~.crushes.Crushes`); the world fails (:meth:`conditions`)."""
        s, failed = self.state, self.senses.state.failed
        for w, reason in self.crushes.found(mask).items():
            if s.crushes[w] is None and failed[w] is None:
                s.crushes[w] = reason
                self._refuse(w, reason, {}, ends, moves)

    def _rams(
        self,
        ends: list[SkillEnd],
        mask: np.ndarray,
        centres: np.ndarray,
        shift: np.ndarray,
        travel: np.ndarray,
        moves: MoveRunner,
        stood_on: np.ndarray,
    ) -> None:
        """Find the pushes that ram more than the robot may push, in the worlds in ``mask``. A push rams the movable
        objects that the pushed object presses, directly or through others, and that lie ahead of it: their centres
        beyond its front face, or the contacts through which it or another pressed object presses them facing along
        the push (:func:`pressed_along`: an object caught in the crook of a hook, behind the hook's front face, is
        rammed, books lying on it or not). What rides on it is weighed when the push starts, as each push leg starts
        (:meth:`.push_rules.PushRules.load_rule`) and while it moves (:meth:`_riders`); what it drags by friction,
        pressing down on it, is not rammed (its weight loads the push: :mod:`.push_force`), but what bears it up and
        goes along under it is.
        The travel of each rammed object (its centre's, and the sweep of its corners as it turns while a ram presses its
        side: :func:`side_swings`) adds up from push to push until the robot pushes it itself, and so does what it
        travels on after the ram, the push over or not, until it comes to rest (a drum tapped by a pushed box rolls on:
        the push set it moving); what the pushed object or a rammed one rams on its own way after the push, until it
        comes to rest, is rammed by the push too (:meth:`_coasting_rams`). At rest is moving no more than :data:`CREEP`
        a tick in 3-D for :data:`REST_TIME` on end, no faster than its slowest meanwhile (found by an adversarial run: a
        pushed box that wedged for one tick at an edge, then slid free down a ramp into a 15 kg crate, was forgotten at
        the pause; ``shift`` is in 3-D). What the stride of a walk or a climb drives back under the feet (``stood_on``,
        from :meth:`_shoves`) rams as a pushed object does, until it comes to rest, once it has travelled ``shove``
        across under them (found by an adversarial run: a 15 cm walk along a 3 kg board on free rollers kicked it back
        into a 10 kg crate on ice, off its pad, with no push and no touch); it rams what it meets, not what rides on it
        or what it rides on (a second run: a lever on a loose 6 kg roller, rolling a few centimetres as it tips under
        the feet, lifts the cube on its far end as a lever should); what it and what goes along with it weigh is weighed
        whatever they ram (:meth:`_stride_loads`). Once the pushed object and the objects it rammed that travelled more
        than ``shove`` weigh more than the push limit, the robot shoved them (a light object used as a ram moves no more
        than the robot may push): the world fails (:meth:`conditions`) and a move in progress is stopped and refused,
        naming them."""
        s, m = self.state, moves.state
        dt, here = self.scene.control_dt, mask[:, None]
        s.still = np.where(here & (travel <= STILL), s.still + dt, np.where(here, 0.0, s.still))
        creeping = here & (travel <= CREEP)
        s.crept = np.where(creeping, s.crept + dt, np.where(here, 0.0, s.crept))
        s.slowest = np.where(creeping, np.minimum(s.slowest, travel), np.where(here, np.inf, s.slowest))
        shift = shift[:, :, :2]
        step = np.linalg.norm(shift, axis=2)  # (nworld, nobject) each object's travel this tick, across
        settled = here & (s.crept >= REST_TIME) & (travel <= s.slowest + STILL)  # not speeding up (:meth:`~.doze`)
        touched = self._owned(self.senses.state.touching[:, self.scene.robot_body].any(axis=1))
        stirred = here & (s.dormant_by >= 0) & (travel > WAKE)
        s.doze(settled, here, travel, touched, borne_along(self.senses, stirred, travel))
        s.rammed_by[settled] = -1
        s.coasting[settled] = False
        s.drift[here & (s.still >= REST_TIME)] = 0.0
        ridden = stood_on & (mask & m.moving & (m.pushing < 0))[:, None]
        turned = turns(self.senses, ridden, s.last_frames) > STILL  # what turns in place under the feet rides too
        ride = np.where(turned, np.maximum(step, 2 * STILL), step)  # (it counts as ridden; the stride weighs the turn)
        ridden &= ride > STILL
        s.drift += np.where(ridden, ride, 0.0)
        s.coasting |= ridden & self._driven()  # a lever tipping under the feet rocks, a cart rolls away: the stride
        # drives back what the feet stand on, and it rams like a pushed object
        worlds = np.flatnonzero(mask & m.moving & (m.pushing >= 0))
        met = np.zeros(s.coasting.shape, dtype=bool)  # what a ram presses this tick
        if worlds.size:
            index = m.pushing[worlds]
            s.coasting[worlds, index] = True
            met[worlds] = self._rammed(worlds, index, centres, m.u[worlds])
            s.rammed_by[worlds] = np.where(met[worlds], index[:, None], s.rammed_by[worlds])
        self._coasting_rams(worlds, m.pushing[worlds], mask, centres, shift, step, met)
        travelling = (s.rammed_by >= 0) & mask[:, None]
        pushing = np.where(m.moving, m.pushing, -1)
        swung = side_swings(self.senses, met & travelling, s.last_frames, self._object_normals, s.rammed_by, pushing)
        s.carried += np.where(travelling, step, 0.0) + swung
        s.last_frames = np.where(mask[:, None, None], self.senses.frames(), s.last_frames)
        moved = travelling & (s.carried > self.config.shove)
        candidates = np.flatnonzero(moved.any(axis=1))
        if candidates.size:
            self._weigh_rams(ends, candidates, moved[candidates], moves)

    def _coasting_rams(
        self,
        pushing: np.ndarray,
        pushed: np.ndarray,
        mask: np.ndarray,
        centres: np.ndarray,
        shift: np.ndarray,
        step: np.ndarray,
        met: np.ndarray,
    ) -> None:
        """What a pushed object, or one its push rammed, rams on its own way once the push is over, until it comes to
        rest, is rammed by that push too (found by an adversarial run: a 4.2 kg drum pushed at walking pace and left
        to roll on across ice knocked a 10 kg crate off a deck, and one pushed to the top of a ramp a 15 kg one; only
        what it pressed while the push ran was weighed). Read along each one's own way this tick, in the worlds in
        ``mask``; in the worlds ``pushing``, where a push runs, its object ``pushed`` is read by the push itself. What
        they press this tick is marked in ``met`` (nworld, nobject)."""
        s = self.state
        pushed_now = np.zeros(s.coasting.shape, dtype=bool)
        pushed_now[pushing, pushed] = True
        rolling = (s.coasting | (s.rammed_by >= 0)) & ~pushed_now & mask[:, None] & (step > STILL)
        worlds, objects = np.nonzero(rolling)
        if not worlds.size:
            return
        way = shift[worlds, objects] / step[worlds, objects][:, None]
        rammed = self._rammed(worlds, objects, centres, way)
        source = np.where(s.rammed_by[worlds, objects] >= 0, s.rammed_by[worlds, objects], objects)
        for k in np.flatnonzero(rammed.any(axis=1)).tolist():
            w = int(worlds[k])
            hit = rammed[k] & (np.arange(rammed.shape[1]) != source[k])
            if self._driven()[w, source[k]]:  # it rams what it meets, not what rides on it or what it rides on
                normals = self._object_normals(w)
                hit &= ~(bears_up(normals[source[k]]) | bears_up(normals[:, source[k]]))
            s.rammed_by[w, hit & (s.rammed_by[w] < 0)] = source[k]
            met[w] |= hit

    def _stride_loads(self, ends: list[SkillEnd], mask: np.ndarray, centres: np.ndarray, moves: MoveRunner) -> None:
        """Stop and refuse the moves, in the worlds in ``mask``, whose stride moves more than the push limit, ramming
        or not (:class:`~.stride_loads.StrideLoads`); the world fails (:meth:`conditions`)."""
        s, limit = self.state, self.limits.max_push_mass
        for w, (reason, mass) in self.strides.weigh(s, mask, centres, s.still >= REST_TIME, self.grouped).items():
            self._shoved(w, reason, {"mass": round(mass, 3), "limit": limit}, ends, moves)

    def _riders(self, ends: list[SkillEnd], mask: np.ndarray, moves: MoveRunner) -> None:
        """Weigh what a push carries while it moves, in the worlds in ``mask`` where another movable object touches the
        pushed one (:meth:`.push_rules.PushRules.load_rule`: two anvils that slid onto a pushed sled rode along): once
        that has been over the push limit for :data:`RIDE_TIME` on end (a box pushed against the next box of a
        staircase reads it as riding on it for a moment), the world fails (:meth:`conditions`) and the push is stopped
        and refused."""
        s, m, state, names = self.state, moves.state, self.senses.state, self.scene.object_names
        worlds = np.flatnonzero(mask & m.moving & (m.pushing >= 0))
        s.overloaded[mask & ~(m.moving & (m.pushing >= 0))] = np.nan
        if worlds.size == 0:
            return
        mine = self.facts.bodies[m.pushing[worlds]] > 0  # (k, nbody) the pushed objects' bodies
        near = self._owned(np.einsum("kb,kbc->kc", mine, state.touching[worlds])) & self.facts.movable
        near[np.arange(len(worlds)), m.pushing[worlds]] = False
        s.overloaded[worlds[~near.any(axis=1)]] = np.nan
        for w in worlds[near.any(axis=1)].tolist():
            heavy = self.pushes.load_rule(w, int(m.pushing[w]))
            now = float(state.time[w])
            s.overloaded[w] = np.nan if heavy is None else np.fmin(s.overloaded[w], now)
            if heavy is None or now - s.overloaded[w] < RIDE_TIME:
                continue
            self._shoved(w, f"pushing {names[m.pushing[w]]} carried too much: {heavy[0]}", heavy[1], ends, moves)

    def _push_footing(self, ends: list[SkillEnd], mask: np.ndarray, moves: MoveRunner) -> None:
        """Stop and refuse the pushes, in the worlds in ``mask``, whose robot has come to stand on a movable object
        (:meth:`.push_rules.PushRules.footing`: a push called from a fixed stage walked on onto a loose deck; found by
        an adversarial run); the world fails (:meth:`conditions`)."""
        m = moves.state
        worlds = np.flatnonzero(mask & m.moving & (m.pushing >= 0))
        for w, reason in self.pushes.footing(worlds, m.pushing[worlds]).items():
            self._shoved(w, reason, {}, ends, moves)

    def _bump_strains(
        self, ends: list[SkillEnd], mask: np.ndarray, shift: np.ndarray, moves: MoveRunner, stood_on: np.ndarray
    ) -> None:
        """Stop and refuse the walks and climbs, in the worlds in ``mask``, that moved what the robot ran into
        (:meth:`_shoves`; not what a foot stands on, ``stood_on``) with more force than a push of it may take
        (:meth:`.push_force.PushForce.bumps`); the world fails (:meth:`conditions`). What they move rams as a pushed
        object does (found by an adversarial run: a light bar nudged under 3 cm rolled a 20 kg drum off a stage)."""
        s, m = self.state, moves.state
        free = (
            ~s.pressed & ~stood_on & (s.drift == 0) & (mask & m.moving & (m.pushing < 0))[:, None] & self.facts.movable
        )
        bumping = free & ~np.isnan(s.bumped[:, :, 0])
        moved, pushed = self.forces.bumps(bumping, free, shift, s.bump_force, s.bump_travel)
        s.coasting |= moved  # what it moves rams as a pushed object does, until it comes to rest (:meth:`_rams`)
        for w, reason, measured in pushed:
            self._shoved(w, reason, measured, ends, moves)

    def _strains(self, ends: list[SkillEnd], mask: np.ndarray, travel: np.ndarray, moves: MoveRunner) -> None:
        """Stop and refuse the pushes, in the worlds in ``mask``, that have taken more force than the robot may push
        with (:class:`~.push_force.PushForce`; ``travel``: each object's this tick); the world fails
        (:meth:`conditions`)."""
        for w, reason, measured in self.forces.check(mask, moves, travel, self.state.strained, self.state.force_limit):
            self._shoved(w, reason, measured, ends, moves)

    def _rammed(self, worlds: np.ndarray, index: np.ndarray, centres: np.ndarray, u: np.ndarray) -> np.ndarray:
        """(k, nobject) the objects that the push of object ``index[i]`` along ``u[i]`` rams in world ``worlds[i]``
        this tick (see :meth:`_rams`)."""
        extent = np.zeros((len(worlds), 2))
        for o in np.unique(index):  # the pushed objects' x-y extents
            lo, hi = self.senses.boxes(int(o))
            extent[index == o] = (hi - lo)[worlds[index == o], :2]
        front = np.einsum("ki,ki->k", np.abs(u), extent) / 2  # from the pushed object's centre to its front face
        ahead = np.einsum("koi,ki->ko", centres[worlds] - centres[worlds, index][:, None], u) > front[:, None]
        pressed = pressed_by(self.senses, worlds, index)
        rammed = pressed & (ahead | stuck_to(self.senses, self.magnets, worlds, index, pressed))
        rows = np.flatnonzero((pressed & ~ahead).any(axis=1))  # the normals only where they can add a rammed one
        normals = {w: self._object_normals(w) for w in set(worlds[rows].tolist())}  # a world's once: rows share it
        for k in rows:
            rammed[k] |= pressed_along(normals[int(worlds[k])], int(index[k]), pressed[k], u[k])
        return rammed

    def _driven(self) -> np.ndarray:
        """(nworld, nobject) the objects the stride has driven ``shove`` across under the feet since they last rested
        (or were pushed): they ram as pushed objects do."""
        return self.state.drift > self.config.shove

    def _weigh_rams(self, ends: list[SkillEnd], worlds: np.ndarray, moved: np.ndarray, moves: MoveRunner) -> None:
        """Fail the ``worlds`` where a pushed object and the objects its push rammed and ``moved`` (k, nobject) weigh
        more than the push limit; stop and refuse the move in progress there."""
        s, names, limit = self.state, self.scene.object_names, self.limits.max_push_mass
        masses = self.senses.masses(worlds)
        for k, w in enumerate(worlds.tolist()):
            for pusher in np.unique(s.rammed_by[w, moved[k]]).tolist():
                group = moved[k] & (s.rammed_by[w] == pusher)
                mass = float(masses[k, pusher] + masses[k, group].sum())
                if mass <= limit:
                    continue
                ram = (
                    f"{names[pusher]}, driven by the stride of the robot on it,"
                    if self._driven()[w, pusher]
                    else f"{names[pusher]}, moved by the robot's walk or climb,"
                    if s.bump_travel[w, pusher] > 0
                    else f"pushing {names[pusher]}"
                )
                reason = (
                    f"{ram} rammed {', '.join(names[o] for o in np.flatnonzero(group))}: "
                    f"{mass:.1f} kg in all, over the push limit of {limit:.1f} kg (a push moves only what the robot "
                    "may push)"
                )
                self._shoved(w, reason, {"mass": round(mass, 3), "limit": limit}, ends, moves)

    def _object_normals(self, w: int) -> np.ndarray:
        """(nobject, nobject, 3) the summed contact normals from each object onto each other in world ``w``."""
        return self.facts.sums.pairs(self.senses.sim.contact_normals(w))
