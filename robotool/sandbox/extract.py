"""Turn a language model's answer into program text: fences, prose, line endings, tabs, imports."""

from __future__ import annotations

import ast
import codeop
import itertools
import re
import warnings
from dataclasses import dataclass

from robotool.sandbox.validate import MAX_PROGRAM_CHARS, ProgramRejected, check_parse_cost, parse_program

_FENCE = re.compile(r"^[ \t]*(```+|~~~+)[ \t]*([\w+-]*)[^\n]*$", re.MULTILINE)
_PYTHON_TAGS = frozenset({"python", "python3", "py", ""})
_IMPORTS = {"np": "import numpy as np", "math": "import math"}


@dataclass(frozen=True)
class Extraction:
    """A program taken from an LM answer, and how many non-blank lines of the answer were left out."""

    code: str
    dropped_lines: int

    @property
    def note(self) -> str | None:
        """A sentence for the user when text was left out (prose, other blocks, lines that do not parse)."""
        if not self.dropped_lines:
            return None
        return f"{self.dropped_lines} non-blank line(s) of the reply outside the program were left out"


def extract_program(text: str) -> str:
    """The Python program in an LM answer, ready for :func:`validate` (see :func:`extract`)."""
    return extract(text).code


def extract(text: str) -> Extraction:
    """The Python program in an LM answer, with a count of the answer's lines left out of it.

    Takes the Python (or untagged) Markdown code blocks, joined in order, when there are any (an
    unclosed last block runs to the end); otherwise the longest run of lines that parses as Python,
    dropping prose before and after. Normalizes Windows and old Mac line endings, a BOM, non-breaking
    spaces and tab indentation (a tab is four spaces), and adds ``import numpy as np`` /
    ``import math`` at the top when the program uses ``np.`` / ``math.`` without importing them.
    Raises :class:`ProgramRejected` when no program is found.
    """
    if len(text) > MAX_PROGRAM_CHARS:
        raise ProgramRejected(None, "text", f"answer is longer than {MAX_PROGRAM_CHARS} characters")
    check_parse_cost(text, "answer")
    text = text.replace("\r\n", "\n").replace("\r", "\n").replace("\ufeff", "").replace("\u00a0", " ")
    text = "\n".join(_expand_indent_tabs(line) for line in text.split("\n"))
    blocks, fence_lines = _fenced_blocks(text)
    code = ("\n\n".join(blocks) if blocks else _longest_parsing_run(text)).strip("\n")
    if not code.strip():
        raise ProgramRejected(None, "text", "no Python program found in the answer")
    tree = parse_program(code)
    if not _has_action(tree):
        raise ProgramRejected(None, "text", "no Python program found in the answer (only prose or names)")
    missing = [stmt for alias, stmt in _IMPORTS.items() if _uses(tree, alias) and not _imports(tree, alias)]
    dropped = _non_blank(text) - _non_blank(code) - fence_lines
    return Extraction(code="\n".join([*missing, code]) + "\n", dropped_lines=max(dropped, 0))


def _non_blank(text: str) -> int:
    """How many lines of ``text`` hold something other than white space."""
    return sum(1 for line in text.split("\n") if line.strip())


def _fenced_blocks(text: str) -> tuple[list[str], int]:
    """Contents of the Python or untagged fenced blocks, in order, and how many fence lines enclose them
    (one pass over the fences)."""
    blocks: list[str] = []
    fence_lines = 0
    fences = list(_FENCE.finditer(text))
    i = 0
    while i < len(fences):
        opening = fences[i]
        j = i + 1
        while j < len(fences) and not (fences[j].group(1)[0] == opening.group(1)[0] and not fences[j].group(2)):
            j += 1
        end = fences[j].start() if j < len(fences) else len(text)
        if opening.group(2).lower() in _PYTHON_TAGS:
            blocks.append(text[opening.end() + 1 : end].strip("\n"))
            fence_lines += 1 + (j < len(fences))
        i = j + 1
    return blocks, fence_lines


def _longest_parsing_run(text: str) -> str:
    """The longest run of whole lines that parses and acts, preferring the earliest; "" if none is found.

    Each line may start a run; one that cannot start a program on its own (prose such as "Here is
    the code:") is ruled out by compiling that line alone. From a start, a syntax error at line k
    of a candidate means no run from there can extend past line k-1, so each start costs a few
    parses. A parse that succeeds without any action, made of one-line statements only, rules out
    every later start inside it. The whole search is bounded by :data:`SEARCH_EFFORT` parsed
    characters per character of text; past that, the best run found so far is kept.
    """
    lines = text.split("\n")
    offsets = list(itertools.accumulate((len(line) + 1 for line in lines), initial=0))
    budget = SEARCH_EFFORT * len(text) + _PARSE_OVERHEAD_CHARS * 64
    best = (0, 0)
    start = 0
    while start < len(lines) and budget > 0:
        next_start = start + 1
        end = len(lines)
        if not lines[start].strip() or not _can_start_program(lines[start]):
            start = next_start
            continue
        while end - start > best[1] - best[0] and budget > 0:
            candidate = text[offsets[start] : offsets[end] - 1]
            budget -= len(candidate) // 16 + _PARSE_OVERHEAD_CHARS  # slicing and encoding the candidate
            try:
                tree = _quiet_parse(candidate)
            except SyntaxError as e:
                error_line = start + (e.lineno or 1)
                budget -= offsets[min(error_line, end)] - offsets[start]
                end = min(end - 1, error_line - 1)
                continue
            except (ValueError, RecursionError, MemoryError):
                break
            budget -= len(candidate)
            if _has_action(tree):
                best = (start, end)
            elif all(statement.end_lineno == statement.lineno for statement in tree.body):
                next_start = end
            break
        start = next_start
    return text[offsets[best[0]] : offsets[best[1]] - 1] if best[1] > best[0] else ""


SEARCH_EFFORT = 4
"""Characters the unfenced-program search may parse per character of the answer."""

_PARSE_OVERHEAD_CHARS = 256


def _can_start_program(line: str) -> bool:
    """False when the line alone is invalid Python however it continues (complete or incomplete is fine)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            codeop.compile_command(line, symbol="exec")
    except (SyntaxError, ValueError, OverflowError, MemoryError, RecursionError):
        return False
    return True


def _quiet_parse(code: str) -> ast.Module:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # SyntaxWarnings about text that is not the program
        return ast.parse(code)


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
