"""How the lockstep runner talks to a skill program, trusted or sandboxed.

A program runs until it calls a skill; the call crosses to the runner as a :class:`SkillRequest`,
and the runner later answers it with a :class:`SkillReply`. The runner drives many programs at once,
so sending a reply (:meth:`ProgramSession.resume`) and waiting for the next request
(:meth:`ProgramSession.wait`) are separate steps: it resumes every world first, then collects.

Trusted Python callables run in a thread (:class:`TrustedSession`); generated code runs behind
the sandbox's process boundary, which implements the same protocol.
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from multiprocessing.connection import wait as connection_wait
from typing import Any, Protocol, cast, runtime_checkable


@dataclass(frozen=True)
class SkillRequest:
    """A program called skill ``name`` with positional ``args``."""

    name: str
    args: tuple[Any, ...]


@dataclass(frozen=True)
class SkillReply:
    """The runner's answer to a skill call: a value, or an error raised inside the program."""

    value: Any = None
    error: str | None = None


@dataclass(frozen=True)
class ProgramEnded:
    """The program finished (``error`` is None) or stopped with a reason."""

    error: str | None = None
    output: str = ""


class ProgramSession(Protocol):
    """One running program in one world."""

    def resume(self, reply: SkillReply | None) -> None:
        """Start the program (``None``) or answer its pending skill call."""

    def wait(self) -> SkillRequest | ProgramEnded:
        """Block until the program calls a skill or ends."""

    def close(self) -> None:
        """Stop the program and free its resources."""


@runtime_checkable
class ArrivingSession(Protocol):
    """A session whose messages come through a channel the runner can watch (a sandboxed program's socket)."""

    def channel(self) -> tuple[Connection, float] | None:
        """The channel its next message comes through and the seconds it has left to send it, while it owes one."""

    def arrived(self, at: float) -> None:
        """Its message began to arrive at ``at`` (``time.monotonic()``): it is charged no later time waiting."""


def wait_all(sessions: Sequence[ProgramSession]) -> list[SkillRequest | ProgramEnded]:
    """Each session's :meth:`~ProgramSession.wait`, in the sessions' order; those with a channel
    (:class:`ArrivingSession`) are taken as their messages arrive, each told when its began to arrive, so that a
    program is charged only for its own time and not for the runner's time on the others (found by an adversarial
    run: waited on in turn, a good program whose reply sat unread behind 24 busy-looping ones ran out of its
    wall-clock budget)."""
    results: dict[int, SkillRequest | ProgramEnded] = {}
    watched: dict[int, tuple[Connection, float]] = {}
    for k, session in enumerate(sessions):
        owed = session.channel() if isinstance(session, ArrivingSession) else None
        if owed is None:
            results[k] = session.wait()
        else:
            watched[k] = owed
    started = time.monotonic()
    while watched:
        left = min(budget for _, budget in watched.values()) - (time.monotonic() - started)
        ready = set(connection_wait([conn for conn, _ in watched.values()], timeout=max(left, 0.0)))
        now = time.monotonic()
        arriving = [k for k, (conn, _) in watched.items() if conn in ready]
        for k in arriving:
            cast(ArrivingSession, sessions[k]).arrived(now)
        # one that arrived, else the one out of time first (its wait ends it)
        k = arriving[0] if arriving else min(watched, key=lambda j: watched[j][1])
        del watched[k]
        results[k] = sessions[k].wait()
    return [results[k] for k in range(len(sessions))]


class SkillCallError(RuntimeError):
    """Raised inside a program when the runner answers its skill call with an error."""


TrustedProgram = Callable[[Any], None]
"""A trusted program: called with an object whose attributes are the embodiment's skills."""


class _SkillProxy:
    """Attribute access yields callables that hand skill calls to the runner and block."""

    def __init__(self, session: TrustedSession, skill_names: frozenset[str]):
        self._session = session
        self._names = skill_names

    def __getattr__(self, name: str) -> Callable[..., Any]:
        if name not in self._names:
            raise AttributeError(f"unknown skill {name!r}")
        return lambda *args: self._session._call(name, args)


@dataclass
class TrustedSession:
    """Runs a trusted Python callable in a daemon thread; only for hand-written code and tests."""

    program: TrustedProgram
    skill_names: frozenset[str]
    _requests: queue.Queue[SkillRequest | ProgramEnded] = field(default_factory=queue.Queue)
    _replies: queue.Queue[SkillReply | None] = field(default_factory=queue.Queue)
    _thread: threading.Thread | None = None
    _closed: bool = False

    def resume(self, reply: SkillReply | None) -> None:
        if self._thread is None:
            self._thread = threading.Thread(target=self._main, daemon=True)
            self._thread.start()
        else:
            self._replies.put(reply)

    def wait(self) -> SkillRequest | ProgramEnded:
        return self._requests.get()

    def close(self) -> None:
        if self._thread is not None and self._thread.is_alive():
            self._closed = True
            self._replies.put(None)

    def _call(self, name: str, args: tuple[Any, ...]) -> Any:
        self._requests.put(SkillRequest(name, args))
        reply = self._replies.get()
        if reply is None or self._closed:
            raise _Stop
        if reply.error is not None:
            raise SkillCallError(reply.error)
        return reply.value

    def _main(self) -> None:
        try:
            self.program(_SkillProxy(self, self.skill_names))
        except _Stop:
            return
        except Exception as e:
            self._requests.put(ProgramEnded(error=f"{type(e).__name__}: {e}"))
            return
        self._requests.put(ProgramEnded())


class _Stop(BaseException):
    """Unwinds a trusted program's thread when its session is closed."""
