"""The quadruped's push rules, checked when a push starts and as each push leg starts: what a push of an object would
move (the object, what rides on it and what is stuck to it) and whether the robot may push it from where it stands
(:func:`~.push.rule_violation`); the referee also weighs what a push carries, and reads what the robot stands on,
while it moves."""

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

FOOTPRINT = 4  # points a side of the grid under each of a pushed object's parts where its friction is read
BORNE = 0.5  # N: what bears another object up by less bears none of it


class PushRules:
    """Weighs pushes in the worlds of one batched simulator (no state of its own)."""

    def __init__(self, senses: Senses, rays: Rays, limits: QuadrupedLimits, magnets: Magnets):
        self.senses, self.rays, self.limits, self.magnets = senses, rays, limits, magnets
        self.facts, self.scene = senses.facts, senses.scene

    def push_rules(self, w: int, index: int) -> tuple[str, dict[str, float]] | None:
        """Check the push rules in world ``w`` from rays under the feet and the object, and the masses it moves; then
        whether the feet can hold the push (:meth:`grip_rule`)."""
        z, objects, feet_on = self._feet_surface(w)
        on = _stood_on(z[None], objects[None])[0]
        movable = next((self.scene.object_names[o] for o in on if o >= 0 and self.facts.movable[o]), None)
        below, support, friction = self._support(w, index)
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
        return broken or self._grip(w, index, mass, support, friction, feet_on)

    def load_rule(self, w: int, index: int) -> tuple[str, dict[str, float]] | None:
        """Check the push limit alone in world ``w`` as a push leg of object ``index`` starts: what rides on it or is
        stuck to it may have come since the push rules were checked (an anvil that slid onto a sled during the walk
        to the push's start rides along)."""
        return mass_violation(*self._load(w, index), self.limits)

    def footing(self, worlds: np.ndarray, pushed: np.ndarray) -> dict[int, str]:
        """World -> the rule broken, in those of ``worlds`` (k,) where a push of object ``pushed`` (k,) runs and the
        robot stands on a movable object now: it pushes only from the ground or a fixed object (:meth:`push_rules`),
        also after it walked onto something else along the push."""
        if worlds.size == 0:
            return {}
        z, objects, _ = self._feet_surfaces(worlds)
        on = _stood_on(z, objects)
        movable = (on >= 0) & self.facts.movable[np.maximum(on, 0)]
        broken = {}
        for k in np.flatnonzero(movable.any(axis=1)).tolist():
            name, own = self.scene.object_names[pushed[k]], on[k, movable[k]]
            why = "it" if pushed[k] in own else f"{self.scene.object_names[own[0]]}, which is movable,"
            broken[int(worlds[k])] = f"cannot push {name}: the robot came to stand on {why} while pushing"
        return broken

    def _grip(
        self, w: int, index: int, mass: float, support: int, friction: float, feet_on: np.ndarray
    ) -> tuple[str, dict[str, float]] | None:
        """Whether the robot's feet hold a push of object ``index`` in world ``w``: the push must slide ``mass`` (kg:
        the object with what rides on it or is stuck to it) on its support (the geom ``support`` it rests on most,
        -1: none), which takes its weight times the ``friction`` between them (:meth:`_support`), and drag what it
        bears up in part (:meth:`_drag`); the feet hold :meth:`feet_hold`. A push that takes more is refused: on
        that footing the feet, not the object, would slide."""
        drag, dragged = self._drag(w, self._borne(w, index), friction)
        force = mass * GRAVITY * friction + drag
        robot, holds, floor, grip = self.feet_hold(w, feet_on)
        if force <= holds:
            return None
        also = f", and {drag:.1f} N to drag {', '.join(dragged)}" if dragged else ""
        return (
            f"sliding it takes {force:.1f} N ({mass:.1f} kg on {self.rays.surface_name(support)} at friction "
            f"{friction:.3g}{also}), more than the {holds:.1f} N the robot's feet hold ({robot:.1f} kg on {floor} at "
            f"friction {grip:.3g}): its feet would slip",
            {"force": round(force, 2), "limit": round(holds, 2), "friction": round(grip, 4)},
        )

    def sliding_force(self, w: int, index: int) -> tuple[float, float, list[str]]:
        """What sliding object ``index`` in world ``w`` takes now (N: what it moves slid on its support, and what it
        bears up in part dragged, as :meth:`_grip` reads them), the part of it that drags, and what it drags; (0, 0, [])
        when it drags nothing (its support is then not read: the rays cost)."""
        borne = self._borne(w, index)
        if not borne:
            return 0.0, 0.0, []
        _, _, friction = self._support(w, index)
        drag, dragged = self._drag(w, borne, friction)
        return self._load(w, index)[0] * GRAVITY * friction + drag, drag, dragged

    def _borne(self, w: int, index: int) -> list[tuple[int, float]]:
        """Each movable object that what a push of object ``index`` in world ``w`` moves (:meth:`_carried`) bears up in
        part (an anvil lying partly on a pushed sled, partly on a fixed rail), with the force (N) it bears it up by,
        read from the solver's contact forces."""
        owner = self.scene.body_object
        moved = np.isin(owner, [index, *(o for part in self._carried(w, index) for o in part)])
        up = self.senses.sim.contact_forces(np.array([w]), moved)[0, :, 2]  # N each body is borne up by the moved
        movable = (owner >= 0) & self.facts.movable[np.maximum(owner, 0)] & ~self.scene.robot_body
        objects = np.unique(owner[movable & ~moved & (up > BORNE)]).tolist()
        return [(o, float(up[owner == o].clip(min=0.0).sum())) for o in objects]

    def _drag(self, w: int, borne: list[tuple[int, float]], friction: float) -> tuple[float, list[str]]:
        """The force (N) a push in world ``w`` takes beyond sliding what it moves at ``friction``, and the names of
        what adds it: each object ``borne`` up in part (:meth:`_borne`) is pressed onto what the push moves with the
        force it bears there (which loads the push at ``friction``), and is dragged along until it slides on it or its
        other supports slide under it, whichever takes less (at its own friction, the least either pair has)."""
        drag, dragged = 0.0, []
        for o, share in borne:
            rest = max(self.senses.mass(w, o) * GRAVITY - share, 0.0)
            drag += share * friction + min(share, rest) * self._own_friction(w, o)
            dragged.append(self.scene.object_names[o])
        return drag, dragged

    def feet_hold(self, w: int, feet_on: np.ndarray | None = None) -> tuple[float, float, str, float]:
        """What the robot's feet hold in world ``w`` (frictionless in the simulation: the x-y servos push from the
        world): its mass (kg), the force (N: its weight times the friction under the feet, each foot a quarter of it,
        on the geoms ``feet_on`` (4,) whose friction it meets, :meth:`_feet_surface`; None: read them), the name of
        the most slippery surface under them and their mean friction, as the world's perturbation scales it."""
        feet_on = self._feet_surface(w)[2] if feet_on is None else feet_on
        robot = float(self.senses.sim.body_mass[w, self.scene.robot_body].sum())
        grip = self.rays.friction(np.array([w]), feet_on[None])[0]
        floor = self.rays.surface_name(int(feet_on[np.argmin(grip)]))
        return robot, robot * GRAVITY * float(grip.mean()), floor, float(grip.mean())

    def feet_holds(self, worlds: np.ndarray) -> np.ndarray:
        """(k,) N what the robot's feet hold in ``worlds`` where they stand now (:meth:`feet_hold`'s force, read in
        every world at once)."""
        feet_on = self._feet_surfaces(worlds)[2]
        robot = self.senses.sim.body_mass[worlds][:, self.scene.robot_body].sum(axis=1)
        return robot * GRAVITY * self.rays.friction(worlds, feet_on).mean(axis=1)

    def sliding_friction(self, w: int, index: int) -> float:
        """The friction object ``index`` slides at on its support in world ``w`` (:meth:`_support`)."""
        return self._support(w, index)[2]

    def _own_friction(self, w: int, index: int) -> float:
        """The largest friction of object ``index``'s geoms in world ``w``, as its perturbation scales it."""
        return float(self.rays.friction(np.array([w]), np.flatnonzero(self.facts.geom_object == index)[None]).max())

    def _feet_surface(self, w: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Under the robot's feet in world ``w``: the heights (4,), the objects (-1: none) and the geoms whose friction
        the feet meet (-1: none; a cloth lying on what carries them where it is the more slippery,
        :meth:`~.rays.Rays.grip`)."""
        z, objects, feet_on = self._feet_surfaces(np.array([w]))
        return z[0], objects[0], feet_on[0]

    def _feet_surfaces(self, worlds: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`_feet_surface` in ``worlds`` (k,) at once: each (k, 4)."""
        centres = feet(self.senses.state, self.facts.ids)[worlds]
        top = centres[:, :, 2].max(axis=1) + 0.05
        z, _, geoms, cloth = self.rays.surface(worlds, centres[:, :, :2], top)
        return z, self.rays.objects_of(geoms), self.rays.grip(geoms, cloth)

    def _support(self, w: int, index: int) -> tuple[np.ndarray, int, float]:
        """What object ``index`` rests on in world ``w``: the heights under it (:meth:`_under`), the geom it rests on
        most (-1: none; the cloth lying on it, if any) and the friction it slides at: the mean, over :data:`FOOTPRINT`
        points under each of its parts that rest at the height of the highest, of the friction between it and what
        it rests on there (:meth:`~.rays.Rays.sliding`: through a cloth, as the world's perturbation scales them; a
        crate on rubber with an ice seam under its centre slides on the rubber)."""
        world, body = np.array([w]), self.scene.object_body[index]
        top = np.array([self.senses.bounds3(w, index)[1][2] + 0.01])
        below, _, geoms, cloth = self.rays.surface(world, self._under(w, index)[None], top, body)
        highest = int(np.argmax(below[0]))
        support = int(cloth[0, highest] if cloth[0, highest] >= 0 else geoms[0, highest])
        z, _, geoms, cloth = self.rays.surface(world, self._footprint(w, index)[None], top, body)
        own = self._own_friction(w, index)
        cloth = np.where(self.rays.objects_of(cloth) == index, -1, cloth)  # a pushed cloth's own links
        rests = np.abs(z[0] - below[0, highest]) <= RISE
        if not rests.any():
            return below[0], support, own
        on, count = np.unique(np.where(cloth >= 0, cloth, geoms)[0, rests], return_counts=True)
        friction = self.rays.sliding(world, own, geoms, cloth)[0, rests]
        return below[0], int(on[np.argmax(count)]), float(friction.mean())

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

    def _footprint(self, w: int, index: int) -> np.ndarray:
        """(n, 2) points under object ``index`` in world ``w`` where its friction is read: a grid of FOOTPRINT x
        :data:`FOOTPRINT` cell centres over the x-y bounds of each of its geoms (a cloth: under its centre)."""
        if self.facts.cloth[index]:
            return self._under(w, index)
        xpos, xmat = self.senses.sim.geom_poses(np.array([w]))
        mine = np.flatnonzero(self.facts.geom_object == index)
        half = self.scene.model.geom_aabb[mine, 3:]  # (n, 3) each geom's half sizes in its own frame
        reach = np.abs(xmat[w, mine].reshape(-1, 3, 3)) @ half[:, :, None]  # (n, 3, 1) world half extents
        cells = (np.arange(FOOTPRINT) + 0.5) / FOOTPRINT * 2 - 1  # -1..1
        grid = np.stack(np.meshgrid(cells, cells, indexing="ij"), axis=-1).reshape(-1, 2)
        return (xpos[w, mine, None, :2] + grid[None] * reach[:, None, :2, 0]).reshape(-1, 2)

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


def _stood_on(z: np.ndarray, objects: np.ndarray) -> np.ndarray:
    """(k, 4) the objects the robot stands on (-1: the ground, nothing or a foot on a lower surface), from the heights
    ``z`` and objects ``objects`` (each (k, 4)) under its feet: those under the feet on the highest surface."""
    return np.where(z >= z.max(axis=1, keepdims=True) - RISE, objects, -1)
