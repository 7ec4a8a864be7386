"""The package's names and layers: unique module and public class names, no import cycles, a planner apart from sim.

Read from the source with :mod:`ast` (nothing is imported): every ``import`` counts, including those inside
functions and under ``TYPE_CHECKING``, because a cycle hidden in a function is still a cycle in the design.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "robotool"

ROLE_MODULES = frozenset({"__main__"})
"""Module names whose job is their role in a package, so every package may have one (an ``__init__`` is named as
its package)."""

PLUG_INS = "robotool.robots."
"""Plug-in packages (one per robot) whose modules may repeat a role's name: each robot has its own ``skills``."""

SHARED_MODULE_NAMES: dict[str, str] = {
    "planner": "signatures/planner.py is the paper's Planner stage; the planner package is the LM-free search planner",
}
"""Module or package names (singular and plural alike) two places may still share, each with why; a name that
no longer collides must leave."""

SHARED_NAMES: dict[str, str] = {
    "Plan": "the quadruped controller's private alias for a motion plan generator, moved with the controller",
}
"""Public names two modules may still share, each with why; a name that no longer collides must leave."""

KNOWN_CYCLES: list[frozenset[str]] = []
"""Import cycles still to be removed; one that is gone must leave."""


PLANNER_INTO_SIMULATOR: set[tuple[str, str]] = set()
"""Planner modules that still import a simulator module; one that no longer does must leave."""


def _modules(root: Path = PACKAGE) -> dict[str, Path]:
    """Dotted module name -> file, for every module of the package."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _public_types(tree: ast.Module) -> list[str]:
    """Names of a module's public classes and public type aliases (``Name = ...`` in CamelCase)."""
    names = []
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            names.append(node.name)
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            is_type_var = isinstance(node.value, ast.Call) and getattr(node.value.func, "id", "") == "TypeVar"
            for target in targets:
                if isinstance(target, ast.Name) and _camel_case(target.id) and not is_type_var:
                    names.append(target.id)
    return [n for n in names if not n.startswith("_")]


def _camel_case(name: str) -> bool:
    return name[:1].isupper() and not name.isupper() and "_" not in name


def _imported(module: str, path: Path, node: ast.Import | ast.ImportFrom, modules: dict[str, Path]) -> set[str]:
    """The package's modules an import statement loads (the deepest one each name resolves to)."""
    if isinstance(node, ast.Import):
        wanted = [alias.name for alias in node.names]
    else:
        base = node.module or ""
        if node.level:
            package = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
            package = package[: len(package) - (node.level - 1)]
            base = ".".join([*package, node.module] if node.module else package)
        wanted = [f"{base}.{alias.name}" if f"{base}.{alias.name}" in modules else base for alias in node.names]
    found = set()
    for name in wanted:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        if name and name != module:
            found.add(name)
    return found


def import_graph(root: Path = PACKAGE) -> dict[str, set[str]]:
    """Module -> the package's modules it imports anywhere in its source."""
    modules = _modules(root)
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for module, path in modules.items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import | ast.ImportFrom):
                graph[module] |= _imported(module, path, node, modules)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[frozenset[str]]:
    """The strongly connected components with more than one module (Tarjan, iteratively)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[frozenset[str]] = []
    for start in graph:
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(frozenset(component))
    return found


def _own_name(module: str) -> str:
    """A module's or package's name, singular (``programs`` and ``program`` are one name to a reader)."""
    return module.rpartition(".")[2].removesuffix("s")


def _plug_in_roles(modules: list[str]) -> bool:
    """Modules of one role, each in its own plug-in package (``robotool.robots.<robot>.skills`` and the like)."""
    owners = [m.split(".")[2] if m.startswith(PLUG_INS) and m.count(".") >= 3 else None for m in modules]
    return None not in owners and len(set(owners)) == len(owners)


def shared_module_names(modules: list[str]) -> dict[str, list[str]]:
    """Names (singular) that more than one module or package has, but for one role in several plug-ins."""
    by_name: dict[str, list[str]] = defaultdict(list)
    for module in modules:
        if module != "robotool" and module.rpartition(".")[2] not in ROLE_MODULES:
            by_name[_own_name(module)].append(module)
    return {name: found for name, found in by_name.items() if len(found) > 1 and not _plug_in_roles(found)}


def test_no_two_modules_or_packages_share_a_name() -> None:
    shared = shared_module_names(list(_modules()))
    assert set(shared) - set(SHARED_MODULE_NAMES) == set(), f"modules sharing a name: {shared}"
    gone = set(SHARED_MODULE_NAMES) - set(shared)
    assert not gone, f"no longer shared, remove from SHARED_MODULE_NAMES: {gone}"


def test_a_plural_twin_is_the_same_name_and_plug_ins_may_repeat_a_role() -> None:
    assert _own_name("robotool.programs") == _own_name("robotool.program") == "program"
    assert _own_name("robotool.tasks") == _own_name("robotool.sim.task") == "task"
    per_robot = ["robotool.robots.arm.skills", "robotool.robots.quadruped.skills"]
    assert shared_module_names(per_robot) == {}
    assert shared_module_names([*per_robot, "robotool.sim.skills"]) == {"skill": [*per_robot, "robotool.sim.skills"]}
    assert shared_module_names(["robotool.robots.arm.goals", "robotool.robots.arm.sim.goals"]) != {}


def test_no_two_public_classes_share_a_name() -> None:
    by_name: dict[str, list[str]] = defaultdict(list)
    for module, path in _modules().items():
        for name in _public_types(ast.parse(path.read_text(encoding="utf-8"))):
            by_name[name].append(module)
    shared = {name: found for name, found in by_name.items() if len(found) > 1}
    assert set(shared) - set(SHARED_NAMES) == set(), f"public types sharing a name: {shared}"
    gone = set(SHARED_NAMES) - set(shared)
    assert not gone, f"no longer shared, remove from SHARED_NAMES: {gone}"


def test_no_import_cycles() -> None:
    found = cycles(import_graph())
    assert [c for c in found if c not in KNOWN_CYCLES] == [], "import cycles"
    assert [c for c in KNOWN_CYCLES if c not in found] == [], "cycle gone: remove it from KNOWN_CYCLES"


def _write(root: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = root / "pkg" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root / "pkg"


@pytest.mark.parametrize(
    ("files", "expected"),
    [
        ({"__init__.py": "", "a.py": "import pkg.b\n", "b.py": "from pkg import c\n", "c.py": ""}, []),
        (  # a cycle through an import inside a function
            {"__init__.py": "", "a.py": "from pkg.b import x\n", "b.py": "def x():\n    from pkg import a\n"},
            [frozenset({"pkg.a", "pkg.b"})],
        ),
        (  # relative imports, and a cycle under TYPE_CHECKING
            {
                "__init__.py": "",
                "sub/__init__.py": "",
                "sub/a.py": "from ..b import y\n",
                "b.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .sub import a\n",
            },
            [frozenset({"pkg.sub.a", "pkg.b"})],
        ),
    ],
)
def test_cycle_finder_sees_every_import(tmp_path: Path, files: dict[str, str], expected: list[frozenset[str]]) -> None:
    assert cycles(import_graph(_write(tmp_path, files))) == expected


def test_public_types_are_classes_and_aliases_not_constants_or_type_variables() -> None:
    tree = ast.parse(
        "from typing import TypeVar\nclass A: ...\nclass _B: ...\nChoice = int | str\nMAX = 3\nT = TypeVar('T')\n"
        "Colour: type = tuple\n"
    )
    assert _public_types(tree) == ["A", "Choice", "Colour"]


def test_the_planner_does_not_reach_into_the_simulator() -> None:
    graph = import_graph()
    reaching = {
        (module, imported)
        for module, imports in graph.items()
        if module.startswith("robotool.planner")
        for imported in imports
        if imported == "robotool.sim" or imported.startswith("robotool.sim.")
    }
    assert reaching - PLANNER_INTO_SIMULATOR == set(), "the planner imports simulator internals"
    assert PLANNER_INTO_SIMULATOR - reaching == set(), "no longer imported: remove it from PLANNER_INTO_SIMULATOR"
