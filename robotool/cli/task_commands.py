"""``robotool tasks``, ``robotool describe`` and ``robotool render``: the built-in tasks, a task's description and
its picture (nothing runs a program)."""

from __future__ import annotations

import argparse

from rich.console import Console
from rich.table import Table

from robotool import tasks
from robotool.cli.command import UsageError, set_command
from robotool.cli.options import TASK_HELP, Verbs, output_file, positive_int, seed
from robotool.cli.outputs import write_file
from robotool.cli.verbs import add_verb
from robotool.safe_text import console_plain
from robotool.task.concepts import needs_tool
from robotool.task.describe import describe

MAX_PIXELS = 16384
"""The widest and tallest picture ``render`` accepts; the renderer's own limit (smaller) is checked when it draws."""


def cmd_tasks(args: argparse.Namespace, console: Console, errors: Console) -> int:
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
        table.add_row(name, task.embodiment, task.category, task.goal.text(), "yes" if needs_tool(task) else "no")
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
        write_file(args.out, lambda: tasks.write_instance(instance, args.out))
        console.print(
            f"wrote {instance.task.name} to {args.out}: {instance.description}", markup=False, highlight=False
        )
    verdict = "needs a tool" if instance.needs_tool else "needs no tool"
    console.print(f"# {verdict}; {'solvable' if instance.solvable else 'not solvable'}", markup=False, style="dim")
    return 0


def cmd_describe(args: argparse.Namespace, console: Console, errors: Console) -> int:
    """Print the natural-language description of a task."""
    task = tasks.load(args.task)
    console.print(console_plain(describe(task)), markup=False, highlight=False, soft_wrap=True)  # any task file's text
    return 0


def cmd_render(args: argparse.Namespace, console: Console, errors: Console) -> int:
    """Draw a task's scene, labelled, to a PNG."""
    from robotool.render.still import render_scene

    task = tasks.load(args.task)
    if args.out.suffix.lower() != ".png":
        raise UsageError(f"--out must name a .png file, got {args.out}")
    with console.status(f"drawing {task.name}"):
        render_scene(task, args.out, width=args.width, height=args.height)
    console.print(f"wrote {args.out}", markup=False, highlight=False)
    return 0


def register(verbs: Verbs) -> None:
    """Add ``tasks``, ``describe`` and ``render`` to the ``robotool`` verbs."""
    p = add_verb(verbs, "tasks")
    p.add_argument("--show", metavar="NAME", help="print this built-in task's YAML (a start for a new task file)")
    p.add_argument("--family", help="write an instance of this procedural family instead of listing")
    p.add_argument("--seed", type=seed, help="the instance's seed (with --family; default: 0)")
    p.add_argument("--out", type=output_file, help="the YAML file to write (with --family; default: print it)")
    set_command(p, cmd_tasks)
    p = add_verb(verbs, "describe")
    p.add_argument("task", metavar="TASK_OR_FILE", help=TASK_HELP)
    set_command(p, cmd_describe)
    p = add_verb(verbs, "render")
    p.add_argument("task", metavar="TASK_OR_FILE", help=TASK_HELP)
    p.add_argument("--out", type=output_file, required=True, help="the PNG file to write")
    p.add_argument("--width", type=positive_int(MAX_PIXELS), default=960, help="picture width in pixels")
    p.add_argument("--height", type=positive_int(MAX_PIXELS), default=540, help="picture height in pixels")
    set_command(p, cmd_render)
