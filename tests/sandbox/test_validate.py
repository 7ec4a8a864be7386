"""The sandbox's static allowlist: what typical generated programs need passes, the rest is named."""

from __future__ import annotations

import contextlib
import math
import re

import numpy as np
import pytest

from robotool.sandbox import ProgramRejected, validate
from robotool.sandbox.allowlist import BUILTINS, MATH_NAMES, NUMPY_CONSTANTS, NUMPY_FUNCTIONS, NUMPY_LINALG
from robotool.sandbox.strict import check_user_program

# CPU seconds for 100 kB: linear work takes about one on a slow 2-core machine, a quadratic blow-up minutes
CPU_LIMIT_S = 5.0

ARM_PROGRAM = """\
import numpy as np
import math

def above(point, height=0.1):
    return [point[0], point[1], point[2] + height]

low, high = get_workspace_range()[0]
milk = np.array(get_graspable_point("milk"))
size = get_size("milk")
open_gripper()
move_to_position(above(milk.tolist()))
move_to_position(milk)
close_gripper()
for step in range(3):
    target = milk + np.array([0.0, 0.0, 0.05 * (step + 1)])
    move_to_position(target)
distance = np.linalg.norm(milk[:2]) + math.hypot(size[0], size[1])
names = sorted({"a": 1, "b": 2}.items(), key=lambda kv: -kv[1])
print(f"milk at {milk.round(3)}, distance {distance:.2f}, {names}")
"""

QUADRUPED_PROGRAM = """\
board = get_position("surfboard")
gap = get_position("sofa_2")[0] - get_size("sofa_2")[0] / 2
push_to_position("surfboard", [gap, board[1], board[2]])
i = 0
while i < 2 and abs(board[0]) >= 0:
    i += 1
walk_to_position(position=[gap + 0.3, 0.0, 0.0])
climb_to_position([1.45, 0.0, 0.34])
"""


@pytest.mark.parametrize(("code", "embodiment"), [(ARM_PROGRAM, "arm"), (QUADRUPED_PROGRAM, "quadruped")])
def test_typical_programs_pass(code: str, embodiment: str) -> None:
    validate(code, embodiment)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("code", "line", "construct", "words"),
    [
        ("x = 1\nimport os\n", 2, "import os", "import of 'os' is not allowed; only `import numpy as np`"),
        ("p = get_center('milk')\n\nq = p.__class__\n", 3, "p.__class__", "'__class__' is not allowed"),
        ("def f():\n    return open('/etc/passwd')\n", 2, "open('/etc/passwd')", "built-in 'open'"),
        ("x = np.zeros(3)\n", 1, "np", "'np' is used but never imported; add `import numpy as np`"),
        ("import math\ny = math.tau\nz = cmath.pi\n", 3, "cmath", "name 'cmath' is never assigned"),
        ("move_to_position([0.1, 0.2])\nget_center(3)\n", 2, "get_center(3)", "name must be an object name"),
        ("move_to_position(pos=[0, 0, 0])\n", 1, "move_to_position(pos=[0, 0, 0])", "no parameter 'pos'"),
        ("f = move_to_position\n", 1, "move_to_position", "can only be called"),
        ("@staticmethod\ndef f():\n    pass\n", 2, "def f():", "decorators are not allowed"),
        ("x = [1]\nx.append(2)\nx.pop().__class__\n", 3, "x.pop().__class__", "'__class__'"),
        # raw escapes in a string or a comment run as Python, but a saved program would obey them in a terminal (an
        # adversarial run: a reply's clipboard write reached the `solve --out` file); a bidi override reads otherwise
        ('x = 1\nprint("\x1b]52;c;ZWNobw==\x07\x1b[2J")\n', 2, "U+001B", "raw control character U+001B"),
        ("# \u202e evil\nprint(1)\n", 1, "U+202E", "RIGHT-TO-LEFT OVERRIDE"),
        # an adversarial run: a name with a variation selector, or one that is a Hangul filler, shows as another name
        # (``lift`` and ``lift`` + U+FE00 are two variables), and a lone carriage return breaks the line where a
        # terminal writes the rest over it (a call hidden behind a comment)
        ("z = 0.3\nlift\ufe00 = 0.1\n", 2, "U+FE00", "raw invisible (VARIATION SELECTOR-1) character U+FE00"),
        ("\u3164 = 1\n", 1, "U+3164", "HANGUL FILLER"),
        ("x = 1\n\u115f = 2\n", 2, "U+115F", "HANGUL CHOSEONG FILLER"),
        ("x = 1  # \u2028 y = 2\n", 1, "U+2028", "LINE SEPARATOR"),
        ("x = 1\nopen_gripper()\r# done\n", 2, "U+000D", "a carriage return not before a newline"),
    ],
)
def test_rejection_names_line_and_construct(code: str, line: int, construct: str, words: str) -> None:
    with pytest.raises(ProgramRejected) as caught:
        validate(code, "arm")
    rejected = caught.value
    assert isinstance(rejected, ValueError)
    assert (rejected.line, rejected.construct) == (line, construct)
    assert words in str(rejected) and str(rejected).startswith(f"line {line}: ")
    assert "\n" not in str(rejected)


def test_lines_may_end_in_a_carriage_return_and_a_newline() -> None:
    validate("x = 1\r\nprint(x)\r\n", "arm")


def test_first_problem_in_source_order_is_reported() -> None:
    with pytest.raises(ProgramRejected, match="line 2: import of 'sys'"):
        validate("x = 1\nimport sys\nopen('f')\n", "arm")


def test_skills_are_per_embodiment() -> None:
    validate("walk_to_position([1.0, 0.0, 0.0])\n", "quadruped")
    with pytest.raises(ProgramRejected, match="'walk_to_position' is a quadruped skill; the arm's skills"):
        validate("walk_to_position([1.0, 0.0, 0.0])\n", "arm")


def test_protected_names_cannot_be_rebound() -> None:
    for code in ("np = 1\n", "def f(math):\n    return 0\n", "for print in range(3):\n    pass\n", "len = 3"):
        with pytest.raises(ProgramRejected, match="cannot be assigned"):
            validate(code, "arm")


@pytest.mark.parametrize("code", ["(" * 300 + ")" * 300, "x = " + "-" * 100_000 + "1", "x = 1" * 50_000])
def test_pathological_text_is_rejected_not_crashing(code: str) -> None:
    with pytest.raises(ProgramRejected):
        validate(code, "arm")


def test_deep_nesting_is_named_in_the_rejection() -> None:
    with pytest.raises(ProgramRejected, match=r"^program is nested too deeply$"):
        validate("f = " + "lambda: " * 11_000 + "1", "arm")


@pytest.mark.parametrize(
    ("code", "words"),
    [
        ("x = " + "-" * 99_000 + "1", "^program is nested too deeply$"),  # the parser runs out of memory
        ("x = 1" + " + 1" * 24_000, "^program is nested too deeply$"),  # the parser's recursion limit
        ("x = 1\n" * 20_000, "^program is longer than 100000 characters$"),  # refused before it is parsed
    ],
)
def test_a_users_own_file_that_cannot_be_parsed_is_told_why(code: str, words: str) -> None:
    """The strict reading of a program file gives the same reasons as the validator (a parser that runs out
    of memory raised an empty MemoryError, shown as "program cannot be parsed: ")."""
    with pytest.raises(ProgramRejected, match=words):
        check_user_program(code, "arm")


def test_allowlisted_names_exist_where_the_worker_looks_them_up() -> None:
    import builtins

    assert all(hasattr(np, n) for n in NUMPY_FUNCTIONS | NUMPY_CONSTANTS)
    assert all(hasattr(np.linalg, n) for n in NUMPY_LINALG)
    assert all(hasattr(math, n) for n in MATH_NAMES)
    assert all(hasattr(builtins, n) for n in BUILTINS)
    dangerous = {"load", "save", "fromfile", "memmap", "ctypeslib", "lib", "testing", "loadtxt", "frompyfunc"}
    assert not dangerous & NUMPY_FUNCTIONS
    assert not {"open", "getattr", "type", "exec", "eval", "vars", "globals", "object"} & BUILTINS


@pytest.mark.parametrize(
    ("code", "words"),
    [
        ("def f(getattr):\n    return getattr\n", "'getattr' cannot be assigned: it is a Python built-in name"),
        ("g = lambda open=1: open\n", "'open' cannot be assigned"),
        ("def f(*vars, **globals):\n    return 0\n", "'vars' cannot be assigned"),
        ("for type in [1]:\n    pass\n", "'type' cannot be assigned"),
        ("x = [eval for eval in range(3)]\n", "'eval' cannot be assigned"),
        ("if (exec := 1):\n    pass\n", "'exec' cannot be assigned"),
        ("def f(x=getattr):\n    return x\n", "built-in 'getattr' is not allowed"),
    ],
)
def test_forbidden_names_cannot_be_bound_anywhere(code: str, words: str) -> None:
    with pytest.raises(ProgramRejected, match=words):
        validate(code, "arm")


def test_names_resolve_through_scopes() -> None:
    validate("def f(a):\n    b = a + 1\n    g = lambda c: b + c\n    return g(2)\nx = f(1)\n", "arm")
    validate("y = 2\ndef f():\n    return y\n", "arm")
    with pytest.raises(ProgramRejected, match="line 3: name 'b' is not defined here"):
        validate("def f(a):\n    b = a\nprint(b)\n", "arm")
    with pytest.raises(ProgramRejected, match="line 3: name 'a' is not defined here"):
        validate("g = lambda a: a\nh = g(1)\nprint(a)\n", "arm")


@pytest.mark.parametrize(
    "code",
    [
        "x = getattr\n" * 8_000,  # a problem on every line
        "open(1); " * 10_000,  # a problem every few characters of one line
        "def f(a):\n" + "    a = a + 1\n" * 7_000,  # one deep scope
        "x = [" + "1, " * 33_000 + "]\n",
        "move_to_position([0.1, 0.2, 0.3])\n" * 2_900,
        'x = f"' + "{1}" * 30_000 + '"',
    ],
    ids=["bad-lines", "bad-one-line", "long-function", "long-literal", "many-calls", "f-string-fields"],
)
def test_validation_of_100_kb_stays_linear(code: str) -> None:
    import time

    assert 90_000 <= len(code) <= 100_000
    started = time.process_time()
    with contextlib.suppress(ProgramRejected):
        validate(code, "arm")
    assert time.process_time() - started < CPU_LIMIT_S


@pytest.mark.parametrize("argument", ["0x" + "f" * 5000, "[0x" + "f" * 5000 + ", 0, 0]"], ids=["int", "list"])
def test_an_integer_too_long_to_print_is_a_clear_rejection(argument: str) -> None:
    """Showing the bad argument must not fail: decimal conversion of such an integer raises ValueError."""
    with pytest.raises(ProgramRejected, match="too large to show"):
        validate(f"move_to_position({argument})\n", "arm")


@pytest.mark.parametrize(
    ("code", "words"),
    [
        ("x = ｅｖａｌ('1')\n", "built-in 'eval' is not allowed"),  # NFKC-normalised by the parser
        ("x = (1).__ｃlass__\n", "'__class__' is not allowed"),
        ("f = str.format\n", "'.format' is not allowed"),
        ("x = list(map(str.format_map, ['{a.__class__}'], [{'a': 1}]))\n", "'.format_map' is not allowed"),
        ("g = (i for i in [1])\nf = g.gi_frame\n", "'.gi_frame' is not allowed"),
        ("f = lambda: 0\nc = f.__code__\n", "'__code__' is not allowed"),
        ("import numpy as np\nnp.sin.at(np.zeros(3), [0])\n", "np.sin.at is not allowed"),
        ("import numpy as np\nr = np.add.reduce\n", "np.add.reduce is not allowed"),
        ("import numpy as np\nnp.set_printoptions(formatter={'all': print})\n", "np.set_printoptions is not allowed"),
        ("import numpy as np\nnp.seterrcall(print)\n", "np.seterrcall is not allowed"),
        ("import numpy as np\nv = np.vectorize(lambda x: x)\n", "np.vectorize is not allowed"),
        ("import numpy as np\nu = np.frompyfunc(print, 1, 1)\n", "np.frompyfunc is not allowed"),
        ("import numpy as np\np = np.zeros(3).ctypes\n", "'.ctypes' is not allowed"),
        ("import numpy as np\ni = np.zeros(3).__array_interface__\n", "'__array_interface__' is not allowed"),
        ("import numpy as np\nm = np.memmap('/etc/passwd')\n", "np.memmap is not allowed"),
        ("import numpy as np\nx = np.load('/etc/passwd', allow_pickle=True)\n", "np.load is not allowed"),
        ("match 1:\n    case _:\n        pass\n", "match statements are not allowed"),
        ("class A:\n    pass\n", "class definitions are not allowed"),
        ("def f():\n    yield 1\n", "yield (generators) is not allowed"),
        ("x: open = 1\n", "built-in 'open' is not allowed"),
    ],
)
def test_introspection_and_numpy_side_doors_are_refused(code: str, words: str) -> None:
    with pytest.raises(ProgramRejected, match=re.escape(words)):
        validate(code, "arm")


@pytest.mark.parametrize(
    "code",
    [
        'p = get_graspable_point("milk")\nOptional: open_gripper()\n',  # a model's prose label before a call
        "x: move_to_position([0.4, 0.0, 0.3]) = 1\n",
        "def f(a: open_gripper()) -> None:\n    pass\n",
        "def f(a) -> close_gripper():\n    pass\n",
    ],
)
def test_a_call_in_an_annotation_is_refused(code: str) -> None:
    """Found by an adversarial run: ``Optional: open_gripper()`` after a program parsed as an annotation, which Python
    evaluates where it stands, so the gripper opened. An annotation without a call stays allowed."""
    with pytest.raises(ProgramRejected, match="a call in an annotation is not allowed"):
        validate(code, "arm")
    validate("x: float = 1.0\ndef f(a: float) -> float:\n    return a\n", "arm")
