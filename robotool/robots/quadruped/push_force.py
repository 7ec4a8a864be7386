"""The push force rule: a push may take no more force than pushing an object of the push limit takes.

The push limit weighs what a push moves (the object, what rides on it, what is stuck to it, what it rams), but an
object pushed may also drag, lift or tip what else lies on it: a chair pushed out from under a lever's end that
carries a heavy sandbag, a pallet dragging a crate whose other edge rests on a strip. Their weight loads the push
whether or not they count as moved. So while a push moves, in each world where the robot touches a movable object,
the force the robot's bodies put on the movable objects along the push is read from the solver's contact forces
(:meth:`~robotool.sim.backend.BatchedSim.contact_forces`); its limit is ``push_force_margin`` times the force that
slides ``max_push_mass`` on the pushed object's support (its weight times the friction between them, read once per
push leg), and no more than the robot's feet hold (frictionless in the simulation: the x-y servos push from the
world): its weight times the friction under them, as the push rules read it (:meth:`.PushRules.feet_hold`, a cloth
under them included), read at every tick it is weighed, where the feet stand then (a push that starts on rubber and
carries on with the feet on ice holds what the ice does). A push of an object that takes more than either while the
object moves (faster than ``settled_speed``: a push pressed against what stands in the way moves nothing) for
``push_strain_time`` in all over the run (the forces are read at an instant: knocks and starts peak) moves more than
the robot may push, or more than its feet could push: the referee refuses it and the world fails. A walk or a climb
that moves what it ran into is weighed the same way where that bears up another object in part (:meth:`PushForce.bumps`:
the shove rule's 3 cm would let it slide a loaded prop away). (The tunables are in
:class:`~robotool.robots.quadruped.quadruped_config.QuadrupedConfig`.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robotool.robots.quadruped.body import GRAVITY
from robotool.robots.quadruped.move_runner import MoveRunner
from robotool.robots.quadruped.push_rules import PushRules
from robotool.robots.quadruped.quadruped_config import QuadrupedConfig
from robotool.robots.quadruped.quadruped_skills import BELLY_HEIGHT, QuadrupedLimits
from robotool.robots.quadruped.sensing import Senses
from robotool.robots.quadruped.terrain import quarter_turns

BUMP_REACH = 0.02
"""m from the torso's box within which what moves during a walk may have been knocked by it."""
KNOCK_COS = 0.5
"""What the robot moves goes its way: an object's travel counts when it is within 60 degrees of the body's (a cube a
lever lifts beside the torso moves up, not along the walk)."""
BUMP_TRAVEL = 0.005
"""m a walk may move what it ran into, while that bears up another in part, before the force it took is weighed."""


@dataclass(frozen=True)
class PushForceBodies:
    """Which bodies push (the robot's) and which are pushed (the movable objects')."""

    robot: np.ndarray  # (nbody,) bool
    movable: np.ndarray  # (nbody,) bool


class PushForce:
    """Weighs the force of the robot's pushes in every world (its state is the referee's)."""

    def __init__(self, senses: Senses, pushes: PushRules, limits: QuadrupedLimits, config: QuadrupedConfig):
        self.senses, self.pushes, self.scene = senses, pushes, senses.scene
        self.mass, self.margin, self.time = limits.max_push_mass, config.push_force_margin, config.push_strain_time
        self.still = config.settled_speed * senses.scene.control_dt  # m a tick: what moves less stands still
        owner = self.scene.body_object
        movable = (owner >= 0) & senses.facts.movable[np.maximum(owner, 0)]
        self.bodies = PushForceBodies(robot=np.asarray(self.scene.robot_body, dtype=bool), movable=movable)

    def check(
        self, mask: np.ndarray, moves: MoveRunner, travel: np.ndarray, strained: np.ndarray, limits: np.ndarray
    ) -> list[tuple[int, str, dict[str, float]]]:
        """Weigh the pushes under way in the worlds in ``mask`` whose robot touches a movable object and whose pushed
        object moved this tick (``travel`` (nworld, nobject) m); (world, reason, measured) for each push that has now
        taken more than its limit for ``push_strain_time``. ``strained`` (nworld, nobject) s each object's pushes
        have taken more, added up over the run, and ``limits`` (nworld, 2) N the limits of the push leg under way
        (the push limit's, read once per leg, NaN: not read yet; then what the feet hold, read now) are updated in
        place."""
        m, state, names = moves.state, self.senses.state, self.scene.object_names
        robot, movable = self.bodies.robot, self.bodies.movable
        pushing = mask & m.moving & (m.pushing >= 0)
        if not pushing.any():
            return []
        touches = state.touching[:, robot][:, :, movable].any(axis=(1, 2))
        moved = travel[np.arange(len(mask)), m.pushing] > self.still
        worlds = np.flatnonzero(pushing & touches & moved)
        if worlds.size == 0:
            return []
        for w in worlds[np.isnan(limits[worlds, 0])].tolist():
            limits[w, 0] = self.margin * self.mass * GRAVITY * self.pushes.sliding_friction(w, int(m.pushing[w]))
        limits[worlds, 1] = self.pushes.feet_holds(worlds)  # where the feet stand now: a push walked onto ice
        forces = self.senses.sim.contact_forces(worlds, robot)[:, movable, :2].sum(axis=1)  # (k, 2) on what it pushes
        along = np.einsum("ki,ki->k", forces, m.u[worlds])
        out = []
        for k in np.flatnonzero(along > limits[worlds].min(axis=1)).tolist():
            w, index = int(worlds[k]), int(m.pushing[worlds[k]])
            strained[w, index] += self.scene.control_dt
            if strained[w, index] < self.time - 1e-9:
                continue
            limit = float(limits[w].min())
            near = self.scene.body_object[state.touching[w][self.scene.body_object == index].any(axis=0) & movable]
            others = [names[o] for o in np.unique(near) if o != index]
            touching = f" (touching {', '.join(others)})" if others else ""
            took = f"pushing {names[index]}{touching} took over {limit:.0f} N for {strained[w, index]:.1f} s"
            if limits[w, 1] < limits[w, 0]:
                feet = self.pushes.feet_hold(w)
                reason = (
                    f"{took} ({along[k]:.0f} N now), the most the robot's feet hold on {feet[2]} at friction "
                    f"{limit / (feet[0] * GRAVITY):.3g}: its feet would slip"
                )
            else:
                reason = (
                    f"{took} ({along[k]:.0f} N now), {self.margin:g} times what sliding {self.mass:.1f} kg, the push "
                    "limit, on its support takes: it moves more than the robot may push"
                )
            out.append((w, reason, {"force": round(float(along[k]), 1), "limit": round(limit, 1)}))
        return out

    def bumps(
        self, bumping: np.ndarray, free: np.ndarray, shift: np.ndarray, needed: np.ndarray, travel: np.ndarray
    ) -> tuple[np.ndarray, list[tuple[int, str, dict[str, float]]]]:
        """Weigh what a walk or a climb moves of what it runs into: ``bumping`` (nworld, nobject), the movable objects
        the robot touched outside a push, that no foot stands on and the stride does not drive, while a walk or a climb
        runs, and of those ``free`` to be, the ones within :data:`BUMP_REACH` of the torso (a knock that parts within a
        tick leaves no touch to read). While the robot touches one or it lies that near, the most sliding it takes (what
        the push rules read: :meth:`.PushRules.sliding_force`; read before a knock too, which may lift its load a while)
        is kept in ``needed`` (N); its travel across this tick (``shift`` (nworld, nobject, 3) m), where it goes the
        body's way (:data:`KNOCK_COS`), adds up in ``travel`` (m); both are updated in place. An object that bears up
        another in part, moved :data:`BUMP_TRAVEL` or more, whose sliding took more than a push of it may
        (``push_force_margin`` times the push limit's force on its support, and what the feet hold), was pushed by the
        walk, however little it moved (found by an adversarial run: a walk's torso slid a light hook 1-3 cm from under a
        25 kg plank's end, which took 60-130 N, under the shove rule's ``shove``, and dropped the plank); what bears
        nothing up is weighed by the shove rule. Returns which objects the walk moved this tick (nworld, nobject), and
        (world, reason, measured) for each that it pushed."""
        step = np.linalg.norm(shift[:, :, :2], axis=2)
        watched = bumping | self._near_torso(free)
        velocity = self.senses.state.qvel[:, self.senses.facts.ids.qvel[:2]]  # (nworld, 2) the body's, across
        along = np.einsum("woi,wi->wo", shift[:, :, :2], velocity)
        moving = watched & (step > self.still) & (along > KNOCK_COS * step * np.linalg.norm(velocity, axis=1)[:, None])
        travel += np.where(moving, step, 0.0)
        names, out = self.scene.object_names, []
        for w, o in zip(*np.nonzero(watched), strict=True):
            w, o = int(w), int(o)
            if self._touches_another(w, o):  # else it bears nothing up (most ticks: a step beside the robot)
                force, drag, _ = self.pushes.sliding_force(w, o)
                needed[w, o] = max(needed[w, o], force) if drag > 0.0 else needed[w, o]
            if travel[w, o] < BUMP_TRAVEL or needed[w, o] == 0.0:
                continue
            pushes = self.margin * self.mass * GRAVITY * self.pushes.sliding_friction(w, o)
            limit = min(pushes, float(self.pushes.feet_hold(w)[1]))
            if needed[w, o] > limit:
                reason = (
                    f"the robot ran into {names[o]} and moved it {travel[w, o]:.3f} m while it bore up another object "
                    f"in part, which took {needed[w, o]:.0f} N, over the {limit:.0f} N pushing it may take (a walk or "
                    "a climb does not push things: push_to_position does, within the push rules)"
                )
                out.append((w, reason, {"force": round(float(needed[w, o]), 1), "limit": round(limit, 1)}))
        return moving, out

    def _touches_another(self, w: int, index: int) -> bool:
        """Whether object ``index`` touches another movable object in world ``w`` (the robot's bodies aside)."""
        touching = self.senses.state.touching[w][self.scene.body_object == index].any(axis=0)
        return bool((touching & self.bodies.movable & (self.scene.body_object != index)).any())

    def _near_torso(self, objects: np.ndarray) -> np.ndarray:
        """(nworld, nobject) which of ``objects`` lie within :data:`BUMP_REACH` of the torso's box (from the belly up:
        the body's origin is at the feet's bottom)."""
        out = np.zeros(objects.shape, dtype=bool)
        worlds = np.flatnonzero(objects.any(axis=1))
        if worlds.size == 0:
            return out
        senses, height = self.senses, self.senses.facts.height
        centre = senses.state.xpos[worlds, senses.facts.ids.body] + [0.0, 0.0, (height + BELLY_HEIGHT) / 2]
        odd = (quarter_turns(senses.yaw(worlds)) % 2 == 1)[:, None]  # turned a quarter: length along y
        half = np.hstack([np.where(odd, senses.facts.half[::-1], senses.facts.half), np.full((len(worlds), 1), 0.0)])
        half[:, 2] = (height - BELLY_HEIGHT) / 2
        for o in np.flatnonzero(objects[worlds].any(axis=0)).tolist():
            lo, hi = senses.boxes(o)
            gap = np.maximum(lo[worlds] - (centre + half), (centre - half) - hi[worlds]).max(axis=1)
            out[worlds, o] = objects[worlds, o] & (gap <= BUMP_REACH)
        return out
