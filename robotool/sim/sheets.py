"""Sheets (paper): what rests on them moves with them by friction; their edge never shoves anything.

A sheet is too limp to push or lift anything with its edge: driven edge-first into a standing object
it buckles or slips under without moving it. An object rests on a sheet only once it got there itself
(pushed or put onto the sheet while the sheet lay still) or stood on it from the start, and only while its
own support is on the sheet: at least :data:`SUPPORT_SHARE` of its base over the sheet and its centre of mass
over it (an object half on the sheet is held back by the table as much as the sheet pulls it). From then on
the sheet's carrier geom for that object is in place (:func:`robotool.sim.build.make_spec`), so the object
rides on the sheet by friction, until its support leaves the sheet (less than :data:`LEAVE_SHARE` of its base
over it, or its centre off it), it is lifted off, or the sheet itself is lifted off the table (held up by an
edge, it droops and carries nothing: :data:`RAISED`); otherwise the carrier lies far below. A sheet pinned down
(an object standing partly on it, not riding it, presses it with more than :data:`PIN_FORCE` of friction: a crate
with a corner on it; or a fixed object stands on it) carries nothing either, and it is held to the table (its weld
:func:`~robotool.sim.build.sheet_pin_name`) for as long as the pull on it stays within that friction: a pull past it
slides it a tick at a time, and a fixed object holds it whatever pulls (found by an adversarial run: paper under a
60 kg crate, or under a block bolted down, was dragged out by its free end and lifted, as a sheet meets nothing but
the ground and the robot). A sheet slid (or laid) under a standing object got there, not the object: once the sheet
moving more than the object brought more of the object's base over it (any share, not only its centre), no nudge
makes the object rest on the sheet until its base has left the sheet entirely, whatever order the slides and nudges
came in.
:meth:`Sheets.update` applies this rule after every control tick, per world.
"""

from __future__ import annotations

import mujoco
import numpy as np

from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.build import (
    DEFAULT_FRICTION,
    GROUND_FRICTION,
    SHEET_CARRIER_DROP,
    contact_friction,
    rests_on_sheet,
    sheet_carrier_name,
    sheet_friction,
    sheet_pin_name,
)
from robotool.sim.compiled_scene import Scene
from robotool.task import geometry
from robotool.task.scene import SceneObject

MOVED = 0.002  # m per control tick: a body that moved less than this lay still
LIFTED = 0.01  # m above a sheet's top: an object this high is off it
BOLTED_GAP = 0.001  # m above a sheet's top: a fixed object whose base is this near stands on the sheet
RAISED = 0.002  # m: a sheet whose underside is held this high above the ground droops and carries nothing
PIN_FORCE = 10.0  # N of friction from what stands partly on a sheet (not riding it), on both its faces, that pins it
SUPPORT_SHARE = 0.9  # of an object's base over a sheet, with its centre, for it to come to rest on the sheet
LEAVE_SHARE = 0.5  # an object resting on a sheet leaves it when less of its base than this is over it
BASE_SAMPLES = 9  # points along each side of a face of an object (a grid; a disc on a cylinder's ends)
BASE_DEPTH = 0.003  # m: an object's surface points this near its lowest are its base, where it stands
GAINED = 1e-3  # of an object's base: more than this came over the sheet during a tick


class Sheets:
    """The sheet pairs of a scene and the rule that switches them, in every world."""

    def __init__(self, scene: Scene, nworld: int):
        model, task = scene.model, scene.task
        self.links: list[tuple[int, int, int]] = []  # (sheet object, object, carrier geom)
        self.pins: list[tuple[int, int]] = []  # (sheet object, its weld to the table)
        self.bolted: list[tuple[int, int]] = []  # (sheet object, a fixed object that may stand on it)
        self.draped: list[tuple[int, int, float]] = []  # (sheet object, a cloth's link body, the pair's friction)
        on = []
        for s, sheet in enumerate(task.objects):
            if not (sheet.is_sheet and sheet.movable):
                continue
            self.pins.append((s, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_EQUALITY, sheet_pin_name(sheet.name))))
            for i, obj in enumerate(task.objects):
                geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, sheet_carrier_name(sheet.name, obj.name))
                if geom >= 0:
                    self.links.append((s, i, geom))
                    on.append(rests_on_sheet(obj, sheet))
                elif not obj.movable and not obj.is_sheet:
                    self.bolted.append((s, i))
                elif obj.shape == "cloth":
                    mu = sheet_friction(sheet, obj) + _on_table(sheet)
                    self.draped += [(s, int(b), mu) for b in np.flatnonzero(scene.body_object == i)]
        self.scene = scene
        self.half = {s: np.asarray(task.objects[s].size[:2]) / 2 for s, _ in self.pins}
        self.thickness = {s: min(task.objects[s].size) for s, _ in self.pins}
        self.placed = {
            g: model.geom_pos[g] + (0.0 if o else SHEET_CARRIER_DROP) * np.array([0.0, 0.0, 1.0])
            for (_, _, g), o in zip(self.links, on, strict=True)
        }
        objects = {i for _, i, _ in self.links} | {i for _, i in self.bolted}
        self.surface = {i: surface_points(task.objects[i]) for i in objects}
        self.pin_friction = np.array(  # per pair: what presses the object on the table presses the sheet there too,
            [  # so both the sheet's faces hold it
                sheet_friction(task.objects[s], task.objects[i]) + _on_table(task.objects[s]) for s, i, _ in self.links
            ]
        )
        self.link_half = {b: scene.model.geom_size[scene.model.body_geomadr[b]] for _, b, _ in self.draped}
        self.ground = np.arange(scene.model.nbody) == 0  # the world body: the table's plane
        self.on = np.tile(np.array(on, dtype=bool), (nworld, 1))
        self.share = np.zeros(self.on.shape)  # (nworld, nlink): share of the object's base over its sheet
        self.slid_under = np.zeros_like(self.on)  # the sheet got under the object, not the other way round
        self.previous: np.ndarray | None = None

    def update(self, sim: BatchedSim, state: BatchState, active: np.ndarray) -> None:
        """Switch each sheet pair on where its object came to rest on the sheet, off where it left it."""
        if not self.pins:
            return
        bodies = self.scene.object_body
        xpos = state.xpos[:, bodies]  # (nworld, nobject, 3)
        previous = xpos if self.previous is None else self.previous
        step = np.linalg.norm(xpos - previous, axis=2)  # (nworld, nobject): how far each moved this tick
        moved = step > MOVED
        first = self.previous is None
        self.previous = xpos.copy()
        measured = [self._measure(s, i, xpos, state, LIFTED) for s, i, _ in self.links]
        hold = self._hold(sim, [np.where(resting, share, 0.0) for _, share, resting in measured], xpos, state)
        pinned = hold > PIN_FORCE
        for k, (s, i, geom) in enumerate(self.links):
            centre_over, share, resting = measured[k]
            resting = resting & ~pinned[:, s]
            before = np.where(first, 0.0, self.share[:, k])
            gained = resting & (share > before + GAINED)  # more of its base came over the sheet this tick ...
            # ... because the sheet moved under it (at least as far as it did), or it stood over the sheet at the start
            # without resting on it
            sheet_moved = moved[:, s] & (step[:, s] >= step[:, i])
            slid = gained & ~self.on[:, k] & np.where(first, centre_over, sheet_moved)
            off = ~resting | (share == 0.0)
            self.slid_under[:, k] = np.where(active, (self.slid_under[:, k] | slid) & ~off, self.slid_under[:, k])
            self.share[:, k] = np.where(active, np.where(resting, share, 0.0), self.share[:, k])
            supported = resting & centre_over & (share >= SUPPORT_SHARE)
            arrive = active & supported & ~self.on[:, k] & ~self.slid_under[:, k] & moved[:, i] & ~moved[:, s]
            leave = active & self.on[:, k] & ~(resting & centre_over & (share >= LEAVE_SHARE))
            for worlds, on in ((np.flatnonzero(arrive), True), (np.flatnonzero(leave), False)):
                if worlds.size:
                    self.on[worlds, k] = on
                    drop = 0.0 if on else SHEET_CARRIER_DROP
                    sim.set_geom_pos(worlds, geom, self.placed[geom] - np.array([0.0, 0.0, drop]))
        self._pin(sim, state, active, pinned, hold)

    def _pin(
        self, sim: BatchedSim, state: BatchState, active: np.ndarray, pinned: np.ndarray, hold: np.ndarray
    ) -> None:
        """Hold each pinned sheet to the table in the ``active`` worlds, and let it go where it is no longer pinned or
        the pull on it passed ``hold`` (N, (nworld, nobject)) in the last tick: it slides, and is held again the next
        tick where it is still pinned."""
        for s, eq in self.pins:
            on = state.eq_active[:, eq]
            slips = np.zeros(len(on), dtype=bool)
            weighed = np.flatnonzero(active & on & np.isfinite(hold[:, s]))
            if weighed.size:
                pull = np.linalg.norm(sim.weld_load(weighed, eq)[:, :3], axis=1)
                slips[weighed] = pull > hold[weighed, s]
            for worlds, attach in (
                (np.flatnonzero(active & on & (~pinned[:, s] | slips)), False),
                (np.flatnonzero(active & ~on & pinned[:, s]), True),
            ):
                if worlds.size:
                    sim.set_weld(worlds, eq, attach)

    def _draped(self, s: int, b: int, xpos: np.ndarray, state: BatchState) -> np.ndarray:
        """(nworld,) whether cloth link body ``b`` lies on sheet ``s``: its centre over the sheet, its underside within
        :data:`LIFTED` of the sheet's top."""
        sheet = self.scene.object_body[s]
        local = np.einsum("wji,wj->wi", state.xmat(sheet), state.xpos[:, b] - xpos[:, s])
        over = np.all(np.abs(local[:, :2]) <= self.half[s], axis=1)
        top = xpos[:, s, 2] + self.thickness[s] / 2
        return over & (state.xpos[:, b, 2] - self.link_half[b][2] < top + LIFTED)

    def _measure(
        self, s: int, i: int, xpos: np.ndarray, state: BatchState, gap: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Object ``i`` on sheet ``s`` as they lie, (nworld,) each: whether the object's centre is over the sheet, the
        share of its base over the sheet, and whether it rests there (its base within ``gap`` of the sheet's top, the
        sheet flat on the ground)."""
        bodies = self.scene.object_body
        rot = state.xmat(bodies[s])  # (nworld, 3, 3)
        local = np.einsum("wji,wj->wi", rot, xpos[:, i] - xpos[:, s])
        centre_over = np.all(np.abs(local[:, :2]) <= self.half[s], axis=1)
        turn = state.xmat(bodies[i])  # (nworld, 3, 3): the object's frame in the world
        heights = xpos[:, i, None, 2] + turn[:, 2, :] @ self.surface[i].T  # (nworld, npoint)
        bottom = heights.min(axis=1)
        base = heights <= bottom[:, None] + BASE_DEPTH  # (nworld, npoint): where it stands, as it lies
        in_sheet = rot[:, :, :2].transpose(0, 2, 1) @ turn  # (nworld, 2, 3): the object's axes in the sheet's x-y
        across = local[:, None, :2] + self.surface[i] @ in_sheet.transpose(0, 2, 1)  # its points in the sheet
        over = np.all(np.abs(across) <= self.half[s], axis=2)
        share = (over & base).sum(axis=1) / base.sum(axis=1)
        top = xpos[:, s, 2] + self.thickness[s] / 2
        flat = top - self.thickness[s] < RAISED  # a sheet held up by an edge droops: it carries nothing
        return centre_over, share, flat & (bottom < top + gap)

    def _hold(self, sim: BatchedSim, shares: list[np.ndarray], xpos: np.ndarray, state: BatchState) -> np.ndarray:
        """(nworld, nobject) N: the friction with which what stands partly on each sheet, not riding it, holds it
        down (``shares``: per pair, the share of the object's base resting on the sheet): the share of the force with
        which the table bears the object up, its own weight and whatever it carries (found by an adversarial run: a
        60 kg crate on a 1 kg block standing on paper was not counted); the links of a cloth lying on it alike;
        without bound where a fixed object stands on it."""
        hold = np.zeros((len(xpos), len(self.scene.task.objects)))
        standing = [np.where(self.on[:, k], 0.0, shares[k]) for k in range(len(self.links))]
        draped = [self._draped(s, b, xpos, state) for s, b, _ in self.draped]
        pressing = np.flatnonzero(np.any([*standing, *draped], axis=0)) if standing or draped else np.zeros(0, int)
        if pressing.size:
            up = np.zeros((len(xpos), self.scene.model.nbody))
            up[pressing] = np.maximum(sim.contact_forces(pressing, self.ground)[..., 2], 0.0)
            bodies = self.scene.object_body
            for k, (s, i, _) in enumerate(self.links):
                hold[:, s] += standing[k] * self.pin_friction[k] * up[:, bodies[i]]
            for (s, b, mu), over in zip(self.draped, draped, strict=True):
                hold[:, s] += np.where(over, mu * up[:, b], 0.0)
        for s, i in self.bolted:
            _, share, resting = self._measure(s, i, xpos, state, BOLTED_GAP)
            hold[resting & (share > 0.0), s] = np.inf
        return hold


def _on_table(sheet: SceneObject) -> float:
    """The friction between a sheet and the table under it (:func:`~robotool.sim.build.contact_friction`)."""
    return float(contact_friction(sheet.friction or DEFAULT_FRICTION, GROUND_FRICTION))


def surface_points(obj: SceneObject) -> np.ndarray:
    """Points spread over an object's surface in its body frame (n, 3): a grid of :data:`BASE_SAMPLES` a side on each
    face of a box part; a cylinder part's end discs and rings along its side. Those lowest as the object lies now are
    its base (:data:`BASE_DEPTH`), whichever way it was placed (a cube given a roll stands on a side) or has tipped."""
    rot, centre = geometry.rotation_matrix(obj.rpy), np.asarray(obj.center)
    t = np.linspace(-1.0, 1.0, BASE_SAMPLES)
    a, b = (g.ravel() for g in np.meshgrid(t, t))
    disc = np.column_stack([a, b])[np.hypot(a, b) <= 1.0 + 1e-9]
    around = np.linspace(0.0, 2 * np.pi, 4 * BASE_SAMPLES, endpoint=False)
    points = []
    for part in geometry.object_parts(obj):
        if part.kind == "box":  # (part frame, in half sizes) each face: one axis at -1 or 1, the others on the grid
            faces = [
                np.insert(np.column_stack([a, b]), axis, side, axis=1) for axis in range(3) for side in (-1.0, 1.0)
            ]
            local = np.vstack(faces) * part.half
        else:  # a cylinder: its axis is the part's z, radius half[0], half-length half[2]
            r, h = part.half[0], part.half[2]
            ends = [np.column_stack([disc * r, np.full(len(disc), side * h)]) for side in (-1.0, 1.0)]
            ring = np.column_stack([np.cos(around) * r, np.sin(around) * r])
            side = [np.column_stack([ring, np.full(len(ring), z * h)]) for z in t]
            local = np.vstack([*ends, *side])
        points.append((part.center + local @ part.rot.T - centre) @ rot)
    return np.vstack(points)
