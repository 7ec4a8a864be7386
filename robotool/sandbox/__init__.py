"""Validation and isolated execution of generated skill programs.

``extract_program`` turns an LM answer into program text, ``validate`` checks it against the
allowlist, and ``SandboxSession`` runs it in a worker process under :class:`SandboxLimits`, speaking
the runner's :class:`~robotool.program_session.ProgramSession` protocol, behind the operating-system layers
of :mod:`robotool.sandbox.jail` (``layers_in_use`` says which are in force).
"""

from robotool.sandbox.extract import Extraction, extract, extract_program
from robotool.sandbox.jail import SandboxLayers, SandboxWarning
from robotool.sandbox.limits import SandboxLimits
from robotool.sandbox.session import SandboxSession, start_sessions
from robotool.sandbox.validate import ProgramRejected, validate
from robotool.sandbox.zygote import layers_in_use

__all__ = [
    "Extraction",
    "ProgramRejected",
    "SandboxLayers",
    "SandboxLimits",
    "SandboxSession",
    "SandboxWarning",
    "extract",
    "extract_program",
    "layers_in_use",
    "start_sessions",
    "validate",
]
