"""The ``robotool`` command line and the ``python -m robotool.eval`` / ``python -m robotool.optimize`` entry points.

:mod:`~robotool.cli.dispatch` (the ``robotool`` verbs; :mod:`~robotool.cli.verbs` names them),
:mod:`~robotool.cli.eval_command`, :mod:`~robotool.cli.optimize_command`, :mod:`~robotool.cli.options` (what every
command line shares),
:mod:`~robotool.cli.summary` (console summaries), :mod:`~robotool.cli.internal_error` (a bug's one line).
"""

from robotool.cli.dispatch import main

__all__ = ["main"]
