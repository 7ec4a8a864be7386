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
    """A program taken from an LM answer, how many non-blank lines of the answer were left out, and which
    of several code blocks was chosen (None when there was one or none)."""

    code: str
    dropped_lines: int
    chosen: str | None = None

    @property
    def note(self) -> str | None:
        """A sentence for the user when text was left out (reasoning, prose, other blocks)."""
        parts = [self.chosen] if self.chosen else []
        if self.dropped_lines:
            parts.append(f"{self.dropped_lines} non-blank line(s) of the reply outside the program were left out")
        return "; ".join(parts) or None


def extract_program(text: str) -> str:
    """The Python program in an LM answer, ready for :func:`validate` (see :func:`extract`)."""
    return extract(text).code


def extract(text: str) -> Extraction:
    """The Python program in an LM answer, with a count of the answer's lines left out of it.

    Extraction chooses a block, never cuts one. Reasoning (``<think>...</think>``) is never code. Of
    several Python (or untagged) Markdown code blocks, the one a line just before it marks as final
    ("Final program:") is taken, else the last one that is more than names (an unclosed last block runs to
    the end); blocks are never joined, and :attr:`Extraction.chosen` says which was taken. Without a block,
    the program is the reply with prose before and after it left out; when a line that looks like code
    would be left out too, the program does not parse as a whole and its syntax error is raised.
    Normalizes Windows and old Mac line endings, a BOM, non-breaking spaces and tab indentation (a tab is
    four spaces), and adds ``import numpy as np`` / ``import math`` at the top when the program uses
    ``np.`` / ``math.`` without importing them. Raises :class:`ProgramRejected` when no program is found or
    it does not parse.
    """
    if len(text) > MAX_PROGRAM_CHARS:
        raise ProgramRejected(None, "text", f"answer is longer than {MAX_PROGRAM_CHARS} characters")
    check_parse_cost(text, "answer")
    text = text.replace("\r\n", "\n").replace("\r", "\n").replace("\ufeff", "").replace("\u00a0", " ")
    text = "\n".join(_expand_indent_tabs(line) for line in text.split("\n"))
    text = without_reasoning(text)
    blocks = _fenced_blocks(text)
    chosen = None
    if blocks:
        index, why = _choose_block(blocks)
        code = blocks[index].code.strip("\n")
        if len(blocks) > 1:
            chosen = f"the reply held {len(blocks)} code blocks; block {index + 1} ({why}) was used, not joined"
        fence_lines = blocks[index].fence_lines
    else:
        code, fence_lines = _unfenced_program(text).strip("\n"), 0
    if not code.strip():
        raise ProgramRejected(None, "text", "no Python program found in the answer")
    tree = parse_program(code)
    if not _has_action(tree):
        raise ProgramRejected(None, "text", "no Python program found in the answer (only prose or names)")
    missing = [stmt for alias, stmt in _IMPORTS.items() if _uses(tree, alias) and not _imports(tree, alias)]
    dropped = _non_blank(text) - _non_blank(code) - fence_lines
    return Extraction(code="\n".join([*missing, code]) + "\n", dropped_lines=max(dropped, 0), chosen=chosen)


_REASONING = re.compile(r"<(think|thinking|reasoning)>.*?(?:</\1>|\Z)", re.DOTALL | re.IGNORECASE)
_REASONING_END = re.compile(r"^.*?</(?:think|thinking|reasoning)>", re.DOTALL | re.IGNORECASE)


def without_reasoning(text: str) -> str:
    """``text`` without the model's reasoning: ``<think>...</think>`` spans (an unclosed one runs to the end),
    and everything before a closing tag whose opening tag the server left out."""
    text = _REASONING.sub("", text)
    return _REASONING_END.sub("", text, count=1)


def _non_blank(text: str) -> int:
    """How many lines of ``text`` hold something other than white space."""
    return sum(1 for line in text.split("\n") if line.strip())


@dataclass(frozen=True)
class _Block:
    code: str
    fence_lines: int
    label: str
    """The last non-blank line of text before the block's opening fence."""


def _fenced_blocks(text: str) -> list[_Block]:
    """The Python or untagged fenced blocks, in order (one pass over the fences)."""
    blocks: list[_Block] = []
    fences = list(_FENCE.finditer(text))
    i = 0
    previous_end = 0
    while i < len(fences):
        opening = fences[i]
        j = i + 1
        while j < len(fences) and not (fences[j].group(1)[0] == opening.group(1)[0] and not fences[j].group(2)):
            j += 1
        end = fences[j].start() if j < len(fences) else len(text)
        if opening.group(2).lower() in _PYTHON_TAGS:
            before = [line for line in text[previous_end : opening.start()].split("\n") if line.strip()]
            label = before[-1].strip() if before else ""
            blocks.append(_Block(text[opening.end() + 1 : end].strip("\n"), 1 + (j < len(fences)), label))
        previous_end = fences[j].end() if j < len(fences) else len(text)
        i = j + 1
    return blocks


_FINAL = re.compile(r"\b(final|corrected|fixed|revised|complete)\b", re.IGNORECASE)


def _choose_block(blocks: list[_Block]) -> tuple[int, str]:
    """The index of the block to run and why: the last one marked final, else the last that is more than
    names (an output listing is not a program), else the last."""
    marked = [k for k, block in enumerate(blocks) if _FINAL.search(block.label)]
    if marked:
        return marked[-1], f"marked {blocks[marked[-1]].label[:60]!r}"
    for k in range(len(blocks) - 1, -1, -1):
        try:
            tree = _quiet_parse(blocks[k].code)
        except (SyntaxError, ValueError, RecursionError, MemoryError):
            return k, "the last"
        if _has_action(tree):
            return k, "the last" if k == len(blocks) - 1 else "the last that is a program"
    return len(blocks) - 1, "the last"


_CODE_LINE = re.compile(
    r"""^\s*(?:
        [A-Za-z_][\w.]*(?:\s*,\s*[A-Za-z_]\w*)*\s*(?:\(|\[|[-+*/%]?=(?!=))   # a call, subscript or assignment
      | (?:for|while|if|elif|else|def|class|try|except|finally|with)\b.*:\s*(?:\#.*)?$  # a compound statement
      | (?:import|from)\s+[\w.]+(?:\s+import\b.*)?\s*$                       # an import
      | (?:print|exec)\s+["'\w(]                                             # a Python 2 statement
      | (?:return|pass|break|continue|raise)\b
    )""",
    re.VERBOSE,
)


def _unfenced_program(text: str) -> str:
    """The program of a reply without code blocks: the longest run of lines that parses and acts, when every
    line left out is prose; raises :class:`ProgramRejected` with the syntax error of the whole code when a line
    that looks like code would be left out (the program would be cut)."""
    lines = text.split("\n")
    start, end = _longest_parsing_run(text)
    code_like = [k for k, line in enumerate(lines) if (k < start or k >= end) and _CODE_LINE.match(line)]
    if not code_like:
        return "\n".join(lines[start:end])
    first, last = (
        min([*code_like, *([start] if end > start else [])]),
        max([*code_like, *([end - 1] if end > start else [])]),
    )
    whole = "\n".join(lines[first : last + 1])
    parse_program(whole)  # raises the syntax error that stops the code from parsing as a whole
    return whole


def _longest_parsing_run(text: str) -> tuple[int, int]:
    """The longest run of whole lines that parses and acts, preferring the earliest, as (first line, end line);
    an empty span if none is found.

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
    return best


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
