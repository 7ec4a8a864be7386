"""``robotool solve``: write a skill program for a task with the RoboTool program (a language model), or with the
LM-free search planner, and report it."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from rich.console import Console

from robotool import tasks
from robotool.cli.command import UsageError, check_batch, set_command
from robotool.cli.internal_error import EXIT_INTERNAL_ERROR
from robotool.cli.options import (
    MAX_REPAIRS,
    TASK_HELP,
    Verbs,
    add_candidate_options,
    add_lm_options,
    add_world_options,
    count,
    lm_from,
    output_file,
    positive_int,
)
from robotool.cli.outputs import (
    add_html_option,
    add_video_options,
    check_video_args,
    solve_videos,
    write_file,
    write_page,
)
from robotool.cli.verbs import add_verb
from robotool.program.lm import DEFAULT_FORMAT_RETRIES
from robotool.program.methods import STAGES_BY_METHOD
from robotool.safe_text import json_text

if TYPE_CHECKING:
    from rich.status import Status

    from robotool.program.lm_program import RoboTool

MAX_TOKENS = 1_000_000
"""The largest token limit of an LM reply that ``--max-tokens`` accepts (far above any model's)."""
WAIT_LINE_EVERY = 30
"""Seconds between the lines that tell a console that is not a terminal a reply is still awaited."""


def cmd_solve(args: argparse.Namespace, console: Console, errors: Console) -> int:
    """Solve a task with the RoboTool program, or with the LM-free search planner, and print the summary. Exit
    status 0 when solved, 1 when not, 70 when a bug in robotool (a controller that raised) ended a candidate's world."""
    from robotool.cli.summary import print_solution, print_solution_verdict
    from robotool.program.lm import HOW_TO_CONFIGURE

    check_batch(args.candidates if args.planner == "lm" else 1, args.worlds)
    task = tasks.load(args.task)
    check_video_args(args, folder=True)
    program = _lm_program(args)
    lm = None
    if args.planner == "lm":
        lm = lm_from(args, max_tokens=args.max_tokens)
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
        write_file(args.out, lambda: args.out.write_text(solution.code, encoding="utf-8"))
        console.print(f"wrote the best program to {args.out}", markup=False, highlight=False)
    if args.json:
        write_file(args.json, lambda: args.json.write_text(json_text(solution, indent=2), encoding="utf-8"))
        console.print(f"wrote the report to {args.json}", markup=False, highlight=False)
    videos = solve_videos(args, task, solution, console) if args.video else {}
    if args.html:
        from robotool.report_page import solution_page

        write_page(args.html, lambda: solution_page(args.html, task, solution, videos), console)
    print_solution_verdict(solution, console)
    if any(r.internal_error is not None for c in solution.candidates for r in c.rollouts):  # each logged in one line
        return EXIT_INTERNAL_ERROR
    return 0 if solution.success else 1


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


def register(verbs: Verbs) -> None:
    """Add ``solve`` to the ``robotool`` verbs."""
    p = add_verb(verbs, "solve")
    p.add_argument("task", metavar="TASK_OR_FILE", help=TASK_HELP)
    p.add_argument(
        "--planner",
        choices=["lm", "search"],
        default="lm",
        help="lm: the RoboTool program (falls back to search without a model); search: LM-free planner",
    )
    lm = add_lm_options(p)
    lm.add_argument("--max-tokens", type=positive_int(MAX_TOKENS), help="token limit of each LM reply")
    lm.add_argument(
        "--format-retries",
        type=count(MAX_REPAIRS),
        default=DEFAULT_FORMAT_RETRIES,
        metavar="N",
        help="times a stage is asked again, shown what was wrong, after a reply that does not parse",
    )
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
    add_candidate_options(p)
    add_world_options(p)
    p.add_argument("--out", type=output_file, help="write the best program here")
    p.add_argument("--json", type=output_file, help="write the full report here as JSON")
    add_video_options(p, folder=True, help_text="write an MP4 of the best program in each chosen world to this folder")
    add_html_option(p)
    set_command(p, cmd_solve)
