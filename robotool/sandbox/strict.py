"""The strict reading of a user's own program file: Python as written, nothing dropped or added.

Only language-model replies go through the lenient :func:`~robotool.sandbox.extract.extract_program`;
a program a person wrote is parsed exactly as it is, so a syntax error anywhere stops it before it runs.
"""

from __future__ import annotations

import ast

from robotool.sandbox.validate import ProgramRejected, check_program_size, parse_program, validate


def check_user_program(code: str, embodiment: str) -> str:
    """Parse ``code`` strictly and check it against the sandbox allowlist; returns it unchanged.

    Raises :class:`ProgramRejected`; a syntax error names its line and column.
    """
    check_program_size(code)
    try:
        ast.parse(code)
    except SyntaxError as e:
        where = f" at column {e.offset}" if e.offset else ""
        raise ProgramRejected(e.lineno, "syntax", f"syntax error{where}: {e.msg}") from None
    except (ValueError, RecursionError, MemoryError):
        parse_program(code)  # raises the same rejection as for a generated program, with its reason
    validate(code, embodiment)
    return code
