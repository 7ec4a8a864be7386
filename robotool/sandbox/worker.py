"""The worker process: applies the limits and the OS layers, then runs one program in a restricted namespace.

Runs in a child forked from the zygote (:mod:`robotool.sandbox.zygote`), never in the host. The
program's globals hold only the allowlisted builtins, a restricted ``__import__`` that hands out
namespaces of the allowlisted numpy/math functions (wrapped so that no object or structured array
comes out of them), a ``str`` and a ``map`` that keep addresses and object arrays out
(:mod:`robotool.sandbox.values`, which also rewrites the program so that no operator or method hands
it one), and one stub per skill that checks the arguments, sends the call to the host and blocks for
the answer. Everything the worker says goes to the host through its socket as a
:class:`WorkerMessage`; its stdin, stdout and stderr are ``/dev/null``.
"""

from __future__ import annotations

import ast
import builtins
import inspect
import json
import math
import os
import re
import resource
import signal
import sys
import unicodedata  # noqa: F401  compiling "\N{...}" imports it; a jailed worker cannot load modules
import warnings
from collections.abc import Callable
from multiprocessing.connection import Connection
from types import SimpleNamespace
from typing import Any, NoReturn

import numpy as np
import numpy.ma

from robotool.program_session import SkillCallError
from robotool.robots.skills import SkillSpec, check_arguments
from robotool.safe_text import encodable
from robotool.sandbox.allowlist import (
    BUILTINS,
    LOOP_TYPE_KEYWORDS,
    MATH_NAMES,
    NUMPY_CONSTANTS,
    NUMPY_FUNCTIONS,
    NUMPY_LINALG,
    NUMPY_TYPES,
)
from robotool.sandbox.jail import SOCKET_FD, WorkerJail
from robotool.sandbox.limits import SandboxLimits
from robotool.sandbox.messages import MAX_ARGUMENT_CHARS, WorkerMessage
from robotool.sandbox.values import (
    ADDRESS,
    ADDRESS_SHOWN,
    HELPERS,
    SafeMap,
    SafeStr,
    check_dtype,
    rewrite,
    without_addresses,
)

PROGRAM_FILENAME = "<program>"
MAX_ERROR_CHARS = 500
UNDESCRIBABLE = "the error could not be described"
"""What a program's error reads as when describing it fails too."""

_HOST_DIRECTORIES = sorted(
    {
        d
        for d in (os.path.dirname(os.path.dirname(os.path.abspath(__file__))), sys.prefix, sys.base_prefix, *sys.path)
        if len(d) > 1
    },
    key=len,
    reverse=True,
)


class _NumpyFunction:
    """An allowlisted numpy function whose arguments and results carry no object or structured dtype.

    Object arrays and structured dtypes are how numpy lays references over raw memory; programs
    only need numbers. The repr names the function, not where it lives in memory.
    """

    __slots__ = ("_dtype_position", "_function", "_name")

    def __init__(self, name: str, function: Callable[..., Any]):
        self._name = name
        self._function = function
        self._dtype_position = _dtype_position(function)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        if any(kwargs.get(k) is not None for k in LOOP_TYPE_KEYWORDS):
            raise TypeError(f"{self._name}: signature= is not allowed in programs; use dtype= with a numeric type")
        if "dtype" in kwargs:
            check_dtype(np.dtype(kwargs["dtype"]))
        if self._dtype_position is not None and len(args) > self._dtype_position:
            check_dtype(np.dtype(args[self._dtype_position]))
        for array in _arrays_in((*args, *kwargs.values())):
            check_dtype(array.dtype)
        result = self._function(*args, **kwargs)
        for array in _arrays_in(result if isinstance(result, tuple) else (result,)):
            check_dtype(array.dtype)
        return result

    def __repr__(self) -> str:
        return f"<function {self._name}>"


def _dtype_position(function: Callable[..., Any]) -> int | None:
    """Where ``function`` takes ``dtype`` as a positional argument (``np.var(a, axis, dtype)``), or None."""
    parameters = list(inspect.signature(function).parameters.values())
    positional = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
    return next((i for i, p in enumerate(parameters) if p.name == "dtype" and p.kind in positional), None)


def _arrays_in(values: tuple[Any, ...]) -> list[np.ndarray[Any, Any]]:
    """The arrays among ``values`` and inside the lists and tuples among them (``np.stack([a, b])``)."""
    found = []
    for value in values:
        items = value if isinstance(value, list | tuple) else (value,)
        found += [item for item in items if isinstance(item, np.ndarray)]
    return found


_MODULES: dict[str, SimpleNamespace] = {
    "numpy": SimpleNamespace(
        **{n: _NumpyFunction(f"np.{n}", getattr(np, n)) for n in NUMPY_FUNCTIONS},
        **{n: getattr(np, n) for n in NUMPY_CONSTANTS | NUMPY_TYPES},
        linalg=SimpleNamespace(**{n: _NumpyFunction(f"np.linalg.{n}", getattr(np.linalg, n)) for n in NUMPY_LINALG}),
    ),
    "math": SimpleNamespace(**{n: getattr(math, n) for n in MATH_NAMES}),
}


class _LimitExceeded(BaseException):
    """Ends the program with the message of the limit it hit."""


def serve(fd: int, jail: WorkerJail) -> NoReturn:
    """Enter the jail, wait for the program and apply its limits, seal, wait for the go, run, report, exit.

    ``fd`` is this worker's socket to the host. The program arrives when its session is created and
    the go when the runner starts it, so the set-up overlaps with whatever the host does in between
    (building and settling the simulation). The seccomp filter is loaded once the limits are set,
    before the program's text is compiled: the compiler is the first code that reads it. Never returns.
    """
    null = os.open(os.devnull, os.O_RDWR)
    with open("/proc/self/statm") as f:
        address_space = int(f.read().split()[0]) * resource.getpagesize()
    jail.enter()
    conn = _isolate(fd, null)
    try:
        start = json.loads(conn.recv_bytes())
        limits = SandboxLimits.model_validate(start["limits"])
        _apply_limits(limits, address_space)
        program = _Program(conn, tuple(SkillSpec.model_validate(s) for s in start["skills"]), limits)
        jail.seal()
        code = program.prepare(start["code"], python_checks=start.get("python_checks", True))
        conn.recv_bytes()
        error = program.run(code)
        conn.send_bytes(WorkerMessage(error=error, output=program.take_output()).model_dump_json().encode())
    except (EOFError, OSError):
        os._exit(1)  # the host went away
    os._exit(0)


def _isolate(fd: int, null: int) -> Connection:
    """Keep only descriptors 0-3: stdin, stdout and stderr on /dev/null (``null``), and the host
    socket ``fd``, moved to 3. Close the rest."""
    os.dup2(fd, SOCKET_FD)
    for std in (0, 1, 2):
        os.dup2(null, std)
    os.closerange(SOCKET_FD + 1, resource.getrlimit(resource.RLIMIT_NOFILE)[0])
    return Connection(SOCKET_FD)


def _apply_limits(limits: SandboxLimits, address_space: int) -> None:
    """CPU and memory budgets, and no new files, processes or core dumps for this process.

    ``address_space`` is the worker's size before the program, in bytes. After :func:`_isolate`
    descriptors 0-3 are all in use, so a descriptor limit of 4 leaves no room to open a file or a
    socket. (The process limit binds only for a worker that no longer runs as root.)
    """
    memory = address_space + limits.memory_mb * 2**20
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    # SIGPROF's default action ends the process, even inside a long C call such as 10**10**9.
    signal.setitimer(signal.ITIMER_PROF, limits.cpu_s)
    backstop = math.ceil(limits.cpu_s) + 1
    resource.setrlimit(resource.RLIMIT_CPU, (backstop, backstop + 1))
    for limit, value in (
        (resource.RLIMIT_NOFILE, SOCKET_FD + 1),
        (resource.RLIMIT_FSIZE, 0),
        (resource.RLIMIT_CORE, 0),
        (resource.RLIMIT_NPROC, 0),
    ):
        resource.setrlimit(limit, (value, value))


class _Skill:
    """A skill as the program sees it: calling it sends the call to the host and returns the reply."""

    __slots__ = ("_program", "_spec")

    def __init__(self, program: _Program, spec: SkillSpec):
        self._program = program
        self._spec = spec

    def __call__(self, *args: object, **kwargs: object) -> Any:
        return self._program.call_skill(self._spec, args, kwargs)

    def __repr__(self) -> str:
        return f"<skill {self._spec.name}>"


class _Print:
    """The program's ``print``: a bound method's repr would show the worker's internals and an address."""

    __slots__ = ("_program",)

    def __init__(self, program: _Program):
        self._program = program

    def __call__(self, *args: object, **kwargs: object) -> None:
        unknown = sorted(set(map(str, kwargs)) - {"sep", "end", "file", "flush"})
        if unknown:
            raise TypeError(f"print() got an unexpected keyword argument {_safe_str(unknown[0])!r}")
        if kwargs.get("file") is not None:
            raise TypeError("print() in a program writes to its output only: leave out file=")
        self._program.print(*args, sep=kwargs.get("sep"), end=kwargs.get("end"))

    def __repr__(self) -> str:
        return "<built-in function print>"


class _Program:
    """One program's namespace, output buffer and skill-call channel."""

    def __init__(self, conn: Connection, skills: tuple[SkillSpec, ...], limits: SandboxLimits):
        self.conn = conn
        self.skills = skills
        self.limits = limits
        self.output: list[str] = []
        self.printed = 0
        self.calls = 0
        self.namespace: dict[str, Any] = {}

    def prepare(self, code: str, *, python_checks: bool) -> Any:
        """Compile the program and build its namespace; a program that does not compile ends at run.

        ``python_checks=False`` gives the program every builtin (``print`` still goes to the host):
        only tests of the OS layers ask for it (see ``SandboxSession``).
        """
        warnings.showwarning = self.show_warning
        every_builtin = {**vars(builtins), "print": _Print(self)}
        self.namespace = {"__builtins__": self.builtins() if python_checks else every_builtin}
        self.namespace.update({spec.name: _Skill(self, spec) for spec in self.skills})
        try:
            if not python_checks:
                return compile(code, PROGRAM_FILENAME, "exec")
            self.namespace.update(HELPERS)
            return compile(rewrite(ast.parse(code, PROGRAM_FILENAME)), PROGRAM_FILENAME, "exec")
        except (SyntaxError, ValueError, RecursionError, MemoryError) as e:
            return e

    def run(self, code: Any) -> str | None:
        """Run the compiled program to its end; the error that stopped it, or None."""
        try:
            if isinstance(code, BaseException):
                raise code
            exec(code, self.namespace)
        except _LimitExceeded as e:
            return str(e)
        except MemoryError:
            return f"memory limit exceeded ({self.limits.memory_mb} MiB)"
        except BaseException as e:  # the program's error is its world's result
            return _describe(e)
        return None

    def builtins(self) -> dict[str, Any]:
        table = {name: getattr(builtins, name) for name in BUILTINS}
        table["print"] = _Print(self)
        table["str"] = SafeStr
        table["map"] = SafeMap
        table["__import__"] = _import
        return table

    def print(self, *args: object, sep: object = None, end: object = None, flush: object = False) -> None:
        """The builtin's behaviour, into the output buffer (``flush`` is accepted and ignored)."""
        text = (" " if sep is None else str(sep)).join(map(str, args)) + ("\n" if end is None else str(end))
        text = without_addresses(text)
        self.printed += len(text)
        if self.printed > self.limits.max_output_chars:
            limit = self.limits.max_output_chars
            raise _LimitExceeded(f"output limit exceeded (printed more than {limit} characters)")
        self.output.append(encodable(text))

    def show_warning(self, message: Warning | str, category: type[Warning], *_: object, **__: object) -> None:
        self.print(f"warning: {_public_name(category)}: {_safe_str(message)}")

    def take_output(self) -> str:
        text = "".join(self.output)
        self.output.clear()
        return text

    def call_skill(self, spec: SkillSpec, args: tuple[object, ...], kwargs: dict[str, object]) -> Any:
        """Check the arguments (positions: finite numbers of the right shape), send the call, return the reply."""
        params = [p for p, _ in spec.params]
        unknown = set(kwargs) - set(params[len(args) :])
        if unknown:
            raise TypeError(f"{spec.signature} got an unexpected argument {_safe_str(sorted(map(str, unknown))[0])!r}")
        values = (*args, *(kwargs[p] for p in params[len(args) :] if p in kwargs))
        checked = check_arguments(spec, values)
        if any(isinstance(v, str) and len(v) > MAX_ARGUMENT_CHARS for v in checked):
            raise ValueError(f"{spec.name}: an object name has at most {MAX_ARGUMENT_CHARS} characters")
        self.calls += 1
        if self.calls > self.limits.max_skill_calls:
            raise _LimitExceeded(self.limits.skill_calls_exceeded())
        message = WorkerMessage(call=spec.name, args=list(checked), output=self.take_output())
        self.conn.send_bytes(message.model_dump_json().encode())
        reply = json.loads(self.conn.recv_bytes())
        if reply["error"] is not None:
            raise SkillCallError(reply["error"])
        return reply["value"]


def _import(name: str, _globals: object = None, _locals: object = None, fromlist: object = (), level: int = 0) -> Any:
    """``import numpy`` and ``import math`` give the allowlisted namespaces; nothing else imports.

    C code imports through the running program's ``__import__`` too (numpy's array methods load
    their Python halves, such as ``numpy._core._methods``, on first use). It passes a list as
    ``fromlist`` and takes the module from ``sys.modules`` itself, ignoring what this returns; so
    for a module already loaded this returns None and hands the program nothing. Import statements
    pass None or a tuple and are refused.
    """
    if name in _MODULES and not fromlist and level == 0:
        return _MODULES[name]
    if isinstance(fromlist, list) and name in sys.modules:
        return None
    raise ImportError(f"import of {_safe_str(name)!r} is not allowed")


def _describe(error: BaseException) -> str:
    """``line N: Type: message`` with the program's line where the error happened.

    The type is the nearest public class (numpy raises private subclasses), host paths and memory
    addresses are masked, and a message that cannot itself be turned into text becomes
    :data:`UNDESCRIBABLE`.
    """
    line, tb = None, error.__traceback__
    while tb is not None:
        if tb.tb_frame.f_code.co_filename == PROGRAM_FILENAME:
            line = tb.tb_lineno
        tb = tb.tb_next
    where = f"line {line}: " if line else ""
    return f"{where}{_public_name(type(error))}: {_safe_str(error)}"[:MAX_ERROR_CHARS]


_PUBLIC_NAMES = {"_Print.__call__()": "print()", "_Print": "print", "_Skill": "skill", "_NumpyFunction": "function"}
_PRIVATE_NAME = re.compile("|".join(re.escape(name) for name in _PUBLIC_NAMES))
"""The worker's own classes as errors would name them, and the public names shown instead."""


def _public_name(kind: type) -> str:
    return next((k.__name__ for k in kind.__mro__ if not k.__name__.startswith("_")), "Error")


def _safe_str(value: object) -> str:
    """``str(value)`` with host paths and addresses masked; :data:`UNDESCRIBABLE` if that fails."""
    try:
        text = str(value)[: MAX_ERROR_CHARS * 4]
        for directory in _HOST_DIRECTORIES:
            text = text.replace(directory, "...")
        return encodable(_PRIVATE_NAME.sub(lambda m: _PUBLIC_NAMES[m.group()], ADDRESS.sub(ADDRESS_SHOWN, text)))
    except BaseException:  # a hostile __str__, a huge integer, no memory left
        return UNDESCRIBABLE
