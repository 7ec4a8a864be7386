"""The files ``solve`` and ``run`` write besides their report: videos of chosen worlds and pages for a browser.

Bad ``--video``/``--video-worlds``/``--plan`` arguments are refused before anything runs; a file that cannot be
written ends in one line naming it.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from rich.console import Console

from robotool.cli.command import UsageError
from robotool.cli.options import output_file, output_folder
from robotool.task.task_model import Task

if TYPE_CHECKING:
    from robotool.rollout import Rollout
    from robotool.sim.recorder import StateRecorder, Track
    from robotool.solution import Solution

HTML_HELP = "write a page to open in a browser: the program, its worlds' skill-call traces, the scene and any videos"


def write_file(path: Path, write: Callable[[], object]) -> None:
    """Run ``write``; a file system error becomes a one-line :class:`UsageError` naming ``path``."""
    try:
        write()
    except OSError as e:
        raise UsageError(f"cannot write {path}: {e.strerror or e}") from None


def video_worlds(text: str) -> list[int]:
    """``--video-worlds``: world numbers joined by commas (``0,2``), sorted, each at least 0."""
    try:
        worlds = sorted({int(w) for w in text.split(",")})
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected world numbers joined by commas, e.g. 0,2; got {text!r}") from None
    if worlds[0] < 0:
        raise argparse.ArgumentTypeError(f"world numbers start at 0, got {worlds[0]}")
    return worlds


def check_video_args(args: argparse.Namespace, *, folder: bool) -> None:
    """Refuse bad --video / --video-worlds before anything runs; --video-worlds defaults to world 0."""
    if args.video is None:
        if args.video_worlds is not None:
            raise UsageError("--video-worlds goes with --video")
        return
    args.video_worlds = args.video_worlds or [0]
    if not folder and args.video.suffix.lower() != ".mp4":
        raise UsageError(f"--video must name an .mp4 file, got {args.video}")
    if folder and args.video.suffix.lower() == ".mp4" and not args.video.is_dir():  # (a folder of videos is made)
        raise UsageError(f"--video names the folder the videos go in (an MP4 per chosen world), got {args.video}")
    outside = [w for w in args.video_worlds if w >= args.worlds]
    if outside:
        raise UsageError(
            f"--video-worlds {','.join(map(str, outside))}: only worlds 0..{args.worlds - 1} run "
            f"(--worlds {args.worlds})"
        )


def run_recorder(args: argparse.Namespace) -> StateRecorder | None:
    """A recorder of the worlds to film (and of world 0 for --plan), only when a video or a plan was asked for."""
    check_video_args(args, folder=False)
    if args.plan is not None and args.plan.suffix.lower() != ".png":
        raise UsageError(f"--plan must name a .png file, got {args.plan}")
    worlds = set(args.video_worlds or []) | ({0} if args.plan is not None else set())
    if not worlds:
        return None
    from robotool.sim.recorder import StateRecorder

    return StateRecorder(sorted(worlds))


def write_world_videos(
    task: Task,
    rollouts: Mapping[int, Rollout] | Sequence[Rollout],
    tracks: Mapping[int, Track],
    paths: dict[int, Path],
    console: Console,
) -> None:
    """Draw the recorded worlds' videos to ``paths`` (world -> file) and say what was written."""
    from robotool.render.run_videos import write_videos

    with console.status(f"drawing {len(paths)} video(s)"):
        videos = write_videos(task, rollouts, tracks, paths)
    for v in videos:
        line = f"wrote {v.path} ({v.frames} frames at {v.fps} fps, {v.duration:.1f} s simulated)"
        console.print(line, markup=False, highlight=False, soft_wrap=True)


def write_page(path: Path, page: Callable[[], str], console: Console) -> None:
    """Write ``report.html``-style page ``page()`` to ``path`` (--html)."""
    with console.status(f"writing {path}"):
        write_file(path, lambda: path.write_text(page(), encoding="utf-8"))
    console.print(f"wrote {path}: open it in a browser", markup=False, highlight=False)


def solve_videos(args: argparse.Namespace, task: Task, solution: Solution, console: Console) -> dict[int, Path]:
    """Run the best program again in the chosen worlds, recorded, and write their videos to the folder.

    World ``k`` is the chosen candidate's ``k``-th world, perturbed from the seed its rollout recorded.
    Returns each world's video (none when no program was found)."""
    from robotool.render.run_videos import rerun_recorded

    ran = solution.candidates[solution.best].rollouts if solution.best is not None else []
    if solution.code is None or len(ran) <= max(args.video_worlds):
        console.print("no program was found, so there is no video", style="yellow", markup=False, highlight=False)
        return {}
    with console.status(f"recording the best program in world(s) {args.video_worlds}"):
        world_seeds = {w: ran[w].seed for w in args.video_worlds}
        rollouts, tracks = rerun_recorded(task, solution.code, world_seeds, backend=args.backend)
    paths = {w: args.video / f"{task.name}-world{w}.mp4" for w in args.video_worlds}
    write_world_videos(task, rollouts, tracks, paths, console)
    return paths


def add_video_options(p: argparse.ArgumentParser, *, folder: bool, help_text: str) -> None:
    """``--video`` (a folder, or with ``folder=False`` one MP4 file) and ``--video-worlds``."""
    p.add_argument(
        "--video",
        type=output_folder if folder else output_file,
        metavar="DIR" if folder else "OUT.mp4",
        help=help_text,
    )
    p.add_argument("--video-worlds", type=video_worlds, metavar="K[,K...]", help="the worlds to film (default: 0)")


def add_html_option(parser: argparse.ArgumentParser) -> None:
    """``--html FILE.html``: the page of what ran."""
    parser.add_argument("--html", type=output_file, metavar="FILE.html", help=HTML_HELP)
