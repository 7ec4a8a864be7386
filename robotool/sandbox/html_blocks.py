"""HTML code blocks in a model's reply (``<pre><code class="language-python">``), written as Markdown fences."""

from __future__ import annotations

import html
import re

_HTML_OPEN = re.compile(r"<pre\b[^>]*>[ \t]*<code\b([^>]*)>", re.IGNORECASE)
_HTML_CLOSE = re.compile(r"</code>\s*</pre>", re.IGNORECASE)
_HTML_LANGUAGE = re.compile(r"\blang(?:uage)?-([\w.+-]+)")


def html_code_blocks(text: str) -> str:
    """``text`` with each HTML code block (``<pre><code class="language-python">...</code></pre>``) written as a fenced
    one, its first line included."""
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
