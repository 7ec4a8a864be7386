"""What a running program may hold: no object or structured arrays, and no text that carries a memory address.

Runs in the worker. numpy builds an ``object`` array whenever an operand holds something that is not a
plain number (``np.zeros(2) + [10**30, 1]``, ``x.clip(0, [10**30, 1])``, ``divmod(np.float64(1), [10**30])``),
inside array operators and methods that no wrapper sees. So the program's code is rewritten before it
is compiled: the value of every call, binary operation and in-place operation passes through
:func:`guarded`, which refuses such arrays and masks addresses in new text, and the program's ``map``
checks what it makes. Every other expression only moves values that one of these made.

Reprs of functions, generators, iterators and bound methods carry the object's address
(``<function <lambda> at 0x7f...>``), from which a program could recover what ``id()`` (withheld) gives.
Text reaches the program from an object through ``str`` (the program's ``str`` masks), f-strings and
``%`` (masked by :func:`guarded`) and ``print`` (masked by the worker).
"""

from __future__ import annotations

import ast
import builtins
import operator
import re
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

ADDRESS = re.compile(r"0x[0-9a-fA-F]{4,}")
ADDRESS_BYTES = re.compile(rb"0x[0-9a-fA-F]{4,}")
ADDRESS_SHOWN = "0x..."
"""What a masked address reads as."""

GUARD = "__robotool_guarded"
IN_PLACE = "__robotool_in_place"
SLICE = "__robotool_slice"
_HELD = "__robotool_held"
_KEY = "__robotool_key"

_IN_PLACE_OPERATORS: dict[str, Callable[[Any, Any], Any]] = {
    "Add": operator.iadd, "Sub": operator.isub, "Mult": operator.imul, "Div": operator.itruediv,
    "FloorDiv": operator.ifloordiv, "Mod": operator.imod, "Pow": operator.ipow, "MatMult": operator.imatmul,
    "LShift": operator.ilshift, "RShift": operator.irshift, "BitAnd": operator.iand, "BitOr": operator.ior,
    "BitXor": operator.ixor,
}  # fmt: skip


def check_dtype(dtype: np.dtype[Any]) -> None:
    """Refuse object and structured dtypes: how numpy lays references over raw memory."""
    if dtype.hasobject or dtype.kind == "V":
        raise TypeError(f"arrays of dtype {dtype.str!r} are not allowed in programs; use numbers")


def without_addresses(text: str) -> str:
    """``text`` with every ``0x``-address masked."""
    return ADDRESS.sub(ADDRESS_SHOWN, text) if "0x" in text else text


def guarded(value: Any) -> Any:
    """``value`` if a program may hold it: arrays (alone or in a tuple, as ``divmod`` gives) must be numeric;
    text comes back with its addresses masked."""
    kind = type(value)
    if kind is str:
        return without_addresses(value)
    if kind is bytes:
        return ADDRESS_BYTES.sub(ADDRESS_SHOWN.encode(), value) if b"0x" in value else value
    if isinstance(value, np.ndarray):
        check_dtype(value.dtype)
    elif kind is tuple:
        for item in value:
            if isinstance(item, np.ndarray):
                check_dtype(item.dtype)
    return value


def in_place(target: Any, value: Any, op: str) -> Any:
    """``target op= value`` as Python does it (in place where the type can), checked."""
    return guarded(_IN_PLACE_OPERATORS[op](target, value))


class _Builtin(type):
    """A class that stands in for a builtin: its repr is the builtin's (``print(map)``), not the worker's."""

    shown_as = ""

    def __repr__(cls) -> str:
        return f"<class '{cls.shown_as}'>"


class _StrType(_Builtin):
    def __instancecheck__(cls, value: object) -> bool:
        return isinstance(value, str)

    def __subclasscheck__(cls, kind: type) -> bool:
        return issubclass(kind, str)


class SafeStr(str, metaclass=_StrType):
    """The program's ``str``: the builtin, with addresses masked; ``isinstance(x, str)`` and ``str.join`` work."""

    __slots__ = ()
    shown_as = "str"

    # misc: __new__ returns the builtin's plain str on purpose (a SafeStr is never made: only isinstance matters)
    def __new__(cls, *args: Any, **kwargs: Any) -> str:  # type: ignore[misc]
        return without_addresses(str(*args, **kwargs))


class SafeMap(metaclass=_Builtin):
    """The program's ``map``: the builtin, each value it makes checked by :func:`guarded` (``map(divmod, ...)``)."""

    __slots__ = ("_values",)
    shown_as = "map"

    def __init__(self, function: Callable[..., Any], *iterables: Any):
        self._values = builtins.map(function, *iterables)

    def __iter__(self) -> Iterator[Any]:
        return self

    def __next__(self) -> Any:
        return guarded(next(self._values))

    def __repr__(self) -> str:
        return "<map object>"


HELPERS: dict[str, Any] = {GUARD: guarded, IN_PLACE: in_place, SLICE: slice}
"""Names the rewritten code calls; the validator refuses every name starting with ``_`` in programs."""


def rewrite(tree: ast.Module) -> ast.Module:
    """The program with its calls, binary operations, f-strings and in-place operations guarded."""
    return ast.fix_missing_locations(_Guard().visit(tree))


def _call(name: str, *args: ast.expr) -> ast.Call:
    return ast.Call(func=ast.Name(name, ast.Load()), args=list(args), keywords=[])


class _Guard(ast.NodeTransformer):
    def wrap(self, node: ast.expr) -> ast.expr:
        return ast.copy_location(_call(GUARD, node), node)

    def visit_Call(self, node: ast.Call) -> ast.expr:
        self.generic_visit(node)  # rewrites the children in place
        return self.wrap(node)

    def visit_BinOp(self, node: ast.BinOp) -> ast.expr:
        self.generic_visit(node)
        return self.wrap(node)

    def visit_JoinedStr(self, node: ast.JoinedStr) -> ast.expr:
        self.generic_visit(node)
        return self.wrap(node)

    def visit_FormattedValue(self, node: ast.FormattedValue) -> ast.FormattedValue:
        """The value is guarded; a format spec stays an f-string part (its own values are guarded)."""
        node.value = self.visit(node.value)
        if node.format_spec is not None:
            assert isinstance(node.format_spec, ast.JoinedStr)
            node.format_spec.values = [self.visit(v) for v in node.format_spec.values]
        return node

    def visit_AugAssign(self, node: ast.AugAssign) -> ast.stmt:
        """``x op= v`` -> ``x = in_place(x, v, op)``; ``a[i] op= v`` evaluates ``a`` and ``i`` once, as Python does."""
        value = self.visit(node.value)
        op = type(node.op).__name__
        target = node.target
        if isinstance(target, ast.Name):
            current: ast.expr = ast.Name(target.id, ast.Load())
            store: ast.expr = ast.Name(target.id, ast.Store())
        elif isinstance(target, ast.Subscript):
            held = ast.NamedExpr(ast.Name(_HELD, ast.Store()), self.visit(target.value))
            key = ast.NamedExpr(ast.Name(_KEY, ast.Store()), self.visit(_slices_as_values(target.slice)))
            current = ast.Subscript(held, key, ast.Load())
            store = ast.Subscript(ast.Name(_HELD, ast.Load()), ast.Name(_KEY, ast.Load()), ast.Store())
        else:  # attribute targets: refused by the validator
            self.generic_visit(node)
            return node
        assign = ast.Assign(targets=[store], value=_call(IN_PLACE, current, value, ast.Constant(op)))
        return ast.copy_location(assign, node)


def _slices_as_values(index: ast.expr) -> ast.expr:
    """``a[1:2, 0]``'s index as an expression that can be held: ``slice(1, 2), 0``."""
    if isinstance(index, ast.Slice):
        parts = [p if p is not None else ast.Constant(None) for p in (index.lower, index.upper, index.step)]
        return _call(SLICE, *parts)
    if isinstance(index, ast.Tuple):
        return ast.Tuple([_slices_as_values(e) for e in index.elts], ast.Load())
    return index
