"""Everything a worker says goes through the protocol: safe error descriptions, capped sizes, no leaks."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest
from fixtures.sandbox_driver import run_to_end

from robotool.program_session import ProgramEnded, SkillReply, SkillRequest
from robotool.sandbox import ProgramRejected, SandboxLimits, SandboxSession, start_sessions, validate
from robotool.sandbox.messages import max_world_bytes
from robotool.sandbox.session import OUTPUT_CUT
from robotool.sandbox.worker import UNDESCRIBABLE, _import

LIMITS = SandboxLimits(cpu_s=2.0, wall_s=20.0, memory_mb=128, max_output_chars=5_000, max_skill_calls=50)


def run(code: str, limits: SandboxLimits = LIMITS, *, unchecked: bool = False) -> ProgramEnded:
    return run_to_end(code, limits, unchecked=unchecked)


def test_an_error_whose_description_fails_becomes_a_fixed_message() -> None:
    ended = run("d = {}\nk = 10 ** 5000\nx = d[k]\n")
    assert ended.error == f"line 3: KeyError: {UNDESCRIBABLE}"


def test_lone_surrogates_in_output_and_errors_are_escaped() -> None:
    ended = run("print('a\\ud800b')\nx = {}['\\udfff']\n")
    assert ended.output == "a\\ud800b\n"
    assert ended.error == "line 2: KeyError: '\\udfff'"


def test_error_names_are_public_and_addresses_are_masked() -> None:
    ended = run("import numpy as np\nx = np.array([1]) + 'a'\n")
    assert ended.error is not None and ended.error.startswith("line 2: UFuncTypeError: ")
    ended = run("f = lambda: 0\nx = {}[f]\n")
    assert ended.error == "line 2: KeyError: <function <lambda> at 0x...>"


def test_reprs_name_skills_and_numpy_functions_without_internals() -> None:
    ended = run("import numpy as np\nprint(np.linalg.norm, np.clip)\n")
    assert ended.output == "<function np.linalg.norm> <function np.clip>\n"
    ended = run("print(repr(move_to_position))\n", unchecked=True)
    assert ended.output == "<skill move_to_position>\n"
    ended = run("print(print)\nprint(1, 2, sep=print)\n")
    assert ended.output == "<built-in function print>\n1<built-in function print>2\n"


def test_no_host_path_appears_in_an_error() -> None:
    ended = run("import numpy as np\nnp.linalg.inv(np.zeros((2, 3)))\n")
    assert ended.error is not None and "LinAlgError" in ended.error
    ended = run("import json\njson.loads('{')\n", unchecked=True)
    assert ended.error is not None and "/" not in ended.error


@pytest.mark.parametrize(
    "code",
    [
        "import numpy as np\nx = np.array([None, 1])\n",
        "import numpy as np\nx = np.array([1, 2], 'O')\n",
        "import numpy as np\nx = np.zeros(2, 'V8')\n",
        "import numpy as np\nx = np.full(2, 'a', 'O')\n",
    ],
)
def test_numpy_functions_refuse_object_and_structured_arrays(code: str) -> None:
    ended = run(code)
    assert ended.error is not None and "not allowed in programs" in ended.error


@pytest.mark.parametrize(
    ("function", "args", "typed"),
    [
        ("var", ([1.0, 2.0],), ((None, "O"), {})),  # np.var(a, axis, dtype): an object loop, a plain result
        ("sum", ([1.0, 2.0],), ((None, "O"), {})),
        ("cumsum", ([1.0, 2.0],), ((None, "V8"), {})),
        ("power", (2, 3), ((), {"sig": "OO->O"})),  # numpy's hidden alias of signature=
        ("maximum", (1.0, 2.0), ((), {"signature": ("O", "O", "O")})),
        ("clip", ([1.0], 0, 1), ((), {"signature": "OOO->O"})),  # clip passes its keywords on to a ufunc
    ],
)
def test_numpy_functions_refuse_object_loops_however_the_type_is_passed(
    function: str, args: tuple[object, ...], typed: tuple[tuple[object, ...], dict[str, object]]
) -> None:
    """The worker's numpy functions check a dtype given by position and refuse loop signatures before
    numpy runs: the validator cannot see through ``f(*args, **kwargs)`` nor values held in variables."""
    numpy_function = getattr(_import("numpy"), function)
    more_args, kwargs = typed
    with pytest.raises(TypeError, match="not allowed in programs"):
        numpy_function(*args, *more_args, **kwargs)
    assert numpy_function(*args) is not None  # the same call without the type works


def test_numpy_functions_refuse_object_array_arguments() -> None:
    """An object array that a program got some other way (see below) reaches no numpy function, alone or
    in a list; numeric arrays still do."""
    numpy_view = _import("numpy")
    boxed = np.add(np.zeros(2), [10**30, 1])  # what the program below holds, from its `+`
    for function, args in (("sum", (boxed,)), ("stack", ([boxed, boxed],)), ("where", ([True, False], boxed, 0))):
        with pytest.raises(TypeError, match="not allowed in programs"):
            getattr(numpy_view, function)(*args)
    assert numpy_view.stack([np.zeros(2), np.ones(2)]).shape == (2, 2)


@pytest.mark.parametrize(
    "code",
    [
        "boxed = np.zeros(2) + [10 ** 30, 1]\nboxed[0] = print\nprint(boxed)\n",  # an array operator
        "x = np.zeros(2).clip(0, [10**30, 1])\n",  # an array method
        "x = np.zeros(2).dot([[10**30, 1], [1, 1]])\n",
        "x = np.float64(1) + [10**30, 1]\n",  # a numpy scalar's operator
        "x = np.float64(1)\nx += [10**30, 1]\n",  # an in-place operator on a name
        "x = [np.float64(1)]\nx[0] += [10**30, 1]\n",  # ... on an item
        "x = sum([np.float64(1), [10**30, 1]])\n",  # a builtin doing the arithmetic
        "x = list(map(sum, [[np.float64(1), [10**30, 1]]]))\n",  # ... called by map
        "x = np.maximum(np.zeros(2), [10**30, 1])\n",  # a numpy function
        "x = f'{np.zeros(2) - [10**30, 1]}'\n",  # inside an f-string
    ],
)
def test_no_route_gives_a_program_an_object_array(code: str) -> None:
    """numpy makes an object array of a list holding an integer beyond 64 bits, inside operators and methods
    that no wrapper sees: every value a call or an operator makes is checked."""
    ended = run("import numpy as np\n" + code)
    assert ended.error is not None and "arrays of dtype '|O' are not allowed in programs" in ended.error


def test_guarded_code_keeps_python_semantics() -> None:
    """The rewrite of in-place operators evaluates the target once and still updates arrays in place."""
    code = (
        "import numpy as np\na = [1, 2, 3]\na[1:] += [4]\nd = {'k': 1}\nd['k'] += 2\nx = 3\nx **= 2\n"
        "v = np.zeros(3)\nw = v\nv[1:] += 1\nv += 2\nprint(a, d, x, w.tolist(), f'{x:>{x}}', divmod(7, 2))\n"
    )
    assert run(code) == ProgramEnded(error=None, output="[1, 2, 3, 4] {'k': 3} 9 [2.0, 3.0, 3.0]         9 (3, 1)\n")


def test_no_address_reaches_the_program() -> None:
    """Reprs of functions, iterators and bound methods reach the program's text with their addresses masked,
    whichever way it turns them into text; ``str`` still works as the type."""
    code = (
        "f = lambda: 0\nit = iter([])\ns = str([f, it, [].append])\nprint(s, f'{f!r}', '%s' % f, b'%a' % f)\n"
        "print(list(map(str, [f])), s[s.index('0x'):][:6], isinstance(s, str), str.join('-', ['a', 'b']), str)\n"
    )
    ended = run(code)
    assert ended.error is None
    assert ended.output == (
        "[<function <lambda> at 0x...>, <list_iterator object at 0x...>, <built-in method append of list object "
        "at 0x...>] <function <lambda> at 0x...> <function <lambda> at 0x...> b'<function <lambda> at 0x...>'\n"
        "['<function <lambda> at 0x...>'] 0x...> True a-b <class 'str'>\n"
    )


def test_errors_and_reprs_do_not_name_the_workers_classes() -> None:
    assert run("print(str, map, map(abs, [1]))\n").output == "<class 'str'> <class 'map'> <map object>\n"
    ended = run("print(1, foo=2)\n")
    assert ended.error == "line 1: TypeError: print() got an unexpected keyword argument 'foo'"
    assert "_" not in run("print(1, file=2)\n").error.split(":", 1)[1]


@pytest.mark.parametrize(
    "code",
    [
        "import numpy as np\nb = np.ndarray((4,), buffer=np.zeros(4), dtype=np.int64)\n",
        "import numpy as np\nx = np.zeros(3).astype('O')\n",
        "import numpy as np\nx = np.zeros(3).astype(object)\n",
        "import numpy as np\nx = np.zeros(3).view(np.int64)\n",
        "import numpy as np\nx = np.empty(3)\n",
        "import numpy as np\nx = np.frombuffer(b'abcdefgh')\n",
        "import numpy as np\nx = np.zeros(3).strides\n",
    ],
)
def test_buffer_aliasing_primitives_are_refused(code: str) -> None:
    with pytest.raises(ProgramRejected):
        validate(code, "arm")


def test_numeric_astype_still_works() -> None:
    code = "import numpy as np\nx = np.array([1.7, 2.2])\nprint(x.astype(int).tolist(), x.astype('float32').tolist())\n"
    assert run(code) == ProgramEnded(error=None, output="[1, 2] [1.7000000476837158, 2.200000047683716]\n")


def test_a_worker_that_floods_the_host_is_cut_off() -> None:
    """A worker speaking the protocol itself (Python checks off) with maximal messages."""
    code = (
        "import json\nfrom multiprocessing.connection import Connection\nhost = Connection(3)\n"
        "while True:\n"
        "    host.send_bytes(json.dumps({'call': 'get_center', 'args': ['milk'], 'output': 'x' * 30000}).encode())\n"
        "    host.recv_bytes()\n"
    )
    ended = run(code, unchecked=True)
    assert ended.error == "the worker sent more data than its limits allow"
    assert ended.output == "x" * LIMITS.max_output_chars + OUTPUT_CUT
    assert max_world_bytes(LIMITS) < 10 * 2**20


@pytest.mark.parametrize(
    "sent", [b"", b"\x00\x00\x00\x64", b'\x00\x00\x00\x64{"call": '], ids=["none", "header", "part"]
)
def test_a_worker_that_stops_mid_message_is_held_to_the_wall_clock(sent: bytes) -> None:
    """A worker that sends part of a message and sleeps uses no CPU; the host must not wait for the rest."""
    code = f"import os, time\nos.write(3, {sent!r})\ntime.sleep(1000)\n"
    started = time.monotonic()
    ended = run(code, LIMITS.model_copy(update={"wall_s": 1.0}), unchecked=True)
    assert ended.error == "wall-clock limit exceeded (1 s of program time)"
    assert time.monotonic() - started < 10


def test_output_shaped_like_protocol_frames_stays_output() -> None:
    """NUL bytes, a length header, a JSON skill call and terminal escapes printed by a program are its output."""
    fake = '\x00\x00\x00\x1a{"call": "close_gripper"}\x00\x1b[2J\r'
    ended = run(f"print({fake!r})\nc = get_center('milk')\nprint(len(c))\n")
    assert ended == ProgramEnded(error=None, output=fake + "\n3\n")


def test_a_worker_that_stops_reading_its_replies_is_held_to_the_wall_clock() -> None:
    """Skill calls sent without reading the answers fill the socket buffer: the host's reply must not block."""
    code = (
        "import json, time\nfrom multiprocessing.connection import Connection\nhost = Connection(3)\n"
        "for i in range(500):\n"
        "    host.send_bytes(json.dumps({'call': 'get_center', 'args': ['milk']}).encode())\n"
        "time.sleep(1000)\n"
    )
    limits = LIMITS.model_copy(update={"wall_s": 1.0, "max_skill_calls": 500})
    session = SandboxSession(code, "arm", limits, test_only_skip_python_checks=True)
    session.resume(None)
    slowest_resume = 0.0
    message = session.wait()
    while isinstance(message, SkillRequest):
        started = time.monotonic()
        session.resume(SkillReply(value=[0.3, 0.0, 0.1]))  # the runner resumes every world before waiting
        slowest_resume = max(slowest_resume, time.monotonic() - started)
        message = session.wait()
    session.close()
    assert message.error == "wall-clock limit exceeded (1 s of program time)"
    assert slowest_resume < 0.1


def test_a_batch_keeps_at_most_its_output_budget() -> None:
    limits = LIMITS.model_copy(update={"max_batch_output_chars": 100})
    sessions = start_sessions(["print('y' * 80)\n"] * 3, "arm", limits)
    outputs = []
    for session in sessions:
        session.resume(None)
        ended = session.wait()
        assert isinstance(ended, ProgramEnded) and ended.error is None
        outputs.append(ended.output)
        session.close()
    assert outputs == ["y" * 80 + "\n", "y" * 19 + OUTPUT_CUT, OUTPUT_CUT]  # never cut silently


def test_a_malformed_message_ends_only_that_world() -> None:
    code = "from multiprocessing.connection import Connection\nConnection(3).send_bytes(b'{\"call\": 5}')\n"
    ended = run(code, unchecked=True)
    assert ended.error == "the worker sent a malformed message"
    assert json.loads('{"ok": 1}')  # the host process carries on


@pytest.mark.parametrize(
    "args",
    [
        "[" * 50_000 + "]" * 50_000,  # nesting that a recursive parser would choke on
        '["' + "m" * 50_000 + '"]',  # a huge object name
        "[" + ", ".join(["[1, 2, 3]"] * 10) + ", [[[1]]]]",
    ],
    ids=["deep", "long-name", "nested"],
)
def test_oversized_or_deep_skill_arguments_are_malformed(args: str) -> None:
    code = (
        "from multiprocessing.connection import Connection\n"
        f'Connection(3).send_bytes(b\'{{"call": "get_center", "args": \' + {args!r}.encode() + b\'}}\')\n'
    )
    assert run(code, unchecked=True).error == "the worker sent a malformed message"


def test_a_long_object_name_is_the_programs_error() -> None:
    ended = run("c = get_center('m' * 300)\n")
    assert ended.error == "line 1: ValueError: get_center: an object name has at most 200 characters"


@pytest.mark.parametrize(
    ("code", "words"),
    [
        ("import numpy as np\nx = np.full(3, print)\n", "dtype '|O' are not allowed"),
        ("import numpy as np\nx = np.where([True], [print], [len])\n", "dtype '|O' are not allowed"),
        ("import numpy as np\nx = np.asarray({1: 2})\n", "dtype '|O' are not allowed"),
        ("import numpy as np\nx = np.ones((2,) * 64)\n", "ValueError"),
        ("import numpy as np\nx = np.tile([1.0], 10 ** 10)\n", "memory limit exceeded"),
        ("import numpy as np\nx = np.array([1.0], ndmin=10 ** 9)\n", "ValueError"),
        ("import numpy as np\nx = np.array(3.0).item(10 ** 20)\n", "OverflowError"),
        ("import math\nx = math.factorial(10 ** 7)\n", "CPU time limit exceeded"),
        ("x = f'{1:{10 ** 10}}'\n", "memory limit exceeded"),
    ],
)
def test_c_functions_reachable_from_allowed_names_end_as_program_errors(code: str, words: str) -> None:
    ended = run(code, LIMITS.model_copy(update={"cpu_s": 1.0}))
    assert ended.error is not None and words in ended.error


@pytest.mark.parametrize(
    "smuggle",
    [
        "np.asarray([print])",
        "np.concatenate([[print], [1]])",
        "np.where([True], [print], [1])",
        "np.full(2, print)",
        "np.tile([print], 2)",
        "np.repeat([print], 2)",
        "np.zeros(2) * [print, 1]",
        "np.clip([print], 0, 1)",
        "np.sum([[1], [print]])",
        "np.round([print])",
        "np.minimum([10 ** 30, 1], 3)",
        "np.cumsum([10 ** 30, 1])",
    ],
)
def test_numpy_functions_build_no_array_holding_a_builtin(smuggle: str) -> None:
    """Escape attempts: a builtin (or an integer beyond 64 bits) handed to numpy functions that would build an object
    array from it, which the program then fills with ``print``; each run ends with a TypeError, before any output."""
    ended = run(f"import numpy as np\nboxed = {smuggle}\nboxed[0] = print\nboxed[0]('escaped')\n")
    assert ended.error is not None and "TypeError" in ended.error, ended
    assert "escaped" not in ended.output
