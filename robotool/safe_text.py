"""Text from programs, language models and task files, made safe for each place the host writes it.

Generated programs print what they like, raise errors with messages they choose and name objects as
they like; a language model writes plans, diagnoses and code. A raw escape byte in that text can
clear the screen, retitle the window, write the clipboard (OSC 52) or paint a fake success line; a
``$`` makes matplotlib parse mathtext (and fail, or draw what the program wants); a ``]`` or a trailing
backslash ends a Markdown link early. So every kind of sink has one escaper here, registered in
:data:`SINKS`, and every write of such text goes through its sink's escaper:

- every control character, the Unicode controls that reorder or hide text, the invisible characters
  (soft hyphen, invisible operators, Unicode tag characters), lone surrogates and the line and paragraph separators are
  shown as visible escapes (``\\x1b``, ``\\u202e``);
- what the sink's own syntax would read (rich markup, Markdown, mathtext, the prompt's field markers) is made
  inert;
- the length is capped (a cut ends in ``…``).

Memory addresses a program saw are masked too (:func:`mask_addresses`), hex and decimal.
"""

from __future__ import annotations

import html
import json
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any
from urllib.parse import quote

from pydantic import BaseModel
from rich.console import Console, ConsoleOptions, RenderableType
from rich.markup import escape as rich_escape
from rich.segment import Segment
from rich.status import Status
from rich.text import Text

_UNICODE_CONTROLS = (  # Unicode's format characters (Cf) and its default-ignorable code points: text that shows nothing
    r"\u00ad\u034f\u0600-\u0605\u061c\u06dd\u070f\u0890\u0891\u08e2\u115f\u1160\u17b4\u17b5\u180b-\u180f"
    r"\u200b-\u200f\u2028-\u202e\u2060-\u206f\u3164\ufe00-\ufe0f\ufeff\uffa0\ufff0-\ufffb\U000110bd\U000110cd"
    r"\U00013430-\U0001343f\U0001bca0-\U0001bca3\U0001d173-\U0001d17a\U000e0000-\U000e0fff"
    r"\ud800-\udfff"  # lone surrogates (a task file's "\ud800" escape): no encoding can write them
)
_CONTROLS = re.compile(rf"[\x00-\x08\x0b-\x1f\x7f-\x9f{_UNICODE_CONTROLS}]")
INVISIBLE = re.compile(rf"[{_UNICODE_CONTROLS}]")
"""The characters that show nothing, or reorder or hide the text around them (not the ASCII controls)."""
_CONTROLS_AND_BREAKS = re.compile(rf"[\x00-\x1f\x7f-\x9f{_UNICODE_CONTROLS}]")

CUT = "…"
"""Ends text cut at its sink's limit."""


def _visible(match: re.Match[str]) -> str:
    code = ord(match.group())
    return f"\\x{code:02x}" if code <= 0xFF else f"\\u{code:04x}" if code <= 0xFFFF else f"\\U{code:08x}"


def terminal_safe(text: str) -> str:
    """``text`` with control characters escaped; newlines and tabs are kept."""
    return _CONTROLS.sub(_visible, text)


def one_line(text: str) -> str:
    """``text`` with control characters, newlines and tabs escaped: safe inside a table cell."""
    return _CONTROLS_AND_BREAKS.sub(_visible, text)


def capped(text: str, limit: int) -> str:
    """``text`` cut to at most ``limit`` characters, the cut marked with :data:`CUT`."""
    return text if len(text) <= limit else text[: limit - len(CUT)] + CUT


_HEX_ADDRESS = re.compile(r"(?<![0-9A-Za-z_])(0[xX])?([0-9a-fA-F]{9,16})(?![0-9A-Za-z_])")
_SHORT_HEX = re.compile(r"0[xX][0-9a-fA-F]{4,8}(?![0-9A-Za-z_])")
_LOWEST, _HIGHEST = 2**32, 2**48
"""Numbers in this range read as user-space addresses on a 64-bit machine (the heap and mappings of a
process sit at 0x55... and 0x7f...; 32-bit values and 17-digit floats stay as they are)."""
ADDRESS_SHOWN = "<address>"


def _address(match: re.Match[str]) -> str:
    prefix, digits = match.groups()
    decimal = not prefix and digits.isdigit()
    if decimal and match.string[max(match.start() - 1, 0) : match.start()] == ".":
        return match.group()  # the fraction of a float
    value = int(digits) if decimal else int(digits, 16)
    return ADDRESS_SHOWN if _LOWEST <= value < _HIGHEST else match.group()


def mask_addresses(text: str) -> str:
    """``text`` with memory-address-like numbers masked: ``0x`` hex of 4 digits or more, and hex or decimal
    numbers of 9 to 16 digits in the user-space range (``KeyError: (140622246014272, '7fe52b056d40')``)."""
    return _SHORT_HEX.sub(ADDRESS_SHOWN, _HEX_ADDRESS.sub(_address, text))


# -- one escaper per kind of sink ------------------------------------------------------------------


def console_markup(text: str) -> str:
    """For a rich markup string: controls escaped (newlines kept), markup escaped, capped."""
    return rich_escape(terminal_safe(capped(text, CONSOLE_CHARS)))


def console_plain(text: str) -> str:
    """For text printed with ``markup=False``: controls escaped (newlines kept), capped."""
    return terminal_safe(capped(text, CONSOLE_CHARS))


_MARKDOWN_SPECIAL = re.compile(r"([\\`*\[\]<>#|~$&])|(?<![0-9A-Za-z])_|_(?![0-9A-Za-z])")
_MARKDOWN_BLOCK_START = re.compile(r"^(\d*)([-+.)])(?=\s)")


def _markdown_escape(match: re.Match[str]) -> str:
    return "\\" + match.group()


def markdown_text(text: str) -> str:
    """For Markdown on one line: controls and line breaks escaped, every character Markdown (or GitHub's math
    and HTML) would read there backslash-escaped (``_`` inside a word reads as itself), and a list marker at
    the start too, capped; safe as a table cell, a list item and link text."""
    escaped = _MARKDOWN_SPECIAL.sub(_markdown_escape, one_line(capped(text, MARKDOWN_CHARS)))
    return _MARKDOWN_BLOCK_START.sub(r"\1\\\2", escaped)


def plot_text(text: str) -> str:
    """For matplotlib: on one line, controls escaped, every ``$`` escaped (no mathtext), capped."""
    return one_line(capped(text, PLOT_CHARS)).replace("$", r"\$")


def picture_text(text: str) -> str:
    """For text drawn with PIL: on one line (a newline would start a line over the picture), controls
    escaped, capped (fitting the width cuts it further)."""
    return one_line(capped(text, PICTURE_CHARS))


_PROMPT_MARKERS = re.compile(r"\[\[|\]\]")


def model_text(text: str) -> str:
    """For a prompt: on one line, controls escaped, the adapters' field markers (``[[ ## code ## ]]``)
    broken up, capped."""
    return _PROMPT_MARKERS.sub(lambda m: " ".join(m.group()), one_line(capped(text, MODEL_CHARS)))


def prompt_block(text: str) -> str:
    """For a prompt, a block of lines (a task's description): controls escaped (newlines and tabs kept), the
    adapters' field markers broken up, so that no text of a task file opens a field of its own."""
    return _PROMPT_MARKERS.sub(lambda m: " ".join(m.group()), terminal_safe(text))


def html_text(text: str, limit: int | None = None) -> str:
    """For an HTML page (text or an attribute value): controls escaped (newlines and tabs kept, inside ``<pre>``
    they lay out code), ``& < > " '`` as entities, capped at ``limit`` characters (default :data:`HTML_CHARS`; a cut
    says how long the text was)."""
    limit = HTML_CHARS if limit is None else limit
    if len(text) > limit:
        note = f" ({len(text)} characters in all)"
        text = capped(text, limit - len(note)) + note
    return html.escape(terminal_safe(text), quote=True)


def url_path(path: str) -> str:
    """For a relative path an HTML page links to (``src``, ``href``): percent-encoded, ``/`` kept, so that every
    character of a file name reaches the browser as itself (a control, a quote or a ``:`` that would read as a
    scheme stays inert) and still names the file."""
    return quote(path, safe="/")


def encodable(text: str) -> str:
    """``text`` with its lone surrogates written as escapes (``\\ud800``), so that it encodes as UTF-8: fit to send."""
    return text.encode("utf-8", "backslashreplace").decode("utf-8")


def json_string(text: str) -> str:
    """One string as JSON: every non-ASCII and control character as a ``\\u`` escape."""
    return json.dumps(text, ensure_ascii=True)


def json_text(model: BaseModel, *, indent: int | None = None) -> str:
    """A model as a JSON document, escaped like :func:`json_string`: a file that ``cat`` shows stays inert."""
    return model.model_dump_json(indent=indent, ensure_ascii=True)


CONSOLE_CHARS = 4000
MARKDOWN_CHARS = 300
PLOT_CHARS = 120
PICTURE_CHARS = 300
MODEL_CHARS = 1000
HTML_CHARS = 4000


@dataclass(frozen=True)
class Sink:
    """A kind of place the host writes text that a program or a model controls, and its escaper."""

    where: str
    escape: Callable[[str], str]
    one_line: bool


SINKS: dict[str, Sink] = {
    "console": Sink("rich markup on the terminal: tables, notes, plans", console_markup, one_line=False),
    "console-plain": Sink("program output and errors on the terminal, markup off", console_plain, one_line=False),
    "markdown": Sink("report.md: table cells, notes, picture captions", markdown_text, one_line=True),
    "plot": Sink("matplotlib text: the plan view's labels and title, the report's plots", plot_text, one_line=True),
    "picture": Sink("captions and labels drawn on pictures and video frames", picture_text, one_line=True),
    "model": Sink("text shown to a language model: the repair trace", model_text, one_line=True),
    "html": Sink("report.html: tables, stages, code, traces, captions", html_text, one_line=False),
    "json": Sink("JSON files and lines: reports, results, journals, prompt logs", json_string, one_line=True),
}
"""Every kind of sink by name; tests/test_output_safety.py runs a hostile string through each."""


# -- the terminal, whatever text reaches it --------------------------------------------------------


class TerminalConsole(Console):
    """A rich console that shows every character a terminal would act on as a visible escape, whatever reaches it:
    strings (paths the user typed, ``wrote out.json``), :class:`~rich.text.Text`, tables, status lines. Text that a
    program or a model controls still goes through :func:`console_markup` or :func:`console_plain` (markup escaped,
    length capped); this console is what keeps host text that embeds a file name the user gave (the name of an
    output file can hold an escape sequence) inert. Rich's own styles and cursor moves are kept. A status line's
    text is shown as it is, never read as markup (a file name with ``[/x]`` in it). Emoji codes stay text."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("emoji", False)
        super().__init__(*args, **kwargs)

    def render_str(self, text: str, **kwargs: Any) -> Text:
        return super().render_str(terminal_safe(text), **kwargs)

    def render(self, renderable: RenderableType, options: ConsoleOptions | None = None) -> Iterator[Segment]:
        for segment in super().render(renderable, options):
            if segment.control is None and _CONTROLS.search(segment.text):
                yield Segment(terminal_safe(segment.text), segment.style)
            else:
                yield segment

    def status(self, status: RenderableType, **kwargs: Any) -> Status:
        return _PlainStatus(_plain(status), console=self, **kwargs)


def _plain(status: RenderableType) -> RenderableType:
    return Text(terminal_safe(status)) if isinstance(status, str) else status


class _PlainStatus(Status):
    """A status line whose text, given or updated, is never read as markup."""

    def update(self, status: RenderableType | None = None, **kwargs: Any) -> None:
        super().update(None if status is None else _plain(status), **kwargs)
