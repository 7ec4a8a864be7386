"""Where the quadruped's weight rests: its centre of mass, its feet's contacts and the support they give.

The support of a set of feet is the convex hull of their centres in x-y: the centre of mass is supported when it
lies inside it (three or four feet; with fewer the robot cannot stand). Everything is vectorised over worlds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robotool.robots.quadruped.body import BodyIds
from robotool.robots.quadruped.terrain import FOOT_NAMES, FOOT_RADIUS
from robotool.sim.backend import BatchState
from robotool.sim.compiled_scene import Scene

CYCLE = (0, 2, 3, 1)  # the feet counter-clockwise around the footprint (rear-right, front-right, front-left, ...)
FOOT_GROUPS = {  # how a set of feet without support is named, from the most specific
    "front": (2, 3),
    "rear": (0, 1),
    "left": (1, 3),
    "right": (0, 2),
}


def centre_of_mass(state: BatchState, ids: BodyIds) -> np.ndarray:
    """The robot's centre of mass in every world (nworld, 3); the feet turn with the body."""
    bodies = np.array([ids.body, *ids.feet])
    points = state.xpos[:, bodies] + np.einsum("wij,kj->wki", state.xmat(ids.body), ids.com_offsets)
    return np.einsum("k,wki->wi", ids.masses, points) / ids.masses.sum()


def feet(state: BatchState, ids: BodyIds) -> np.ndarray:
    """The feet's sphere centres in every world (nworld, 4, 3)."""
    up = state.xmat(ids.body)[:, :, 2]
    return state.xpos[:, ids.feet] + up[:, None, :] * FOOT_RADIUS


def feet_touching(state: BatchState, ids: BodyIds, bodies: np.ndarray) -> np.ndarray:
    """(nworld, 4) whether each foot touches any of ``bodies`` (a boolean mask over the model's bodies)."""
    return np.any(state.touching[:, ids.feet][:, :, bodies], axis=2)


def tilt(state: BatchState, ids: BodyIds) -> np.ndarray:
    """Angle between the body's up axis and the world's, radians (nworld,)."""
    up = state.xmat(ids.body)[:, 2, 2]
    return np.arccos(np.clip(up, -1.0, 1.0))


def supported(com: np.ndarray, foot_xy: np.ndarray, touching: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """(nworld,) whether the centre of mass ``com`` (nworld, >=2) lies inside the support of the touching feet.

    ``foot_xy`` (nworld, 4, >=2); ``margin`` (m) shrinks the support. Fewer than three touching feet support nothing.
    """
    nworld = com.shape[0]
    order = np.array(CYCLE)
    pts = foot_xy[:, order, :2]
    on = touching[:, order]
    inside = on.sum(axis=1) >= 3
    for j in range(4):  # each touching foot, to the next touching foot counter-clockwise
        nxt = np.full(nworld, -1)
        for step in (3, 2, 1):  # the nearest wins: written last
            k = (j + step) % 4
            nxt = np.where(on[:, k], k, nxt)
        a = pts[:, j]
        b = pts[np.arange(nworld), np.maximum(nxt, 0)]
        edge = b - a
        rel = com[:, :2] - a
        length = np.maximum(np.linalg.norm(edge, axis=1), 1e-9)
        cross = (edge[:, 0] * rel[:, 1] - edge[:, 1] * rel[:, 0]) / length
        inside &= ~on[:, j] | (cross >= margin)
    return inside


def unsupported_feet(touching: np.ndarray) -> str:
    """Words for the feet of one world (4,) that touch nothing, e.g. 'the front feet'."""
    free = {i for i in range(4) if not touching[i]}
    if not free:
        return "its feet"
    for name, group in FOOT_GROUPS.items():
        if free == set(group):
            return f"the {name} feet"
    return "the " + ", ".join(FOOT_NAMES[i] for i in sorted(free)) + (" feet" if len(free) > 1 else " foot")


LIMP_DEPTH = FOOT_RADIUS
"""m: how far below the top of what it lies on a cloth's link's centre may be and still rest on it (over a rounded
top, a bunched cloth)."""


@dataclass(frozen=True)
class Parts:
    """The parts of the scene's objects that bear weight apart: a rigid object is one part (its root body, with the
    bounding box of its shapes), a cloth one per link (each link's box). A cloth is limp: weight put on one of its
    links goes to what that link lies on, not to wherever the rest of the cloth lies."""

    body: np.ndarray  # (npart,) each part's body (a rigid object's root body)
    owner: np.ndarray  # (npart,) the object it belongs to
    member: np.ndarray  # (npart, nbody) the bodies whose contacts are its contacts
    lo: np.ndarray  # (npart, 3) its box in its body's frame
    hi: np.ndarray  # (npart, 3)
    limp: np.ndarray  # (npart,) a cloth's link

    @classmethod
    def of(cls, scene: Scene, corners: list[np.ndarray]) -> Parts:
        """``corners``: each object's corners in its body frame (:func:`robotool.sim.object_goals.local_corners`)."""
        model, owner_of = scene.model, scene.body_object
        cloth = [o.shape == "cloth" for o in scene.task.objects]
        bodies = [
            int(b) for b in np.flatnonzero(owner_of >= 0) if cloth[owner_of[b]] or b == scene.object_body[owner_of[b]]
        ]
        owner = owner_of[bodies]
        limp = np.array([cloth[o] for o in owner], dtype=bool)
        member = np.zeros((len(bodies), model.nbody), dtype=bool)
        lo, hi = np.zeros((len(bodies), 3)), np.zeros((len(bodies), 3))
        for p, (b, o) in enumerate(zip(bodies, owner, strict=True)):
            if limp[p]:
                member[p, b] = True
                half = model.geom_size[np.flatnonzero(model.geom_bodyid == b)[0]]  # the link's box, on its origin
                lo[p], hi[p] = -half, half
            else:
                member[p] = owner_of == o
                lo[p], hi[p] = corners[o].min(axis=0), corners[o].max(axis=0)
        return cls(np.array(bodies, dtype=int), owner, member, lo, hi, limp)

    def of_objects(self, load: np.ndarray) -> np.ndarray:
        """(k, npart) the parts of the objects in ``load`` (k, nobject)."""
        return load[:, self.owner]

    def objects(self, parts: np.ndarray, nobject: int) -> np.ndarray:
        """(k, nobject) the objects with a part in ``parts`` (k, npart)."""
        out = np.zeros((parts.shape[0], nobject), dtype=bool)
        np.logical_or.at(out.T, self.owner, parts.T)
        return out


def resting_on(state: BatchState, parts: Parts, worlds: np.ndarray) -> np.ndarray:
    """[k, a, b]: part ``a`` rests on part ``b`` (:class:`Parts`) in world ``worlds[k]``: they touch, and

    - a rigid ``a``: ``b``'s centre lies below ``a``'s underside along ``a``'s own up axis (a board lying flat on
      ``b``, or leaning on it from the floor);
    - a cloth's link ``a``: its centre lies over ``b``'s top, in ``b``'s frame: within ``b``'s footprint, no more
      than :data:`LIMP_DEPTH` below its top (a link hanging down ``b``'s side, or lying on the floor beside it, or in
      the crook of an L, lies on none of it)."""
    member = parts.member.astype(float)
    touching = (member @ state.touching[worlds].astype(float) @ member.T) > 0  # (k, npart, npart)
    centres = state.xpos[worlds][:, parts.body]  # (k, npart, 3)
    frames = np.stack([state.xmat(int(b))[worlds] for b in parts.body], axis=1)  # (k, npart, 3, 3)
    offset = centres[:, None, :, :] - centres[:, :, None, :]  # [k, a, b]: from a's centre to b's
    below = np.einsum("kaj,kabj->kab", frames[:, :, :, 2], offset) < parts.lo[None, :, None, 2]
    within = np.einsum("kbji,kabj->kabi", frames, -offset)  # a's centre in b's frame
    footprint = (within[..., :2] >= parts.lo[None, None, :, :2]) & (within[..., :2] <= parts.hi[None, None, :, :2])
    over = footprint.all(axis=3)
    over &= within[..., 2] >= parts.hi[None, None, :, 2] - LIMP_DEPTH
    return touching & np.where(parts.limp[None, :, None], over, below)


def pass_weight(rests: np.ndarray, load: np.ndarray, carrier: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where a weight put on the objects ``load`` (k, nobject) goes: a ``carrier`` object (nobject,) that carries it
    passes it on to each object it rests on (``rests``, :func:`resting_on`), along chains of them; any other object
    keeps it. Returns the objects that carry it (k, nobject) and, for each one reached, the object that passed it on.
    """
    via = np.zeros(load.shape, dtype=int)
    for _ in range(load.shape[1]):
        passing = rests & (load & carrier)[:, :, None]
        more = load | passing.any(axis=1)
        via = np.where(more & ~load, np.argmax(passing, axis=1), via)
        if np.array_equal(more, load):
            break
        load = more
    return load, via
