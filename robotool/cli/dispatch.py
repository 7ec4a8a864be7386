"""The ``robotool`` command line: ``robotool tasks|describe|solve|run|render|eval|optimize``, one parser with a
subcommand per verb (each verb's module declares its own, from the shared option groups of
:mod:`~robotool.cli.options`). Only the module of the verb being run is imported (the others are listed by name
and help line, :mod:`~robotool.cli.verbs`), so that a quick command does not wait for what another verb needs.

User mistakes (a bad task file, an unknown task, a bad number, an output path that cannot be written)
end with one readable line and exit status 2, never a traceback; output paths are checked before any
work starts.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Collection, Sequence

from robotool.cli.command import run_line
from robotool.cli.options import Parser
from robotool.cli.verbs import VERBS
from robotool.version import version


def build_parser(full: Collection[str] | None = None) -> argparse.ArgumentParser:
    """The argument parser with every verb: those in ``full`` (default: all) and the others of their modules with
    their arguments, the rest by name and help line only."""
    parser = Parser(prog="robotool", description="Creative robot tool use with language models.")
    parser.add_argument("--version", action="version", version=f"robotool {version()}")
    verbs = parser.add_subparsers(dest="verb", metavar="COMMAND")
    modules = {verb.module for name, verb in VERBS.items() if full is None or name in full}
    registered: set[str] = set()
    for name, verb in VERBS.items():
        if verb.module not in modules:
            verbs.add_parser(name, help=verb.help)
        elif verb.module not in registered:  # a module registers all of its verbs at once
            importlib.import_module(verb.module).register(verbs)
            registered.add(verb.module)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    args = list(sys.argv[1:] if argv is None else argv)
    verb = next((a for a in args if not a.startswith("-")), None)
    return run_line(build_parser([verb] if verb in VERBS else []), args)


if __name__ == "__main__":
    sys.exit(main())
