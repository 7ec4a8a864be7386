"""Typed errors that robotool raises for conditions a user can fix (the message says how)."""

from __future__ import annotations

from typing import Literal


class RobotoolError(Exception):
    """Base class of robotool's user-facing errors; the message is one line that names the fix."""


class RobotoolWarning(UserWarning):
    """Base class of robotool's warnings: one line that says what is missing and how to get it."""


LMFailureKind = Literal[
    "no_key", "authentication", "unknown_model", "unreachable", "quota", "retries_exhausted", "not_a_reply"
]


class LMUnavailableError(RobotoolError):
    """A language-model call could not be attempted or never got an answer (not a result of the method).

    ``kind`` says why; the evaluator does not journal runs that end with this error, so they are retried later.
    """

    def __init__(self, kind: LMFailureKind, message: str) -> None:
        super().__init__(message)
        self.kind: LMFailureKind = kind
