"""The ``robotool`` command line: ``robotool tasks|describe|solve|run|render|eval|optimize``.

User mistakes (a bad task file, an unknown task, a bad number, an output path that cannot be written)
end with one readable line and exit status 2, never a traceback; output paths are checked before any
work starts.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from rich.console import Console
from rich.table import Table

from robotool import tasks
from robotool.cli.internal_error import report_internal_error
from robotool.cli.options import (
    ADAPTER_HELP,
    ADAPTERS,
    BACKEND_HELP,
    DEFAULT_WORLDS,
    EXIT_USAGE,
    LOG_PROMPTS_HELP,
    REPAIR_HELP,
    TIMEOUT_HELP,
    Parser,
    count,
    make_console,
    output_file,
    output_folder,
    positive_int,
    print_error,
    seconds,
    seed,
    temperature,
    warn_if_warp_on_cpu,
    warnings_in_one_line,
)
from robotool.errors import RobotoolError
from robotool.program.lm import DEFAULT_FORMAT_RETRIES, LMConfigError
from robotool.program.methods import STAGES_BY_METHOD
from robotool.safe_text import json_text
from robotool.sandbox.validate import ProgramRejected
from robotool.task.concepts import needs_tool
from robotool.task.describe import describe
from robotool.task.task_file import TaskFileError
from robotool.task.task_model import Task
from robotool.version import version
from robotool.vocabulary import BACKENDS

if TYPE_CHECKING:
    from rich.status import Status

    from robotool.program.lm_program import RoboTool
    from robotool.rollout import Rollout
    from robotool.sim.recorder import StateRecorder, Track
    from robotool.solution import Solution

RUN_WORLDS = 1
"""``run`` checks one program once by default; ask for more with ``--worlds``."""

Command = Callable[[argparse.Namespace, Console], int]


class UsageError(ValueError):
    """A mistake in how a command was called; reported in one line with exit status 2."""


def _goal_text(task: Task) -> str:
    goal = task.goal
    if goal.lifted is not None:
        return f"lifted {goal.lifted.object} >= {goal.lifted.height} m"
    if goal.lowered is not None:
        return f"lowered {goal.lowered.object} <= {goal.lowered.height} m"
    return f"{goal.kind} {goal.object}"


def cmd_tasks(args: argparse.Namespace, console: Console) -> int:
    """List the built-in tasks, print one's YAML (``--show``), or write one generated instance of a family."""
    if args.show is not None:
        if args.family is not None or args.seed is not None or args.out is not None:
            raise UsageError("--show prints a built-in task; it does not go with --family, --seed or --out")
        console.print(tasks.source(args.show), markup=False, highlight=False, end="", soft_wrap=True)
        return 0
    if args.family is not None:
        return _write_generated(args, console)
    if args.seed is not None or args.out is not None:
        raise UsageError("--seed and --out go with --family")
    table = Table(title="Built-in tasks")
    for column in ("name", "embodiment", "category", "goal", "needs a tool"):
        table.add_column(column, no_wrap=column in ("name", "category"))
    for name in tasks.names():
        task = tasks.load(name)
        table.add_row(name, task.embodiment, task.category, _goal_text(task), "yes" if needs_tool(task) else "no")
    console.print(table)
    console.print(
        "robotool tasks --show NAME prints a task's YAML to start a new one from",
        style="dim",
        markup=False,
        highlight=False,
    )
    return 0


def _write_generated(args: argparse.Namespace, console: Console) -> int:
    if args.family not in tasks.families():
        raise UsageError(f"unknown family {args.family!r}; families: {', '.join(tasks.families())}")
    instance = tasks.generate(args.family, args.seed if args.seed is not None else 0)
    if args.out is None:
        console.print(instance.task.to_yaml(), markup=False, highlight=False, end="", soft_wrap=True)
    else:
        _write(args.out, lambda: tasks.write_instance(instance, args.out))
        console.print(
            f"wrote {instance.task.name} to {args.out}: {instance.description}", markup=False, highlight=False
        )
    verdict = "needs a tool" if instance.needs_tool else "needs no tool"
    console.print(f"# {verdict}; {'solvable' if instance.solvable else 'not solvable'}", markup=False, style="dim")
    return 0


def _write(path: Path, write: Callable[[], object]) -> None:
    """Run ``write``; a file system error becomes a one-line :class:`UsageError` naming ``path``."""
    try:
        write()
    except OSError as e:
        raise UsageError(f"cannot write {path}: {e.strerror or e}") from None


def cmd_describe(args: argparse.Namespace, console: Console) -> int:
    """Print the natural-language description of a task."""
    task = tasks.load(args.task)
    console.print(describe(task), markup=False, highlight=False, soft_wrap=True)
    return 0


def cmd_solve(args: argparse.Namespace, console: Console) -> int:
    """Solve a task with the RoboTool program, or with the LM-free search planner, and print the summary."""
    from robotool.cli.summary import print_solution, print_solution_verdict
    from robotool.program.lm import HOW_TO_CONFIGURE, make_lm

    task = tasks.load(args.task)
    _check_video_args(args, folder=True)
    program = _lm_program(args)
    lm = None
    if args.planner == "lm":
        lm = make_lm(
            args.lm,
            api_base=args.api_base,
            api_key_env=args.api_key_env,
            temperature=args.temperature,
            max_tokens=args.max_tokens,
            cache=not args.no_cache,
            timeout=args.timeout,
        )
        if lm is None and args.program is not None:
            raise UsageError(f"--program runs its stages on a language model. {HOW_TO_CONFIGURE}")
        if lm is None:
            console.print(
                f"{HOW_TO_CONFIGURE}\nSolving with the LM-free search planner instead.",
                style="yellow",
                markup=False,
                highlight=False,
            )
    if lm is None:
        from robotool.planner import solve

        with console.status(f"searching for a program for {task.name} ({args.worlds} world(s) per candidate)"):
            solution = solve(task, worlds=args.worlds, seed=args.seed, backend=args.backend)
    else:
        import dspy

        from robotool.program.lm_calls import reporting_waits

        assert program is not None
        doing = f"solving {task.name} with {program.method_name}: {args.candidates} candidate(s) x " + (
            f"{args.worlds} world(s) on {lm.model}"
        )
        with (
            console.status(doing) as status,
            dspy.context(lm=lm),
            reporting_waits(_wait_shower(console, status, doing)),
        ):
            solution = program(task=task).solution
    print_solution(solution, console)
    if args.out and solution.code:
        _write(args.out, lambda: args.out.write_text(solution.code, encoding="utf-8"))
        console.print(f"wrote the best program to {args.out}", markup=False, highlight=False)
    if args.json:
        _write(args.json, lambda: args.json.write_text(json_text(solution, indent=2), encoding="utf-8"))
        console.print(f"wrote the report to {args.json}", markup=False, highlight=False)
    videos = _solve_videos(args, task, solution, console) if args.video else {}
    if args.html:
        from robotool.report_page import solution_page

        _write_page(args.html, lambda: solution_page(args.html, task, solution, videos), console)
    print_solution_verdict(solution, console)
    return 0 if solution.success else 1


WAIT_LINE_EVERY = 30
"""Seconds between the lines that tell a console that is not a terminal a reply is still awaited."""


def _wait_shower(console: Console, status: Status, doing: str) -> Callable[[str, int | None, float], None]:
    """Shows, while a reply is awaited, the stage and the seconds so far: in the status line on a terminal, else
    a line every :data:`WAIT_LINE_EVERY` seconds."""

    def show(stage: str, candidate: int | None, seconds: float) -> None:
        whose = f"the {stage}'s reply" + (f" for candidate {candidate}" if candidate is not None else "")
        if console.is_terminal:
            status.update(f"{doing}: waiting {seconds:.0f} s for {whose}")
        elif int(seconds) % WAIT_LINE_EVERY == 0:
            console.print(f"waiting {seconds:.0f} s for {whose}", markup=False, highlight=False, style="dim")

    return show


def _lm_program(args: argparse.Namespace) -> RoboTool | None:
    """The RoboTool program ``solve`` asked for (None for the search planner); a ``--program`` file is loaded
    (and checked) here, before anything runs."""
    if args.planner == "search":
        if args.program is not None:
            raise UsageError("--program is a compiled LM program; it does not go with --planner search")
        return None
    from robotool.program.lm_program import RoboTool

    options = {
        "candidates": args.candidates,
        "worlds_per_candidate": args.worlds,
        "backend": args.backend,
        "seed": args.seed,
        "temperature": args.temperature,
        "adapter": args.adapter,
        "format_retries": args.format_retries,
        "log_prompts": args.log_prompts,
        "repair_rounds": args.repair,
    }
    if args.program is None:
        return RoboTool.method(args.method or "robotool", **options)
    if args.method is None:
        return RoboTool.from_compiled(args.program, **options)
    return RoboTool.method(args.method, **options).load(args.program)


def cmd_run(args: argparse.Namespace, console: Console) -> int:
    """Run a skill program file (parsed strictly, as written) against a task and report what happened."""
    from robotool.cli.summary import print_run, print_run_verdict
    from robotool.execute import run

    task = tasks.load(args.task)
    try:
        code = args.program.read_text(encoding="utf-8-sig")  # as Python reads source: a BOM is allowed
    except FileNotFoundError:
        raise UsageError(f"program file not found: {args.program}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise UsageError(f"cannot read the program {args.program}: {getattr(e, 'strerror', None) or e}") from None
    recorder = _run_recorder(args)
    try:
        with console.status(f"running {args.program} on {task.name} in {args.worlds} world(s)"):
            report = run(task, code, worlds=args.worlds, seed=args.seed, backend=args.backend, recorder=recorder)
    except ProgramRejected as e:
        raise UsageError(f"{args.program}: {e}") from None
    print_run(report, console)
    if args.json:
        _write(args.json, lambda: args.json.write_text(json_text(report, indent=2), encoding="utf-8"))
        console.print(f"wrote the report to {args.json}", markup=False, highlight=False)
    if args.plan:
        from robotool.render.top_view import write_plan
        from robotool.sim import build

        assert recorder is not None
        write_plan(args.plan, task, report.rollouts[0], scene=build(task), track=recorder.tracks[0])
        console.print(f"wrote the plan of world 0 to {args.plan}", markup=False, highlight=False)
    videos: dict[int, Path] = {}
    if args.video:
        from robotool.render.run_videos import video_paths

        assert recorder is not None
        videos = video_paths(args.video, args.video_worlds)
        _write_videos(task, report.rollouts, recorder.tracks, videos, console)
    if args.html:
        from robotool.report_page import run_page

        _write_page(args.html, lambda: run_page(args.html, task, report, videos), console)
    print_run_verdict(report, console)
    return 0 if report.success else 1


# -- pictures and videos -------------------------------------------------------------------------


def cmd_render(args: argparse.Namespace, console: Console) -> int:
    """Draw a task's scene, labelled, to a PNG."""
    from robotool.render.still import render_scene

    task = tasks.load(args.task)
    if args.out.suffix.lower() != ".png":
        raise UsageError(f"--out must name a .png file, got {args.out}")
    with console.status(f"drawing {task.name}"):
        render_scene(task, args.out, width=args.width, height=args.height)
    console.print(f"wrote {args.out}", markup=False, highlight=False)
    return 0


def _video_worlds(text: str) -> list[int]:
    try:
        worlds = sorted({int(w) for w in text.split(",")})
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected world numbers joined by commas, e.g. 0,2; got {text!r}") from None
    if worlds[0] < 0:
        raise argparse.ArgumentTypeError(f"world numbers start at 0, got {worlds[0]}")
    return worlds


def _check_video_args(args: argparse.Namespace, *, folder: bool) -> None:
    """Refuse bad --video / --video-worlds before anything runs; --video-worlds defaults to world 0."""
    if args.video is None:
        if args.video_worlds is not None:
            raise UsageError("--video-worlds goes with --video")
        return
    args.video_worlds = args.video_worlds or [0]
    if not folder and args.video.suffix.lower() != ".mp4":
        raise UsageError(f"--video must name an .mp4 file, got {args.video}")
    outside = [w for w in args.video_worlds if w >= args.worlds]
    if outside:
        raise UsageError(
            f"--video-worlds {','.join(map(str, outside))}: only worlds 0..{args.worlds - 1} run "
            f"(--worlds {args.worlds})"
        )


def _run_recorder(args: argparse.Namespace) -> StateRecorder | None:
    """A recorder of the worlds to film (and of world 0 for --plan), only when a video or a plan was asked for."""
    _check_video_args(args, folder=False)
    if args.plan is not None and args.plan.suffix.lower() != ".png":
        raise UsageError(f"--plan must name a .png file, got {args.plan}")
    worlds = set(args.video_worlds or []) | ({0} if args.plan is not None else set())
    if not worlds:
        return None
    from robotool.sim.recorder import StateRecorder

    return StateRecorder(sorted(worlds))


def _write_videos(
    task: Task,
    rollouts: Mapping[int, Rollout] | Sequence[Rollout],
    tracks: Mapping[int, Track],
    paths: dict[int, Path],
    console: Console,
) -> None:
    from robotool.render.run_videos import write_videos

    with console.status(f"drawing {len(paths)} video(s)"):
        videos = write_videos(task, rollouts, tracks, paths)
    for v in videos:
        line = f"wrote {v.path} ({v.frames} frames at {v.fps} fps, {v.duration:.1f} s simulated)"
        console.print(line, markup=False, highlight=False, soft_wrap=True)


def _write_page(path: Path, page: Callable[[], str], console: Console) -> None:
    """Write ``report.html``-style page ``page()`` to ``path`` (--html)."""
    with console.status(f"writing {path}"):
        _write(path, lambda: path.write_text(page(), encoding="utf-8"))
    console.print(f"wrote {path}: open it in a browser", markup=False, highlight=False)


def _solve_videos(args: argparse.Namespace, task: Task, solution: Solution, console: Console) -> dict[int, Path]:
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
    _write_videos(task, rollouts, tracks, paths, console)
    return paths


def _add_video_options(p: argparse.ArgumentParser, *, folder: bool, help_text: str) -> None:
    p.add_argument(
        "--video",
        type=output_folder if folder else output_file,
        metavar="DIR" if folder else "OUT.mp4",
        help=help_text,
    )
    p.add_argument("--video-worlds", type=_video_worlds, metavar="K[,K...]", help="the worlds to film (default: 0)")


HTML_HELP = "write a page to open in a browser: the program, its worlds' skill-call traces, the scene and any videos"
_TASK_HELP = "a built-in task name (see robotool tasks) or a YAML/JSON task file"


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    parser = Parser(prog="robotool", description="Creative robot tool use with language models.")
    parser.add_argument("--version", action="version", version=f"robotool {version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    p = sub.add_parser("tasks", help="list the built-in tasks, print one, or write a generated one")
    p.add_argument("--show", metavar="NAME", help="print this built-in task's YAML (a start for a new task file)")
    p.add_argument("--family", help="write an instance of this procedural family instead of listing")
    p.add_argument("--seed", type=seed, help="the instance's seed (with --family; default: 0)")
    p.add_argument("--out", type=output_file, help="the YAML file to write (with --family; default: print it)")
    p.set_defaults(func=cmd_tasks)
    p = sub.add_parser("describe", help="print the scene description the language model reads")
    p.add_argument("task", metavar="TASK_OR_FILE", help=_TASK_HELP)
    p.set_defaults(func=cmd_describe)

    p = sub.add_parser("solve", help="write a skill program for a task (language model or search planner)")
    p.add_argument("task", metavar="TASK_OR_FILE", help=_TASK_HELP)
    p.add_argument(
        "--planner",
        choices=["lm", "search"],
        default="lm",
        help="lm: the RoboTool program (falls back to search without a model); search: LM-free planner",
    )
    p.add_argument("--lm", help="model string DSPy accepts, e.g. openai/gpt-4o-mini (default: $ROBOTOOL_LM)")
    p.add_argument("--api-base", help="base URL of an OpenAI-compatible server, e.g. http://127.0.0.1:8000/v1")
    p.add_argument("--api-key-env", help="environment variable holding the API key")
    p.add_argument(
        "--temperature",
        type=temperature,
        help="sampling temperature of every LM call (default: the model's for one candidate, 0.7 to 1.0 spread "
        "over several)",
    )
    p.add_argument("--max-tokens", type=positive_int, help="token limit of each LM reply")
    p.add_argument("--timeout", type=seconds, metavar="SECONDS", help=TIMEOUT_HELP)
    p.add_argument("--adapter", choices=ADAPTERS, help=ADAPTER_HELP)
    p.add_argument(
        "--format-retries",
        type=count,
        default=DEFAULT_FORMAT_RETRIES,
        metavar="N",
        help="times a stage is asked again, shown what was wrong, after a reply that does not parse",
    )
    p.add_argument("--log-prompts", type=output_file, metavar="FILE", help=LOG_PROMPTS_HELP)
    p.add_argument("--no-cache", action="store_true", help="do not reuse cached LM replies")
    p.add_argument(
        "--method",
        choices=list(STAGES_BY_METHOD),
        help="the program or an ablation (default: robotool, or the method --program was compiled for)",
    )
    p.add_argument(
        "--program",
        type=Path,
        metavar="PROGRAM.json",
        help="a compiled program (robotool optimize): its optimised prompts and demonstrations",
    )
    p.add_argument("--candidates", type=positive_int, default=1, help="candidate programs to sample (K)")
    p.add_argument("--repair", type=count, default=0, metavar="N", help=REPAIR_HELP)
    p.add_argument("--worlds", type=positive_int, default=DEFAULT_WORLDS, help="perturbed worlds per candidate (R)")
    p.add_argument("--backend", choices=BACKENDS, help=BACKEND_HELP)
    p.add_argument("--seed", type=seed, default=0, help="seed of the world perturbations")
    p.add_argument("--out", type=output_file, help="write the best program here")
    p.add_argument("--json", type=output_file, help="write the full report here as JSON")
    _add_video_options(p, folder=True, help_text="write an MP4 of the best program in each chosen world to this folder")
    p.add_argument("--html", type=output_file, metavar="FILE.html", help=HTML_HELP)
    p.set_defaults(func=cmd_solve)

    p = sub.add_parser("run", help="run a skill program file against a task and report what happened")
    p.add_argument("task", metavar="TASK_OR_FILE", help=_TASK_HELP)
    p.add_argument(
        "program",
        metavar="PROGRAM.py",
        type=Path,
        help="the skill program, parsed strictly as Python (a syntax error stops it before it runs)",
    )
    p.add_argument(
        "--worlds",
        type=positive_int,
        default=RUN_WORLDS,
        help=f"perturbed worlds to run it in (default: {RUN_WORLDS}, one quick check; solve and eval "
        f"use {DEFAULT_WORLDS} to rank candidates)",
    )
    p.add_argument("--seed", type=seed, default=0, help="seed of the world perturbations")
    p.add_argument("--backend", choices=BACKENDS, help=BACKEND_HELP)
    p.add_argument("--json", type=output_file, help="write the full report here as JSON")
    _add_video_options(p, folder=False, help_text="write the rollout as MP4 (several worlds: OUT-world<k>.mp4)")
    p.add_argument("--html", type=output_file, metavar="FILE.html", help=HTML_HELP)
    p.add_argument(
        "--plan",
        type=output_file,
        metavar="PLAN.png",
        help="draw world 0 from above: path, pushes, refusals (matplotlib, no OpenGL)",
    )
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("render", help="draw a task's scene, labelled, to a PNG (headless)")
    p.add_argument("task", metavar="TASK_OR_FILE", help=_TASK_HELP)
    p.add_argument("--out", type=output_file, required=True, help="the PNG file to write")
    p.add_argument("--width", type=positive_int, default=960, help="picture width in pixels")
    p.add_argument("--height", type=positive_int, default=540, help="picture height in pixels")
    p.set_defaults(func=cmd_render)

    # `robotool eval ...` is handed to the evaluator's own parser in main(); listed here for --help.
    sub.add_parser("eval", help="the offline evaluator (same as python -m robotool.eval; see robotool eval -h)")
    sub.add_parser(
        "optimize", help="compile the program's prompts (same as python -m robotool.optimize; see robotool optimize -h)"
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["eval"]:
        from robotool.cli.eval_command import main as eval_main

        return eval_main(argv[1:], prog="robotool eval")
    if argv[:1] == ["optimize"]:
        from robotool.cli.optimize_command import main as optimize_main

        return optimize_main(argv[1:], prog="robotool optimize")
    parser = build_parser()
    args = parser.parse_args(argv)
    warnings_in_one_line()
    console = make_console()
    errors = make_console(stderr=True)
    if args.command is None:
        parser.print_help()
        return 0
    warn_if_warp_on_cpu(getattr(args, "backend", None), errors)
    func: Command = args.func
    try:
        return func(args, console)
    except (TaskFileError, LMConfigError, RobotoolError, UsageError, ProgramRejected) as e:
        print_error(errors, str(e))
        return EXIT_USAGE
    except Exception as e:  # anything else is a bug in robotool, not the user's mistake
        return report_internal_error(errors, e, f"robotool {args.command}")


if __name__ == "__main__":
    sys.exit(main())
