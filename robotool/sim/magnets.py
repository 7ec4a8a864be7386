"""Magnetic objects weld to each other on contact (chains included), and let go past what a magnet holds, per world.

:func:`robotool.sim.build.make_spec` adds an inactive weld ``magnet__<a>__<b>`` for every pair of magnetic objects;
:meth:`Magnets.update` activates it, at the current relative pose, in every world where the two bodies touch. A magnet
holds a bounded load, read where the two meet (of the parts that touch, the patch where the smaller of the two faces
that face each other overlaps the other part, :func:`join_face`; found by an adversarial run: read from the boxes around
whole objects, a hook's 3 cm bar end stuck to a wall held a patch as tall as its 25 cm upright, which touched nothing,
and a 3.5 kg bracket hung from it): a force up to :data:`HOLD_FORCE`; a couple that peels the patch off about one of its
edges up to :data:`HOLD_FORCE` times the patch's half width across that edge (the pull of the whole patch at its far
edge), and a twist about its normal up to :data:`HOLD_FORCE` times its smaller half width (as if that pull held by
friction at the patch's edge). Past any of these the weld lets go, and that pair attaches again only after the two have
come apart: a board stuck by its 2 cm end face to a cabinet's side holds a couple of 2 N m, so it does not carry a robot
across a gap as a cantilever, and a bar held across a 3 cm post by a 3 cm square patch holds 3 N m of twist, not the 9 N
m of a cantilevered 3.5 kg bar turned so that its load twists it.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.compiled_scene import Scene
from robotool.sim.object_goals import local_corners

HOLD_FORCE = 200.0
"""N a magnet pair holds (about 20 kg hanging): three times the most the button task's cubes carry when the paper's
program drives the chain into the next cube's centre (61 N, sideways), forty times the reference program's."""


class Magnets:
    """The magnet welds of a scene and the rules that attach and release them."""

    def __init__(self, scene: Scene):
        model = scene.model
        self.pairs = [
            (eq, model.eq_obj1id[eq], model.eq_obj2id[eq])
            for eq in range(model.neq)
            if model.equality(eq).name.startswith("magnet__")
        ]
        corners = local_corners(scene)  # each object's parts' corners in its body frame, 8 a part
        self.boxes = {
            int(b): [_box(part) for part in np.split(corners[o], len(corners[o]) // 8)]
            for _, b1, b2 in self.pairs
            for b in (b1, b2)
            for o in [int(scene.body_object[b])]
        }
        self._let_go: np.ndarray | None = None  # (nworld, neq): released, not attached again until apart

    def update(self, sim: BatchedSim, state: BatchState, active: np.ndarray) -> None:
        """In the ``active`` worlds, release every attached pair that carries more than a magnet holds, and attach
        every pair that touches, is not attached, and has not let go without coming apart since."""
        if not self.pairs:
            return
        if self._let_go is None:
            self._let_go = np.zeros(state.eq_active.shape, dtype=bool)
        for eq, b1, b2 in self.pairs:
            touching = state.touching[:, b1, b2]
            self._let_go[:, eq] &= touching
            held = np.flatnonzero(active & state.eq_active[:, eq])
            if held.size:
                face = join_face(state, held, (b1, self.boxes[b1]), (b2, self.boxes[b2]))
                over = face.overloaded(sim.weld_load(held, eq), state.xpos[held, b2])
                if over.any():
                    sim.set_weld(held[over], eq, False)
                    self._let_go[held[over], eq] = True
            worlds = np.flatnonzero(active & ~state.eq_active[:, eq] & touching & ~self._let_go[:, eq])
            if worlds.size:
                sim.set_weld(worlds, eq, True)


BodyBox = tuple[np.ndarray, np.ndarray]  # a box in a body's frame: its centre and half sizes
BodyParts = tuple[int, list[BodyBox]]  # a body and the boxes of its parts, in its frame


def _box(corners: np.ndarray) -> BodyBox:
    """The box (centre, half sizes) around ``corners`` (k, 3) in a body's frame."""
    low, high = corners.min(axis=0), corners.max(axis=0)
    return (low + high) / 2, (high - low) / 2


@dataclass(frozen=True)
class JoinFace:
    """Where two magnetic bodies meet, per world (k of them): the centre (k, 3) of the patch where the smaller of the
    faces that face each other overlaps the other body, its two in-plane unit axes (k, 2, 3) with their half lengths
    (k, 2), and its unit normal (k, 3)."""

    centre: np.ndarray
    axes: np.ndarray
    half: np.ndarray
    normal: np.ndarray

    def where(self, chosen: np.ndarray, other: JoinFace) -> JoinFace:
        """Per world, ``other``'s patch where ``chosen`` (k,), else this one."""
        return JoinFace(
            centre=np.where(chosen[:, None], other.centre, self.centre),
            axes=np.where(chosen[:, None, None], other.axes, self.axes),
            half=np.where(chosen[:, None], other.half, self.half),
            normal=np.where(chosen[:, None], other.normal, self.normal),
        )

    def overloaded(self, load: np.ndarray, origin: np.ndarray) -> np.ndarray:
        """(k,) whether a weld load (k, 6: force, then torque about ``origin`` (k, 3), as
        :meth:`~robotool.sim.backend.BatchedSim.weld_load` gives it) is more than the magnet holds."""
        force = load[:, :3]
        couple = load[:, 3:] + np.cross(origin - self.centre, force)  # about the face's centre
        peel = np.abs(np.einsum("kij,kj->ki", self.axes, couple))  # (k, 2): about each in-plane axis
        twist = np.abs(np.einsum("kj,kj->k", self.normal, couple))
        return (
            (np.linalg.norm(force, axis=1) > HOLD_FORCE)
            | (peel > HOLD_FORCE * self.half[:, ::-1]).any(axis=1)  # about one axis it pivots across the other
            | (twist > HOLD_FORCE * self.half.min(axis=1))
        )


def join_face(state: BatchState, worlds: np.ndarray, one: BodyParts, two: BodyParts) -> JoinFace:
    """The patch where two touching bodies meet in ``worlds`` (each ``(body, boxes of its parts in its frame)``): of
    the pairs of their parts, the one nearest to touching (the least gap between the boxes along their axes); of each of
    its two boxes, the face the other box lies beyond (least inside its plane), where the other box's extent covers it;
    of the two, the smaller."""
    (body, parts), (other, other_parts) = one, two
    best: JoinFace | None = None
    least = np.full(len(worlds), np.inf)
    for box, other_box in itertools.product(parts, other_parts):
        (first, gap), (second, other_gap) = (
            _facing(state, worlds, (body, box), (other, other_box)),
            _facing(state, worlds, (other, other_box), (body, box)),
        )
        face = second.where(first.half.prod(axis=1) <= second.half.prod(axis=1), first)  # the smaller
        apart = np.maximum(gap, other_gap)
        nearer = apart < least
        least = np.where(nearer, apart, least)
        best = face if best is None else best.where(nearer, face)
    assert best is not None
    return best


def _facing(
    state: BatchState, worlds: np.ndarray, one: tuple[int, BodyBox], two: tuple[int, BodyBox]
) -> tuple[JoinFace, np.ndarray]:
    """The face of the first box that the second lies beyond (of its six, the one whose plane the second box reaches
    least far inside: about 0 for the face they touch on), cut to the part of it the second box's extent covers, and
    how far beyond it the second box lies (k,; < 0: inside its plane)."""
    (body, (centre, half)), (other, (other_centre, other_half)) = one, two
    rot, other_rot = state.xmat(body)[worlds], state.xmat(other)[worlds]  # (k, 3, 3): axes as columns
    origin = state.xpos[worlds, body] + rot @ centre
    other_origin = state.xpos[worlds, other] + other_rot @ other_centre
    local = np.einsum("kji,kj->ki", rot, other_origin - origin)  # (k, 3): the other's centre on this box's axes
    reach = np.abs(np.swapaxes(rot, 1, 2) @ other_rot) @ other_half  # (k, 3): its half extent along each axis
    gaps = np.concatenate([local - reach - half, -local - reach - half], axis=1)  # (k, 6): beyond +x..+z, -x..-z
    face = np.argmax(gaps, axis=1)
    axis, side = face % 3, np.where(face < 3, 1.0, -1.0)
    k = np.arange(len(worlds))
    normal = rot[k, :, axis] * side[:, None]
    others = np.stack([(axis + 1) % 3, (axis + 2) % 3], axis=1)  # (k, 2)
    axes = np.stack([rot[k, :, others[:, 0]], rot[k, :, others[:, 1]]], axis=1)  # (k, 2, 3)
    along, extent = np.take_along_axis(local, others, 1), np.take_along_axis(reach, others, 1)  # (k, 2) in-plane
    low, high = np.maximum(-half[others], along - extent), np.minimum(half[others], along + extent)
    middle = np.einsum("ki,kij->kj", (low + high) / 2, axes)
    patch = JoinFace(origin + normal * half[axis][:, None] + middle, axes, np.maximum(high - low, 0.0) / 2, normal)
    return patch, gaps[k, face]
