"""Magnetic objects weld to each other on contact (chains included), per world.

:func:`robotool.sim.build.make_spec` adds an inactive weld ``magnet__<a>__<b>`` for every pair of
magnetic objects; :meth:`Magnets.update` activates it, at the current relative pose, in every world
where the two bodies touch.
"""

from __future__ import annotations

import numpy as np

from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.compiled_scene import Scene


class Magnets:
    """The magnet welds of a scene and the rule that attaches them."""

    def __init__(self, scene: Scene):
        model = scene.model
        self.pairs = [
            (eq, model.eq_obj1id[eq], model.eq_obj2id[eq])
            for eq in range(model.neq)
            if model.equality(eq).name.startswith("magnet__")
        ]

    def update(self, sim: BatchedSim, state: BatchState, active: np.ndarray) -> None:
        """Attach every magnet pair that touches in an ``active`` world and is not attached yet."""
        for eq, b1, b2 in self.pairs:
            worlds = np.flatnonzero(active & ~state.eq_active[:, eq] & state.touching[:, b1, b2])
            if worlds.size:
                sim.set_weld(worlds, eq, True)
