"""Sandboxed programs behind the runner's :class:`~robotool.program_session.ProgramSession` protocol."""

from __future__ import annotations

import contextlib
import functools
import signal
import time
from collections.abc import Sequence
from multiprocessing.connection import Connection

from pydantic import ValidationError

from robotool import robots
from robotool.program_session import ProgramEnded, SkillReply, SkillRequest
from robotool.robots.skills import SkillArgumentError
from robotool.safe_text import mask_addresses
from robotool.sandbox.limits import SandboxLimits
from robotool.sandbox.messages import (
    GO,
    WorkerMessage,
    encode_reply,
    encode_start,
    frame,
    max_message_bytes,
    max_world_bytes,
    receive,
    write_by,
)
from robotool.sandbox.validate import ProgramRejected, validate
from robotool.sandbox.zygote import Worker, zygote

CLOSED = "closed before the program ended"
TOO_MUCH_DATA = "the worker sent more data than its limits allow"
MALFORMED = "the worker sent a malformed message"
OUTPUT_CUT = "\n[output cut here: the program's or its batch's output limit is reached]\n"
"""Ends a program's kept output where a limit cut it (once)."""


class OutputBudget:
    """Characters of program output a batch may still keep (shared by its sessions)."""

    def __init__(self, chars: int):
        self.left = chars


class SandboxSession:
    """One generated program, validated, then run in its own worker process.

    A program the validator rejects gets no worker: :meth:`wait` returns ``ProgramEnded`` with the
    rejection. A worker that crashes, overruns a limit or sends anything malformed ends only this
    session, with the reason; the host and the other sessions carry on. ``worker`` is one from a
    batch (:func:`start_sessions`); by default the session spawns its own.

    ``test_only_skip_python_checks`` skips the validator and gives the program every builtin (so
    ``import os`` works), so that tests can show what the OS layers alone stop. Nothing else may set it.
    """

    def __init__(
        self,
        code: str,
        embodiment: str,
        limits: SandboxLimits | None = None,
        *,
        worker: Worker | None = None,
        batch_output: OutputBudget | None = None,
        test_only_skip_python_checks: bool = False,
    ):
        self.code = code
        self.embodiment = embodiment
        self.limits = (limits or SandboxLimits()).for_batch(1)  # a batch's share is already smaller
        self._ended: ProgramEnded | None = None
        self._output: list[str] = []
        self._output_chars = 0
        self._output_cut = False
        self._calls = 0
        self._started = False
        self._owed_since: float | None = None
        self._arrived: float | None = None  # when the message owed began to arrive, once the runner saw it
        self._wall_spent = 0.0
        self._received = 0
        self._unsent = b""
        self._batch_output = batch_output or OutputBudget(self.limits.max_batch_output_chars)
        self._worker = worker
        rejection = None if test_only_skip_python_checks else _rejection(code, embodiment)
        if rejection is not None:
            self._end(f"program rejected: {rejection}")
            return
        if self._worker is None:
            (self._worker,) = zygote().spawn(1)
        skills = robots.get(embodiment).skills
        start = encode_start(code, skills, self.limits, python_checks=not test_only_skip_python_checks)
        self._send(start)

    @property
    def worker_pid(self) -> int | None:
        """The worker's process id as this process sees it; None when the program was rejected."""
        return None if self._worker is None else self._worker.host_pid

    def resume(self, reply: SkillReply | None) -> None:
        """Start the program (``None``) or answer its pending skill call."""
        if self._ended is not None:
            return
        if self._started == (reply is None):
            raise ValueError("resume(None) starts the program; after that, resume() takes a SkillReply")
        self._started = True
        assert self._worker is not None, "a session has its worker until it ends"
        self._send(GO if reply is None else encode_reply(reply))
        self._owed_since, self._arrived = time.monotonic(), None

    def channel(self) -> tuple[Connection, float] | None:
        """The worker's socket and the program's wall time left, while it owes a message
        (:class:`~robotool.program_session.ArrivingSession`)."""
        if self._ended is not None or self._owed_since is None or self._worker is None or self._unsent:
            return None  # (a reply not yet written in full: wait() writes it first)
        return self._worker.conn, self.limits.wall_s - self._wall_spent - (time.monotonic() - self._owed_since)

    def arrived(self, at: float) -> None:
        """Its message began to arrive at ``at``: the program's time stops there, but for the time :meth:`wait` then
        spends reading it."""
        if self._arrived is None:
            self._arrived = at

    def wait(self) -> SkillRequest | ProgramEnded:
        """Block until the program calls a skill or ends (or overruns its wall-clock budget)."""
        if self._ended is not None:
            return self._ended
        worker = self._worker
        assert worker is not None, "a session has its worker until it ends"
        if self._owed_since is None:
            raise RuntimeError("wait() without a pending resume()")
        waited = time.monotonic()
        owed = (self._arrived or waited) - self._owed_since  # its own time, to when its message began to arrive
        deadline = waited + max(self.limits.wall_s - self._wall_spent - owed, 0.0)
        try:
            self._unsent = write_by(worker.conn, self._unsent, deadline)
            if self._unsent:  # the worker stopped reading what it is owed
                raise TimeoutError
            data = receive(worker.conn, max_message_bytes(self.limits), deadline)
        except TimeoutError:
            return self._end(f"wall-clock limit exceeded ({self.limits.wall_s:g} s of program time)")
        except (EOFError, ConnectionError):  # reset when it died holding an unread reply
            return self._end(self._death_reason(worker.zygote.exit_code(worker.pid)))
        except OSError:
            return self._end(MALFORMED)
        self._wall_spent += owed + (time.monotonic() - waited)
        self._owed_since = self._arrived = None
        self._received += len(data)
        if self._received > max_world_bytes(self.limits):
            return self._end(TOO_MUCH_DATA)
        try:
            message = WorkerMessage.model_validate_json(data)
        except ValidationError:
            return self._end(MALFORMED)
        self._add_output(message.output)
        if message.call is None:
            return self._end(message.error)
        self._calls += 1
        if self._calls > self.limits.max_skill_calls:
            return self._end(self.limits.skill_calls_exceeded())
        try:
            args = robots.get(self.embodiment).check_call(message.call, tuple(message.args))
        except SkillArgumentError as e:
            return self._end(str(e))
        return SkillRequest(message.call, args)

    def close(self) -> None:
        """Stop the worker if it still runs; idempotent."""
        if self._ended is None:
            self._end(CLOSED)

    def _add_output(self, text: str) -> None:
        room = max(min(self.limits.max_output_chars - self._output_chars, self._batch_output.left), 0)
        kept = text[:room]
        self._output.append(kept)
        self._output_chars += len(kept)
        self._batch_output.left -= len(kept)
        if len(kept) < len(text) and not self._output_cut:
            self._output_cut = True
            self._output.append(OUTPUT_CUT)

    def _send(self, message: bytes) -> None:
        """Queue a message to the worker and write what its socket takes now; :meth:`wait` writes the rest
        within the program's wall time, so the host never blocks on a worker that stops reading."""
        assert self._worker is not None, "a session has its worker until it ends"
        self._unsent += frame(message)
        with contextlib.suppress(OSError):  # a dead worker: wait() reports how it ended
            self._unsent = write_by(self._worker.conn, self._unsent, deadline=0.0)

    def _death_reason(self, code: int) -> str:
        if code in (-signal.SIGPROF, -signal.SIGXCPU):
            return f"CPU time limit exceeded ({self.limits.cpu_s:g} s)"
        if code == -signal.SIGKILL:
            return "the worker was killed (out of memory?)"
        if code == -signal.SIGSYS:
            return "the worker was stopped by the sandbox's system-call filter (SIGSYS)"
        if code < 0:
            return f"the worker crashed ({signal.Signals(-code).name})"
        return f"the worker exited without finishing the program (status {code})"

    def _end(self, error: str | None) -> ProgramEnded:
        # masked here, where they enter the host: an address a program found stays out of every sink
        output = mask_addresses("".join(self._output))
        self._ended = ProgramEnded(error=None if error is None else mask_addresses(error), output=output)
        if self._worker is not None:
            self._worker.zygote.release(self._worker.pid)
            self._worker.conn.close()
            self._worker = None
        return self._ended


@functools.lru_cache(maxsize=256)
def _rejection(code: str, embodiment: str) -> str | None:
    """Why the program is rejected, or None; cached, as a batch repeats each candidate in R worlds."""
    try:
        validate(code, embodiment)
    except ProgramRejected as e:
        return str(e)
    return None


def start_sessions(codes: Sequence[str], embodiment: str, limits: SandboxLimits | None = None) -> list[SandboxSession]:
    """One session per program, their workers spawned in one batch (a rejected program's is released).

    The batch shares one output budget (``limits.max_batch_output_chars``) and its memory: each program
    may add at most ``limits.batch_memory_mb / len(codes)`` MiB (see :meth:`SandboxLimits.for_batch`).
    """
    limits = (limits or SandboxLimits()).for_batch(len(codes))
    budget = OutputBudget(limits.max_batch_output_chars)
    workers = zygote().spawn(len(codes))
    return [
        SandboxSession(c, embodiment, limits, worker=w, batch_output=budget)
        for c, w in zip(codes, workers, strict=True)
    ]
