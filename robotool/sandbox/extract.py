"""Turn a language model's answer into program text: fences, prose, line endings, tabs, imports."""

from __future__ import annotations

import ast
import re

from robotool.sandbox.validate import MAX_PROGRAM_CHARS, ProgramRejected, parse_program

_FENCE = re.compile(r"^[ \t]*(```+|~~~+)[ \t]*([\w+-]*)[^\n]*$", re.MULTILINE)
_PYTHON_TAGS = frozenset({"python", "python3", "py", ""})
_IMPORTS = {"np": "import numpy as np", "math": "import math"}


def extract_program(text: str) -> str:
    """The Python program in an LM answer, ready for :func:`validate`.

    Takes the Python (or untagged) Markdown code blocks, joined in order, when there are any (an
    unclosed last block runs to the end); otherwise the longest run of lines that parses as Python,
    dropping prose before and after. Normalizes Windows and old Mac line endings, a BOM, non-breaking
    spaces and tab indentation (a tab is four spaces), and adds ``import numpy as np`` /
    ``import math`` at the top when the program uses ``np.`` / ``math.`` without importing them.
    Raises :class:`ProgramRejected` when no program is found.
    """
    if len(text) > MAX_PROGRAM_CHARS:
        raise ProgramRejected(None, "text", f"answer is longer than {MAX_PROGRAM_CHARS} characters")
    text = text.replace("\r\n", "\n").replace("\r", "\n").replace("\ufeff", "").replace("\u00a0", " ")
    text = "\n".join(_expand_indent_tabs(line) for line in text.split("\n"))
    blocks = _fenced_blocks(text)
    code = ("\n\n".join(blocks) if blocks else _longest_parsing_run(text)).strip("\n")
    if not code.strip():
        raise ProgramRejected(None, "text", "no Python program found in the answer")
    tree = parse_program(code)
    if not _has_action(tree):
        raise ProgramRejected(None, "text", "no Python program found in the answer (only prose or names)")
    missing = [stmt for alias, stmt in _IMPORTS.items() if _uses(tree, alias) and not _imports(tree, alias)]
    return "\n".join([*missing, code]) + "\n"


def _fenced_blocks(text: str) -> list[str]:
    """Contents of the Python or untagged fenced blocks, in order."""
    blocks: list[str] = []
    fences = list(_FENCE.finditer(text))
    i = 0
    while i < len(fences):
        opening = fences[i]
        closing = next((f for f in fences[i + 1 :] if f.group(1)[0] == opening.group(1)[0] and not f.group(2)), None)
        end = closing.start() if closing else len(text)
        if opening.group(2).lower() in _PYTHON_TAGS:
            blocks.append(text[opening.end() + 1 : end].strip("\n"))
        if closing is None:
            break
        i = fences.index(closing) + 1
    return blocks


def _longest_parsing_run(text: str) -> str:
    """The longest run of whole lines that parses, preferring the earliest; "" if none does.

    A syntax error at line k of a candidate means no run starting there can extend past line k-1,
    so each start costs a few parses, not one per end line.
    """
    lines = text.split("\n")
    best = (0, 0)
    for start in range(len(lines)):
        end = len(lines)
        while end - start > best[1] - best[0]:
            try:
                tree = ast.parse("\n".join(lines[start:end]))
            except SyntaxError as e:
                end = min(end - 1, start + (e.lineno or 1) - 1)
                continue
            except (ValueError, RecursionError, MemoryError):
                break
            if _has_action(tree):
                best = (start, end)
            break
    return "\n".join(lines[best[0] : best[1]])


def _has_action(tree: ast.Module) -> bool:
    """True when some statement does more than name a value (prose like ``Done`` parses as a name)."""
    return not all(_names_a_value(s) for s in tree.body)


def _names_a_value(statement: ast.stmt) -> bool:
    return isinstance(statement, ast.Expr) and isinstance(statement.value, ast.Name | ast.Constant)


def _expand_indent_tabs(line: str) -> str:
    stripped = line.lstrip(" \t")
    return line[: len(line) - len(stripped)].replace("\t", "    ") + stripped


def _uses(tree: ast.Module, alias: str) -> bool:
    return any(isinstance(n, ast.Name) and n.id == alias for n in ast.walk(tree))


def _imports(tree: ast.Module, alias: str) -> bool:
    imports = (n for n in ast.walk(tree) if isinstance(n, ast.Import))
    return any((a.asname or a.name) == alias for n in imports for a in n.names)
