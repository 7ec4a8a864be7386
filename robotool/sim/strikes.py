"""Strikes on a fragile object: something moving meeting it faster than a fall of its ``max_drop`` would land.

A fall (:class:`~robotool.sim.object_goals.FallTracker`) is the object's own: its centre dropping onto a surface that is
not soft, other than the robot. That misses glass struck by what moves: a dish dropped onto the gripper's palm, a block
dropped onto a dish lying still. So a fragile object also breaks when the robot or a movable object that is not soft
comes to touch it at more than ``sqrt(2 g max_drop)``, the speed a fall of ``max_drop`` lands at, or to touch a movable
object resting on it (a block dropped onto the lid of a glass jar drives the lid into the jar). The speed is the other
body's, where the object's centre is (its travel and turn since the reading before: the tip of a swung stick strikes
faster than its middle moves), relative to the object's centre, read before they touched (the larger of the last reading
before and the first one touching); where it comes to touch the object itself, its speed at the contact points too, if
faster (found by an adversarial run: a plank leaning on a block, shoved off it, swung down about its low end onto a 1.5
m glass floor at 2.2-2.4 m/s, while its speed where the glass's centre lies was 1.1 m/s). What touches it already
strikes where it touches it anew, :data:`REGION` away, at its speed toward it there (a pole toppled about its foot on
the glass). A fixed object (a glass table, floor or shelf: large, its centre far from where it is met) is read where it
is nearest each striker, and at the speed toward it there (found by a run that looked for honest programs the judge
fails: a pin rolling on a fixed glass plate was read at its spin times the way to the plate's centre, and fingers rising
past a block's side at their speed away from the glass). A soft movable object cushions its blow: the object falling
onto it lands softly, and one it shoves sideways moves away (driven into a wall, the wall's strike is read). It strikes
only coming down on the object, pressing it onto what it rests on, with its own downward speed, and only with more
energy than the object's own fall of ``max_drop`` takes up: faster than ``sqrt(M / m)`` times the limit (M the object's
mass, m its own), and never slower than the limit (found by an adversarial run: a 3 kg sandbag let go 0.43 m above a
glass dish left it whole, as soft objects struck nothing). Nor does it pass on a blow it lies under.

The object itself driven into what does not move breaks the same way (found by an adversarial run: a stick shoved a dish
sideways into a fixed wall at 2.5 times the limit, and the fall rule reads only the drop of its centre): a new touch of
a fixed object that is not soft (a wall, a shelf, a stool, a button) at more than the limit, the object's own speed (its
centre's, as a fall is read) being the speed they meet at. The floor (the world's own bodies) is left to the fall rule:
it is flat and under everything, so the object comes to it only by falling, which the fall rule reads as the documented
drop of its centre (counting a landing's speed would break a dish pushed off a low step sideways, however small its
drop), and nothing drives it sideways into it. A fragile object's fall past ``max_drop`` makes the goal read every
physics step, so a landing on the robot is read at the step it happens; so does a striker that could meet the object
faster than the limit before the next tick, and the object could meet a fixed object so (:meth:`StrikeWatch.watched`):
read only at ticks, a block let go a little above a dish lands between two readings, each slower than the landing.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from robotool.sim.backend import BatchedSim, BatchState, cross, quat_to_mat
from robotool.sim.compiled_scene import Scene

GRAVITY = 9.81  # m/s^2
GAIN = 2 * GRAVITY  # m/s^2: the most a striker is taken to gain on the object in a control interval (a fall, a shove)
REGION = 0.05  # m from every point a striker touched the object at the last reading: where it touches it anew


class StrikeWatch:
    """The strikes on one fragile object in every world: :meth:`update` says how fast things came to touch it."""

    def __init__(self, scene: Scene, sim: BatchedSim, index: int, max_drop: float):
        self.sim = sim
        objects = scene.task.objects
        owner = scene.body_object
        movable = np.array([o.movable for o in objects])
        striker = scene.robot_body | ((owner >= 0) & (owner != index) & movable[np.maximum(owner, 0)])
        self.strikers = np.flatnonzero(striker)  # the robot's bodies and the other movable objects'
        self.mine = np.flatnonzero(owner == index)
        self.mine_mask = owner == index  # (nbody,)
        self.robot = scene.robot_body[self.strikers]  # which strikers are the robot's
        of = owner[self.strikers]
        self.soft = ~self.robot & np.array([objects[o].soft for o in of.tolist()], dtype=bool)
        self.loose = ~self.robot & ~self.soft  # the movable objects among them that may rest on it and pass a blow on
        self.body = int(scene.object_body[index])
        self.dof = int(scene.model.body_dofadr[self.body])  # its free joint's linear velocity, in the world frame
        self.fixed_object = self.dof < 0  # a fixed object (no joint) is struck at the striker's own speed
        self.limit = float(np.sqrt(2 * GRAVITY * max_drop))
        mass = np.array([objects[o].effective_mass if o >= 0 else 1.0 for o in of.tolist()])
        cushioned = self.limit * np.sqrt(np.maximum(objects[index].effective_mass / mass, 1.0))
        self.limits = np.where(self.soft, cushioned, self.limit)  # (nstriker,) the speed each strikes beyond
        radius = body_radii(scene)
        self.striker_radius, self.mine_radius = radius[self.strikers], radius[self.mine]
        self.names = ["the robot" if scene.robot_body[b] else objects[owner[b]].name for b in self.strikers.tolist()]
        self.fixed = FixedBodies(scene, index)
        self.names += self.fixed.names  # a strike's bodies: the strikers, then the fixed objects
        mover = scene.robot_body | (scene.model.body_weldid != 0)  # what moves: the robot, movable objects, soft too
        self.movers = np.flatnonzero(mover & (owner != index))
        self._time: np.ndarray | None = None
        self._xpos = np.zeros(0)
        self._xmat = np.zeros(0)
        self._direct = np.zeros(0, dtype=bool)  # (nworld, nstriker): touching it directly
        self._pairs = np.zeros(0, dtype=bool)  # (nworld, nstriker, nstriker): which strikers touch each other
        self._carried = np.zeros(0, dtype=bool)  # (nworld, nstriker): resting on it
        self._speed = np.zeros(0)
        self._walls = np.zeros(0, dtype=bool)  # (nworld, nfixed): touching a fixed object
        self._own = np.zeros(0)  # (nworld,): the object's own speed
        self._regions: dict[int, dict[int, np.ndarray]] = {}  # world -> striker -> (n, 3) where it touched the object

    def update(self, state: BatchState, active: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Read the ``active`` worlds: (nworld,) the fastest strike that began since the last reading (0: none),
        (nworld, nstriker + nfixed) which bodies came to touch the object then, directly or through a movable object
        resting on it (touching it or one that does, its centre above the object's: a lid on a jar passes on the blow of
        what lands on it), and through which striker each did (-1: directly); a fixed object it came to touch met it at
        its own speed."""
        xpos = state.xpos[:, self.strikers]
        xmat = state.frames()[:, self.strikers]
        direct = np.asarray(state.touching[:, self.mine][:, :, self.strikers].any(axis=1))
        pairs = np.asarray(state.touching[:, self.strikers][:, :, self.strikers])  # [w, s, c]: s touches c
        carried = self._resting(direct, pairs, self.loose & self._above(state))
        onto = pairs & carried[:, None, :]  # s touches c, which rests on the object
        walls = self.fixed.touching(state, self.mine)
        own = self.own_velocity(state)
        own_speed = np.linalg.norm(own, axis=1)
        if self._time is None:
            self._time, self._xpos, self._xmat = state.time.copy(), xpos, xmat
            self._direct, self._pairs, self._carried = direct, pairs, carried
            self._speed = np.zeros(direct.shape)
            self._walls, self._own = walls, own_speed
        rate = 1.0 / np.where(state.time > self._time, state.time - self._time, np.inf)[:, None, None]
        spin = _turn(self._xmat, xmat) * rate  # (nworld, nstriker, 3): each body's angular velocity
        travel = (xpos - self._xpos) * rate
        if self.fixed_object:  # a table, a floor, a shelf: read where it is nearest, coming toward it
            near = self._nearest(state, xpos)
            moving = travel + cross(spin, near - xpos)
            relative = _toward(moving, near - xpos)
        else:
            moving = travel + cross(spin, state.xpos[:, None, self.body] - xpos)  # where the object's centre is
            relative = np.linalg.norm(own[:, None] - moving, axis=2)  # (nworld, nstriker)
        speed = np.where(self.soft, np.maximum(-moving[:, :, 2], 0.0), relative)  # a soft one's own, coming down
        at_contacts, elsewhere = self._at_contacts(active[:, None] & direct, xpos, travel, spin, own)
        speed = np.where(direct & ~self._direct, np.maximum(speed, at_contacts), speed)
        fresh = onto & ~self._pairs  # a new touch of what rests on the object (not one it came to rest under)
        via = fresh.any(axis=2) & ~direct & ~self._touching()  # (what rested on it already does not strike it anew)
        meeting = np.maximum(speed, self._speed)
        new = active[:, None] & ((direct & ~self._direct) | via) & (~self.soft | (meeting > self.limits))
        struck = np.where(new, meeting, 0.0).max(axis=1, initial=0.0)
        landed = active[:, None] & direct & self._direct & (elsewhere > self.limits)  # touching, it lands elsewhere
        new |= landed
        struck = np.maximum(struck, np.where(landed, elsewhere, 0.0).max(axis=1, initial=0.0))
        met = active[:, None] & walls & ~self._walls  # (nworld, nfixed): a new touch of a fixed object
        struck = np.maximum(struck, np.where(met.any(axis=1), np.maximum(own_speed, self._own), 0.0))
        keep = active[:, None]
        self._time = np.where(active, state.time, self._time)
        self._xpos = np.where(keep[:, :, None], xpos, self._xpos)
        self._xmat = np.where(keep[:, :, None, None], xmat, self._xmat)
        self._direct = np.where(keep, direct, self._direct)
        self._pairs = np.where(keep[:, :, None], pairs, self._pairs)
        self._carried = np.where(keep, carried, self._carried)
        self._speed = np.where(keep, speed, self._speed)
        self._walls = np.where(keep, walls, self._walls)
        self._own = np.where(active, own_speed, self._own)
        through = np.where(via, np.argmax(fresh, axis=2), -1)
        return struck, np.hstack([new, met]), np.hstack([through, np.full(met.shape, -1)])

    def _at_contacts(
        self, touching: np.ndarray, xpos: np.ndarray, travel: np.ndarray, spin: np.ndarray, own: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Read where the strikers ``touching`` (nworld, nstriker) the object touch it: (nworld, nstriker) the speed
        each comes to it at there (the fastest of its contact points; a soft one's own, coming down), and the speed
        it comes to it at where it touches it anew, :data:`REGION` or more from every point it touched at the last
        reading (toward the object, along the contact's normal: a pole standing on glass that topples lands its top
        on it; found by an adversarial run, where only the pole's first touch was read), 0 elsewhere. ``travel`` and
        ``spin`` are each striker's velocity at its origin ``xpos`` and its angular velocity, ``own`` the object's.
        The points are kept for the next reading."""
        at_contacts, elsewhere = np.zeros(touching.shape), np.zeros(touching.shape)
        worlds = np.flatnonzero(touching.any(axis=1)).tolist()
        self._regions = {w: self._regions[w] for w in worlds if w in self._regions}  # (not touching: forgotten)
        for w in worlds:
            points, bodies, normals = self.sim.contact_points(w, self.mine_mask)
            before, regions = self._regions.get(w, {}), {}
            for k in np.flatnonzero(touching[w]).tolist():
                mine = bodies == self.strikers[k]
                at, normal = points[mine], normals[mine]
                if not len(at):
                    continue
                regions[k] = at
                velocity = travel[w, k] + np.cross(spin[w, k], at - xpos[w, k]) - own[w]  # (n, 3)
                down = np.maximum(-velocity[:, 2], 0.0)
                toward = np.abs(np.einsum("ni,ni->n", velocity, normal))
                meeting = toward if self.fixed_object else np.linalg.norm(velocity, axis=1)
                at_contacts[w, k] = float((down if self.soft[k] else meeting).max())
                if k in before:
                    apart = np.linalg.norm(at[:, None] - before[k][None], axis=2).min(axis=1) >= REGION
                    if apart.any():
                        elsewhere[w, k] = float((down if self.soft[k] else toward)[apart].max())
            self._regions[w] = regions
        return at_contacts, elsewhere

    def _nearest(self, state: BatchState, points: np.ndarray) -> np.ndarray:
        """(nworld, n, 3) the point of the boxes around the object's geoms nearest each of ``points`` (nworld, n, 3)."""
        centres, frames = self.fixed.mine.poses(state)  # (nworld, k, 3), (nworld, k, 3, 3): axes as columns
        apart = points[:, :, None] - centres[:, None]  # (nworld, n, k, 3)
        local = np.clip(np.einsum("wkij,wnki->wnkj", frames, apart), -self.fixed.mine_half, self.fixed.mine_half)
        placed = centres[:, None] + np.einsum("wkij,wnkj->wnki", frames, local)
        pick = np.linalg.norm(placed - points[:, :, None], axis=3).argmin(axis=2)  # (nworld, n)
        return np.take_along_axis(placed, pick[:, :, None, None], axis=2)[:, :, 0]

    def own_velocity(self, state: BatchState) -> np.ndarray:
        """(nworld, 3) the object's linear velocity in the world frame (none for a fixed object)."""
        if self.fixed_object:
            return np.zeros((len(state.time), 3))
        return np.asarray(state.qvel[:, self.dof : self.dof + 3])

    def name(self, striker: int, through: int) -> str:
        """Who struck: a striker's name, and what it struck through (-1: nothing)."""
        return self.names[striker] + (f" through {self.names[through]}" if through >= 0 else "")

    def _touching(self) -> np.ndarray:
        """(nworld, nstriker) which strikers touched the object at the last reading, directly or through what rests
        on it."""
        return self._direct | (self._pairs & self._carried[:, None, :]).any(axis=2)

    @staticmethod
    def _resting(direct: np.ndarray, pairs: np.ndarray, above: np.ndarray) -> np.ndarray:
        """(nworld, nstriker) the movable objects ``above`` the object that rest on it: touching it, or touching one
        that does (a board on the lid of a jar passes a blow on as the lid does)."""
        resting = direct & above
        while True:
            more = resting | ((pairs & resting[:, None, :]).any(axis=2) & above)
            if np.array_equal(more, resting):
                return resting
            resting = more

    def _above(self, state: BatchState) -> np.ndarray:
        """(nworld, nstriker) whether each striker's centre lies above the object's."""
        return np.asarray(state.xpos[:, self.strikers, 2] > state.xpos[:, None, self.body, 2])

    def watched(self, state: BatchState, dt: float, held: np.ndarray) -> np.ndarray:
        """(nworld,) the worlds where a striker not touching the object could meet it faster than the limit within
        ``dt``: its last speed plus :data:`GAIN` over ``dt`` passes the limit, and its bounding sphere lies within
        what that start and gain cover in ``dt`` of the object's. The robot is left out where it ``held`` (nworld,)
        the object (in its grip, the object moves with the hand). So are the worlds where the object could meet a
        fixed object it does not touch faster than the limit (:meth:`_could_meet_fixed`)."""
        if self._time is None:
            return np.zeros(len(state.time), dtype=bool)
        struck = self._could_strike(state, dt, held)
        return struck.any(axis=1) | self._could_meet_fixed(state, dt, struck)

    def _could_strike(self, state: BatchState, dt: float, held: np.ndarray) -> np.ndarray:
        """(nworld, nstriker) the strikers that could meet the object faster than the limit within ``dt``
        (:meth:`watched`)."""
        reach = self._speed + GAIN * dt  # (nworld, nstriker): the fastest it could meet the object by the next tick
        cover = self._speed * dt + GAIN * dt**2 / 2  # and the farthest it could come
        xpos = state.xpos[:, self.strikers]
        apart = xpos[:, :, None] - state.xpos[:, None, self.mine]  # (nworld, nstriker, nmine, 3)
        gap = (np.linalg.norm(apart, axis=3) - self.striker_radius[:, None] - self.mine_radius[None, :]).min(axis=2)
        if self._carried.any():  # near what rests on the object is near it
            radii = self.striker_radius[:, None] + self.striker_radius[None, :]
            between = np.linalg.norm(xpos[:, :, None] - xpos[:, None, :], axis=3) - radii  # [w, s, c]
            gap = np.minimum(gap, np.where(self._carried[:, None, :], between, np.inf).min(axis=2))
        could = (gap < cover) & (reach > self.limits) & ~self._touching()
        return could & ~(held[:, None] & self.robot[None, :])

    def _could_meet_fixed(self, state: BatchState, dt: float, struck: np.ndarray) -> np.ndarray:
        """(nworld,) the worlds where the object could meet a fixed object it does not touch faster than the limit
        within ``dt``: its speed plus what it could gain over ``dt`` passes the limit, and the gap between their boxes
        is within what that start and gain cover. It gains :data:`GAIN` where something that moves touches it or a
        striker could strike it (``struck``: a shove), else gravity's pull at most (sliding or falling)."""
        nworld = len(state.time)
        if not len(self.fixed.names) or self.fixed_object:
            return np.zeros(nworld, dtype=bool)
        speed = np.linalg.norm(self.own_velocity(state), axis=1)
        pushed = np.asarray(state.touching[:, self.mine][:, :, self.movers].any(axis=(1, 2))) | struck.any(axis=1)
        gain = np.where(pushed, GAIN, GRAVITY)
        fast = speed + gain * dt > self.limit
        if not fast.any():
            return fast
        cover = speed * dt + gain * dt**2 / 2
        near = (self.fixed.gaps(state) < cover[:, None]) & ~self._walls
        return fast & near.any(axis=1)


class FixedBodies:
    """The bodies of the fixed objects that are not soft (a wall, a shelf, a stool, a button's housing and face), which
    a fragile object breaks on when driven into them too fast, and the gaps it keeps from them, read from the boxes
    around their geoms and its own (:func:`box_gaps`). The floor is not among them (see the module's docstring)."""

    def __init__(self, scene: Scene, index: int):
        objects, owner, model = scene.task.objects, scene.body_object, scene.model
        still = np.array([not o.movable and not o.soft for o in objects])
        fixed = (owner >= 0) & (owner != index) & still[np.maximum(owner, 0)]
        self.bodies = np.flatnonzero(fixed)
        self.names = [objects[owner[b]].name for b in self.bodies.tolist()]
        shaped = model.geom_rbound > 0  # (a plane bounds nothing)
        geoms = np.flatnonzero(shaped & fixed[model.geom_bodyid])
        self.column = np.searchsorted(self.bodies, model.geom_bodyid[geoms])  # each geom's fixed body
        mine = np.flatnonzero(shaped & (owner[model.geom_bodyid] == index))
        half = geom_half_sizes(model)
        self.geoms, self.mine = GeomFrames.of(model, geoms), GeomFrames.of(model, mine)
        self.geom_half, self.mine_half = half[geoms], half[mine]

    def touching(self, state: BatchState, mine: np.ndarray) -> np.ndarray:
        """(nworld, nfixed) which fixed bodies touch the object (its bodies ``mine``)."""
        return np.asarray(state.touching[:, mine][:, :, self.bodies].any(axis=1))

    def gaps(self, state: BatchState) -> np.ndarray:
        """(nworld, nfixed) at most how far the object's geoms are from each fixed body's (0 or less: they may
        touch), read from the boxes around them."""
        ours, theirs = self.mine.poses(state), self.geoms.poses(state)
        gap = box_gaps(*ours, self.mine_half, *theirs, self.geom_half).min(axis=1)  # (nworld, the fixed bodies' ngeom)
        out = np.full((len(state.time), len(self.bodies)), np.inf)
        np.minimum.at(out.T, self.column, gap.T)
        return out


@dataclass(frozen=True)
class GeomFrames:
    """Some geoms of a model, placed in every world by their bodies' poses: each one's body, and its position and
    rotation in that body's frame."""

    body: np.ndarray  # (k,)
    pos: np.ndarray  # (k, 3)
    rot: np.ndarray  # (k, 3, 3)

    @classmethod
    def of(cls, model: mujoco.MjModel, geoms: np.ndarray) -> GeomFrames:
        return cls(model.geom_bodyid[geoms], model.geom_pos[geoms], quat_to_mat(model.geom_quat[geoms]))

    def centres(self, state: BatchState) -> np.ndarray:
        """(nworld, k, 3) the geoms' centres in every world."""
        return self._placed(state)[0]

    def poses(self, state: BatchState) -> tuple[np.ndarray, np.ndarray]:
        """Centres (nworld, k, 3) and frames (nworld, k, 3, 3; axes as columns) of the geoms in every world."""
        centre, frame = self._placed(state)
        return centre, frame @ self.rot

    def _placed(self, state: BatchState) -> tuple[np.ndarray, np.ndarray]:
        """The geoms' centres (nworld, k, 3) and their bodies' frames (nworld, k, 3, 3)."""
        frame = state.frames()[:, self.body]
        return state.xpos[:, self.body] + np.einsum("wkij,kj->wki", frame, self.pos), frame


def geom_half_sizes(model: mujoco.MjModel) -> np.ndarray:
    """(ngeom, 3) the half sizes of a box around each geom, in its frame: a box's own, a cylinder's radius and
    half-length, a capsule's with its caps, a sphere's radius; a cube of its bounding radius for any other shape."""
    size, kind = model.geom_size, model.geom_type
    r = size[:, 0]
    out = np.repeat(model.geom_rbound[:, None], 3, axis=1)
    geom = mujoco.mjtGeom
    box, cyl, cap, sphere = (
        kind == int(t) for t in (geom.mjGEOM_BOX, geom.mjGEOM_CYLINDER, geom.mjGEOM_CAPSULE, geom.mjGEOM_SPHERE)
    )
    out[box] = size[box]
    out[cyl] = np.stack([r, r, size[:, 1]], axis=1)[cyl]
    out[cap] = np.stack([r, r, size[:, 1] + r], axis=1)[cap]
    out[sphere] = r[sphere, None]
    return out


def box_gaps(
    ca: np.ndarray, ra: np.ndarray, ha: np.ndarray, cb: np.ndarray, rb: np.ndarray, hb: np.ndarray
) -> np.ndarray:
    """(nworld, na, nb) a lower bound of the distance between each of boxes ``a`` and each of boxes ``b`` (centres
    (nworld, n, 3), axes as columns (nworld, n, 3, 3), half sizes (n, 3)): the widest gap between their shadows on
    the six axes of their faces (a separating axis; 0 or less where they may overlap). A box's shadow on an axis never
    exceeds the box, so no gap read is wider than the true one."""
    d = cb[:, None] - ca[:, :, None]  # (nworld, na, nb, 3)
    cos = np.abs(np.einsum("waik,wbij->wabkj", ra, rb))  # [.., k, j]: |a's axis k . b's axis j|
    on_a = np.abs(np.einsum("wabi,waik->wabk", d, ra)) - ha[None, :, None] - np.einsum("wabkj,bj->wabk", cos, hb)
    on_b = np.abs(np.einsum("wabi,wbij->wabj", d, rb)) - hb[None, None] - np.einsum("wabkj,ak->wabj", cos, ha)
    return np.maximum(on_a.max(axis=3), on_b.max(axis=3))


def body_radii(scene: Scene) -> np.ndarray:
    """(nbody,) each body's bounding radius about its origin: the farthest reach of its geoms' bounding spheres (0 for
    a body without geoms, and for a plane, which strikes nothing)."""
    model = scene.model
    reach = np.linalg.norm(model.geom_pos, axis=1) + model.geom_rbound
    radius = np.zeros(model.nbody)
    np.maximum.at(radius, model.geom_bodyid, np.where(model.geom_rbound > 0, reach, 0.0))
    return radius


def _toward(velocity: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """(...) how fast ``velocity`` (..., 3) comes toward a point ``offset`` (..., 3) away (0 moving away; the whole
    speed where the point is where it is)."""
    distance = np.linalg.norm(offset, axis=-1)
    along = np.einsum("...i,...i->...", velocity, offset) / np.maximum(distance, 1e-9)
    return np.where(distance > 1e-9, np.maximum(along, 0.0), np.linalg.norm(velocity, axis=-1))


def _turn(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """The rotation vectors (..., 3) in world axes that turn frames ``before`` into ``after`` (..., 3, 3): axis times
    angle, from the relative rotation's skew part."""
    rel = after @ np.swapaxes(before, -1, -2)
    skew = np.stack(
        [rel[..., 2, 1] - rel[..., 1, 2], rel[..., 0, 2] - rel[..., 2, 0], rel[..., 1, 0] - rel[..., 0, 1]], -1
    )
    sine = np.linalg.norm(skew, axis=-1) / 2
    angle = np.arctan2(sine, (np.trace(rel, axis1=-2, axis2=-1) - 1) / 2)
    return skew / 2 * np.where(sine > 1e-12, angle / np.maximum(sine, 1e-12), 1.0)[..., None]
