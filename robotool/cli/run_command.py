"""``robotool run``: run a skill program file (parsed strictly, as written) against a task and report what
happened."""

from __future__ import annotations

import argparse
import codecs
import io
import re
import tokenize
from pathlib import Path

from rich.console import Console

from robotool import tasks
from robotool.cli.command import UsageError, check_batch, set_command
from robotool.cli.internal_error import EXIT_INTERNAL_ERROR
from robotool.cli.options import DEFAULT_WORLDS, TASK_HELP, Verbs, add_world_options, output_file
from robotool.cli.outputs import (
    add_html_option,
    add_video_options,
    run_recorder,
    write_file,
    write_page,
    write_world_videos,
)
from robotool.cli.verbs import add_verb
from robotool.safe_text import json_text
from robotool.sandbox.validate import MAX_PROGRAM_CHARS, ProgramRejected
from robotool.task.task_file import read_at_most

MAX_PROGRAM_BYTES = 4 * MAX_PROGRAM_CHARS + len(codecs.BOM_UTF8)
"""The most bytes a program file of :data:`~robotool.sandbox.validate.MAX_PROGRAM_CHARS` characters can take (the
sandbox counts the characters)."""
RUN_WORLDS = 1
"""``run`` checks one program once by default; ask for more with ``--worlds``."""


NON_ASCII = bytes(range(128, 256))
"""The bytes that are not ASCII characters (left out to compare a file's ASCII with its text's)."""


def read_source(data: bytes) -> str:
    """The program text Python reads from the source ``data``: UTF-8 with or without a BOM, or in the encoding a coding
    line on its first two lines declares (PEP 263), as long as that encoding reads every ASCII byte of the file as
    itself. Otherwise the program runs otherwise than it shows where it is shown as ASCII or UTF-8 (an editor, a
    terminal): UTF-7's ``+AAo-`` and ``unicode_escape``'s ``\\u000a`` are newlines that turn a comment's end into code,
    a Shift JIS character's second byte may be the backslash that seems to escape a string's closing quote, and an
    ISO-2022 escape sequence shifts what follows out of ASCII: UnicodeError, as for bytes the encoding cannot read.
    SyntaxError for a declaration Python refuses (an unknown encoding), LookupError for a codec that is no text
    encoding."""
    encoding = tokenize.detect_encoding(io.BytesIO(data).readline)[0]
    text = data.decode(encoding)
    if re.sub(r"[^\x00-\x7f]", "", text) != data.translate(None, NON_ASCII).decode("ascii"):
        raise UnicodeError(
            f"its coding line declares {encoding}, which does not read each ASCII character of the file as itself "
            "(the program would run otherwise than it shows): save it as UTF-8 and leave the coding line out"
        )
    return text


def cmd_run(args: argparse.Namespace, console: Console, errors: Console) -> int:
    """Run a skill program file (parsed strictly, as written) against a task and report what happened. Exit status 0
    when every world succeeded, 1 when any failed, 70 when a bug in robotool (a controller that raised) ended one."""
    from robotool.cli.summary import print_run, print_run_verdict
    from robotool.execute import run

    check_batch(1, args.worlds)
    task = tasks.load(args.task)
    try:
        data = read_at_most(args.program, MAX_PROGRAM_BYTES)  # /dev/zero is not read whole
        if len(data) > MAX_PROGRAM_BYTES:
            raise UsageError(f"{args.program}: program is longer than {MAX_PROGRAM_CHARS} characters")
        code = read_source(data)  # as Python reads source: a BOM, or a coding line (PEP 263)
    except FileNotFoundError:
        raise UsageError(f"program file not found: {args.program}") from None
    except (OSError, UnicodeError, SyntaxError) as e:
        raise UsageError(f"cannot read the program {args.program}: {getattr(e, 'strerror', None) or e}") from None
    except LookupError:  # a codec, but not a text encoding (rot13, base64): Python refuses it for source
        raise UsageError(f"cannot read the program {args.program}: encoding problem in its coding line") from None
    recorder = run_recorder(args)
    try:
        with console.status(f"running {args.program} on {task.name} in {args.worlds} world(s)"):
            report = run(task, code, worlds=args.worlds, seed=args.seed, backend=args.backend, recorder=recorder)
    except ProgramRejected as e:
        raise UsageError(f"{args.program}: {e}") from None
    print_run(report, console)
    if args.json:
        write_file(args.json, lambda: args.json.write_text(json_text(report, indent=2), encoding="utf-8"))
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
        write_world_videos(task, report.rollouts, recorder.tracks, videos, console)
    if args.html:
        from robotool.report_page import run_page

        write_page(args.html, lambda: run_page(args.html, task, report, videos), console)
    print_run_verdict(report, console)
    if any(r.internal_error is not None for r in report.rollouts):  # logged in one line as it happened
        return EXIT_INTERNAL_ERROR
    return 0 if report.success else 1


def register(verbs: Verbs) -> None:
    """Add ``run`` to the ``robotool`` verbs."""
    p = add_verb(verbs, "run")
    p.add_argument("task", metavar="TASK_OR_FILE", help=TASK_HELP)
    p.add_argument(
        "program",
        metavar="PROGRAM.py",
        type=Path,
        help="the skill program, parsed strictly as Python (a syntax error stops it before it runs)",
    )
    add_world_options(
        p,
        worlds=RUN_WORLDS,
        worlds_help=f"perturbed worlds to run it in (default: {RUN_WORLDS}, one quick check; solve and eval "
        f"use {DEFAULT_WORLDS} to rank candidates)",
    )
    p.add_argument("--json", type=output_file, help="write the full report here as JSON")
    add_video_options(p, folder=False, help_text="write the rollout as MP4 (several worlds: OUT-world<k>.mp4)")
    add_html_option(p)
    p.add_argument(
        "--plan",
        type=output_file,
        metavar="PLAN.png",
        help="draw world 0 from above: path, pushes, refusals (matplotlib, no OpenGL)",
    )
    set_command(p, cmd_run)
