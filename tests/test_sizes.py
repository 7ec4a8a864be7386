"""No module in robotool/ over MAX_MODULE_LINES lines and no class over MAX_CLASS_LINES: a module or class that
grows past them does several jobs, to be split along its seams (as the quadruped controller was)."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "robotool"
MAX_MODULE_LINES = 600
MAX_CLASS_LINES = 400


def oversized(root: Path = PACKAGE) -> tuple[dict[str, int], dict[str, int]]:
    """Modules (path) over the module limit and classes (path:Class) over the class limit, with their lines."""
    modules, classes = {}, {}
    for path in sorted(root.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        name = str(path.relative_to(root.parent))
        if len(text.splitlines()) > MAX_MODULE_LINES:
            modules[name] = len(text.splitlines())
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ClassDef) and node.end_lineno is not None:
                lines = node.end_lineno - node.lineno + 1
                if lines > MAX_CLASS_LINES:
                    classes[f"{name}:{node.name}"] = lines
    return modules, classes


def test_no_module_or_class_is_over_the_limits() -> None:
    modules, classes = oversized()
    assert modules == {}, f"modules over {MAX_MODULE_LINES} lines: {modules}"
    assert classes == {}, f"classes over {MAX_CLASS_LINES} lines: {classes}"


def test_the_limits_name_the_offenders(tmp_path: Path) -> None:
    package = tmp_path / "robotool"
    package.mkdir()
    (package / "big.py").write_text("x = 1\n" * (MAX_MODULE_LINES + 1))
    body = "".join(f"    a{i} = {i}\n" for i in range(MAX_CLASS_LINES))
    (package / "small.py").write_text(f"class Big:\n{body}\n\nclass Fine:\n    pass\n")
    assert oversized(package) == ({"robotool/big.py": MAX_MODULE_LINES + 1}, {"robotool/small.py:Big": 401})
