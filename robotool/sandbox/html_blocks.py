"""HTML code blocks in a model's reply (``<pre><code class="language-python">``), written as Markdown fences."""

from __future__ import annotations

import html
import re

from robotool.sandbox.fences import fence_pairs

_HTML_OPEN = re.compile(r"^[ \t]*<pre\b[^>]*>[ \t]*<code\b([^>]*)>", re.IGNORECASE | re.MULTILINE)
_HTML_CLOSE = re.compile(r"</code>\s*</pre>", re.IGNORECASE)
_HTML_LANGUAGE = re.compile(r"\blang(?:uage)?-([\w.+-]+)")


def html_code_blocks(text: str) -> str:
    """``text`` with each HTML code block (``<pre><code class="language-python">...</code></pre>``, its ``<pre>`` at the
    start of a line, as in HTML) outside Markdown code blocks written as a fenced one, its first line included; a tag
    in a fenced block, or in a comment or string of code (``# shown in <pre><code>``), is code."""
    parts, end = [], 0
    for opening, closing in fence_pairs(text):
        parts += [_converted(text[end : opening.start()]), text[opening.start() : closing.end() if closing else None]]
        end = closing.end() if closing else len(text)
    return "".join([*parts, _converted(text[end:])])


def _converted(text: str) -> str:
    parts, end = [], 0
    while (opening := _HTML_OPEN.search(text, end)) is not None:
        closing = _HTML_CLOSE.search(text, opening.end())
        if closing is None:
            break
        language = _HTML_LANGUAGE.search(opening.group(1))
        code = html.unescape(text[opening.end() : closing.start()]).strip("\n")
        parts += [text[end : opening.start()], f"\n```{language.group(1) if language else ''}\n{code}\n```\n"]
        end = closing.end()
    return "".join([*parts, text[end:]])
