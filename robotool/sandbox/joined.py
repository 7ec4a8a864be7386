"""A program that holds two programs joined in one block: options the reply offers (``# Option 1:`` ... ``# Option
2:``) or a draft and its correction (``# Corrected version``); which one is meant is not clear (found by an adversarial
run: both ran, one after the other)."""

from __future__ import annotations

import ast
import re

from robotool.sandbox.placeholder import comments
from robotool.sandbox.validate import ProgramRejected

_OPTION = re.compile(
    r"^\W*(?:option|alternative|approach|variant|solution|version|method)\s*#?\s*(\d+|[a-c])\s*(?:[:).,—–-]|$)",
    re.IGNORECASE,
)
"""A comment that opens one of several options (``# Option 2: grasp from above``; not ``# Approach 10 cm above``)."""
_CORRECTION = re.compile(
    r"\b(?:corrected|fixed|revised|updated|improved|final)\s+(?:version|code|program|script)\b(?!\s+of\b)|"
    r"^\W*(?:wait|oops)(?:\s*[,.!:;—–]|\s+-)|^\W*(?:alternatively|or,? (?:instead|alternatively))\b|"
    r"^\W*(?:another|or) (?:option|approach|way|version)\s*[:(,—–-]",
    re.IGNORECASE,
)
"""A comment that opens a correction of what came before it, or another way to do it (``# Corrected version``,
``# Wait, that never ...``, ``# Alternatively, from above:``; not ``# Wait for the grip to settle``)."""


def refuse_joined(code: str, tree: ast.Module) -> None:
    """Refuse a program whose own top-level comments, each on a line of its own (or strings standing as statements,
    which read as comments: found by an adversarial run), open two different options, or open a later option or a
    correction after code (:class:`ProgramRejected`, asked again); comments inside a block (``if``/``else`` branches)
    name the cases of one program."""
    lines = code.split("\n")
    alone = {line: text for line, text in comments(code).items() if lines[line - 1].startswith("#")}
    alone.update(_strings_alone(tree))
    options = {match.group(1).lower(): line for line, text in alone.items() if (match := _OPTION.match(text))}
    if len(options) > 1:
        raise ProgramRejected(
            max(options.values()),
            "blocks",
            f"the program holds {len(options)} options ({', '.join(sorted(options))}) joined in one block; give the "
            "one program meant, in one code block",
        )
    for line, text in sorted(alone.items()):
        later = (match := _OPTION.match(text)) is not None and match.group(1).lower() not in ("1", "a")
        if (later or _CORRECTION.search(text)) and any(_statement(lines[k]) for k in range(line - 1)):
            raise ProgramRejected(
                line,
                "blocks",
                f"the program holds code and then another version of it ({lines[line - 1].strip()[:50]!r}) joined in "
                "one block; give the one program meant, in one code block",
            )


def _strings_alone(tree: ast.Module) -> dict[int, str]:
    """The text of each string that stands as a statement between the program's top-level statements
    (``\"\"\"Then lift it.\"\"\"``; not its docstring), by its first line."""
    return {
        node.lineno: node.value.value.strip()
        for node in tree.body[1:]
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)
    }


def _statement(line: str) -> bool:
    """Whether a line holds code (not blank, not only a comment)."""
    stripped = line.strip()
    return bool(stripped) and not stripped.startswith("#")
