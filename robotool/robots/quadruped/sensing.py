"""What the quadruped controller's components read from the batched state: the scene's fixed facts (which objects
are movable, fragile or cloth, the robot's ids and size) and, from the current state, positions, object centres,
bounds and masses (computed once per state)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from robotool.robots.quadruped.body import LEG_SLACK, XY_KP, BodyIds
from robotool.robots.quadruped.object_sums import ObjectSums
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.support import Parts
from robotool.robots.quadruped.terrain import quarter_turns
from robotool.sim.backend import BatchedSim, BatchState, quat_to_mat
from robotool.sim.compiled_scene import Scene
from robotool.sim.object_goals import local_corners, world_corners


@dataclass(frozen=True)
class SceneFacts:
    """What does not change during a run: the robot's ids and size, and per object whether it is movable, fragile
    or a cloth (no per-world state)."""

    ids: BodyIds
    half: np.ndarray  # (2,) m: the body's half length and half width
    height: float  # m: the body's height
    lead: float  # s: setpoint lead that cancels the x-y servos' lag at speed
    reach: float  # m a leg reaches down (the step-down limit and the legs' slack)
    corners: list[np.ndarray]  # each object's box corners (8, 3) in its own frame
    geom_object: np.ndarray  # (ngeom,) the object of each geom (-1: none)
    hit_object: np.ndarray  # (ngeom + 1,) the same, then -1: the object of a ray's hit geom (-1: none) read at it
    cloth: np.ndarray  # (nobject,) bool
    cloth_crossings: int  # the most recasts one ray cast needs: one per cloth link for every layer of cloth
    movable: np.ndarray  # (nobject,) bool
    bodies: np.ndarray  # (nobject, nbody) 1.0 where a body is the object's, else 0.0
    sums: ObjectSums  # sums over each object's bodies (``bodies``)
    fragile: np.ndarray  # (nobject,) bool
    not_robot: np.ndarray  # (nbody,) bool: bodies that are not the robot's
    robot_parts: np.ndarray  # the robot's bodies
    foot_parts: np.ndarray  # (len(robot_parts),) bool: which of them are feet
    parts: Parts  # the objects' parts that bear weight apart (a cloth's links)

    @classmethod
    def of(cls, scene: Scene, limits: QuadrupedLimits) -> SceneFacts:
        model = scene.model
        ids = BodyIds.of(model)
        geom_object = scene.body_object[model.geom_bodyid]
        cloth = np.array([o.shape == "cloth" for o in scene.task.objects], dtype=bool)
        bodies = (scene.body_object[None, :] == np.arange(len(scene.task.objects))[:, None]).astype(float)
        robot = np.flatnonzero(scene.robot_body)
        return cls(
            ids=ids,
            half=np.array(limits.body_size[:2]) / 2,
            height=limits.body_size[2],
            lead=ids.xy_kv / XY_KP,
            reach=limits.max_step_down + LEG_SLACK,
            corners=local_corners(scene),
            geom_object=geom_object,
            hit_object=np.append(geom_object, -1),
            cloth=cloth,
            cloth_crossings=int(cloth[geom_object[geom_object >= 0]].sum()) ** 2,
            movable=np.array([o.movable for o in scene.task.objects]),
            bodies=bodies,
            sums=ObjectSums.of(bodies),
            fragile=np.array([o.fragile is not None for o in scene.task.objects], dtype=bool),
            not_robot=~scene.robot_body,
            robot_parts=robot,
            foot_parts=np.isin(robot, ids.feet),
            parts=Parts.of(scene),
        )


class Senses:
    """The current batched state (``state``, set at every start and tick) and what the components read from it."""

    def __init__(self, sim: BatchedSim, facts: SceneFacts):
        self.sim, self.facts = sim, facts
        self.scene: Scene = sim.scene
        self.state: BatchState = sim.state()
        self._memo: tuple[BatchState | None, dict[Any, np.ndarray]] = (None, {})  # see of_state

    def position(self, w: int) -> np.ndarray:
        """The x-y of the body's slides (the servos' coordinates) in world ``w``."""
        return self.state.qpos[w, self.facts.ids.qpos[:2]].copy()

    def yaw(self, worlds: np.ndarray | int | slice = slice(None)) -> np.ndarray:
        """The body's heading (rad about z, 0: its length along x) in ``worlds`` (default: all)."""
        return self.state.qpos[worlds, self.facts.ids.yaw_qpos]

    def half_now(self, w: int) -> np.ndarray:
        """(2,) m: the x-y half sizes of the body's outline in world ``w`` as it is turned now (quarter turns)."""
        return self.facts.half[::-1].copy() if quarter_turns(self.yaw(w)) % 2 else self.facts.half.copy()

    def centers(self, state: BatchState) -> np.ndarray:
        """Object centres (nworld, nobject, 3), read-only: body origins; a cloth's is the mean of its links."""

        def compute() -> np.ndarray:
            out = state.xpos[:, self.scene.object_body].copy()
            for i in np.flatnonzero(self.facts.cloth):
                out[:, i] = state.xpos[:, self.scene.body_object == i].mean(axis=1)
            return out

        return self.of_state(state, "centres", compute)

    def of_state(self, state: BatchState, key: Any, compute: Callable[[], np.ndarray]) -> np.ndarray:
        """``compute()`` once per state (a tick and the skill starts that follow read the same one), read-only."""
        if self._memo[0] is not state:
            self._memo = (state, {})
        found = self._memo[1].get(key)
        if found is None:
            found = self._memo[1][key] = compute()
            found.flags.writeable = False
        return found

    def bounds3(self, w: int, index: int) -> tuple[np.ndarray, np.ndarray]:
        """World axis-aligned bounds of an object in world ``w``."""
        lo, hi = self.boxes(index)
        return lo[w], hi[w]

    def boxes(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """World axis-aligned bounds (nworld, 3) of an object in every world, read-only."""
        if self.facts.cloth[index]:
            center = self.centers(self.state)[:, index]
            half = np.asarray(self.scene.task.objects[index].size) / 2
            return center - half, center + half
        state, body, corners = self.state, self.scene.object_body[index], self.facts.corners
        found = self.of_state(state, ("corners", index), lambda: world_corners(state, body, corners[index]))
        lo = self.of_state(state, ("lo", index), lambda: found.min(axis=1))
        return lo, self.of_state(state, ("hi", index), lambda: found.max(axis=1))

    def frames(self) -> np.ndarray:
        """(nworld, nobject, 4) each object's orientation now (its body's unit quaternion, w first), read-only."""
        return self.of_state(self.state, "frames", lambda: self.state.xquat[:, self.scene.object_body].copy())

    def sweeps(self, worlds: np.ndarray, objects: np.ndarray, before: np.ndarray, least: float = 0.0) -> np.ndarray:
        """(k,) m the arc the farthest corner of object ``objects[i]`` in world ``worlds[i]`` has swept about the
        vertical as the object turned from orientation ``before[i]`` (a unit quaternion) to now: the vertical part of
        the turn's rotation vector times the corners' largest reach across. A plank swung round a post sweeps its
        ends far while its centre stays; a drum rolling about its level axis, or a board tipping, sweeps nothing. A turn
        of at most ``least`` (rad) sweeps nothing either."""
        out = np.zeros(len(worlds))
        now = quat_to_mat(self.frames()[worlds, objects])
        turn = now @ quat_to_mat(before).transpose(0, 2, 1)  # (k, 3, 3) from then to now, in world axes
        angle = np.arccos(np.clip((np.trace(turn, axis1=1, axis2=2) - 1) / 2, -1.0, 1.0))
        scale = np.where(np.sin(angle) > 1e-6, angle / (2 * np.sin(np.maximum(angle, 1e-6))), 0.5)
        about_z = np.abs(scale * (turn[:, 1, 0] - turn[:, 0, 1]))  # rad: the rotation vector's vertical part
        about_z[about_z <= least] = 0.0
        for o in np.unique(objects).tolist():
            rows = objects == o
            if not self.facts.cloth[o]:
                reach = np.linalg.norm(np.einsum("kij,cj->kci", now[rows], self.facts.corners[o])[:, :, :2], axis=2)
                out[rows] = about_z[rows] * reach.max(axis=1)
        return out

    def bounds(self, w: int, index: int) -> tuple[np.ndarray, np.ndarray]:
        """World axis-aligned x-y bounds of an object in world ``w``."""
        lo, hi = self.bounds3(w, index)
        return lo[:2], hi[:2]

    def mass(self, w: int, index: int) -> float:
        """World ``w``'s (perturbed) mass of object ``index``, all its bodies."""
        return float(self.sim.body_mass[w, self.scene.body_object == index].sum())

    def masses(self, worlds: np.ndarray) -> np.ndarray:
        """(k, nobject) each of ``worlds``' (perturbed) masses of every object, all its bodies (summed as
        :meth:`mass` sums them; read from the simulator each time: no state of its own)."""
        mass = self.sim.body_mass[worlds]
        return np.stack([mass[:, bodies].sum(axis=1) for bodies in self.facts.sums.bodies], axis=1)
