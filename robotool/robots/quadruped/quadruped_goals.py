"""The quadruped's own goal kind, ``robot_on``, as named sub-conditions over batched state."""

from __future__ import annotations

import numpy as np

from robotool.robots.quadruped.body import BodyIds
from robotool.robots.quadruped.support import (
    Parts,
    bears_up,
    centre_of_mass,
    feet,
    feet_touching,
    pass_weight,
    resting_on,
    supported,
)
from robotool.robots.quadruped.terrain import FOOT_RADIUS
from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.compiled_scene import Scene
from robotool.sim.embodiment import ReadAtTicks
from robotool.sim.object_goals import local_corners

EDGE_REACH = FOOT_RADIUS / 2
"""m: how far past a top's edge a foot's centre may be and still bear on it (its contact faces upward, within 30
degrees); a foot against a side face has its centre a whole radius out."""


class RobotOnGoal(ReadAtTicks):
    """``robot_on: obj``: the robot's weight rests on ``obj``.

    Its centre of mass lies over the support of the feet whose weight reaches ``obj`` (at least three of them), and
    every foot touches something (none hangs over a gap). A foot's weight reaches ``obj`` when it stands on ``obj``
    (it touches ``obj`` with its centre over ``obj``'s top, within :data:`EDGE_REACH` of its edges, and ``obj``
    presses it up: a foot pressing on a side face, from the floor beside it, carries nothing), or when it stands over
    ``obj``'s footprint on a movable object (not fragile) that rests on ``obj``, directly or through others (a board
    lying on a sofa), as the judge traces weight elsewhere (:func:`resting_on`, :func:`pass_weight`). ``obj``'s top
    and footprint are those of the face that looks up now (a wall box turned on its side has its top where it
    stands).
    """

    def __init__(self, scene: Scene, sim: BatchedSim):
        self.scene, self.sim = scene, sim
        self.name = scene.task.goal.object
        self.index = scene.object_index(self.name)
        self.ids = BodyIds.of(scene.model)
        self.target = scene.body_object == self.index
        self.not_robot = ~scene.robot_body
        self.corners = local_corners(scene)
        self.lo, self.hi = self.corners[self.index].min(axis=0), self.corners[self.index].max(axis=0)
        objects = scene.task.objects
        self.parts = Parts.of(scene)
        self.carrier = np.array([o.movable and o.fragile is None for o in objects], dtype=bool)[self.parts.owner]
        self.nobject = len(objects)

    def update(self, state: BatchState, active: np.ndarray, credited: np.ndarray) -> None:
        """Nothing to remember: the goal holds at the end."""

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        foot_xyz = feet(state, self.ids)
        height, footprint = self._in_target_frame(state, foot_xyz)
        above = height >= -EDGE_REACH  # not beside or under its top (nor in an L's crook)
        on_top = self._borne_up(state) & self._over(footprint, EDGE_REACH) & above
        on_target = on_top | (self._through_carriers(state) & self._over(footprint, 0.0) & above)
        weight = supported(centre_of_mass(state, self.ids), foot_xyz, on_target)
        standing = np.all(feet_touching(state, self.ids, self.not_robot), axis=1)
        return {f"robot_weight_on_{self.name}": weight, "robot_feet_all_supported": standing}

    def _borne_up(self, state: BatchState) -> np.ndarray:
        """(nworld, 4) whether the target presses each foot up (its contacts with the foot, summed, within
        :data:`~.support.BEARING_ANGLE` of up): a foot on the floor pressing on its side carries nothing onto it,
        however its outline is read (the feet beside a low disc lie inside the square around it)."""
        touching = feet_touching(state, self.ids, self.target)
        out = np.zeros(touching.shape, dtype=bool)
        for w in np.flatnonzero(touching.any(axis=1)):
            normals = self.sim.contact_normals(int(w))[self.target][:, self.ids.feet].sum(axis=0)  # onto each foot
            out[w] = touching[w] & bears_up(normals)
        return out

    def _through_carriers(self, state: BatchState) -> np.ndarray:
        """(nworld, 4) whether each foot stands on carriers that pass its weight to the target (a cloth's link passes
        it to what that link lies on): a carrier the foot touches counts only where it presses the foot up, as the
        target must (found by an adversarial run: slats standing on a rug and leaning on the feet of a robot held up
        by a deck over the rug credited it with standing on the rug)."""
        on_feet = state.touching[:, self.ids.feet].astype(float)  # (nworld, 4, nbody)
        under = (on_feet @ self.parts.member.T.astype(float) > 0) & self.carrier  # (nworld, 4, npart)
        out = np.zeros(under.shape[:2], dtype=bool)
        worlds = np.flatnonzero(under.any(axis=(1, 2)))
        if worlds.size == 0:
            return out
        normals = np.stack([self.sim.contact_normals(int(w)) for w in worlds])  # (k, nbody, nbody, 3)
        onto_feet = np.einsum("pb,kbfx->kfpx", self.parts.member.astype(float), normals[:, :, self.ids.feet])
        under[worlds] &= bears_up(onto_feet)  # (k, 4, npart): each part presses the foot up
        rests = resting_on(normals, self.parts)
        for f in range(under.shape[1]):
            loaded, _ = pass_weight(rests, under[worlds, f], self.carrier)
            out[worlds, f] = self.parts.objects(loaded, self.nobject)[:, self.index]
        return out

    def _in_target_frame(self, state: BatchState, foot_xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The feet's centres against the target's face that looks up now (its local axis nearest the world's up):
        their height above that top (nworld, 4) and, for each foot, how far outside the top's extent it lies along
        each of the other two axes (nworld, 4, 2; 0 inside, positive outside)."""
        body = self.scene.object_body[self.index]
        frame = state.xmat(body)  # (nworld, 3, 3): the target's axes in world coordinates, as columns
        rel = np.einsum("wji,wfj->wfi", frame, foot_xyz - state.xpos[:, body, None, :])
        worlds = np.arange(len(rel))
        up = np.argmax(np.abs(frame[:, 2, :]), axis=1)  # (nworld,)
        sign = np.sign(frame[worlds, 2, up])
        top = np.where(sign > 0, self.hi[up], -self.lo[up])
        height = sign[:, None] * rel[worlds, :, up] - top[:, None]
        flat = np.array([[a for a in range(3) if a != u] for u in range(3)])[up]  # (nworld, 2) the other two axes
        along = np.take_along_axis(rel, flat[:, None, :].repeat(rel.shape[1], axis=1), axis=2)
        outside = np.maximum(self.lo[flat][:, None, :] - along, along - self.hi[flat][:, None, :])
        return height, outside

    def _over(self, outside: np.ndarray, reach: float) -> np.ndarray:
        """(nworld, 4) whether each foot's centre lies over the target's top grown by ``reach`` (``outside``: from
        :meth:`_in_target_frame`)."""
        return np.all(outside <= reach, axis=2)
