"""A program that holds two programs joined in one block: options the reply offers (``# Option 1:`` ... ``# Option
2:``) or a draft and its correction (``# Corrected version``); which one is meant is not clear (found by an adversarial
run: both ran, one after the other)."""

from __future__ import annotations

import re

from robotool.sandbox.placeholder import comments
from robotool.sandbox.validate import ProgramRejected

_OPTION = re.compile(r"^\W*(?:option|alternative|approach|variant|solution)\s*#?\s*(\d+|[a-c])\b", re.IGNORECASE)
"""A comment that opens one of several options (``# Option 2: grasp from above``)."""
_CORRECTION = re.compile(
    r"\b(?:corrected|fixed|revised|updated|improved|final)\s+(?:version|code|program|script)\b|^\W*(?:wait|oops)\b",
    re.IGNORECASE,
)
"""A comment that opens a correction of what came before it (``# Corrected version``, ``# Wait, that never ...``)."""


def refuse_joined(code: str) -> None:
    """Refuse a program whose own comments, each on a line of its own, open two different options, or open a later
    option or a correction after code (:class:`ProgramRejected`, asked again)."""
    lines = code.split("\n")
    alone = {line: text for line, text in comments(code).items() if lines[line - 1].lstrip().startswith("#")}
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
                f"the program holds code and then another version of it ({('# ' + text)[:50]!r}) joined in one "
                "block; give the one program meant, in one code block",
            )


def _statement(line: str) -> bool:
    """Whether a line holds code (not blank, not only a comment)."""
    stripped = line.strip()
    return bool(stripped) and not stripped.startswith("#")
