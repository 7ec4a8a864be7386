"""Videos of program runs: record chosen worlds while a program runs, then write one MP4 per world."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from robotool.execute import run
from robotool.render.video import VideoInfo, render_video
from robotool.rollout import Rollout
from robotool.sim.build import build
from robotool.sim.recorder import StateRecorder
from robotool.task_model import Task


def video_paths(out: Path, worlds: Sequence[int]) -> dict[int, Path]:
    """Where each world's video goes: ``out`` itself for one world, else ``<stem>-world<k>.mp4`` beside it."""
    if len(worlds) == 1:
        return {worlds[0]: out}
    return {w: out.with_name(f"{out.stem}-world{w}{out.suffix}") for w in worlds}


def write_videos(
    task: Task, rollouts: Sequence[Rollout], recorder: StateRecorder, paths: dict[int, Path]
) -> list[VideoInfo]:
    """One MP4 per recorded world (``paths``: world -> file), captioned from that world's rollout."""
    scene = build(task)
    return [render_video(scene, recorder.tracks[w], rollouts[w], path) for w, path in paths.items()]


def rerun_recorded(
    task: Task, code: str, worlds: Sequence[int], *, seed: int, backend: str | None
) -> tuple[list[Rollout], StateRecorder]:
    """Run ``code`` again in worlds ``0 .. max(worlds)`` (world ``r`` perturbed from ``seed + r``, as in
    verification) and record ``worlds``; on the ``mujoco`` backend this repeats the verified rollouts exactly."""
    recorder = StateRecorder(worlds)
    report = run(task, code, worlds=max(worlds) + 1, seed=seed, backend=backend, recorder=recorder)
    return report.rollouts, recorder
