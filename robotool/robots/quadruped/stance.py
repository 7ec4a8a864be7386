"""The quadruped's stance when its goal is read: feet left on a slope steeper than the friction there holds would slide.

The simulated body stands on frictionless feet, held up and sideways by its world-anchored servos, so it stays put on
any slope; a real robot slides off one steeper than its feet's friction holds. Moves check the slopes on their way
(:func:`~.terrain.first_steep`), but not a slope the world turns under a robot standing still: a board tipping past
the drum it rests on as the robot walks past it leaves the robot on its short arm at 20 degrees, on lacquer that holds
15. So once the world has settled, under each foot that touches something, rays read the surface's slope around the
foot (across :data:`REACH` each way along x and along y, each way where both its points lie on the foot's geom: a foot
near a side edge reads the slope along it) and the friction the foot meets there (:meth:`~.rays.Rays.grip`, as the
world's perturbation scales it); a slope steeper than that holds (:func:`~.terrain.too_steep`) is a fall, with the
reason.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robotool.robots.quadruped.body import GRAVITY
from robotool.robots.quadruped.quadruped_config import QuadrupedConfig
from robotool.robots.quadruped.rays import Rays
from robotool.robots.quadruped.sensing import Senses
from robotool.robots.quadruped.support import feet, feet_touching
from robotool.robots.quadruped.terrain import FOOT_NAMES, too_steep
from robotool.rollout import Event
from robotool.sim.backend import BatchState

REACH = 0.04  # m each way from a foot's centre that its surface's slope is read across
SIDEWAYS_SLACK = 5.0  # N a sideways push on the settled body may pass the feet's grip by
AROUND = np.array([[REACH, 0.0], [-REACH, 0.0], [0.0, REACH], [0.0, -REACH]])  # where, about the foot's centre


@dataclass
class StanceState:
    """Per world: why the robot would slide off where it stood when its goal was read (None: it would not), and when
    (the world's time, NaN: not read)."""

    slid: list[str | None]
    time: np.ndarray

    @classmethod
    def empty(cls, nworld: int) -> StanceState:
        return cls(slid=[None] * nworld, time=np.full(nworld, np.nan))


class Stance:
    """Reads the robot's stance at the goal read (state: :class:`StanceState`)."""

    def __init__(self, senses: Senses, rays: Rays, config: QuadrupedConfig):
        self.senses, self.rays, self.config = senses, rays, config
        self.state = StanceState.empty(senses.sim.nworld)

    def read(self, state: BatchState, worlds: list[int]) -> None:
        """Read, in ``worlds`` (settled), whether a foot stands on a slope steeper than its friction holds, or movable
        objects push the body sideways harder than the feet's friction could hold it."""
        if not worlds:
            return
        w = np.asarray(worlds, dtype=int)
        ids = self.senses.facts.ids
        centres = feet(state, ids)[w]  # (k, 4, 3)
        touching = feet_touching(state, ids, self.senses.facts.not_robot)[w]
        xy = centres[:, :, None, :2] + AROUND  # (k, 4, 4, 2)
        top = centres[:, :, 2].max(axis=1) + self.config.ray_height
        read = self.rays.surface(w, np.concatenate([centres[:, :, None, :2], xy], axis=2).reshape(len(w), -1, 2), top)
        z, _, geom, cloth = (a.reshape(len(w), 4, 5) for a in read)
        same = geom == geom[:, :, :1]  # (k, 4, 5): on the foot's own geom
        pairs = np.stack([same[:, :, 1] & same[:, :, 2], same[:, :, 3] & same[:, :, 4]], axis=2)  # along x, along y
        rise = np.stack([z[:, :, 1] - z[:, :, 2], z[:, :, 3] - z[:, :, 4]], axis=2) / (2 * REACH)
        read = pairs.any(axis=2) & (geom[:, :, 0] >= 0) & touching  # a foot near a side edge reads the other way
        tangent = np.where(read, np.linalg.norm(np.where(pairs, rise, 0.0), axis=2), np.nan)
        friction = self.rays.friction(w, self.rays.grip(geom[:, :, 0], cloth[:, :, 0]))
        over, angle, holds = too_steep(tangent, friction)
        for k, world in enumerate(w.tolist()):
            if not over[k].any() or self.state.slid[world] is not None:
                continue
            foot = int(np.argmax(np.where(over[k], angle[k] - holds[k], -np.inf)))
            self.state.slid[world] = (
                f"it stood where it would slide: a slope of {angle[k, foot]:.1f} deg under its {FOOT_NAMES[foot]} "
                f"foot, on {self.rays.surface_name(int(geom[k, foot, 0]))}, exceeds the {holds[k, foot]:.1f} deg "
                "its friction holds"
            )
            self.state.time[world] = float(state.time[world])
        self._pushed_sideways(state, w, np.where(touching, friction, np.nan))  # where no slope said so

    def _pushed_sideways(self, state: BatchState, worlds: np.ndarray, friction: np.ndarray) -> None:
        """Where movable objects push the settled body sideways (their contacts' forces on its bodies, summed across)
        harder than its weight on its feet's friction could hold it, it would slide (found by an adversarial run: a
        25 kg plank leaning on the robot's side pushed it 65-77 N sideways, on a stage whose friction holds 46 N, and
        the world-anchored servos held it)."""
        sim, scene = self.senses.sim, self.senses.scene
        movable = (scene.body_object >= 0) & np.asarray(self.senses.facts.movable)[np.maximum(scene.body_object, 0)]
        pushed = sim.contact_forces(worlds, movable)[:, scene.robot_body, :2].sum(axis=1)  # (k, 2)
        weight = sim.body_mass[worlds][:, scene.robot_body].sum(axis=1) * GRAVITY
        grip = weight * np.nanmean(np.where(np.isnan(friction).all(axis=1, keepdims=True), 0.0, friction), axis=1)
        force = np.linalg.norm(pushed, axis=1)
        for k, world in enumerate(worlds.tolist()):
            if force[k] > grip[k] + SIDEWAYS_SLACK and self.state.slid[world] is None:
                self.state.slid[world] = (
                    f"it stood where it would slide: something pushed it {force[k]:.0f} N sideways, more than the "
                    f"{grip[k]:.0f} N its feet's friction holds"
                )
                self.state.time[world] = float(state.time[world])

    def holds(self) -> list[bool]:
        """Per world: the robot would not slide off where it stood when its goal was read."""
        return [slid is None for slid in self.state.slid]

    def events(self, world: int) -> list[Event]:
        """The robot's fall off a slope in one world, if it would slide."""
        reason = self.state.slid[world]
        if reason is None:
            return []
        return [Event(kind="fell", time=float(self.state.time[world]), detail=reason)]
