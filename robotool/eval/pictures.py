"""Pictures for the evaluation report: each task's scene, and the end state of a representative failed world.

For every task instance and every failure class seen on it, the first failed world (in run order) is
simulated again from its program and its world's seed, recorded, and drawn at its end; the caption
gives the method, run, world, class and the recorded reason. On the ``mujoco`` backend the new rollout
repeats the evaluated one exactly; where it does not (another backend), the caption says so. A run
whose program never ran is drawn at its start. Files go to ``pictures/`` in the results folder.
"""

from __future__ import annotations

from collections.abc import Sequence
from concurrent.futures import Future
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import TYPE_CHECKING, Self

from robotool.eval.executor import PRELOAD
from robotool.eval.failure_classes import FailureClass
from robotool.eval.instances import TaskInstance
from robotool.eval.records import Picture, RunRecord, WorldResult
from robotool.processes import process_pool
from robotool.render.overlay import CaptionLine
from robotool.render.video import RED, end_lines
from robotool.verify import world_failure
from robotool.vocabulary import BackendName

if TYPE_CHECKING:
    from robotool.render.painter import Painter
    from robotool.sim.compiled_scene import Scene

FOLDER = "pictures"
SIZE = (640, 360)  # px


def slug(text: str) -> str:
    return "".join(c if c.isalnum() or c == "_" else "-" for c in text)  # family#3 -> family-3


def representatives(records: Sequence[RunRecord]) -> dict[FailureClass, tuple[RunRecord, WorldResult | None]]:
    """The first failed world of each failure class among one instance's records (None: nothing ran)."""
    found: dict[FailureClass, tuple[RunRecord, WorldResult | None]] = {}
    for record in records:
        if not record.worlds and record.failure_class is not None and record.failure_class not in found:
            found[record.failure_class] = (record, None)
        for world in record.worlds:
            if world.failure_class is not None and world.failure_class not in found:
                found[world.failure_class] = (record, world)
    return found


def write_pictures(
    instances: Sequence[TaskInstance],
    records: Sequence[RunRecord],
    folder: Path,
    backend: BackendName | None,
    processes: int = 1,
) -> list[Picture]:
    """Draw every instance's scene and its representative failures into ``folder/pictures``, the instances
    shared out over ``processes`` processes (each drawing and simulating on its own core)."""
    with PictureDrawer(len(instances), folder, backend, processes) as drawer:
        for instance in instances:
            drawer.draw(instance, [r for r in records if r.key.task == instance.name and r.key.seed == instance.seed])
        return drawer.pictures()


class PictureDrawer:
    """Draws instances' pictures in up to ``processes`` pool processes as they are handed over (the evaluator hands
    over an instance as soon as its last run is recorded, so that drawing overlaps the runs still going); with one
    process, or for an instance whose drawing process died, here when :meth:`pictures` is asked for."""

    def __init__(self, instances: int, folder: Path, backend: BackendName | None, processes: int = 1) -> None:
        self.folder = folder
        self.backend = backend
        self.handed: list[tuple[TaskInstance, list[RunRecord]]] = []
        self.drawing: list[Future[list[Picture]] | None] = []
        self.pool = None
        if processes > 1 and instances > 1:
            self.pool = process_pool(min(processes, instances), preload=PRELOAD)

    def draw(self, instance: TaskInstance, records: Sequence[RunRecord]) -> None:
        """Start drawing ``instance``'s pictures from its ``records`` (run order); not thread-safe."""
        self.handed.append((instance, list(records)))
        future = None
        if self.pool is not None:
            try:
                future = self.pool.submit(_instance_pictures, instance, list(records), self.folder, self.backend)
            except BrokenProcessPool:
                future = None
        self.drawing.append(future)

    def pictures(self) -> list[Picture]:
        """Every picture drawn, instance by instance in the order they were handed over."""
        parts: list[list[Picture]] = []
        for (instance, records), future in zip(self.handed, self.drawing, strict=True):
            part = None
            if future is not None:
                try:
                    part = future.result()
                except BrokenProcessPool:  # a drawing process died (out of memory?): draw it here
                    part = None
            parts.append(part if part is not None else _instance_pictures(instance, records, self.folder, self.backend))
        return [picture for part in parts for picture in part]

    def close(self) -> None:
        """Stop the drawing processes (pictures not yet drawn are dropped)."""
        if self.pool is not None:
            self.pool.shutdown(wait=True, cancel_futures=True)

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _instance_pictures(
    instance: TaskInstance, records: Sequence[RunRecord], folder: Path, backend: BackendName | None
) -> list[Picture]:
    """One instance's scene and representative failures, drawn with one painter (one OpenGL context)."""
    from robotool.render.painter import Painter
    from robotool.render.still import render_scene, render_state
    from robotool.sim import build

    label = instance.label
    scene = build(instance.task)
    painter = Painter(scene, *SIZE)
    try:
        file = f"{FOLDER}/{slug(label)}.png"
        render_scene(scene, folder / file, painter=painter)
        pictures = [Picture(kind="scene", task=label, file=file, caption=f"{label}: the scene at the start")]
        for cls, (record, world) in representatives(records).items():
            file = f"{FOLDER}/{slug(label)}-{cls}.png"
            heading = f"{record.key.method} run {record.key.run}" + (f", world {world.world}" if world else "")
            why = (
                (world.failure if world else None)
                or record.error
                or "; ".join(f for f in record.candidate_failures if f)
                or "no program ran"
            )
            text = f"{heading}: {cls} - {why}"
            lines = [CaptionLine(text, RED)]
            reproduced = None
            if world is None or record.code is None:
                render_state(scene, scene.model.qpos0, folder / file, caption=lines, painter=painter)
            else:
                reproduced = _replay(instance, record, world, scene, folder / file, lines, backend, painter)
            pictures.append(
                Picture(
                    kind="failure",
                    task=label,
                    file=file,
                    failure_class=cls,
                    run=record.key.id,
                    world=world.world if world else None,
                    caption=text,
                    reproduced=reproduced,
                )
            )
    finally:
        painter.close()
    return pictures


def _replay(
    instance: TaskInstance,
    record: RunRecord,
    world: WorldResult,
    scene: Scene,
    path: Path,
    lines: list[CaptionLine],
    backend: BackendName | None,
    painter: Painter,
) -> bool:
    """Simulate the world again and draw its end state, captioned with ``lines`` and how it ended.

    Returns whether it ended as recorded (same failure); the caption says so when it did not.
    """
    from robotool.render.run_videos import rerun_recorded
    from robotool.render.still import render_state

    assert record.code is not None
    rollouts, tracks = rerun_recorded(instance.task, record.code, {world.world: world.seed}, backend=backend)
    again = rollouts[world.world]
    recorded = next((r for r in record.rollouts if r.world == world.world), None)
    told = recorded is not None and not recorded.error  # then the caption's first line says the goal was missed
    extra = end_lines(again, goal_missed=not told)
    now = world_failure(again)
    reproduced = now == world.failure
    if not reproduced:
        extra.insert(0, CaptionLine(f"simulated again, it ended otherwise: {now or 'goal reached'}", RED))
    track = tracks[world.world]
    render_state(
        scene,
        track.qpos[-1],
        path,
        caption=[*lines, *extra],
        mocap_pos=track.mocap_pos[-1],
        painter=painter,
    )
    return reproduced
