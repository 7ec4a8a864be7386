"""The quadruped's push rules, checked when a push starts and as each push leg starts: what a push of an object would
move (the object, what rides on it and what is stuck to it) and whether the robot may push it from where it stands
(:func:`~.push.rule_violation`); the referee also weighs what a push carries while it moves."""

from __future__ import annotations

import numpy as np

from robotool.robots.quadruped.body import GRAVITY
from robotool.robots.quadruped.push import mass_violation, rule_violation
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.rays import Rays
from robotool.robots.quadruped.sensing import Senses
from robotool.robots.quadruped.support import bears_up, feet
from robotool.robots.quadruped.terrain import RISE
from robotool.sim.magnets import Magnets


class PushRules:
    """Weighs pushes in the worlds of one batched simulator (no state of its own)."""

    def __init__(self, senses: Senses, rays: Rays, limits: QuadrupedLimits, magnets: Magnets):
        self.senses, self.rays, self.limits, self.magnets = senses, rays, limits, magnets
        self.facts, self.scene = senses.facts, senses.scene

    def push_rules(self, w: int, index: int) -> tuple[str, dict[str, float]] | None:
        """Check the push rules in world ``w`` from rays under the feet and the object, and the masses it moves; then
        whether the feet can hold the push (:meth:`grip_rule`)."""
        names = self.scene.object_names
        z, objects, feet_on = self._feet_surface(w)
        on = objects[z >= z.max() - RISE]
        on = on[on >= 0]
        movable = next((names[o] for o in on if self.facts.movable[o]), None)
        below, support = self._support(w, index)
        mass, riders, stuck = self._load(w, index)
        broken = rule_violation(
            movable=bool(self.facts.movable[index]),
            mass=mass,
            riders=riders,
            stuck=stuck,
            under_robot=bool(np.isin(index, on)),
            robot_support_movable=movable,
            object_support=float(below.max()),
            robot_support=float(z.max()),
            limits=self.limits,
        )
        return broken or self._grip(w, index, mass, support, feet_on)

    def load_rule(self, w: int, index: int) -> tuple[str, dict[str, float]] | None:
        """Check the push limit alone in world ``w`` as a push leg of object ``index`` starts: what rides on it or is
        stuck to it may have come since the push rules were checked (an anvil that slid onto a sled during the walk
        to the push's start rides along)."""
        return mass_violation(*self._load(w, index), self.limits)

    def leg_rules(self, w: int, index: int) -> tuple[str, dict[str, float]] | None:
        """Check, as a push leg of object ``index`` starts in world ``w``, the push limit (as :meth:`load_rule`) and
        that the friction under the robot's feet holds the push's reaction (:meth:`_grip`): the robot may have walked
        onto another surface since the push rules were checked, and what rides on the object may have changed."""
        load = self._load(w, index)
        heavy = mass_violation(*load, self.limits)
        return heavy or self._grip(w, index, load[0], self._support(w, index)[1], self._feet_surface(w)[2])

    def _grip(
        self, w: int, index: int, mass: float, support: int, feet_on: np.ndarray
    ) -> tuple[str, dict[str, float]] | None:
        """Whether the robot's feet hold a push of object ``index`` in world ``w``: the push must slide ``mass`` (kg:
        the object with what rides on it or is stuck to it) on the geom ``support`` under it (-1: none), which takes
        its weight times the friction between them (the larger of the two geoms', as the simulator combines them); the
        feet (frictionless in the simulation: the x-y servos push from the world) hold the robot's weight times the
        friction under them (each foot a quarter of it, on the geom ``feet_on`` (4,) under it). Frictions as the
        world's perturbation scales them. A push that takes more is refused: on that footing the feet, not the object,
        would slide."""
        world = np.array([w])
        friction = self.sliding_friction(w, index, support)
        force = mass * GRAVITY * friction
        robot = float(self.senses.sim.body_mass[w, self.scene.robot_body].sum())
        grip = self.rays.friction(world, feet_on[None])[0]
        holds = robot * GRAVITY * float(grip.mean())
        if force <= holds:
            return None
        floor = self.rays.surface_name(int(feet_on[np.argmin(grip)]))
        return (
            f"sliding it takes {force:.1f} N ({mass:.1f} kg on {self.rays.surface_name(support)} at friction "
            f"{friction:.3g}), more than the {holds:.1f} N the robot's feet hold ({robot:.1f} kg on {floor} at "
            f"friction {grip.mean():.3g}): its feet would slip",
            {"force": round(force, 2), "limit": round(holds, 2), "friction": round(float(grip.mean()), 4)},
        )

    def sliding_friction(self, w: int, index: int, support: int | None = None) -> float:
        """The friction object ``index`` slides at in world ``w`` on the geom ``support`` under it (-1: none; None:
        read it, :meth:`_support`): the larger of the two geoms', as the simulator combines them, as the world's
        perturbation scales them."""
        support = self._support(w, index)[1] if support is None else support
        world = np.array([w])
        own = self.rays.friction(world, np.flatnonzero(self.facts.geom_object == index)[None]).max()
        return float(max(own, self.rays.friction(world, np.array([[support]]))[0, 0]))

    def _feet_surface(self, w: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Under the robot's feet in world ``w``: the heights (4,), the objects (-1: none) and the geoms (-1: none)."""
        centres = feet(self.senses.state, self.facts.ids)[w]
        top = np.array([float(centres[:, 2].max()) + 0.05])
        z, _, geoms = self.rays.surface(np.array([w]), centres[None, :, :2], top)
        return z[0], self.rays.objects_of(geoms[0]), geoms[0]

    def _support(self, w: int, index: int) -> tuple[np.ndarray, int]:
        """What object ``index`` rests on in world ``w``: the heights under it (:meth:`_under`) and the geom of the
        highest (-1: none)."""
        _, obj_hi = self.senses.bounds3(w, index)
        points = self._under(w, index)
        below, _, geoms = self.rays.surface(
            np.array([w]), points[None], np.array([obj_hi[2] + 0.01]), self.scene.object_body[index]
        )
        return below[0], int(geoms[0, np.argmax(below[0])])

    def _load(self, w: int, index: int) -> tuple[float, list[str], list[str]]:
        """What a push of object ``index`` in world ``w`` moves: its mass (kg) with its riders and what is stuck to
        it (:meth:`_carried`), and their names."""
        names = self.scene.object_names
        riders, stuck = self._carried(w, index)
        mass = float(sum(self.senses.mass(w, o) for o in [index, *riders, *stuck]))
        return round(mass, 3), [names[o] for o in riders], [names[o] for o in stuck]

    def _under(self, w: int, index: int) -> np.ndarray:
        """(n, 2) where object ``index`` rests in world ``w``, as the push rules read its support: under each of its
        parts' centres (an L's handle lies on a shelf while its head sticks out over the floor, and the centre of the
        box around it lies in its crook, in the air), or under its centre for a cloth (its links drape)."""
        if self.facts.cloth[index]:
            lo, hi = self.senses.bounds3(w, index)
            return ((lo + hi) / 2)[None, :2]
        xpos, _ = self.senses.sim.geom_poses(np.array([w]))
        return xpos[w, self.facts.geom_object == index, :2]

    def loaded(self, w: int, index: int) -> bool:
        """Whether another object lies on object ``index`` in world ``w``, borne up by it at least in part (a board's
        raised end resting on a chair, though the board also rests on its fulcrum): its weight on part of the top
        drags on that part as the object is pushed."""
        owner = self.scene.body_object
        mine = owner == index
        normals = self.senses.sim.contact_normals(w)  # (nbody, nbody, 3) from one body onto another
        touching = self.senses.state.touching[w][mine].any(axis=0) & (owner >= 0) & ~mine
        return any((self._bearing(normals, other) & mine).any() for other in np.unique(owner[touching]))

    def _bearing(self, normals: np.ndarray, index: int) -> np.ndarray:
        """(nbody,) the bodies that press up on object ``index`` (``normals``: a world's contact normals)."""
        return bears_up(normals[:, self.scene.body_object == index].sum(axis=1))

    def _carried(self, w: int, index: int) -> tuple[list[int], list[int]]:
        """The movable objects a push of object ``index`` in world ``w`` carries along: those that ride on it and
        those stuck to it (a magnet's weld), recursively, each list without the other's.

        Riders are borne up by nothing else (but the robot): every body whose contacts press up on them
        (:func:`~.support.bears_up`) is the pushed object's or a rider's; what only touches a side, or lies on top,
        bears none of their weight. Where their centres lie does not matter (a crate on the tray of an upright L lies
        lower than the L's centre). What lies on a rider rides too, and what is stuck to what the push moves goes
        with it, whatever bears it up (a slab under a pushed magnetic block is dragged along). A cloth is limp: each
        of its links is borne up apart, and one that lies on what the push moves only carries what lies on it along
        (a crate on a cloth whose far end hangs off the pushed pallet onto the floor rides the pallet); a cloth rides
        when all its links do."""
        owner, cloth = self.scene.body_object, self.facts.cloth
        normals = self.senses.sim.contact_normals(w)  # (nbody, nbody, 3) from one body onto another
        touching = self.senses.state.touching[w]
        movable = (owner >= 0) & self.facts.movable[np.maximum(owner, 0)]
        links = movable & cloth[np.maximum(owner, 0)]
        welds = [(b1, b2) for eq, b1, b2 in self.magnets.pairs if self.senses.state.eq_active[w, eq]]
        moved = owner == index  # the bodies the push moves: the object's, its riders' and the links lying on them
        stuck = np.zeros(len(owner), dtype=bool)
        grown = True
        while grown:
            grown = False
            for b1, b2 in welds:
                if moved[b1] != moved[b2]:
                    other = owner == owner[b2 if moved[b1] else b1]
                    moved |= other
                    stuck |= other
                    grown = True
            near = touching[moved].any(axis=0) & ~moved & movable
            for part in [
                *(np.arange(len(owner)) == b for b in np.flatnonzero(near & links)),
                *(owner == o for o in np.unique(owner[near & ~links])),
            ]:
                bearing = bears_up(normals[:, part].sum(axis=1))  # pressing up on it
                supports = touching[part].any(axis=0) & ~self.scene.robot_body & (owner != owner[part][0]) & bearing
                if np.all(moved[supports]):  # it rests on what the push moves only
                    moved |= part
                    grown = True
        along = [int(o) for o in np.unique(owner[moved]) if o != index and np.all(moved[owner == o])]
        return [o for o in along if not stuck[owner == o].any()], [o for o in along if stuck[owner == o].any()]
