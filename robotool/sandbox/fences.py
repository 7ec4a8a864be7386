"""Markdown code fences in a model's reply, paired the way CommonMark pairs them."""

from __future__ import annotations

import re

FENCE = re.compile(r"^[ \t]*(```+(?=[^`\n]*$)|~~~+)[ \t]*([\w.+-]*)([^\n]*)$", re.MULTILINE)  # fence, tag, the rest
"""A fence line; a backtick fence's info string holds no backtick (```` ```open_gripper``` drops it ```` is prose)."""


def fence_pairs(text: str) -> list[tuple[re.Match[str], re.Match[str] | None]]:
    """Each code block's opening fence and its closing one (None: the block runs to the end), as CommonMark pairs them:
    a fence closes a block when it is of the same character, at least as long, has no info string and is indented at
    most three columns more than the opening (a fence in an indented docstring is code)."""
    fences = list(FENCE.finditer(text))
    pairs: list[tuple[re.Match[str], re.Match[str] | None]] = []
    i = 0
    while i < len(fences):
        opening, j = fences[i], i + 1
        while j < len(fences) and not _closes(opening, fences[j]):
            j += 1
        pairs.append((opening, fences[j] if j < len(fences) else None))
        i = j + 1
    return pairs


def _closes(opening: re.Match[str], fence: re.Match[str]) -> bool:
    mark, close = opening.group(1), fence.group(1)
    indented = fence_indent(fence) <= fence_indent(opening) + 3
    return close[0] == mark[0] and len(close) >= len(mark) and not fence.group(2) and indented


def fence_indent(fence: re.Match[str]) -> int:
    """The columns a fence line is indented by (a tab is four)."""
    line = fence.group(0)
    return len(line[: len(line) - len(line.lstrip(" \t"))].expandtabs(4))


def outside_blocks(text: str) -> str:
    """``text`` without its fenced blocks (their fences included)."""
    parts, end = [], 0
    for opening, closing in fence_pairs(text):
        parts.append(text[end : opening.start()])
        end = closing.end() if closing else len(text)
    return "\n".join([*parts, text[end:]])
