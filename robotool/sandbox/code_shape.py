"""What reads as Python in a model's reply: a line of code rather than prose, a program that acts."""

from __future__ import annotations

import ast
import re
import warnings

_CODE_LINE = re.compile(
    r"""^\s*(?:
        [A-Za-z_][\w.]*(?:\s*,\s*[A-Za-z_]\w*)*\s*(?:\(|\[|[-+*/%]?=(?!=))   # a call, subscript or assignment
      | (?:for|while|if|elif|else|def|class|try|except|finally|with)\b.*:\s*(?:\#.*)?$  # a compound statement
      | (?:import|from)\s+[\w.]+(?:\s+import\b.*)?\s*$                       # an import
      | (?:print|exec)\s+["'\w(]                                             # a Python 2 statement
      | (?:return|pass|break|continue|raise|assert|del|global|nonlocal)\b
      | @[A-Za-z_]                                                             # a decorator
      | \(                                                                     # a parenthesised expression
    )""",
    re.VERBOSE,
)


_CLAUSE = re.compile(r"(?:else|elif|except|finally)\b")


def looks_like_code(line: str) -> bool:
    """Whether a line reads as Python, not prose: a :data:`_CODE_LINE` shape, or a line that parses, alone, as a
    compound statement's head or as a clause after one (``if x: f()``, ``else: g()``, ``[f(w) for w in ws]``,
    ``not f()``, ``lift: float = 0.2``) and does more than name a value."""
    text = line.strip()
    if _CODE_LINE.match(line):
        return True
    if not text or len(text) > 2000 or text.startswith("#"):
        return False
    sources = [text, *([f"{text}\n    pass", f"{text}\n    case _: pass"] if text.endswith(":") else [])]
    if _CLAUSE.match(text):
        sources = [f"{before}: pass\n{source}" for before in ("if 1", "try") for source in sources]
    for source in sources:
        try:
            return has_action(quiet_parse(source))
        except (SyntaxError, ValueError, MemoryError):
            continue
    return False


def calling_line(line: str) -> bool:
    """Whether a line reads as code and parses, alone, as a statement that calls something: a step of a program
    written where none was expected (outside the code blocks, after the answer)."""
    return looks_like_code(line) and calls(line.strip())


def quiet_parse(code: str) -> ast.Module:
    """``ast.parse`` without the warnings that text which is not the program raises."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # SyntaxWarnings about text that is not the program
        return ast.parse(code)


def has_action(tree: ast.Module) -> bool:
    """True when some statement does more than name a value (prose like ``Done`` parses as a name)."""
    return not all(_names_a_value(s) for s in tree.body)


def _names_a_value(statement: ast.stmt) -> bool:
    """An expression statement that only names or displays a value, or negates one (``- close_gripper()``: a diff's
    or a bullet list's line, which parses as Python but is no step of a program)."""
    if not isinstance(statement, ast.Expr):
        return False
    value = statement.value
    return _displays_a_value(value) or (isinstance(value, ast.UnaryOp) and isinstance(value.op, ast.UAdd | ast.USub))


def _displays_a_value(node: ast.expr) -> bool:
    """A name, a constant, or a literal display of them (``[0.35, 0.0, -0.1]``, ``{"code": "..."}``): what an
    output listing or a value given in place of a program parses as."""
    while isinstance(node, ast.UnaryOp):
        node = node.operand
    if isinstance(node, ast.Name | ast.Constant):
        return True
    if isinstance(node, ast.List | ast.Tuple | ast.Set):
        return all(_displays_a_value(e) for e in node.elts)
    if isinstance(node, ast.Dict):
        return all(_displays_a_value(e) for e in [*node.values, *(k for k in node.keys if k is not None)])
    return False


def calls(code: str) -> bool:
    """Whether ``code`` parses as a program that acts and calls something."""
    try:
        tree = quiet_parse(code)
    except (SyntaxError, ValueError, MemoryError):
        return False
    return has_action(tree) and any(isinstance(node, ast.Call) for node in ast.walk(tree))
