"""Standing on a fragile object, for the quadruped's referee: a foot or the belly resting on it, or on a movable object
that rests on it, puts the robot's weight on it, which breaks it (:class:`Crushes`)."""

from __future__ import annotations

import numpy as np

from robotool.robots.quadruped.body import GRAVITY
from robotool.robots.quadruped.sensing import Senses
from robotool.robots.quadruped.support import Weighing, bears_up, feet, pass_weight, resting_on
from robotool.robots.quadruped.terrain import rotated


class Crushes:
    """Finds the worlds whose robot stands on a fragile object (no state of its own)."""

    def __init__(self, senses: Senses):
        self.senses, self.facts, self.scene = senses, senses.facts, senses.scene

    def found(self, mask: np.ndarray) -> dict[int, str]:
        """Find the fragile objects the robot stands on, in the worlds in ``mask``: a foot that touches one with its
        centre above the object's centre, a belly that touches one whose centre lies under the torso, or a foot or the
        belly that it bears up (:meth:`_borne_by`: the foot of a glass L, whose centre lies in the air above it),
        rests the robot's weight on it, which breaks it (a low vase read as a step is no footing); so does standing on a
        movable object that rests on it (:meth:`_loaded`: a board lying on a vase). Returns, for each such world,
        the reason, naming the object."""
        state, facts, names = self.senses.state, self.facts, self.scene.object_names
        bodies = self.scene.object_body[facts.fragile]
        centres = state.xpos[:, bodies]  # (nworld, nfragile, 3)
        foot_z = feet(state, facts.ids)[:, :, 2]
        by_foot = state.touching[:, facts.ids.feet][:, :, bodies] & (foot_z[:, :, None] > centres[:, None, :, 2])
        by_belly = state.touching[:, facts.ids.body][:, bodies]
        if by_belly.any():  # and its centre lies under the torso
            torso = state.xpos[:, facts.ids.body]
            along_body = rotated(centres[:, :, :2] - torso[:, None, :2], -self.senses.yaw())
            by_belly &= np.all(np.abs(along_body) < facts.half, axis=2)
        stood_on = (by_foot.any(axis=1) | by_belly) & mask[:, None]
        stood_on |= self._borne_by(bodies, mask & ~stood_on.any(axis=1))
        loaded, via = self._loaded(mask)
        found = {}
        for w in np.flatnonzero((stood_on | loaded[:, facts.fragile]).any(axis=1)).tolist():
            index = int(np.flatnonzero(facts.fragile)[np.argmax(stood_on[w] | loaded[w, facts.fragile])])
            name = names[index]
            what = name if stood_on[w].any() else f"{names[via[w, index]]}, which rests on {name}"
            found[w] = f"the robot stood on {what}, which is fragile: the robot's weight would break it"
        return found

    def _borne_by(self, bodies: np.ndarray, mask: np.ndarray) -> np.ndarray:
        """(nworld, len(bodies)) which of ``bodies`` bear the robot up, in the worlds in ``mask``: the contacts through
        which one presses on a foot or the torso press it up (:func:`~.support.bears_up`)."""
        state, ids = self.senses.state, self.facts.ids
        robot = np.array([*ids.feet, ids.body])
        touch = state.touching[:, robot][:, :, bodies]  # (nworld, 5, nbodies)
        out = np.zeros((len(mask), len(bodies)), dtype=bool)
        for w in np.flatnonzero(mask & touch.any(axis=(1, 2))):
            normals = self.senses.sim.contact_normals(int(w))[bodies][:, robot]  # from each body onto each robot part
            out[w] = (bears_up(normals) & touch[w].T).any(axis=1)
        return out

    def _loaded(self, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(nworld, nobject) the objects that carry the robot's weight through movable objects, in the worlds in
        ``mask``: a movable object (not fragile) under a foot carries it, and passes it on to each object it rests
        on (:func:`~.support.resting_on`: what bears it up, such as what a board lies on or leans on from the floor,
        or what the very link of a cloth under the foot lies on); a fixed object passes it to the ground.
        Also (nworld, nobject) the object that passed the weight on to each one."""
        state, facts, parts = self.senses.state, self.facts, self.facts.parts
        nworld, nobject = self.senses.sim.nworld, len(self.scene.object_names)
        loaded, via = np.zeros((nworld, nobject), dtype=bool), np.zeros((nworld, nobject), dtype=int)
        carrier = (facts.movable & ~facts.fragile)[parts.owner]
        on_feet = state.touching[:, facts.ids.feet].any(axis=1).astype(float)  # (nworld, nbody)
        under_feet = (on_feet @ parts.member.T.astype(float) > 0) & carrier  # (nworld, npart)
        worlds = np.flatnonzero(mask & under_feet.any(axis=1))
        if worlds.size == 0:
            return loaded, via
        normals = np.stack([self.senses.sim.contact_normals(int(w)) for w in worlds])

        def forces(k: int, bodies: np.ndarray) -> np.ndarray:
            return self.senses.sim.contact_forces(worlds[k : k + 1], bodies)[0]

        weight = GRAVITY * np.asarray(self.senses.sim.body_mass)[worlds] @ parts.member.T
        rests = resting_on(normals, parts, Weighing(forces, weight))
        load, passed_by = pass_weight(rests, under_feet[worlds], carrier)
        loaded[worlds] = parts.objects(load, nobject)
        for o in np.flatnonzero(loaded[worlds].any(axis=0)):  # the part that passed it to one of o's loaded parts
            own = np.flatnonzero(parts.owner == o)
            first = own[np.argmax(load[:, own], axis=1)]
            via[worlds, o] = parts.owner[passed_by[np.arange(len(worlds)), first]]
        return loaded, via
