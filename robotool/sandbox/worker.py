"""The worker process: applies the limits, then runs one validated program in a restricted namespace.

Runs in a child forked from the zygote (:mod:`robotool.sandbox.zygote`), never in the host. The
program's globals hold only the allowlisted builtins, a restricted ``__import__`` that hands out
namespaces of the allowlisted numpy/math functions, and one stub per skill that checks the
arguments, sends the call to the host and blocks for the answer.
"""

from __future__ import annotations

import builtins
import json
import math
import os
import resource
import signal
import warnings
from collections.abc import Callable
from multiprocessing.connection import Connection
from types import SimpleNamespace
from typing import Any, NoReturn

import numpy as np

from robotool.embodiments import EmbodimentName, SkillSpec, check_call, skills
from robotool.programs import SkillCallError
from robotool.sandbox.allowlist import BUILTINS, MATH_NAMES, NUMPY_CONSTANTS, NUMPY_FUNCTIONS, NUMPY_LINALG
from robotool.sandbox.limits import SandboxLimits
from robotool.sandbox.messages import WorkerMessage

PROGRAM_FILENAME = "<program>"
_SOCKET_FD = 3
MAX_ERROR_CHARS = 500

_MODULES: dict[str, SimpleNamespace] = {
    "numpy": SimpleNamespace(
        **{n: getattr(np, n) for n in NUMPY_FUNCTIONS | NUMPY_CONSTANTS},
        linalg=SimpleNamespace(**{n: getattr(np.linalg, n) for n in NUMPY_LINALG}),
    ),
    "math": SimpleNamespace(**{n: getattr(math, n) for n in MATH_NAMES}),
}


class _LimitExceeded(BaseException):
    """Ends the program with the message of the limit it hit."""


def serve(fd: int) -> NoReturn:
    """Wait for the program and apply its limits, wait for the go, run it, report its end, exit.

    ``fd`` is this worker's socket to the host. The program arrives when its session is created and
    the go when the runner starts it, so the set-up overlaps with whatever the host does in between
    (building and settling the simulation). Never returns.
    """
    conn = _isolate(fd)
    try:
        start = json.loads(conn.recv_bytes())
        limits = SandboxLimits.model_validate(start["limits"])
        _apply_limits(limits)
        program = _Program(conn, start["embodiment"], limits)
        conn.recv_bytes()
        error = program.run(start["code"])
        conn.send_bytes(WorkerMessage(error=error, output=program.take_output()).model_dump_json().encode())
    except (EOFError, OSError):
        os._exit(1)  # the host went away
    os._exit(0)


def _isolate(fd: int) -> Connection:
    """Keep only descriptors 0-3: stdin and stdout on /dev/null, stderr (for the worker's own
    tracebacks; /dev/null if closed) and the host socket ``fd``, moved to 3. Close the rest."""
    os.dup2(fd, _SOCKET_FD)
    null = os.open(os.devnull, os.O_RDWR)
    os.dup2(null, 0)
    os.dup2(null, 1)
    try:
        os.fstat(2)
    except OSError:
        os.dup2(null, 2)
    os.closerange(_SOCKET_FD + 1, resource.getrlimit(resource.RLIMIT_NOFILE)[0])
    return Connection(_SOCKET_FD)


def _apply_limits(limits: SandboxLimits) -> None:
    """CPU and memory budgets, and no new files, processes or core dumps for this process.

    After :func:`_isolate` descriptors 0-3 are all in use, so a descriptor limit of 4 leaves no room
    to open a file or a socket. (The process limit binds only when the host does not run as root.)
    """
    with open("/proc/self/statm") as f:
        address_space = int(f.read().split()[0]) * resource.getpagesize()
    memory = address_space + limits.memory_mb * 2**20
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    # SIGPROF's default action ends the process, even inside a long C call such as 10**10**9.
    signal.setitimer(signal.ITIMER_PROF, limits.cpu_s)
    backstop = math.ceil(limits.cpu_s) + 1
    resource.setrlimit(resource.RLIMIT_CPU, (backstop, backstop + 1))
    for limit, value in (
        (resource.RLIMIT_NOFILE, _SOCKET_FD + 1),
        (resource.RLIMIT_FSIZE, 0),
        (resource.RLIMIT_CORE, 0),
        (resource.RLIMIT_NPROC, 0),
    ):
        resource.setrlimit(limit, (value, value))


class _Program:
    """One program's namespace, output buffer and skill-call channel."""

    def __init__(self, conn: Connection, embodiment: EmbodimentName, limits: SandboxLimits):
        self.conn = conn
        self.embodiment = embodiment
        self.limits = limits
        self.output: list[str] = []
        self.printed = 0
        self.calls = 0

    def run(self, code: str) -> str | None:
        """Run the program to its end; the error that stopped it, or None."""
        warnings.showwarning = self.show_warning
        namespace: dict[str, Any] = {"__builtins__": self.builtins()}
        namespace.update({spec.name: self.skill(spec) for spec in skills(self.embodiment)})
        try:
            exec(compile(code, PROGRAM_FILENAME, "exec"), namespace)
        except _LimitExceeded as e:
            return str(e)
        except MemoryError:
            return f"memory limit exceeded ({self.limits.memory_mb} MiB)"
        except Exception as e:  # the program's error is its world's result
            return _describe(e)
        return None

    def builtins(self) -> dict[str, Any]:
        table = {name: getattr(builtins, name) for name in BUILTINS}
        table["print"] = self.print
        table["__import__"] = _import
        return table

    def print(self, *args: object, sep: object = None, end: object = None, flush: object = False) -> None:
        """The builtin's behaviour, into the output buffer (``flush`` is accepted and ignored)."""
        text = (" " if sep is None else str(sep)).join(map(str, args)) + ("\n" if end is None else str(end))
        self.printed += len(text)
        if self.printed > self.limits.max_output_chars:
            limit = self.limits.max_output_chars
            raise _LimitExceeded(f"output limit exceeded (printed more than {limit} characters)")
        self.output.append(text)

    def show_warning(self, message: Warning | str, category: type[Warning], *_: object, **__: object) -> None:
        self.print(f"warning: {category.__name__}: {message}")

    def take_output(self) -> str:
        text = "".join(self.output)
        self.output.clear()
        return text

    def skill(self, spec: SkillSpec) -> Callable[..., Any]:
        params = [p for p, _ in spec.params]

        def call(*args: object, **kwargs: object) -> Any:
            unknown = set(kwargs) - set(params[len(args) :])
            if unknown:
                raise TypeError(f"{spec.signature} got an unexpected argument '{sorted(unknown)[0]}'")
            values = (*args, *(kwargs[p] for p in params[len(args) :] if p in kwargs))
            checked = check_call(self.embodiment, spec.name, values)
            self.calls += 1
            if self.calls > self.limits.max_skill_calls:
                raise _LimitExceeded(self.limits.skill_calls_exceeded())
            message = WorkerMessage(call=spec.name, args=list(checked), output=self.take_output())
            self.conn.send_bytes(message.model_dump_json().encode())
            reply = json.loads(self.conn.recv_bytes())
            if reply["error"] is not None:
                raise SkillCallError(reply["error"])
            return reply["value"]

        call.__name__ = spec.name
        return call


def _import(
    name: str, _globals: object = None, _locals: object = None, fromlist: object = (), level: int = 0
) -> Any:
    """``import numpy`` and ``import math`` give the allowlisted namespaces; nothing else imports."""
    if name in _MODULES and not fromlist and level == 0:
        return _MODULES[name]
    raise ImportError(f"import of {name!r} is not allowed")


def _describe(error: Exception) -> str:
    """``line N: Type: message`` with the program's line where the error happened."""
    line, tb = None, error.__traceback__
    while tb is not None:
        if tb.tb_frame.f_code.co_filename == PROGRAM_FILENAME:
            line = tb.tb_lineno
        tb = tb.tb_next
    where = f"line {line}: " if line else ""
    return f"{where}{type(error).__name__}: {error}"[:MAX_ERROR_CHARS]
