"""The off-screen renderer: the same pixels as ``mujoco.Renderer``, from one OpenGL context shared by every model a
thread draws, and each model's render context freed on its own."""

from __future__ import annotations

import threading

import mujoco
import numpy as np
import pytest

from robotool import sim, tasks
from robotool.render import offscreen
from robotool.render.painter import Painter


@pytest.mark.parametrize("task", ["sofa_traversing", "milk_reaching"])
@pytest.mark.parametrize("shadows", [True, False])
def test_pixels_are_those_of_mujocos_renderer(task: str, shadows: bool) -> None:
    painter = Painter(sim.build(tasks.load(task)), 320, 180, shadows=shadows)
    try:
        ours = painter.pixels()
        theirs = mujoco.Renderer(painter.drawing.model, height=180, width=320)
        try:
            theirs.update_scene(painter.data, painter.camera)
            assert np.array_equal(ours, theirs.render())
        finally:
            theirs.close()
        assert painter.drawing.model.vis.global_.offwidth == 1920  # the model's buffer limit is left as it was
    finally:
        painter.close()


def test_a_thread_draws_every_model_in_one_context_and_a_closed_one_refuses() -> None:
    first = Painter(sim.build(tasks.load("sofa_traversing")), 160, 96)
    second = Painter(sim.build(tasks.load("milk_reaching")), 160, 96)
    try:
        assert first._renderer._context is second._renderer._context
        before = first.pixels()
        second.pixels()  # another model's buffer bound in between
        assert np.array_equal(first.pixels(), before)
    finally:
        second.close()
    first.close()
    with pytest.raises(RuntimeError, match="after close"):
        first.pixels()
    elsewhere: list[object] = []
    thread = threading.Thread(target=lambda: elsewhere.append(offscreen._current_context()))
    thread.start()
    thread.join()
    assert elsewhere and elsewhere[0] is not first._renderer._context  # a context is current in one thread only
