"""Still pictures: a task's scene at its start, or a recorded world at its end."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robotool.render.overlay import CaptionLine
from robotool.render.painter import Painter, RenderError
from robotool.sim.build import build
from robotool.sim.compiled_scene import Scene
from robotool.task.task_model import Task

STILL_SIZE = (960, 540)  # px, width x height


def scene_title(task: Task) -> CaptionLine:
    """The title band of a task's pictures: its name, embodiment and goal."""
    return CaptionLine(f"{task.name} ({task.embodiment}) - goal: {task.goal.text()}")


def save_png(image_path: Path, painter: Painter, caption: list[CaptionLine] | None = None) -> Path:
    """Write the painter's current state as a labelled PNG."""
    image = painter.picture(title=[scene_title(painter.scene.task)], caption=caption or [])
    try:
        image_path.parent.mkdir(parents=True, exist_ok=True)
        image.save(image_path, format="PNG", compress_level=3)  # optimize=True took 5x as long for 10% less
    except OSError as e:
        raise RenderError(f"cannot write {image_path}: {e.strerror or e}") from None
    return image_path


def render_scene(
    task: Task | Scene,
    out: Path,
    *,
    width: int = STILL_SIZE[0],
    height: int = STILL_SIZE[1],
    painter: Painter | None = None,
) -> Path:
    """Draw the task's scene at its start state, labelled, to the PNG ``out`` (with ``painter``, as for
    :func:`render_state`)."""
    mine = painter is None
    scene = task if isinstance(task, Scene) else build(task)
    painter = painter or Painter(scene, width, height)
    try:
        painter.frame()
        return save_png(out, painter)
    finally:
        if mine:
            painter.close()


def render_state(
    scene: Scene,
    qpos: np.ndarray,
    out: Path,
    *,
    caption: list[CaptionLine],
    mocap_pos: np.ndarray | None = None,
    width: int = STILL_SIZE[0],
    height: int = STILL_SIZE[1],
    painter: Painter | None = None,
) -> Path:
    """Draw one state of a world (e.g. the end of a failed rollout) with a caption, to the PNG ``out``.

    The camera keeps both the start state and this one in view. A ``painter`` of the scene (its size wins) is
    used and left open; otherwise one is made for this picture.
    """
    mine = painter is None
    painter = painter or Painter(scene, width, height)
    try:
        painter.frame(np.stack([scene.model.qpos0, qpos]))
        painter.set_state(qpos, mocap_pos)
        return save_png(out, painter, caption)
    finally:
        if mine:
            painter.close()
