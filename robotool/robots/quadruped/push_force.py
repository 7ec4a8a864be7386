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
the robot may push, or more than its feet could push: the referee refuses it and the world fails. (The tunables are
in :class:`~robotool.robots.quadruped.quadruped_config.QuadrupedConfig`.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robotool.robots.quadruped.body import GRAVITY
from robotool.robots.quadruped.move_runner import MoveRunner
from robotool.robots.quadruped.push_rules import PushRules
from robotool.robots.quadruped.quadruped_config import QuadrupedConfig
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.sensing import Senses


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
