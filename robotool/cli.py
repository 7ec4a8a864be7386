"""The ``robotool`` command line: ``robotool tasks``, ``robotool describe TASK``.

User mistakes (a bad task file, an unknown task) end with a readable message and exit status 2,
never a traceback.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence

from rich.console import Console
from rich.table import Table

from robotool import tasks
from robotool.concepts import needs_tool
from robotool.describe import describe
from robotool.scene import Task, TaskFileError

EXIT_USAGE = 2

Command = Callable[[argparse.Namespace, Console], int]


def _goal_text(task: Task) -> str:
    goal = task.goal
    if goal.lifted is not None:
        return f"lifted {goal.lifted.object} >= {goal.lifted.height} m"
    if goal.lowered is not None:
        return f"lowered {goal.lowered.object} <= {goal.lowered.height} m"
    return f"{goal.kind} {goal.object}"


def cmd_tasks(args: argparse.Namespace, console: Console) -> int:
    """List the built-in tasks."""
    table = Table(title="Built-in tasks")
    for column in ("name", "embodiment", "category", "goal", "needs a tool"):
        table.add_column(column, no_wrap=column in ("name", "category"))
    for name in tasks.names():
        task = tasks.load(name)
        table.add_row(name, task.embodiment, task.category, _goal_text(task),
                      "yes" if needs_tool(task) else "no")
    console.print(table)
    return 0


def cmd_describe(args: argparse.Namespace, console: Console) -> int:
    """Print the natural-language description of a task."""
    task = tasks.load(args.task)
    console.print(describe(task), markup=False, highlight=False, soft_wrap=True)
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    parser = argparse.ArgumentParser(
        prog="robotool", description="Creative robot tool use with language models."
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    p = sub.add_parser("tasks", help="list the built-in tasks")
    p.set_defaults(func=cmd_tasks)
    p = sub.add_parser("describe", help="print the scene description the language model reads")
    p.add_argument("task", metavar="TASK_OR_FILE", help="a built-in task name or a YAML/JSON task file")
    p.set_defaults(func=cmd_describe)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    args = build_parser().parse_args(argv)
    console = Console()
    errors = Console(stderr=True)
    func: Command = args.func
    try:
        return func(args, console)
    except TaskFileError as e:
        errors.print(f"[bold red]error:[/] {e}", markup=True, highlight=False, soft_wrap=True)
        return EXIT_USAGE


if __name__ == "__main__":
    sys.exit(main())
