"""What a generated program may name: builtins, numpy and math functions, methods on values.

One table serves both layers of the sandbox: the validator checks every name and attribute in the
program's AST against it, and the worker builds the program's namespace from it, so a name that
slipped past the validator still would not exist at run time. Everything here is an allowlist;
numpy in particular is far too large (file I/O, ctypes, memory maps) to blocklist safely.
"""

from __future__ import annotations

import math

NUMPY_FUNCTIONS: frozenset[str] = frozenset(
    {
        "array", "asarray", "zeros", "ones", "full", "zeros_like", "ones_like", "full_like", "eye",
        "identity", "arange", "linspace", "stack", "vstack", "hstack", "concatenate", "column_stack",
        "append", "copy", "reshape", "transpose", "squeeze", "expand_dims", "flip", "roll", "tile",
        "repeat", "atleast_1d", "atleast_2d", "meshgrid", "clip", "abs", "absolute", "sign", "sqrt",
        "square", "power", "exp", "log", "log10", "log2", "sin", "cos", "tan", "arcsin", "arccos", "arctan",
        "arctan2", "sinh", "cosh", "tanh", "hypot", "deg2rad", "rad2deg", "degrees", "radians", "floor",
        "ceil", "round", "around", "rint", "trunc", "minimum", "maximum", "min", "max", "amin", "amax",
        "argmin", "argmax", "sum", "prod", "mean", "median", "std", "var", "cumsum", "diff", "dot", "cross",
        "inner", "outer", "matmul", "einsum", "allclose", "isclose", "isfinite", "isnan", "isinf", "all",
        "any", "where", "argsort", "sort", "unique", "interp", "mod", "fmod", "remainder", "floor_divide",
    }
)  # fmt: skip
"""``np.<name>`` functions a program may call. Missing on purpose: every constructor that takes a
buffer, strides, an object dtype or gives uninitialised memory (``ndarray``, ``empty``,
``frombuffer``, ``lib.stride_tricks``...); ``dtype=object`` is refused when the program runs."""

NUMPY_TYPES: frozenset[str] = frozenset({"float64", "int64"})
"""``np.<name>`` scalar types, for conversions and ``dtype=``."""

NUMPY_CONSTANTS: frozenset[str] = frozenset({"pi", "e", "inf", "nan", "newaxis"})

NUMPY_LINALG: frozenset[str] = frozenset(
    {"norm", "inv", "det", "solve", "pinv", "lstsq", "eig", "eigh", "svd", "matrix_rank"}
)
"""``np.linalg.<name>`` functions a program may use."""

MATH_NAMES: frozenset[str] = frozenset(n for n in dir(math) if not n.startswith("_"))
"""Every public name of :mod:`math`: pure functions on numbers and constants."""

MODULES: dict[str, str] = {"np": "numpy", "math": "math"}
"""The only imports: alias in the program -> module (``import numpy as np``, ``import math``)."""

BUILTINS: frozenset[str] = frozenset(
    {
        "abs", "all", "any", "bool", "dict", "divmod", "enumerate", "filter", "float", "int", "isinstance",
        "iter", "len", "list", "map", "max", "min", "next", "pow", "print", "range", "reversed", "round",
        "set", "sorted", "str", "sum", "tuple", "zip"
    }
)  # fmt: skip
"""Builtins a program may call. Missing on purpose: type, object, getattr, setattr, vars, dir,
globals, locals, open, exec, eval, compile, __import__, input, breakpoint, help, memoryview."""

VALUE_METHODS: frozenset[str] = frozenset(
    {
        "append", "extend", "insert", "pop", "remove", "index", "count", "copy", "clear", "reverse", "sort",
        "keys", "values", "items", "get", "update", "setdefault", "add", "discard", "union", "intersection",
        "difference", "join", "split", "strip", "lower", "upper", "startswith", "endswith", "replace",
        "tolist", "item", "reshape", "flatten", "ravel", "transpose", "squeeze", "astype", "sum", "mean",
        "min", "max", "argmin", "argmax", "prod", "std", "cumsum", "dot", "round", "clip", "all", "any",
        "T", "shape", "ndim", "size"
    }
)  # fmt: skip
"""Attributes a program may read on its own values (lists, dicts, strings, numpy arrays).
``astype`` takes only a numeric type (checked by the validator).
Missing on purpose: ``format``/``format_map`` (format fields reach attributes by name), ``tofile``,
``dump``, ``ctypes``, ``base``, ``data``, ``view``, ``strides``, generator and frame attributes."""

NUMERIC_TYPE_NAMES: frozenset[str] = frozenset({"float", "int", "bool", "float64", "int64", "float32", "int32"})
"""What ``.astype(...)`` may convert to: these builtins, ``np.<these>`` or these names as strings."""

LOOP_TYPE_KEYWORDS: frozenset[str] = frozenset({"signature", "sig"})
"""Keywords of numpy's ufuncs that choose the loop's types, object loops included (``sig`` is an alias; array
methods such as ``clip`` pass them on): refused by the validator and by the worker's numpy functions."""

NOT_ALLOWED_BECAUSE: dict[str, str] = {
    "format": "str.format can reach private attributes through its fields; use an f-string",
    "format_map": "str.format_map can reach private attributes through its fields; use an f-string",
    "random": "programs must be deterministic",
    "ndarray": "it lays an array over a raw buffer; use np.array",
    "empty": "it returns uninitialised memory; use np.zeros",
    "frombuffer": "it lays an array over a raw buffer; use np.array",
    "view": "it reinterprets an array's memory; use .astype(float)",
    "strides": "programs do not handle memory layout",
}
"""Why a commonly tried name is refused, for the rejection message."""
