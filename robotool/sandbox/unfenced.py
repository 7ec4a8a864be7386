"""The program of a reply without code blocks: the longest run of lines that parses and acts, prose around it."""

from __future__ import annotations

import ast
import itertools
import keyword
import re
import warnings

from robotool.sandbox.code_shape import calls, has_action, looks_like_code, quiet_parse
from robotool.sandbox.validate import ProgramRejected, parse_program


def unfenced_program(text: str) -> str:
    """The program of a reply without code blocks: the longest run of lines that parses and acts (a word such as
    ``Done`` at its ends left out), when every line left out is prose; raises :class:`ProgramRejected` with the syntax
    error of the whole code when a line that looks like code would be left out (the program would be cut), and when
    the line before the run ends in code glued to prose (``Sure! open_gripper()``: its first line would be cut), and
    when the reply's last line is the program cut off (:func:`_cut_off`)."""
    lines = text.split("\n")
    start, end = _without_words_around(lines, *_longest_parsing_run(text))
    last = next((k for k in range(len(lines) - 1, -1, -1) if lines[k].strip()), None)
    if end > start and last is not None and last >= end and _cut_off(lines[last]) and not looks_like_code(lines[last]):
        raise ProgramRejected(
            last + 1,
            "text",
            f"the reply ends in the middle of its program ({lines[last].strip()[:40]!r}): it looks cut off; give the "
            "whole program",
        )
    before = next((k for k in range(start - 1, -1, -1) if lines[k].strip()), None) if end > start else None
    if before is not None and _ends_with_code(lines[before]):
        raise ProgramRejected(
            before + 1,
            "text",
            f"code follows prose on one line ({lines[before].strip()[:40]!r}); put each line of the program on a line "
            "of its own",
        )
    _refuse_two_programs(lines, start, end)
    code_like = [k for k, line in enumerate(lines) if (k < start or k >= end) and looks_like_code(line)]
    if not code_like:
        return "\n".join(lines[start:end])
    first, last = (
        min([*code_like, *([start] if end > start else [])]),
        max([*code_like, *([end - 1] if end > start else [])]),
    )
    whole = "\n".join(lines[first : last + 1])
    parse_program(whole)  # raises the syntax error that stops the code from parsing as a whole
    return whole


def _without_words_around(lines: list[str], start: int, end: int) -> tuple[int, int]:
    """The run ``lines[start:end]`` without the lines at its ends that only name or display a value, unindented
    (``Done`` after a program: prose that parses), when the rest still parses as a whole."""
    first, last = start, end
    while last > first and _only_a_value(lines[last - 1]):
        last -= 1
    while first < last and _only_a_value(lines[first]):
        first += 1
    if (first, last) == (start, end) or first == last:
        return start, end
    try:
        quiet_parse("\n".join(lines[first:last]))
    except (SyntaxError, ValueError, MemoryError):
        return start, end
    return first, last


def _refuse_two_programs(lines: list[str], start: int, end: int) -> None:
    """Refuse a run that is two programs with a line between them that only names a value, unindented (``...``,
    ``OR``; a string is a comment): each part parses and acts alone. The first few such lines are tried."""
    between = [k for k in range(start + 1, end - 1) if _separates(lines[k])]
    for k in between[:4]:
        try:
            parts = [quiet_parse("\n".join(lines[start:k])), quiet_parse("\n".join(lines[k + 1 : end]))]
        except (SyntaxError, ValueError, MemoryError):
            continue
        if all(has_action(part) for part in parts):
            raise ProgramRejected(
                k + 1,
                "text",
                f"the reply holds two programs, one before and one after {lines[k].strip()[:40]!r}, and does not say "
                "which one is meant; give exactly one program, in one code block",
            )


def _separates(line: str) -> bool:
    """Whether an unindented line only names a value other than a string (``...``, ``OR``)."""
    if not _only_a_value(line) or not line.strip():
        return False
    statement = quiet_parse(line).body[0]
    value = statement.value if isinstance(statement, ast.Expr) else None
    return not (isinstance(value, ast.Constant) and isinstance(value.value, str | bytes))


_CUT_NAME = re.compile(r"[A-Za-z_][\w.]*")


def _cut_off(line: str) -> bool:
    """Whether a reply's last line, after its program, is the program cut off mid-line (a reply cut at its length
    limit) that reads as no code line: a name written as code (``close_gripp``, ``move_to_position``: with ``_`` or
    ``.``), or a keyword alone (``if``). A word of prose (``Done``) is none (found by an adversarial run: the cut line
    was left out as a word, and the program ran without its last call; code cut mid-call is its syntax error)."""
    text = line.strip()
    return keyword.iskeyword(text) or (_CUT_NAME.fullmatch(text) is not None and ("_" in text or "." in text))


def _only_a_value(line: str) -> bool:
    if not line.strip():
        return True
    if line[0].isspace() or line.startswith("#"):
        return False
    try:
        return not has_action(quiet_parse(line))
    except (SyntaxError, ValueError, MemoryError):
        return False


_WORD_START = re.compile(r"(?<=[^\w.])(?=[A-Za-z_])")
_CALL_WRITTEN_AS_CODE = re.compile(r"[A-Za-z_][\w.]*\(")


def _ends_with_code(line: str) -> bool:
    """Whether prose ends in a statement that calls something, glued to it (``Sure! open_gripper()``): the line a
    program's first line would be cut from. A call is written ``f(``, not ``gripper (left)``; the last 12 words are
    tried."""
    starts = [found.start() for found in _WORD_START.finditer(line)][-12:]
    return any(_CALL_WRITTEN_AS_CODE.search(line, k) is not None and calls(line[k:]) for k in starts)


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
                tree = quiet_parse(candidate)
            except SyntaxError as e:
                error_line = start + (e.lineno or 1)
                budget -= offsets[min(error_line, end)] - offsets[start]
                end = min(end - 1, error_line - 1)
                continue
            except (ValueError, MemoryError):
                break
            budget -= len(candidate)
            if has_action(tree):
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
    """False when the line alone is invalid Python however it continues (complete or incomplete is fine); as
    ``codeop.compile_command`` decides, but parsed only, never compiled (compiling nested lambdas is superlinear)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                compile(line, "<line>", "exec", _PARSE_ONLY | _INCOMPLETE)
            except SyntaxError:
                try:
                    compile(line + "\n", "<line>", "exec", _PARSE_ONLY | _INCOMPLETE)
                except SyntaxError as e:
                    if "incomplete input" not in str(e):
                        compile(line, "<line>", "exec", _PARSE_ONLY)
    except (SyntaxError, ValueError, OverflowError, MemoryError):
        return False
    return True


_PARSE_ONLY = ast.PyCF_ONLY_AST
_INCOMPLETE = 0x4000 | 0x200
"""``codeop``'s flags PyCF_ALLOW_INCOMPLETE_INPUT and PyCF_DONT_IMPLY_DEDENT: incomplete input is no error."""
