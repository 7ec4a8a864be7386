"""An unexpected exception in a command-line entry point: one line for the user, the traceback in a file.

A user mistake ends a command with exit status 2 and its own message; anything else that escapes a command is
a bug in robotool. It is reported as such in one line that names the file holding the full traceback, and the
command exits with :data:`EXIT_INTERNAL_ERROR` (``EX_SOFTWARE`` of BSD's sysexits). A bug met while a
program runs is recorded instead, as a :class:`robotool.bugs.InternalError`; an evaluation whose runs met one
ends with the same exit status, after its report.
"""

from __future__ import annotations

import datetime
import os
import tempfile
import traceback
from pathlib import Path

from rich.console import Console
from rich.text import Text

from robotool.safe_text import capped, one_line

EXIT_INTERNAL_ERROR = 70
TRACEBACK_PREFIX = "robotool-internal-error"


def write_traceback(error: BaseException, prog: str, folder: Path | None = None) -> Path:
    """Write ``error``'s traceback to a new file in ``folder`` (the temp folder when it is None or unwritable)."""
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    name = f"{TRACEBACK_PREFIX}-{stamp}-{os.getpid()}.txt"
    text = f"{prog}: internal error\n\n" + "".join(traceback.format_exception(error))
    for where in ([folder] if folder is not None else []) + [Path(tempfile.gettempdir())]:
        try:
            where.mkdir(parents=True, exist_ok=True)
            path = where / name
            path.write_text(text, encoding="utf-8")
            return path.resolve()
        except OSError:
            continue
    raise error  # nowhere to write: let Python print it rather than lose it


def report_internal_error(errors: Console, error: BaseException, prog: str, folder: Path | None = None) -> int:
    """Say in one line that ``error`` is a bug in robotool and where its traceback went; the exit status."""
    path = write_traceback(error, prog, folder)
    what = capped(one_line(f"{type(error).__name__}: {error}"), 300)
    errors.print(
        Text.assemble(
            ("internal error:", "bold red"),
            f" {what} (a bug in robotool: please report it with the traceback written to {path})",
        ),
        highlight=False,
        soft_wrap=True,
    )
    return EXIT_INTERNAL_ERROR


def report_broken_runs(errors: Console, broken: int, results: Path) -> int:
    """Say in one line that ``broken`` runs of an evaluation ended by a bug in robotool (each recorded with its
    traceback in ``results``); the exit status."""
    errors.print(
        Text.assemble(
            ("internal error:", "bold red"),
            f" {broken} run(s) ended by a bug in robotool (please report it with their tracebacks, kept in "
            f"{one_line(str(results))})",
        ),
        highlight=False,
        soft_wrap=True,
    )
    return EXIT_INTERNAL_ERROR
