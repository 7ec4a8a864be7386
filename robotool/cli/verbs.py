"""The ``robotool`` verbs: the module that declares each one and the line ``robotool --help`` shows for it, known
without importing that module, so that a command line imports only what its own verb needs."""

from __future__ import annotations

from typing import NamedTuple

from robotool.cli.options import Parser, Verbs


class Verb(NamedTuple):
    """Where a verb's parser and command live (a module with ``register(verbs)``) and its one-line help."""

    module: str
    help: str


VERBS: dict[str, Verb] = {  # in the order ``robotool --help`` lists them
    "tasks": Verb("robotool.cli.task_commands", "list the built-in tasks, print one, or write a generated one"),
    "describe": Verb("robotool.cli.task_commands", "print the scene description the language model reads"),
    "render": Verb("robotool.cli.task_commands", "draw a task's scene, labelled, to a PNG (headless)"),
    "solve": Verb("robotool.cli.solve_command", "write a skill program for a task (language model or search planner)"),
    "run": Verb("robotool.cli.run_command", "run a skill program file against a task and report what happened"),
    "eval": Verb("robotool.cli.eval_command", "the offline evaluator (same as python -m robotool.eval)"),
    "optimize": Verb(
        "robotool.cli.optimize_command", "compile the program's prompts (same as python -m robotool.optimize)"
    ),
}


def add_verb(verbs: Verbs, name: str, description: str | None = None) -> Parser:
    """Add verb ``name``'s parser, with its help line, to the ``robotool`` verbs."""
    return verbs.add_parser(name, help=VERBS[name].help, description=description)
