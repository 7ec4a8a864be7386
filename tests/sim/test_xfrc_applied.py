"""Both backends apply the controllers' ``xfrc_applied`` buffer alike (Warp's CPU device: slow to compile)."""

from __future__ import annotations

import importlib.util
from typing import Any

import numpy as np
import pytest
from fixtures.warp_group import ON_WARP

from robotool import sim

if importlib.util.find_spec("mujoco_warp") is None:  # not imported here: collecting stays quick where deselected
    pytest.skip("mujoco_warp is not installed", allow_module_level=True)

pytestmark = [pytest.mark.slow, ON_WARP]


def test_a_force_on_a_body_lifts_it_alike_on_both_backends(sim_scene: Any) -> None:
    """Three times its weight up on a cube in world 1 lifts it there, the same on C and Warp; world 0 is left be."""
    scene = sim_scene("button_pressing")
    body = int(scene.object_body[scene.object_index("magnetic_cube1")])
    heights = []
    for backend in ("mujoco", "warp"):
        batch = sim.make_sim(scene, 2, backend=backend)
        before = batch.state().xpos[:, body, 2].copy()
        batch.xfrc_applied[1, body, 2] = 3.0 * batch.body_mass[1, body] * 9.81
        batch.step(scene.control_substeps, np.ones(2, dtype=bool))
        heights.append(batch.state().xpos[:, body, 2] - before)
    for rise in heights:
        assert abs(rise[0]) < 1e-3 and rise[1] > 0.01, rise
    np.testing.assert_allclose(heights[1], heights[0], atol=2e-3)
