"""One vocabulary: each word set (stages, methods, backends, skill outcomes) is spelt once, in
robotool/vocabulary.py, and keeps the strings saved results and the command line have always used.

Read from the source with :mod:`ast`: a ``Literal`` type or a list of choices anywhere else in the package that
spells the same words as a vocabulary type is a twin that will drift.
"""

from __future__ import annotations

import ast
from pathlib import Path
from typing import get_args

from robotool import vocabulary
from robotool.program.methods import STAGES_BY_METHOD

PACKAGE = Path(vocabulary.__file__).parent


def _words(node: ast.expr) -> frozenset[str] | None:
    """The strings of a ``Literal[...]`` subscript or a list/tuple of string constants (None for anything else)."""
    if isinstance(node, ast.Subscript) and getattr(node.value, "id", getattr(node.value, "attr", "")) == "Literal":
        node = node.slice
    if (
        isinstance(node, ast.Tuple | ast.List)
        and node.elts
        and all(isinstance(e, ast.Constant) and isinstance(e.value, str) for e in node.elts)
    ):
        return frozenset(e.value for e in node.elts if isinstance(e, ast.Constant))
    return None


def _vocabulary_words() -> dict[frozenset[str], str]:
    words = {}
    for name in ("Stage", "MethodName", "PlannerMethod", "BackendName", "SkillOutcome"):
        words[frozenset(_flat(getattr(vocabulary, name)))] = name
    return words


def _flat(alias: object) -> list[str]:
    return [w for a in get_args(alias) for w in (_flat(a) if get_args(a) else [a])]


def test_no_module_spells_a_vocabulary_word_set_again() -> None:
    known = _vocabulary_words()
    twins: set[str] = set()
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name == "vocabulary.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            found = _words(node) if isinstance(node, ast.expr) else None
            if found is not None and found in known:
                twins.add(f"{path.relative_to(PACKAGE)}:{node.lineno}: {known[found]}")
    assert not twins, "\n".join(sorted(twins))


def test_the_words_keep_the_strings_results_and_the_command_line_use() -> None:
    assert vocabulary.STAGES == ("analyzer", "planner", "calculator", "coder")
    assert set(_flat(vocabulary.FailureStage)) == {*vocabulary.STAGES, "repair", "search", "simulation"}
    assert list(STAGES_BY_METHOD) == ["robotool", "no_analyzer", "no_calculator", "planner_coder", "coder"]
    assert vocabulary.PLANNER_METHODS == ("search", "no_tool") and vocabulary.BACKENDS == ("mujoco", "warp")
    assert set(_flat(vocabulary.SkillOutcome)) == {
        "done",
        "stalled",
        "timeout",
        "refused",
        "fell",
        "error",
        "internal_error",
    }
