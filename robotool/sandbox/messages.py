"""Messages between the host and a worker: JSON, never pickle, since the worker is untrusted.

Host to worker: ``{"code", "embodiment", "limits", "python_checks"}`` when the session is created,
``GO`` when the runner starts the program, then ``{"value", "error"}`` per reply.
Worker to host: :class:`WorkerMessage`, validated by pydantic on arrival.
"""

from __future__ import annotations

import json
import os
import select
import struct
import time
from collections.abc import Sequence
from multiprocessing.connection import Connection
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator

from robotool.program_session import SkillReply
from robotool.robots.skills import SkillSpec
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


def receive(conn: Connection, max_bytes: int, deadline: float) -> bytes:
    """One message from a worker (``Connection.send_bytes`` framing), read in full by ``deadline``
    (a ``time.monotonic()`` time).

    ``Connection.recv_bytes`` waits for the whole message: a worker that sends part of one and then
    sleeps, using no CPU time, would hold the host forever. Raises ``TimeoutError`` when the deadline
    passes, ``EOFError`` when the worker closed its end and ``OSError`` for a message longer than
    ``max_bytes``.
    """
    (size,) = struct.unpack("!i", _read(conn, 4, deadline))
    if size == -1:
        (size,) = struct.unpack("!Q", _read(conn, 8, deadline))
    if not 0 <= size <= max_bytes:
        raise OSError(f"bad message length {size}")
    return _read(conn, size, deadline)


def frame(data: bytes) -> bytes:
    """``data`` with the length header ``Connection.recv_bytes`` reads (messages to a worker are small)."""
    return struct.pack("!i", len(data)) + data


def write_by(conn: Connection, data: bytes, deadline: float) -> bytes:
    """Write as much of ``data`` as the socket takes by ``deadline``; what is left (empty when all of it went).

    Never blocks past the deadline: a blocking write would wait for ever on a worker that stops reading
    once its socket buffer is full (a few hundred unread replies fill it). Raises ``OSError`` when the
    worker is gone.
    """
    fd = conn.fileno()
    os.set_blocking(fd, False)
    view = memoryview(data)
    while view:
        try:
            view = view[os.write(fd, view) :]
        except BlockingIOError:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                break
            select.select([], [fd], [], remaining)
    return bytes(view)


def _read(conn: Connection, count: int, deadline: float) -> bytes:
    data = bytearray()
    while len(data) < count:
        if not conn.poll(max(deadline - time.monotonic(), 0.0)):
            raise TimeoutError("the worker's message did not arrive in time")
        chunk = os.read(conn.fileno(), count - len(data))
        if not chunk:
            raise EOFError
        data += chunk
    return bytes(data)


def max_message_bytes(limits: SandboxLimits) -> int:
    """Largest worker message the host accepts: all allowed output, escaped, plus room for a call."""
    return 6 * limits.max_output_chars + 65_536


def max_world_bytes(limits: SandboxLimits) -> int:
    """Most bytes the host reads from one worker over its whole program: its output, escaped, and
    room for every allowed skill call."""
    return 6 * limits.max_output_chars + 65_536 + 4_096 * limits.max_skill_calls


def encode_start(code: str, skills: Sequence[SkillSpec], limits: SandboxLimits, *, python_checks: bool) -> bytes:
    """The start message: the program, the robot's skills (the worker defines exactly these), the limits."""
    start = {
        "code": code,
        "skills": [s.model_dump(mode="json") for s in skills],
        "limits": limits.model_dump(),
        "python_checks": python_checks,
    }
    return json.dumps(start).encode()


def encode_reply(reply: SkillReply) -> bytes:
    return json.dumps({"value": reply.value, "error": reply.error}, default=_plain).encode()


def _plain(value: object) -> Any:
    """numpy values in a reply become lists and Python numbers."""
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    raise TypeError(f"a skill reply cannot contain {type(value).__name__}")
