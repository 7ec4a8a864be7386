"""Static check of a generated program's AST against the sandbox allowlist.

Allowed: calls to the embodiment's skills, ``import numpy as np`` and ``import math`` with the
functions listed in :mod:`robotool.sandbox.allowlist`, a small set of builtins and value methods,
arithmetic, comparisons, assignments, literals, comprehensions, f-strings, ``for``/``while``/``if``,
``assert``, ``print``, and helper functions (``def`` without decorators, ``lambda``).

Helper functions are allowed on purpose: language models write them often, their bodies pass the
same checks as the rest of the program, and what makes functions dangerous elsewhere (``__code__``,
``__globals__``, ``__closure__``, ``gi_frame``) is reachable only through attributes the allowlist
refuses. Runaway recursion is stopped by the worker's limits like any other runaway computation.

Refused: other imports, classes, ``try``/``with``/``raise``/``global``/``yield``/``async``, any name
or attribute starting with ``_``, attribute assignment, builtins outside the allowlist (``open``,
``exec``, ``getattr``, ``type``...), rebinding a skill, module or builtin name, numpy types that are not
numeric (``dtype=``, ufunc loop ``signature=``), ``*``/``**`` into a method on a value, and skill calls
whose literal arguments the embodiment cannot take.

Why not RestrictedPython (9.0 was read for this): it compiles a much larger language (classes,
imports through a guarded ``__import__``, any attribute not starting with ``_``) and its safety rests
on runtime guards the host must write (``_getattr_``, ``_getitem_``, ``_getiter_``, ``_write_``,
``_print_``). Its policy is a blocklist of private names; ours must be an allowlist of skills, numpy
functions and value methods, with messages that name the skill and the embodiment. Taken from it:
every node type not explicitly allowed is refused (new syntax stays out until reviewed), and its
list of introspection attributes (``gi_frame``, ``f_globals``, ``tb_frame``...), all of which our
attribute allowlist excludes.
"""

from __future__ import annotations

import ast
import builtins
import re
import unicodedata
from collections.abc import Sequence

from robotool import robots
from robotool.robots.skills import SkillArgumentError
from robotool.safe_text import INVISIBLE
from robotool.sandbox.allowlist import (
    BUILTINS,
    LOOP_TYPE_KEYWORDS,
    MATH_NAMES,
    MODULES,
    NOT_ALLOWED_BECAUSE,
    NUMERIC_TYPE_NAMES,
    NUMPY_CONSTANTS,
    NUMPY_FUNCTIONS,
    NUMPY_LINALG,
    NUMPY_TYPES,
    VALUE_METHODS,
)

MAX_PROGRAM_CHARS = 100_000
"""Longer text is refused before parsing."""

IMPORT_HINT = "only `import numpy as np` and `import math`"

_PLAIN_NODES: tuple[type[ast.AST], ...] = (
    ast.Module, ast.Expr, ast.Assign, ast.AugAssign, ast.AnnAssign, ast.For, ast.While, ast.If,
    ast.Break, ast.Continue, ast.Pass, ast.Return, ast.Assert, ast.BoolOp, ast.BinOp, ast.UnaryOp,
    ast.IfExp, ast.Compare, ast.Constant, ast.JoinedStr, ast.FormattedValue, ast.List, ast.Tuple,
    ast.Dict, ast.Set, ast.ListComp, ast.SetComp, ast.DictComp, ast.GeneratorExp, ast.comprehension,
    ast.Subscript, ast.Slice, ast.Starred, ast.NamedExpr, ast.keyword, ast.arguments,
    ast.operator, ast.boolop, ast.cmpop, ast.unaryop, ast.expr_context,
)  # fmt: skip
"""Nodes allowed as they are; their children are still checked."""

_REFUSED_WORDS: dict[type[ast.AST], str] = {
    ast.ClassDef: "class definitions are not allowed",
    ast.AsyncFunctionDef: "async functions are not allowed",
    ast.Try: "try/except is not allowed",
    ast.With: "with statements are not allowed",
    ast.Raise: "raise is not allowed",
    ast.Global: "global is not allowed",
    ast.Nonlocal: "nonlocal is not allowed",
    ast.Delete: "del is not allowed",
    ast.Yield: "yield (generators) is not allowed",
    ast.YieldFrom: "yield (generators) is not allowed",
    ast.Await: "async code is not allowed",
    ast.Match: "match statements are not allowed",
}


class ProgramRejected(ValueError):
    """A program (or LM output) that will not run: ``line`` (None if not tied to one),
    ``construct`` (the offending code or thing, short) and a one-line message."""

    def __init__(self, line: int | None, construct: str, reason: str):
        self.line = line
        self.construct = construct
        self.reason = reason
        super().__init__(f"line {line}: {reason}" if line else reason)


MAX_BRACES = 10_000
"""Most ``{`` characters in a text the host parses: Python 3.11 parses one f-string's replacement
fields in time quadratic in their number (30,000 fields in 90 KB took 0.6 s per parse)."""


def check_parse_cost(text: str, what: str) -> None:
    """Refuse text whose parse would not run in about linear time (see :data:`MAX_BRACES`)."""
    if text.count("{") > MAX_BRACES:
        raise ProgramRejected(None, what, f"{what} has more than {MAX_BRACES} '{{' characters")


def check_program_size(code: str) -> None:
    """Refuse program text longer than :data:`MAX_PROGRAM_CHARS` before anything parses it."""
    if len(code) > MAX_PROGRAM_CHARS:
        raise ProgramRejected(None, "program", f"program is longer than {MAX_PROGRAM_CHARS} characters")


_RAW_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f-\x9f]|\r(?!\n)")
"""The control characters a program's text may not hold raw: tab and newline it may, and a carriage return only before
a newline (Python breaks the line at a lone one, which a terminal shows as the line written over)."""


def check_characters(code: str) -> None:
    """Refuse program text holding a raw control character or a character that shows nothing (a bidi override, a
    zero-width joiner, a variation selector, a Hangul filler: :data:`~robotool.safe_text.INVISIBLE`) anywhere, in a
    string, a comment or a name too. Python runs them there, but the text reaches files and terminals that would obey
    them (an escape sequence that writes the clipboard, clears the screen or paints a fake verdict; text that reads in
    an editor otherwise than it runs: ``lift`` followed by U+FE00 is another name than ``lift``); written as an
    escape (``\\x1b``) in a string, the same character runs the same."""
    places = [found.start() for found in (_RAW_CONTROL.search(code), INVISIBLE.search(code)) if found]  # every Cf too
    if not places:
        return
    at = min(places)
    char = code[at]
    kind = "control" if unicodedata.category(char) == "Cc" else f"invisible ({unicodedata.name(char, 'unnamed')})"
    if char == "\r":
        reason = "a carriage return not before a newline (Python breaks the line there, a terminal writes over it)"
        raise ProgramRejected(code.count("\n", 0, at) + 1, "U+000D", f"the program holds {reason}: end lines with \\n")
    raise ProgramRejected(
        code.count("\n", 0, at) + 1,
        f"U+{ord(char):04X}",
        f"the program holds the raw {kind} character U+{ord(char):04X}: write it as an escape in a string "
        f"(\\u{ord(char):04x}) or leave it out",
    )


def parse_program(code: str) -> ast.Module:
    """Parse program text, turning every way it can fail into a :class:`ProgramRejected`."""
    check_parse_cost(code, "program")
    try:
        return ast.parse(code)
    except SyntaxError as e:
        raise ProgramRejected(e.lineno, "syntax", f"syntax error: {e.msg}") from None
    except (RecursionError, MemoryError):  # the parser's stack overflows (text is at most 100 KB)
        raise ProgramRejected(None, "nesting", "program is nested too deeply") from None
    except ValueError as e:
        raise ProgramRejected(None, "syntax", f"program cannot be parsed: {e}") from None


def validate(code: str, embodiment: str) -> None:
    """Check a program against the sandbox allowlist; raise :class:`ProgramRejected` if it fails.

    The first problem in source order is reported. The work is linear in the program's length:
    one parse, one visit per node, and only the reported problem's source text is cut out.
    """
    check_program_size(code)
    check_characters(code)
    tree = parse_program(code)
    checker = _Checker(embodiment)
    try:
        checker.check_module(tree)
    except RecursionError:
        raise ProgramRejected(None, "nesting", "program is nested too deeply") from None
    checker.check_imports()
    if checker.problems:
        line, node, reason = min(checker.problems, key=lambda p: p[0] or 0)
        raise ProgramRejected(line, _source_line_segment(code, node), reason)


def _source_line_segment(code: str, node: ast.AST | str) -> str:
    """The first source line of ``node`` (or ``node`` itself when it is already text)."""
    if isinstance(node, str):
        return node
    line, start = getattr(node, "lineno", None), getattr(node, "col_offset", None)
    if line is None or start is None:
        return type(node).__name__
    text = _LINE_BREAK.split(code, maxsplit=line)[line - 1].encode()  # offsets count UTF-8 bytes
    end = getattr(node, "end_col_offset", None) if getattr(node, "end_lineno", line) == line else None
    return text[start:end].decode(errors="replace") or type(node).__name__


_LINE_BREAK = re.compile(r"\r\n|\r|\n")


def _scope_bindings(nodes: Sequence[ast.AST]) -> set[str]:
    """Names bound directly in one scope: targets, loop and comprehension variables, function names.

    Nested function and lambda bodies and parameters are their own scopes and are not entered (their
    defaults are evaluated in this one and are).
    """
    names: set[str] = set()
    todo = list(nodes)
    while todo:
        node = todo.pop()
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        if isinstance(node, ast.FunctionDef):
            names.add(node.name)
            todo += [*node.decorator_list, *node.args.defaults, *filter(None, node.args.kw_defaults)]
        elif isinstance(node, ast.Lambda):
            todo += [*node.args.defaults, *filter(None, node.args.kw_defaults)]
        else:
            todo += ast.iter_child_nodes(node)
    return names


def _parameters(args: ast.arguments) -> list[ast.arg]:
    return [*args.posonlyargs, *args.args, *filter(None, [args.vararg, args.kwarg]), *args.kwonlyargs]


class _Checker(ast.NodeVisitor):
    """Visits every node, recording ``(line, node, reason)`` for each problem.

    Names resolve through a stack of scopes (the module, then each enclosing function or lambda),
    so a name is usable only where the program binds it or where it is an allowed builtin.
    """

    def __init__(self, embodiment: str):
        self.embodiment = embodiment
        self.robot = robots.get(embodiment)
        self.skills = {s.name: s for s in self.robot.skills}
        self.scopes: list[set[str]] = []
        self.bound_anywhere: set[str] = set()
        self.imported: set[str] = set()
        self.used_modules: dict[str, int] = {}
        self.problems: list[tuple[int | None, ast.AST | str, str]] = []

    def reject(self, node: ast.AST, reason: str) -> None:
        self.problems.append((getattr(node, "lineno", None), node, reason))

    def check_module(self, tree: ast.Module) -> None:
        self.in_scope(_scope_bindings(tree.body), tree.body)

    def in_scope(self, names: set[str], body: Sequence[ast.AST]) -> None:
        self.scopes.append(names)
        self.bound_anywhere |= names
        for node in body:
            self.visit(node)
        self.scopes.pop()

    def is_bound(self, name: str) -> bool:
        return any(name in scope for scope in self.scopes)

    def check_imports(self) -> None:
        for alias, line in sorted(self.used_modules.items(), key=lambda item: item[1]):
            if alias not in self.imported:
                statement = "import numpy as np" if alias == "np" else "import math"
                self.problems.append((line, alias, f"'{alias}' is used but never imported; add `{statement}`"))

    def generic_visit(self, node: ast.AST) -> None:
        if isinstance(node, _PLAIN_NODES):
            super().generic_visit(node)
            return
        words = _REFUSED_WORDS.get(type(node), f"{type(node).__name__} is not allowed")
        self.reject(node, words)

    # imports

    def visit_Import(self, node: ast.Import) -> None:
        for alias in node.names:
            as_name = alias.asname or alias.name
            if MODULES.get(as_name) == alias.name:
                self.imported.add(as_name)
            else:
                shown = f"{alias.name} as {alias.asname}" if alias.asname else alias.name
                self.reject(node, f"import of '{shown}' is not allowed; {IMPORT_HINT}")

    def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
        names = ", ".join(a.name for a in node.names)
        self.reject(node, f"'from {node.module} import {names}' is not allowed; {IMPORT_HINT}")

    # names and attributes

    def visit_Name(self, node: ast.Name) -> None:
        name = node.id
        if _private(name) or not isinstance(node.ctx, ast.Load):
            self.check_binding(node, name)
        elif name in MODULES:
            self.reject(node, f"'{name}' can only be used as {name}.<function>, not as a value")
        elif name in self.skills:
            self.reject(node, f"skill '{name}' can only be called, not used as a value")
        elif name not in BUILTINS and not self.is_bound(name):
            self.reject(node, self.unknown_name(name, called=False))

    def check_binding(self, node: ast.AST, name: str) -> None:
        """A program may not bind a reserved, skill, module or builtin name, allowed or not, anywhere."""
        if _private(name):
            self.reject(node, f"name '{name}' is not allowed: names starting with '_' are reserved")
        elif name in self.skills or name in MODULES or name in BUILTINS:
            self.reject(node, f"'{name}' cannot be assigned: it is a skill, module or builtin name")
        elif hasattr(builtins, name):
            self.reject(node, f"'{name}' cannot be assigned: it is a Python built-in name; choose another name")

    def unknown_name(self, name: str, *, called: bool) -> str:
        if hasattr(builtins, name):
            return f"built-in '{name}' is not allowed in programs"
        known = ", ".join(self.skills)
        for other in robots.robots():
            if other is not self.robot and other.skill(name) is not None:
                return f"'{name}' is a {other.name} skill; the {self.embodiment}'s skills are: {known}"
        if name in self.bound_anywhere:
            return f"name '{name}' is not defined here: it is assigned only inside another function"
        if called:
            return f"unknown function '{name}'; the {self.embodiment}'s skills are: {known}"
        return f"name '{name}' is never assigned"

    def visit_Attribute(self, node: ast.Attribute) -> None:
        path = _module_path(node)
        if path is None:
            self.visit(node.value)
        else:
            self.used_modules.setdefault(path[0], node.lineno)
        if node.attr.startswith("_"):
            self.reject(node, f"attribute '{node.attr}' is not allowed: names starting with '_' are private")
        elif not isinstance(node.ctx, ast.Load):
            self.reject(node, "assigning to attributes is not allowed")
        elif path is None and node.attr not in VALUE_METHODS:
            self.reject(node, _refusal(f"attribute '.{node.attr}'", node.attr))
        elif path is not None and path not in _MODULE_ATTRIBUTES:
            self.reject(node, _refusal(".".join(path), path[1]))
        elif path == ("np", "linalg"):
            self.reject(node, "'np.linalg' can only be used as np.linalg.<function>, not as a value")

    # calls and definitions

    def visit_Call(self, node: ast.Call) -> None:
        func = node.func
        if isinstance(func, ast.Name) and func.id in self.skills:
            self.check_skill_call(node, func.id)
        elif isinstance(func, ast.Attribute) and _module_path(func) == ("np", "linalg"):
            self.reject(node, "'np.linalg' is a module, not a function")
        elif isinstance(func, ast.Name) and func.id not in BUILTINS and not self.is_bound(func.id):
            self.reject(node, self.unknown_name(func.id, called=True))
        else:
            self.visit(func)
        if isinstance(func, ast.Attribute) and func.attr == "astype" and not _numeric_type_only(node):
            self.reject(node, f"astype() takes one numeric type: {NUMERIC_TYPES_SHOWN}")
        elif isinstance(func, ast.Attribute) and func.attr in _REDUCTIONS and len(node.args) > 1:
            self.reject(node, f".{func.attr}() takes the axis as its only positional argument; name the others")
        if any(k.arg == "dtype" and not _numeric_type(k.value) for k in node.keywords):
            self.reject(node, f"dtype= takes one numeric type: {NUMERIC_TYPES_SHOWN}")
        elif any(k.arg in LOOP_TYPE_KEYWORDS for k in node.keywords):
            self.reject(node, "signature= is not allowed: it picks numpy's internal loop types; use dtype=")
        elif isinstance(func, ast.Attribute) and _module_path(func) is None and _unpacks(node):
            self.reject(node, f"* and ** cannot pass arguments to .{func.attr}(): write each argument out")
        for child in [*node.args, *node.keywords]:
            self.visit(child)

    def check_skill_call(self, node: ast.Call, name: str) -> None:
        spec = self.skills[name]
        if any(isinstance(a, ast.Starred) for a in node.args) or any(k.arg is None for k in node.keywords):
            return
        params = [p for p, _ in spec.params]
        unknown = [k.arg for k in node.keywords if k.arg not in params]
        if unknown:
            self.reject(node, f"{spec.signature} has no parameter '{unknown[0]}'")
            return
        if len(node.args) + len(node.keywords) != len(params):
            self.reject(
                node, f"{spec.signature} takes {len(params)} argument(s), got {len(node.args) + len(node.keywords)}"
            )
            return
        by_name = {k.arg: k.value for k in node.keywords}
        values = [*node.args, *(by_name[p] for p in params[len(node.args) :])]
        try:
            literal = tuple(ast.literal_eval(v) for v in values)
        except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
            return  # not all literal: the worker checks the values when the call happens
        try:
            self.robot.check_call(name, literal)
        except SkillArgumentError as e:
            self.reject(node, str(e))

    def visit_AnnAssign(self, node: ast.AnnAssign) -> None:
        self.check_annotation(node.annotation)
        super().generic_visit(node)

    def check_annotation(self, annotation: ast.expr) -> None:
        """An annotation is evaluated where it stands (a module's or a function's): a call in one runs, which no
        annotation means (``Optional: open_gripper()``, a model's prose label before a call, would open the
        gripper)."""
        call = next((n for n in ast.walk(annotation) if isinstance(n, ast.Call)), None)
        if call is not None:
            self.reject(call, "a call in an annotation is not allowed (annotations are evaluated: the call would run)")
        self.visit(annotation)

    def visit_FunctionDef(self, node: ast.FunctionDef) -> None:
        if node.decorator_list:
            self.reject(node, "decorators are not allowed")
        self.check_binding(node, node.name)
        self.visit(node.args)
        if node.returns:
            self.check_annotation(node.returns)
        own = {a.arg for a in _parameters(node.args)} | _scope_bindings(node.body)
        self.in_scope(own, node.body)

    def visit_Lambda(self, node: ast.Lambda) -> None:
        self.visit(node.args)
        self.in_scope({a.arg for a in _parameters(node.args)}, [node.body])

    def visit_arguments(self, node: ast.arguments) -> None:
        """Parameters are checked as bindings; defaults are evaluated in the enclosing scope."""
        for parameter in _parameters(node):
            self.check_binding(parameter, parameter.arg)
            if parameter.annotation:
                self.check_annotation(parameter.annotation)
        for default in [*node.defaults, *filter(None, node.kw_defaults)]:
            self.visit(default)


_MODULE_ATTRIBUTES: frozenset[tuple[str, ...]] = frozenset(
    {("np", n) for n in NUMPY_FUNCTIONS | NUMPY_CONSTANTS | NUMPY_TYPES | {"linalg"}}
    | {("np", "linalg", n) for n in NUMPY_LINALG}
    | {("math", n) for n in MATH_NAMES}
)


def _module_path(node: ast.Attribute) -> tuple[str, ...] | None:
    """``np.linalg.norm`` -> ("np", "linalg", "norm"); None when the chain does not start at np/math."""
    parts = [node.attr]
    value: ast.expr = node.value
    while isinstance(value, ast.Attribute):
        parts.append(value.attr)
        value = value.value
    if isinstance(value, ast.Name) and value.id in MODULES:
        return (value.id, *reversed(parts))
    return None


NUMERIC_TYPES_SHOWN = "float, int, bool, np.float64, np.int64 or 'float32'"

_REDUCTIONS = frozenset({"sum", "mean", "std", "var", "prod", "cumsum"})
"""Array methods and numpy functions whose second or third positional parameter is ``dtype`` (which must be
checked by name)."""


def _unpacks(call: ast.Call) -> bool:
    """``f(*args)`` or ``f(**kwargs)``: which parameter gets which value is known only at run time.

    Refused for methods on values (numpy's array methods run unwrapped, so the validator's checks of their
    ``dtype`` by name and position are what keeps an object loop from running; the worker refuses an object
    array only once a method returns one); numpy functions are checked again in the worker.
    """
    return any(isinstance(a, ast.Starred) for a in call.args) or any(k.arg is None for k in call.keywords)


def _numeric_type_only(call: ast.Call) -> bool:
    """``x.astype(T)`` with ``T`` a numeric type (see :func:`_numeric_type`)."""
    return len(call.args) == 1 and not call.keywords and _numeric_type(call.args[0])


def _numeric_type(arg: ast.expr) -> bool:
    """A numeric builtin, ``np.<numeric type>`` or its name as a string."""
    if isinstance(arg, ast.Name):
        return arg.id in ("float", "int", "bool")
    if isinstance(arg, ast.Constant):
        return isinstance(arg.value, str) and arg.value in NUMERIC_TYPE_NAMES
    return isinstance(arg, ast.Attribute) and _module_path(arg) in {("np", n) for n in NUMPY_TYPES}


def _private(name: str) -> bool:
    """Names starting with '_' are reserved; '_' alone is the usual throwaway loop variable."""
    return name.startswith("_") and name != "_"


def _refusal(what: str, name: str) -> str:
    reason = NOT_ALLOWED_BECAUSE.get(name)
    return f"{what} is not allowed" + (f": {reason}" if reason else " (not in the sandbox allowlist)")
