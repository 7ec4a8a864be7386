"""Magnetic objects weld to each other on contact (chains included), and let go past what a magnet holds, per world.

:func:`robotool.sim.build.make_spec` adds an inactive weld ``magnet__<a>__<b>`` for every pair of
magnetic objects; :meth:`Magnets.update` activates it, at the current relative pose, in every world
where the two bodies touch. A magnet holds a bounded load: a weld whose constraint force or torque passes
:data:`HOLD_FORCE` or :data:`HOLD_TORQUE` lets go, and that pair attaches again only after the two have come apart
(a board stuck by its end face to a cabinet's side does not carry a robot across a gap).
"""

from __future__ import annotations

import numpy as np

from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.compiled_scene import Scene

HOLD_FORCE = 200.0
"""N a magnet pair holds (about 20 kg hanging): three times the most the button task's cubes carry when the paper's
program drives the chain into the next cube's centre (61 N, sideways), forty times the reference program's."""
HOLD_TORQUE = 20.0
"""N m a magnet pair holds against twisting or peeling (about the second body's origin): ten times the most the button
task's cubes carry (1.9 N m in the paper's program)."""


class Magnets:
    """The magnet welds of a scene and the rules that attach and release them."""

    def __init__(self, scene: Scene):
        model = scene.model
        self.pairs = [
            (eq, model.eq_obj1id[eq], model.eq_obj2id[eq])
            for eq in range(model.neq)
            if model.equality(eq).name.startswith("magnet__")
        ]
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
                load = sim.weld_load(held, eq)
                over = (np.linalg.norm(load[:, :3], axis=1) > HOLD_FORCE) | (
                    np.linalg.norm(load[:, 3:], axis=1) > HOLD_TORQUE
                )
                if over.any():
                    sim.set_weld(held[over], eq, False)
                    self._let_go[held[over], eq] = True
            worlds = np.flatnonzero(active & ~state.eq_active[:, eq] & touching & ~self._let_go[:, eq])
            if worlds.size:
                sim.set_weld(worlds, eq, True)
