"""Downward rays over a cloth: a ray that meets a cloth's link is cast again without that link, and every such ray
is cast again in the same call, each leaving out its own link, with the answers of one ray cast at a time."""

from __future__ import annotations

from typing import Any

import numpy as np

from robotool.robots.quadruped.quadruped_controller import QuadrupedController
from robotool.sim.backend_choice import make_sim


def test_rays_over_a_cloth_recast_every_link_met_in_one_call(sim_scene: Any) -> None:
    scene = sim_scene("sofa_traversing")
    simulator = make_sim(scene, 2)
    try:
        simulator.step(200, np.ones(2, dtype=bool))  # the cloth settles where it lies
        rays = QuadrupedController(simulator, scene.task.limits).plans.rays
        cloth = next(o for o in scene.task.objects if o.shape == "cloth")
        (x, y, _), (sx, sy, _) = cloth.center, cloth.size
        along, across = np.linspace(x - sx / 2, x + sx / 2, 25), np.linspace(y - sy / 2, y + sy / 2, 4)
        grid = np.stack(np.meshgrid(along, across), axis=-1)
        xy = np.repeat(grid.reshape(1, -1, 2), 2, axis=0)
        calls = []
        cast = simulator.rays

        def counted(*args: Any, **kwargs: Any) -> tuple[np.ndarray, np.ndarray]:
            calls.append(args[0].shape)
            return cast(*args, **kwargs)

        simulator.rays = counted  # type: ignore[method-assign]
        z, objects = rays.cast(np.array([0, 1]), xy, np.array([1.0, 1.0]))
        cloth_index = scene.task.object_names.index(cloth.name)
        links = {int(b) for b in scene.model.geom_bodyid if scene.body_object[b] == cloth_index}
        assert len(calls) <= 3 < len(links), (len(calls), len(links))  # the first cast, then one per layer of cloth
        assert cloth_index not in objects  # what carries the cloth is named, not the cloth
        for w in (0, 1):
            for k in range(xy.shape[1]):
                alone_z, alone_objects = rays.heights(w, xy[w, k : k + 1], 1.0)
                assert (alone_z[0], alone_objects[0]) == (z[w, k], objects[w, k])
    finally:
        simulator.close()
