"""The strict reading of a user's own program file: Python as written, nothing dropped or added.

Only language-model replies go through the lenient :func:`~robotool.sandbox.extract.extract_program`;
a program a person wrote is parsed exactly as it is, so a syntax error anywhere stops it before it runs.
"""

from __future__ import annotations

import ast

from robotool.sandbox.validate import ProgramRejected, validate


def check_user_program(code: str, embodiment: str) -> str:
    """Parse ``code`` strictly and check it against the sandbox allowlist; returns it unchanged.

    Raises :class:`ProgramRejected`; a syntax error names its line and column.
    """
    try:
        ast.parse(code)
    except SyntaxError as e:
        where = f" at column {e.offset}" if e.offset else ""
        raise ProgramRejected(e.lineno, "syntax", f"syntax error{where}: {e.msg}") from None
    except (ValueError, RecursionError, MemoryError) as e:
        raise ProgramRejected(None, "syntax", f"program cannot be parsed: {e or type(e).__name__}") from None
    validate(code, embodiment)
    return code
