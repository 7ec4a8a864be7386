"""Validation and isolated execution of generated skill programs.

``extract_program`` turns an LM answer into program text, ``validate`` checks it against the
allowlist, and ``SandboxSession`` runs it in a worker process under :class:`SandboxLimits`, speaking
the runner's :class:`~robotool.programs.ProgramSession` protocol.
"""

from robotool.sandbox.extract import extract_program
from robotool.sandbox.limits import SandboxLimits
from robotool.sandbox.session import SandboxSession, start_sessions
from robotool.sandbox.validate import ProgramRejected, validate

__all__ = [
    "ProgramRejected",
    "SandboxLimits",
    "SandboxSession",
    "extract_program",
    "start_sessions",
    "validate",
]
