"""Bugs in robotool met during a run, kept apart from a program's failures: :class:`InternalError`.

A robot's controller or a solver that raises while a program runs is a bug in robotool, not the program's
failure: the run records an :class:`InternalError` (where, the one-line reason and the traceback), the
traceback is logged, and the evaluator leaves the run out of its success tables.
"""

from __future__ import annotations

import traceback

from pydantic import BaseModel, Field


class InternalError(BaseModel):
    """A bug in robotool met during a run (a controller or a solver raised): neither a success nor a failure."""

    where: str = Field(description="what raised, e.g. 'the controller, in push_to_position, world 2'")
    reason: str = Field(description="the exception's type and message, one line")
    traceback: str = Field("", description="the full traceback ('' when none was caught, e.g. a lost worker)")

    @classmethod
    def of(cls, error: BaseException, where: str) -> InternalError:
        """The record of ``error``, raised in ``where``, with its traceback."""
        return cls(where=where, reason=describe(error), traceback="".join(traceback.format_exception(error)))

    def __str__(self) -> str:
        return f"internal error in {self.where}: {self.reason}"


def describe(error: BaseException) -> str:
    """An exception as one line: its type and message."""
    return " ".join(f"{type(error).__name__}: {error}".split())[:400]
