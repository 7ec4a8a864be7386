"""One command line, start to end: parse it, set up the consoles, run the verb, and end a user mistake in one line.

Every entry point (``robotool VERB``, ``python -m robotool.eval``, ``python -m robotool.optimize``) goes through
:func:`run_line`. A verb is a :class:`Command` that a parser names with :func:`set_command`. A user mistake (a bad
task file, an unusable model setting, a program the sandbox refuses, a :class:`UsageError`) ends with one readable
line and exit status 2; anything else is a bug in robotool, reported in one line with the traceback in a file.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Protocol

from rich.console import Console

from robotool.cli.internal_error import report_internal_error
from robotool.cli.options import EXIT_USAGE, make_console, print_error, warn_if_warp_on_cpu, warnings_in_one_line
from robotool.errors import RobotoolError
from robotool.program.lm import LMConfigError
from robotool.sandbox.validate import ProgramRejected
from robotool.task.task_file import TaskFileError


class UsageError(ValueError):
    """A mistake in how a command was called; reported in one line with exit status 2."""


def check_batch(candidates: int, worlds: int) -> None:
    """Refuse, before anything starts, ``candidates`` x ``worlds`` programs at once when the sandbox cannot give each
    its share of memory (:meth:`~robotool.sandbox.limits.SandboxLimits.for_batch`): a :class:`UsageError`."""
    from robotool.sandbox.limits import BatchTooLarge, SandboxLimits

    try:
        SandboxLimits().for_batch(candidates * worlds)
    except BatchTooLarge as e:
        asked = f"--candidates {candidates} x --worlds {worlds}" if candidates > 1 else f"--worlds {worlds}"
        raise UsageError(f"{asked}: {e}; ask for fewer") from None


class Command(Protocol):
    """A verb: runs with its parsed arguments and two consoles (output, errors); returns the exit status."""

    def __call__(self, args: argparse.Namespace, console: Console, errors: Console) -> int: ...


USER_MISTAKES = (TaskFileError, LMConfigError, RobotoolError, UsageError, ProgramRejected)
"""Errors that are the user's to fix: one line, exit status 2."""


def set_command(parser: argparse.ArgumentParser, command: Command) -> None:
    """Make ``parser`` run ``command``, named in messages as the parser's ``prog`` (e.g. ``robotool solve``)."""
    parser.set_defaults(command=command, prog=parser.prog)


def run_line(parser: argparse.ArgumentParser, argv: Sequence[str] | None = None) -> int:
    """Parse ``argv`` (default: the process's arguments) with ``parser`` and run the command it names; without
    one, print the help. Returns the exit status."""
    args = parser.parse_args(argv)
    command: Command | None = getattr(args, "command", None)
    if command is None:
        parser.print_help()
        return 0
    warnings_in_one_line()
    console, errors = make_console(), make_console(stderr=True)
    warn_if_warp_on_cpu(getattr(args, "backend", None), errors)
    try:
        return command(args, console, errors)
    except USER_MISTAKES as e:
        print_error(errors, str(e))
        return EXIT_USAGE
    except Exception as e:  # anything else is a bug in robotool, not the user's mistake
        return report_internal_error(errors, e, args.prog)
