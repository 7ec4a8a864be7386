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
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol


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
