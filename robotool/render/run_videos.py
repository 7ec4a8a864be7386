"""Videos of program runs: record chosen worlds while a program runs, then write one MP4 per world."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from robotool.render.video import VideoInfo, render_video
from robotool.rollout import Rollout
from robotool.sandbox.strict import check_user_program
from robotool.sim.build import build
from robotool.sim.recorder import StateRecorder, Track
from robotool.task.task_model import Task
from robotool.verify import run_worlds
from robotool.vocabulary import BackendName


def video_paths(out: Path, worlds: Sequence[int]) -> dict[int, Path]:
    """Where each world's video goes: ``out`` itself for one world, else ``<stem>-world<k>.mp4`` beside it."""
    if len(worlds) == 1:
        return {worlds[0]: out}
    return {w: out.with_name(f"{out.stem}-world{w}{out.suffix}") for w in worlds}


def write_videos(
    task: Task,
    rollouts: Mapping[int, Rollout] | Sequence[Rollout],
    tracks: Mapping[int, Track],
    paths: Mapping[int, Path],
) -> list[VideoInfo]:
    """One MP4 per recorded world (``paths``: world -> file), captioned from that world's rollout."""
    scene = build(task)
    return [render_video(scene, tracks[w], rollouts[w], path) for w, path in paths.items()]


def rerun_recorded(
    task: Task, code: str, world_seeds: Mapping[int, int], *, backend: BackendName | None
) -> tuple[dict[int, Rollout], dict[int, Track]]:
    """Run ``code`` again, recorded, in one world per entry of ``world_seeds`` (world -> the seed it was perturbed
    from, as recorded when it first ran); on the ``mujoco`` backend this repeats those rollouts exactly.

    Returns each world's new rollout and its recorded states, keyed like ``world_seeds``.
    """
    labels = list(world_seeds)
    program = check_user_program(code, task.embodiment)
    recorder = StateRecorder(range(len(labels)))
    rollouts = run_worlds(
        task, [program] * len(labels), [world_seeds[w] for w in labels], backend=backend, recorder=recorder
    )
    return (
        {w: rollouts[i] for i, w in enumerate(labels)},
        {w: recorder.tracks[i] for i, w in enumerate(labels)},
    )
