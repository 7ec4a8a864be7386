"""Solids stay apart: an object that passes through another fails the world.

The simulator's contacts are soft: a body that arrives fast sinks into what it meets, by about its speed times the
contact's time constant, before the contact stops it. So a 1 cm rod dropped 0.33 m onto a fixed 2 cm board came out
under it, and a 2 mm rod let go 1 cm above a steel plate a few millimetres thick passed through it (found by an
adversarial run: the rod ended on the floor under a table top that covers all the floor within reach, and a
``lowered`` goal read it there). Nothing solid passes through a solid, so the world fails, whatever the goal.

It is read from the centres of the geoms of the rigid movable objects (a centre always lies inside its own solid),
between two readings of the goal (every control tick, and every physics step where a goal is watched), in the frame
of every box or cylinder of another object (fixed or movable, a cloth's links left out). A centre that was on one side
of the middle of a box, straight over one of its faces, and is now on the other side, still over that face, has passed
through it (or half into it): a centre never lies inside another solid, and any real way round the solid leaves its
shadow over the face. So has one that crossed a cylinder's caps so, or its round side: across the plane through its
axis square to the centre's way, nearer the axis than the radius, within its length (found by an adversarial run: a
deck of steel bars lying side by side let the rod through as the table top had). The first passage of each world is
kept as a ``passed_through`` event.
"""

from __future__ import annotations

import mujoco
import numpy as np

from robotool.rollout import Event
from robotool.sim.backend import BatchState
from robotool.sim.compiled_scene import Scene
from robotool.sim.strikes import GeomFrames, geom_half_sizes

CONDITION = "nothing_passed_through"
"""The sub-condition every goal gets where the scene has something that could pass through something else."""


class PassageWatch:
    """Follows the geom centres of the scene's rigid movable objects through the box-shaped solids of the others."""

    def __init__(self, scene: Scene):
        model, owner, objects = scene.model, scene.body_object, scene.task.objects
        geom_owner = owner[model.geom_bodyid]
        rigid = np.array([o.shape != "cloth" for o in objects])
        movable = np.array([o.movable for o in objects])
        solid = (geom_owner >= 0) & rigid[np.maximum(geom_owner, 0)] & (model.geom_rbound > 0)
        kind = model.geom_type
        box, cylinder = kind == int(mujoco.mjtGeom.mjGEOM_BOX), kind == int(mujoco.mjtGeom.mjGEOM_CYLINDER)
        self.movers = np.flatnonzero(solid & movable[np.maximum(geom_owner, 0)])
        self.walls = np.flatnonzero(solid & (box | cylinder))
        self.half = geom_half_sizes(model)[self.walls]  # a cylinder's: its radius twice, its half-length
        self.round = cylinder[self.walls]  # a cylinder: passed through its caps only, inside its circle
        self.apart = geom_owner[self.movers][:, None] != geom_owner[self.walls][None, :]  # (mover, wall)
        self.mover_frames, self.wall_frames = GeomFrames.of(model, self.movers), GeomFrames.of(model, self.walls)
        self.names = [o.name for o in objects]
        self.mover_owner, self.wall_owner = geom_owner[self.movers], geom_owner[self.walls]
        self._before: np.ndarray | None = None  # (nworld, mover, wall, 3): each centre in each wall's frame
        self.passed: np.ndarray | None = None
        self.passages: dict[int, Event] = {}

    def __bool__(self) -> bool:
        """Whether the scene has something that could pass through something else."""
        return bool(self.apart.any())

    def update(self, state: BatchState, active: np.ndarray) -> None:
        """Read the ``active`` worlds: a centre that has passed through a solid since the last reading fails its
        world."""
        now = self._in_walls(state)
        if self._before is None or self.passed is None:
            self._before, self.passed = now, np.zeros(len(state.time), dtype=bool)
            return
        through = active[:, None, None] & self._through(self._before, now) & self.apart[None]
        for w in map(int, np.flatnonzero(through.any(axis=(1, 2)) & ~self.passed)):
            mover, wall = (int(k[0]) for k in np.nonzero(through[w]))
            self.passed[w] = True
            self.passages[w] = Event(
                kind="passed_through",
                time=float(state.time[w]),
                object=self.names[self.mover_owner[mover]],
                detail=self.names[self.wall_owner[wall]],
            )
        self._before = np.where(active[:, None, None, None], now, self._before)

    def kept_apart(self, nworld: int) -> np.ndarray:
        """(nworld,) bool: the worlds in which nothing has passed through anything."""
        return ~self.passed if self.passed is not None else np.ones(nworld, dtype=bool)

    def events(self, world: int) -> list[Event]:
        """The world's ``passed_through`` event, if something passed through something."""
        event = self.passages.get(world)
        return [] if event is None else [event]

    def _in_walls(self, state: BatchState) -> np.ndarray:
        """(nworld, mover, wall, 3) each mover's centre in each wall's frame (its centre the origin)."""
        centre = self.mover_frames.centres(state)
        wall_centre, wall_frame = self.wall_frames.poses(state)
        offset = centre[:, :, None, :] - wall_centre[:, None, :, :]
        return np.einsum("wkji,wmkj->wmki", wall_frame, offset)

    def _through(self, before: np.ndarray, now: np.ndarray) -> np.ndarray:
        """(nworld, mover, wall) the centres that crossed the middle of a wall from one side to the other, over one of
        its faces both before and now."""
        crossed = before * now < 0.0  # from one side of its middle to the other, along each of its axes
        half = self.half[None, None]
        through = np.zeros(crossed.shape[:3], dtype=bool)
        if crossed.any():  # (on most readings nothing crosses a middle: then nothing passed a face)
            inside = (np.abs(before) < half) & (np.abs(now) < half)  # (nworld, mover, wall, 3): over the wall twice
            through = (
                (crossed[..., 0] & inside[..., 1] & inside[..., 2])
                | (crossed[..., 1] & inside[..., 0] & inside[..., 2])
                | (crossed[..., 2] & inside[..., 0] & inside[..., 1])
            )
            if self.round.any():  # a cylinder: through its caps, over its circle,
                capped = crossed[..., 2] & (np.hypot(before[..., 0], before[..., 1]) < half[..., 0])
                capped &= np.hypot(now[..., 0], now[..., 1]) < half[..., 0]
                through = np.where(self.round[None, None], capped, through)
        if self.round.any():
            through |= self.round[None, None] & self._across(before, now, half[..., 0], half[..., 2])
        return through

    @staticmethod
    def _across(before: np.ndarray, now: np.ndarray, radius: np.ndarray, length: np.ndarray) -> np.ndarray:
        """(nworld, mover, wall) the centres that crossed a cylinder through its round side, within its half-length
        ``length`` (before and now): across the plane through its axis square to their way, nearer the axis than its
        ``radius``."""
        way = now[..., :2] - before[..., :2]
        crossed = ((before[..., :2] * way).sum(axis=-1) < 0.0) & ((now[..., :2] * way).sum(axis=-1) > 0.0)
        if not crossed.any():
            return crossed
        along = (np.abs(before[..., 2]) < length) & (np.abs(now[..., 2]) < length)
        way_length = np.maximum(np.hypot(way[..., 0], way[..., 1]), 1e-12)
        off_axis = np.abs(before[..., 0] * way[..., 1] - before[..., 1] * way[..., 0]) / way_length
        return crossed & (off_axis < radius) & along
