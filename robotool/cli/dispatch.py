"""The ``robotool`` command line: ``robotool tasks|describe|solve|run|render|eval|optimize``, one parser with a
subcommand per verb (each verb's module declares its own, from the shared option groups of
:mod:`~robotool.cli.options`).

User mistakes (a bad task file, an unknown task, a bad number, an output path that cannot be written)
end with one readable line and exit status 2, never a traceback; output paths are checked before any
work starts.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from robotool.cli import eval_command, optimize_command, run_command, solve_command, task_commands
from robotool.cli.command import run_line
from robotool.cli.options import Parser
from robotool.version import version


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every verb."""
    parser = Parser(prog="robotool", description="Creative robot tool use with language models.")
    parser.add_argument("--version", action="version", version=f"robotool {version()}")
    verbs = parser.add_subparsers(dest="verb", metavar="COMMAND")
    task_commands.register(verbs)
    solve_command.register(verbs)
    run_command.register(verbs)
    eval_command.register(verbs)
    optimize_command.register(verbs)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    return run_line(build_parser(), argv)


if __name__ == "__main__":
    sys.exit(main())
