"""Messages between the host and a worker: JSON, never pickle, since the worker is untrusted.

Host to worker: ``{"code", "embodiment", "limits", "python_checks"}`` when the session is created,
``GO`` when the runner starts the program, then ``{"value", "error"}`` per reply.
Worker to host: :class:`WorkerMessage`, validated by pydantic on arrival.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator

from robotool.embodiments import EmbodimentName
from robotool.programs import SkillReply
from robotool.sandbox.limits import SandboxLimits


class WorkerMessage(BaseModel):
    """A skill call (``call`` is the skill's name) or the program's end (``call`` is None), with
    what the program printed since the previous message."""

    model_config = ConfigDict(extra="forbid")

    call: str | None = Field(None, max_length=100)
    args: list[Any] = Field([], max_length=10)
    error: str | None = Field(None, max_length=1_000)
    output: str = ""

    @field_validator("args")
    @classmethod
    def _small_arguments(cls, args: list[Any]) -> list[Any]:
        if not all(_small(a, depth=0) for a in args):
            raise ValueError(
                f"skill arguments are numbers, names of at most {MAX_ARGUMENT_CHARS} characters and short lists"
            )
        return args


MAX_ARGUMENT_CHARS = 200
"""Longest name a skill call may carry (object names are short)."""


def _small(value: object, *, depth: int) -> bool:
    """A number, a short string, or a list of at most 10 small values, at most two lists deep."""
    if isinstance(value, str):
        return len(value) <= MAX_ARGUMENT_CHARS
    if isinstance(value, list | tuple):
        return depth < 2 and len(value) <= 10 and all(_small(v, depth=depth + 1) for v in value)
    return value is None or isinstance(value, bool | int | float)


GO = b"{}"


def max_message_bytes(limits: SandboxLimits) -> int:
    """Largest worker message the host accepts: all allowed output, escaped, plus room for a call."""
    return 6 * limits.max_output_chars + 65_536


def max_world_bytes(limits: SandboxLimits) -> int:
    """Most bytes the host reads from one worker over its whole program: its output, escaped, and
    room for every allowed skill call."""
    return 6 * limits.max_output_chars + 65_536 + 4_096 * limits.max_skill_calls


def encode_start(code: str, embodiment: EmbodimentName, limits: SandboxLimits, *, python_checks: bool) -> bytes:
    start = {"code": code, "embodiment": embodiment, "limits": limits.model_dump(), "python_checks": python_checks}
    return json.dumps(start).encode()


def encode_reply(reply: SkillReply) -> bytes:
    return json.dumps({"value": reply.value, "error": reply.error}, default=_plain).encode()


def _plain(value: object) -> Any:
    """numpy values in a reply become lists and Python numbers."""
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    raise TypeError(f"a skill reply cannot contain {type(value).__name__}")
