"""Text from programs, language models and task files, made safe to show in a terminal or Markdown.

Generated programs print what they like and name objects as they like; a raw escape byte in that
text can clear the screen, retitle the window, write the clipboard (OSC 52) or paint a fake success
line. Every control character, and the Unicode controls that reorder or hide text, is shown as a
visible escape instead (``\\x1b``, ``\\u202e``), as are the invisible characters that hide text
(soft hyphen, invisible operators, Unicode tag characters) and the line and paragraph separators.
"""

from __future__ import annotations

import re

_UNICODE_CONTROLS = r"\u00ad\u061c\u180e\u200b-\u200f\u2028-\u202e\u2060-\u206f\ufeff\ufff9-\ufffb\U000e0000-\U000e007f"
_CONTROLS = re.compile(rf"[\x00-\x08\x0b-\x1f\x7f-\x9f{_UNICODE_CONTROLS}]")
_CONTROLS_AND_BREAKS = re.compile(rf"[\x00-\x1f\x7f-\x9f{_UNICODE_CONTROLS}]")


def _visible(match: re.Match[str]) -> str:
    code = ord(match.group())
    return f"\\x{code:02x}" if code <= 0xFF else f"\\u{code:04x}" if code <= 0xFFFF else f"\\U{code:08x}"


def terminal_safe(text: str) -> str:
    """``text`` with control characters escaped; newlines and tabs are kept."""
    return _CONTROLS.sub(_visible, text)


def one_line(text: str) -> str:
    """``text`` with control characters, newlines and tabs escaped: safe inside a table cell."""
    return _CONTROLS_AND_BREAKS.sub(_visible, text)
