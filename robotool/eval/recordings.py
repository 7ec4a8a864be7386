"""Videos for the evaluation's ``report.html`` (``--videos N``): the first N failed worlds of each task instance
and method, simulated again from the run's program and the seed its world recorded, one MP4 and one plan view
from above (PNG) per world under ``videos/`` in the results folder."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from robotool.eval.instances import TaskInstance
from robotool.eval.pictures import slug
from robotool.eval.records import RunRecord, Video
from robotool.vocabulary import BackendName

FOLDER = "videos"


def failed_worlds(records: Sequence[RunRecord], limit: int) -> list[tuple[RunRecord, int, int]]:
    """The first ``limit`` failed worlds (record, world, seed) of each method among one instance's records, in run
    order; worlds of a run without a program are left out (nothing ran to film)."""
    chosen: list[tuple[RunRecord, int, int]] = []
    taken: dict[str, int] = {}
    for record in records:
        if record.code is None:
            continue
        for world in record.worlds:
            if not world.success and taken.get(record.key.method, 0) < limit:
                taken[record.key.method] = taken.get(record.key.method, 0) + 1
                chosen.append((record, world.world, world.seed))
    return chosen


def write_run_videos(
    instances: Sequence[TaskInstance],
    records: Sequence[RunRecord],
    folder: Path,
    limit: int,
    backend: BackendName | None,
) -> list[Video]:
    """Film the first ``limit`` failed worlds of each instance and method into ``folder/videos``."""
    from robotool.render.run_videos import rerun_recorded, write_videos
    from robotool.render.top_view import write_plan
    from robotool.sim import build

    videos: list[Video] = []
    for instance in instances:
        mine = [r for r in records if r.key.task == instance.name and r.key.seed == instance.seed]
        for record, world, seed in failed_worlds(mine, limit):
            assert record.code is not None
            stem = f"{FOLDER}/{slug(instance.label)}-{slug(record.key.method)}-run{record.key.run}-world{world}"
            (folder / FOLDER).mkdir(exist_ok=True)
            rollouts, tracks = rerun_recorded(instance.task, record.code, {world: seed}, backend=backend)
            write_videos(instance.task, rollouts, tracks, {world: folder / f"{stem}.mp4"})
            scene = build(instance.task)
            write_plan(folder / f"{stem}-plan.png", instance.task, rollouts[world], scene=scene, track=tracks[world])
            videos.append(Video(run=record.key.id, world=world, file=f"{stem}.mp4", plan=f"{stem}-plan.png"))
    return videos
