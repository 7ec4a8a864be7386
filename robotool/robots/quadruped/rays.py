"""Downward rays for the quadruped controller: surface heights and the geoms and objects that carry them, in many
worlds at once through the simulator's batched ray cast (:meth:`~robotool.sim.backend.BatchedSim.rays`); a cloth
carries no load over a gap, so rays see through it to what carries it, and tell which cloth links they passed through:
what lies on a cloth meets the cloth's friction."""

from __future__ import annotations

import numpy as np

from robotool.robots.quadruped.body import ROBOT_GROUP
from robotool.robots.quadruped.quadruped_config import QuadrupedConfig
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.sensing import SceneFacts
from robotool.sim.backend import BatchedSim
from robotool.sim.build import contact_friction


class Rays:
    """Casts downward rays in the worlds of one batched simulator (no state of its own)."""

    def __init__(self, sim: BatchedSim, limits: QuadrupedLimits, facts: SceneFacts, config: QuadrupedConfig):
        self.sim, self.limits, self.facts, self.config = sim, limits, facts, config

    def heights(self, w: int, xy: np.ndarray, top: float, exclude: int = -1) -> tuple[np.ndarray, np.ndarray]:
        """Surface heights and hit objects (-1: ground or nothing) under points ``xy`` in world ``w``."""
        z, objects = self.cast(np.array([w]), xy[None], np.array([top]), exclude)
        return z[0], objects[0]

    def cast(
        self, worlds: np.ndarray, xy: np.ndarray, top: np.ndarray, exclude: int = -1
    ) -> tuple[np.ndarray, np.ndarray]:
        """Downward rays from height ``top`` (per world) over ``xy`` (k, nray, 2) in ``worlds``: surface heights
        and the objects that carry them (-1: ground or nothing); the robot is never hit (see :meth:`surface`)."""
        z, _, geom, _ = self.surface(worlds, xy, top, exclude)
        return z, self.objects_of(geom)

    def surface(
        self, worlds: np.ndarray, xy: np.ndarray, top: np.ndarray, exclude: int = -1
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Downward rays from height ``top`` (per world) over ``xy`` (k, nray, 2) in ``worlds``: the heights the feet
        stand at, the heights of the solids that carry them, those solids' geoms (-1: nothing) and the geoms of the
        most slippery cloth links lying on them that the rays passed through (-1: none; see :meth:`grip`); the robot
        is never hit.

        A cloth is limp: it carries no load over a gap, whichever way it lies. A ray that meets a cloth's link is
        cast again from just above the point it met, that link left out, until it meets something solid, which is
        the geom returned; the feet's height is the cloth's where that solid lies no deeper under it than a step the
        legs climb (a cloth lying on a surface, or bunched up on it, is stepped onto), else the solid's (over a gap
        the feet would sink to it)."""
        start = np.asarray(top, dtype=float)[:, None]
        z, geom = self._cast_from(worlds, xy, start, exclude)
        if not self.facts.cloth_crossings:  # no cloth in the scene
            return z, z, geom, np.full(geom.shape, -1)
        model = self.sim.scene.model
        through = self._on_cloth(geom)
        cloth_top = np.where(through, z, np.nan)
        slick = np.where(through, geom, -1)
        for _ in range(self.facts.cloth_crossings):  # each ray's recasts are its own: every ray on any link at once
            if not through.any():
                break
            rows = np.flatnonzero(through.any(axis=1))
            count = through[rows].sum(axis=1)
            first = np.argsort(~through[rows], axis=1, kind="stable")[:, : count.max()]  # each row's rays to redo first
            redo = np.where(np.arange(first.shape[1])[None, :] < count[:, None], first, first[:, :1])  # padded
            z_again, geom_again = self._cast_from(
                worlds[rows],
                np.take_along_axis(xy[rows], redo[:, :, None], axis=1),
                np.take_along_axis(z[rows], redo, axis=1) + self.config.cloth_step,
                model.geom_bodyid[np.take_along_axis(geom[rows], redo, axis=1)],  # each ray leaves its link out
            )
            z[rows[:, None], redo], geom[rows[:, None], redo] = z_again, geom_again
            through = self._on_cloth(geom)
            slick = np.where(through & ((slick < 0) | (self._raw(geom) < self._raw(slick))), geom, slick)
        lying = cloth_top - z <= self.limits.max_step_up  # False where no cloth was met (NaN)
        return np.where(lying, cloth_top, z), z, geom, np.where(lying, slick, -1)

    def objects_of(self, geom: np.ndarray) -> np.ndarray:
        """The object each ray's hit geom (-1: none) belongs to (-1: none, or not an object's)."""
        return self.facts.hit_object[geom]

    def surface_name(self, geom: int) -> str:
        """What a ray's hit geom (-1: none) is: its object's name, the ground (no object's geom) or nothing."""
        if geom < 0:
            return "nothing"
        thing = int(self.facts.geom_object[geom])
        return self.sim.scene.object_names[thing] if thing >= 0 else "the ground"

    def friction(self, worlds: np.ndarray, geom: np.ndarray) -> np.ndarray:
        """The sliding friction of the hit geoms ``geom`` (k, ...) (-1: none, 0) in ``worlds`` (k,), as each world's
        perturbation scales it."""
        scale = self.sim.friction_scale[worlds].reshape(-1, *([1] * (geom.ndim - 1)))
        return self._raw(geom) * scale

    def grip(self, geom: np.ndarray, cloth: np.ndarray) -> np.ndarray:
        """The geoms whose friction the feet meet where rays hit the solids ``geom`` through the cloth links ``cloth``
        (-1: none; :meth:`surface`): a foot grips a cloth at the cloth's friction, and the cloth, lying on the solid,
        slides on it; the most slippery of them sets what the feet hold."""
        if not self.facts.cloth_crossings:  # no cloth in the scene
            return geom
        return np.where((cloth >= 0) & (self._raw(cloth) < self._raw(geom)), cloth, geom)

    def sliding(self, worlds: np.ndarray, own: float, geom: np.ndarray, cloth: np.ndarray) -> np.ndarray:
        """The friction an object whose geoms' largest friction is ``own`` (as the perturbation scales it) slides at
        on the solids ``geom`` (k, ...) under it in ``worlds`` (k,), through the cloth links ``cloth`` (-1: none;
        :meth:`surface`): each pair at :func:`~robotool.sim.build.contact_friction` of its two frictions, as the
        simulator combines them; on a cloth, the object slides on the cloth or the cloth with it on the solid,
        whichever slides first."""
        scale = self.sim.friction_scale[worlds].reshape(-1, *([1] * (geom.ndim - 1)))
        mine = own / scale  # as declared, as the pair rule reads frictions; where nothing is hit, its own
        solid, limp = np.where(geom >= 0, self._raw(geom), mine), self._raw(cloth)
        on_cloth = np.minimum(contact_friction(mine, limp), contact_friction(limp, solid))
        return np.where(cloth >= 0, on_cloth, contact_friction(mine, solid)) * scale

    def _raw(self, geom: np.ndarray) -> np.ndarray:
        """The unscaled friction of geoms ``geom`` (-1: none, 0)."""
        return np.where(geom >= 0, self.sim.scene.model.geom_friction[np.maximum(geom, 0), 0], 0.0)

    def _on_cloth(self, geom: np.ndarray) -> np.ndarray:
        """Whether each ray's hit geom (-1: none) belongs to a cloth."""
        objects = self.objects_of(geom)
        return (objects >= 0) & self.facts.cloth[np.maximum(objects, 0)]

    def _cast_from(
        self, worlds: np.ndarray, xy: np.ndarray, start: np.ndarray, exclude: int | np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Downward rays from heights ``start`` ((k, nray), or (k, 1): one per world) over ``xy`` (k, nray, 2) in
        ``worlds``, the robot and body ``exclude`` (one for all rays, or (k, nray): each ray's own) left out: surface
        heights (0 where nothing is hit) and the geoms hit (-1: none). A ray that starts inside a geom (a wall taller
        than the rays' start) would meet it where it leaves it, at its bottom: it reads that geom at the ray's start
        instead (``from_inside``), something at least that high."""
        pnt = np.empty((*xy.shape[:2], 3))
        pnt[..., :2] = xy
        pnt[..., 2] = start
        vec = np.zeros(pnt.shape)
        vec[..., 2] = -1.0
        dist, geom = self.sim.rays(worlds, pnt, vec, exclude_body=exclude, skip_group=ROBOT_GROUP, from_inside=True)
        return np.where(np.isfinite(dist), start - dist, 0.0), geom
