"""Where the quadruped's weight rests: its centre of mass, its feet's contacts and the support they give.

The support of a set of feet is the convex hull of their centres in x-y: the centre of mass is supported when it
lies inside it (three or four feet; with fewer the robot cannot stand). Everything is vectorised over worlds.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from robotool.robots.quadruped.body import BodyIds
from robotool.robots.quadruped.terrain import FOOT_NAMES, FOOT_RADIUS, clamp
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
    """The robot's centre of mass in every world (nworld, 3), read-only; the feet turn with the body."""

    def compute() -> np.ndarray:
        bodies = np.array([ids.body, *ids.feet])
        points = state.xpos[:, bodies] + np.einsum("wij,kj->wki", state.xmat(ids.body), ids.com_offsets)
        return np.einsum("k,wki->wi", ids.masses, points) / ids.masses.sum()

    return state.derived(("centre_of_mass", ids.body), compute)


def feet(state: BatchState, ids: BodyIds) -> np.ndarray:
    """The feet's sphere centres in every world (nworld, 4, 3), read-only."""

    def compute() -> np.ndarray:
        up = state.xmat(ids.body)[:, :, 2]
        return state.xpos[:, ids.feet] + up[:, None, :] * FOOT_RADIUS

    return state.derived(("feet", ids.body), compute)


def feet_touching(state: BatchState, ids: BodyIds, bodies: np.ndarray) -> np.ndarray:
    """(nworld, 4) whether each foot touches any of ``bodies`` (a boolean mask over the model's bodies)."""
    return np.any(state.touching[:, ids.feet][:, :, bodies], axis=2)


def tilt(state: BatchState, ids: BodyIds) -> np.ndarray:
    """Angle between the body's up axis and the world's, radians (nworld,)."""
    up = state.xmat(ids.body)[:, 2, 2]
    return np.arccos(clamp(up, -1.0, 1.0))


def _next_touching() -> np.ndarray:
    """(16, 4): for each set of touching feet (bit k: foot ``CYCLE[k]`` touches), the position in :data:`CYCLE` of
    the next touching foot counter-clockwise from each position (-1: none)."""
    table = np.full((16, 4), -1)
    for pattern, j in np.ndindex(16, 4):
        for step in (1, 2, 3):
            if pattern >> ((j + step) % 4) & 1:
                table[pattern, j] = (j + step) % 4
                break
    return table


_NEXT_TOUCHING = _next_touching()
_ORDER = np.array(CYCLE)
_NEXT_FOOT = _ORDER[np.maximum(_NEXT_TOUCHING, 0)]  # the same as feet (the first where none is)
_BITS = 1 << np.arange(4)  # a set of touching feet, in CYCLE's order, as the row of _NEXT_TOUCHING


def supported(com: np.ndarray, foot_xy: np.ndarray, touching: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """(nworld,) whether the centre of mass ``com`` (nworld, >=2) lies inside the support of the touching feet.

    ``foot_xy`` (nworld, 4, >=2); ``margin`` (m) shrinks the support. Fewer than three touching feet support nothing.
    """
    pts = foot_xy[:, _ORDER, :2]
    on = touching[:, _ORDER]
    nxt = _NEXT_FOOT[on.astype(int) @ _BITS]  # (nworld, 4): each touching foot's next one
    edge = foot_xy[np.arange(len(nxt))[:, None], nxt, :2] - pts
    rel = com[:, None, :2] - pts
    length = np.maximum(np.sqrt(edge[..., 0] * edge[..., 0] + edge[..., 1] * edge[..., 1]), 1e-9)  # as norm gives
    cross = (edge[..., 0] * rel[..., 1] - edge[..., 1] * rel[..., 0]) / length
    return (on.sum(axis=1) >= 3) & np.all(~on | (cross >= margin), axis=1)


_LARGEST = np.finfo(float).max


def known_lengths(lengths: np.ndarray) -> np.ndarray:
    """Lengths (>= 0; NaN: unknown) with an unknown one read as 0 and inf as the largest float: what
    ``np.nan_to_num(lengths, nan=0.0)`` gives, at a quarter of its cost (the referee reads them every tick)."""
    return np.where(np.isnan(lengths), 0.0, np.minimum(lengths, _LARGEST))


def unsupported_feet(touching: np.ndarray) -> str:
    """Words for the feet of one world (4,) that touch nothing, e.g. 'the front feet'."""
    free = {i for i in range(4) if not touching[i]}
    if not free:
        return "its feet"
    for name, group in FOOT_GROUPS.items():
        if free == set(group):
            return f"the {name} feet"
    return "the " + ", ".join(FOOT_NAMES[i] for i in sorted(free)) + (" feet" if len(free) > 1 else " foot")


BEARING_ANGLE = np.radians(60.0)
"""rad: a contact whose summed normal lies within this of up bears weight: what it presses up carries on it."""


FOOTING_ANGLE = np.radians(30.0)
"""rad: a foot stands on what presses it up within this of up, which may then move with it; a rim that presses a
frictionless foot up at a steeper angle takes more of its push sideways than up, and is pushed, not stood on."""


PARTLY_UP = 0.05
"""Summed contact normals whose upward part is at least this share of their length press partly up."""
BEARING_SHARE = 0.1
"""The share of a part's weight that contacts pressing it partly up must lift to bear it up (:func:`resting_on`)."""


@dataclass(frozen=True)
class Weighing:
    """How :func:`resting_on` weighs contacts that press partly up in k worlds: ``forces(i, bodies)`` (nbody, 3) N is
    the force ``bodies`` put on each body through their contacts in the i-th world
    (:meth:`~robotool.sim.backend.BatchedSim.contact_forces`), ``weight`` (k, npart) N each part's weight."""

    forces: Callable[[int, np.ndarray], np.ndarray]
    weight: np.ndarray


def bears_up(normals: np.ndarray, within: float = BEARING_ANGLE) -> np.ndarray:
    """Whether summed contact normals (..., 3), each from one body onto another, press it up: within ``within``
    (rad, default :data:`BEARING_ANGLE`) of up (none where nothing touches)."""
    return normals[..., 2] > np.cos(within) * np.linalg.norm(normals, axis=-1)


@dataclass(frozen=True)
class Parts:
    """The parts of the scene's objects that bear weight apart: a rigid object is one part (all its bodies), a cloth
    one per link. A cloth is limp: weight put on one of its links goes to what that link lies on, not to wherever the
    rest of the cloth lies."""

    owner: np.ndarray  # (npart,) the object each part belongs to
    member: np.ndarray  # (npart, nbody) the bodies whose contacts are its contacts

    @classmethod
    def of(cls, scene: Scene) -> Parts:
        owner_of = scene.body_object
        cloth = [o.shape == "cloth" for o in scene.task.objects]
        rows = [owner_of == o for o in range(len(cloth)) if not cloth[o]]
        owner = [o for o in range(len(cloth)) if not cloth[o]]
        for b in np.flatnonzero(owner_of >= 0):
            if cloth[owner_of[b]]:
                rows.append(np.arange(len(owner_of)) == b)
                owner.append(int(owner_of[b]))
        return cls(np.array(owner, dtype=int), np.array(rows, dtype=bool).reshape(len(owner), len(owner_of)))

    def objects(self, parts: np.ndarray, nobject: int) -> np.ndarray:
        """(k, nobject) the objects with a part in ``parts`` (k, npart)."""
        out = np.zeros((parts.shape[0], nobject), dtype=bool)
        np.logical_or.at(out.T, self.owner, parts.T)
        return out


def resting_on(normals: np.ndarray, parts: Parts, weighing: Weighing | None = None) -> np.ndarray:
    """[k, a, b]: part ``a`` rests on part ``b`` (:class:`Parts`) in each of k worlds: ``b`` bears it up, the contacts
    through which ``b`` presses on ``a`` summing to a normal within :data:`BEARING_ANGLE` of up (a board lying on
    ``b`` or leaning on its edge from the floor, a cloth's link lying on it), however either is turned or shaped; what
    only touches a side (in the crook of an L, down a wall) or lies on top bears nothing. ``normals`` (k, nbody, nbody,
    3): each world's summed contact normals from one body onto another
    (:meth:`~robotool.sim.backend.BatchedSim.contact_normals`). With a ``weighing``, where ``b`` presses ``a`` partly
    up but its normals sum beyond that angle (a board's lip pressed hard on a vase's side, its edge on the vase's
    top), ``b`` bears ``a`` up when its force lifts at least :data:`BEARING_SHARE` of ``a``'s weight."""
    member = parts.member.astype(float)
    onto = np.einsum("pb,kbcx,qc->kpqx", member, normals, member)  # [k, b, a]: from part b onto part a
    rests = bears_up(onto)
    if weighing is not None:
        unsure = (onto[..., 2] > PARTLY_UP * np.linalg.norm(onto, axis=-1)) & ~rests
        for k, b in zip(*np.nonzero(unsure.any(axis=2)), strict=True):
            lift = member @ weighing.forces(int(k), parts.member[b])[:, 2]  # (npart,) N from part b up onto each part
            rests[k, b] |= unsure[k, b] & (lift >= BEARING_SHARE * weighing.weight[k])
    rests = rests.transpose(0, 2, 1).copy()
    rests[:, np.arange(len(parts.owner)), np.arange(len(parts.owner))] = False
    return rests


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
