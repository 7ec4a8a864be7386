"""A program that says it leaves part of itself out (``# ... rest of the code unchanged ...``, ``...``): a fragment."""

from __future__ import annotations

import ast
import contextlib
import io
import re
import tokenize

from robotool.sandbox.validate import ProgramRejected

_ELIDED = re.compile(
    r"\b(?:unchanged|omitted|elided|for brevity|not shown|as before|same as (?:before|above|earlier|previously)"
    r"|remains? the same|stays? the same|goes here|here as before)\b",
    re.IGNORECASE,
)
"""Words that say code was left out or kept as it was."""
_LEFT_OUT = re.compile(r"\b(?:rest|remainder|remaining|code|program|script|lines|logic|steps|else)\b", re.IGNORECASE)
"""What such words are said of: the rest, the code, the steps (``# (rest unchanged)``)."""
_ELLIPSIS_PHRASE = re.compile(
    r"^(?:\.\.\.|\u2026)\W*(?:\(?\s*(?:rest|remainder|remaining|same|existing|previous|original|other|more|code|etc"
    r"|unchanged|omitted|and so on)\b.*)?$",
    re.IGNORECASE,
)
"""A comment that opens with an ellipsis and names nothing done (``# ...``, ``# ... (same as before)``)."""
_REST_OF_CODE = re.compile(
    r"^\W*(?:the )?(?:rest|remainder) of (?:the |your |my )?(?:code|program|script|function)"
    r"(?:\W+(?:goes )?here)?\W*$",
    re.IGNORECASE,
)
"""A comment that only names the code left out (``# rest of the code``, ``# ... rest of code here``)."""
_ONLY_ELIDED = re.compile(
    r"^\W*(?:same as (?:above|before|earlier|previously)|etc|and so on|unchanged|as before)\W*$", re.IGNORECASE
)
"""A comment that says only that something is as it was (``# same as above``, ``# etc.``, ``# [unchanged]``)."""
_KEPT_ELSEWHERE = re.compile(
    r"\b(?:as you had (?:it|them)|(?:as )?in your (?:program|code|version|script|draft)|from your "
    r"(?:program|code|version|script|draft))\b",
    re.IGNORECASE,
)
"""Words that point at code kept in another program (``# rest as you had it``, ``# the other steps as in your
program``)."""
_TODO = re.compile(r"\b(?:TODO|FIXME|XXX)\b|\byour code here\b|\bimplement\b|\bfill in\b", re.IGNORECASE)


def refuse_placeholder(code: str, tree: ast.Module) -> None:
    """Refuse a program that says it leaves part of itself out: a comment saying code was omitted or unchanged
    (``# ... rest of the code unchanged ...``, ``# (rest unchanged)``, ``# ... (same as before)``), ``...`` as a
    statement or a value, or ``pass`` under a TODO comment. A comment about the task (``# the rest of the walk is
    done``) is none.
    """
    found = _placeholder(code, tree)
    if found is not None:
        line, text = found
        raise ProgramRejected(
            line,
            "placeholder",
            f"the program holds a placeholder for code left out ({text[:60]!r}); give the whole program, with no "
            "part left out, in one code block",
        )


def _placeholder(code: str, tree: ast.Module) -> tuple[int, str] | None:
    """The line number and text of the first placeholder in ``code`` (parsed as ``tree``), or None."""
    lines = code.split("\n")
    found_comments = comments(code)
    found = [
        (line, f"# {text}")
        for line, text in found_comments.items()
        if _says_left_out(text, alone=lines[line - 1].lstrip().startswith("#"))
    ]
    for node in ast.walk(tree):
        if isinstance(node, ast.Expr | ast.Assign | ast.AnnAssign) and _elided(node.value):  # ``...``, ``p = ...``
            found.append((node.lineno, lines[node.lineno - 1].strip()))
        elif isinstance(node, ast.Pass):
            note = found_comments.get(node.lineno) or found_comments.get(_line_above(lines, node.lineno), "")
            if _TODO.search(note):
                found.append((node.lineno, f"# {note} / pass"))
    return min(found) if found else None


def _elided(value: ast.expr | None) -> bool:
    """Whether a statement's value is ``...`` (a value left out; found by an adversarial run: ``p = ...  # as before``
    ran and failed at run time)."""
    return isinstance(value, ast.Constant) and value.value is Ellipsis


def _says_left_out(comment: str, alone: bool) -> bool:
    """Whether a comment's text says code was left out or kept as it was, rather than what the program does; a
    comment on a line of its own (``alone``) may also say so in fewer words (``# same as above``, ``# etc.``, ``# rest
    as you had it``: found by an adversarial run), which beside code say what that code does (``z = 0.1  # same as
    above``)."""
    return bool(
        _ELLIPSIS_PHRASE.match(comment)
        or _REST_OF_CODE.match(comment)
        or (_ELIDED.search(comment) and _LEFT_OUT.search(comment))
        or (alone and (_ONLY_ELIDED.match(comment) or _KEPT_ELSEWHERE.search(comment)))
    )


def comments(code: str) -> dict[int, str]:
    """The text of each comment in ``code`` (which parses), by line number; string literals hold none."""
    found: dict[int, str] = {}
    with contextlib.suppress(tokenize.TokenError, SyntaxError):  # what ast accepts and tokenize does not: no comments
        for token in tokenize.generate_tokens(io.StringIO(code).readline):
            if token.type == tokenize.COMMENT:
                found[token.start[0]] = token.string.lstrip("#").strip()
    return found


def _line_above(lines: list[str], lineno: int) -> int:
    """The number of the last non-blank line before line ``lineno`` (0 when none)."""
    k = lineno - 1
    while k > 0 and not lines[k - 1].strip():
        k -= 1
    return k
