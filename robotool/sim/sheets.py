"""Sheets (paper): what rests on them moves with them by friction; their edge never shoves anything.

A sheet is too limp to push or lift anything with its edge: driven edge-first into a standing object
it buckles or slips under without moving it. An object rests on a sheet only once it got there itself
(pushed or put onto the sheet while the sheet lay still) or stood on it from the start; from then on the
sheet's carrier geom for that object is in place (:func:`robotool.sim.build.make_spec`), so the object
rides on the sheet by friction, until it leaves the sheet's footprint, is lifted off, or the sheet
itself is lifted off the table (held up by an edge, it droops and carries nothing); otherwise the
carrier lies far below. A sheet slid (or laid) under a standing object got there, not the object: the
object came over the sheet while the sheet moved more than it did, and until it leaves the sheet's
footprint again no nudge makes it rest on the sheet. :meth:`Sheets.update` applies this rule after every
control tick, per world.
"""

from __future__ import annotations

import mujoco
import numpy as np

from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.build import SHEET_CARRIER_DROP, is_sheet, rests_on_sheet, sheet_carrier_name
from robotool.sim.compiled_scene import Scene

MOVED = 0.002  # m per control tick: a body that moved less than this lay still
LIFTED = 0.01  # m above a sheet's top: an object this high is off it


class Sheets:
    """The sheet pairs of a scene and the rule that switches them, in every world."""

    def __init__(self, scene: Scene, nworld: int):
        model, task = scene.model, scene.task
        self.links: list[tuple[int, int, int]] = []  # (sheet object, object, carrier geom)
        on = []
        for s, sheet in enumerate(task.objects):
            for i, obj in enumerate(task.objects):
                if not (is_sheet(sheet) and sheet.movable) or i == s:
                    continue
                geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, sheet_carrier_name(sheet.name, obj.name))
                if geom >= 0:
                    self.links.append((s, i, geom))
                    on.append(rests_on_sheet(obj, sheet))
        self.scene = scene
        self.half = {s: np.asarray(task.objects[s].size[:2]) / 2 for s, _, _ in self.links}
        self.thickness = {s: min(task.objects[s].size) for s, _, _ in self.links}
        self.depth = {i: task.objects[i].center[2] - task.objects[i].bottom for _, i, _ in self.links}
        self.placed = {
            g: model.geom_pos[g] + (0.0 if o else SHEET_CARRIER_DROP) * np.array([0.0, 0.0, 1.0])
            for (_, _, g), o in zip(self.links, on, strict=True)
        }
        self.on = np.tile(np.array(on, dtype=bool), (nworld, 1))
        self.over = self.on.copy()  # (nworld, nlink): the object was over its sheet, resting, at the last tick
        self.slid_under = np.zeros_like(self.on)  # the sheet got under the object, not the other way round
        self.previous: np.ndarray | None = None

    def update(self, sim: BatchedSim, state: BatchState, active: np.ndarray) -> None:
        """Switch each sheet pair on where its object came to rest on the sheet, off where it left it."""
        if not self.links:
            return
        bodies = self.scene.object_body
        xpos = state.xpos[:, bodies]  # (nworld, nobject, 3)
        previous = xpos if self.previous is None else self.previous
        step = np.linalg.norm(xpos - previous, axis=2)  # (nworld, nobject): how far each moved this tick
        moved = step > MOVED
        first = self.previous is None
        self.previous = xpos.copy()
        for k, (s, i, geom) in enumerate(self.links):
            rot = state.xmat(bodies[s])  # (nworld, 3, 3)
            local = np.einsum("wji,wj->wi", rot, xpos[:, i] - xpos[:, s])
            over = np.all(np.abs(local[:, :2]) <= self.half[s], axis=1)
            top = xpos[:, s, 2] + self.thickness[s] / 2
            flat = top - self.thickness[s] < LIFTED  # a sheet held up by an edge droops: it carries nothing
            resting = flat & (xpos[:, i, 2] - self.depth[i] < top + LIFTED)
            came = active & over & resting & ~self.over[:, k]  # came over the sheet during this tick
            slid = came & (first | (step[:, s] >= step[:, i]))  # ... because the sheet moved (or it was there)
            self.slid_under[:, k] = np.where(
                active, (self.slid_under[:, k] | slid) & over & resting, self.slid_under[:, k]
            )
            self.over[:, k] = np.where(active, over & resting, self.over[:, k])
            arrive = active & over & resting & ~self.on[:, k] & ~self.slid_under[:, k] & moved[:, i] & ~moved[:, s]
            leave = active & self.on[:, k] & ~(over & resting)
            for worlds, on in ((np.flatnonzero(arrive), True), (np.flatnonzero(leave), False)):
                if worlds.size:
                    self.on[worlds, k] = on
                    drop = 0.0 if on else SHEET_CARRIER_DROP
                    sim.set_geom_pos(worlds, geom, self.placed[geom] - np.array([0.0, 0.0, drop]))
