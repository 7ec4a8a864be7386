"""The package's names and layers: unique module and public class names, no import cycles, the packages' layer
table, and an LM-free core that never loads DSPy.

Read from the source with :mod:`ast` (nothing is imported): every ``import`` counts, including those inside
functions and under ``TYPE_CHECKING``, because a cycle hidden in a function is still a cycle in the design. One
test imports the planner in a child interpreter, to see that DSPy stays unloaded at run time too.
"""

from __future__ import annotations

import ast
import subprocess
import sys
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
    "task": "task/ is the model of one task (file, goal, scene, geometry, key concepts); tasks/ is the catalogue of "
    "built-in task files and procedural families, the way robots/ is the catalogue of robots",
}
"""Module or package names (singular and plural alike) two places may still share, each with why; a name that
no longer collides must leave."""

SHARED_NAMES: dict[str, str] = {}
"""Public names two modules may still share, each with why; a name that no longer collides must leave."""

KNOWN_CYCLES: list[frozenset[str]] = []
"""Import cycles still to be removed; one that is gone must leave."""

BASE_MODULES = frozenset(
    {"bugs", "errors", "safe_text", "version", "processes", "gl_backend", "rollout", "program_session", "vocabulary"}
)
"""Top-level modules every layer may use: typed errors, the records of robotool's own bugs, the vocabulary, text
escaping, the version, process pools, the OpenGL choice, a run's records and the runner <-> program protocol.
They import nothing of robotool but each other."""

ROBOT_CONTRACT = frozenset({"registry", "skills", "limits_table"})
"""The modules of ``robotool/robots/`` that every robot shares (the contract); each other folder there is a robot."""

DSPY_FREE_RECORDS = frozenset({"models", "traces"})
"""The modules of ``robotool/signatures/`` that hold the stages' pydantic records and import no DSPy."""

LAYERS: dict[str, frozenset[str]] = {
    "base": frozenset(),
    "task": frozenset({"robots"}),
    "robots": frozenset({"base", "task", "sim", "planner"}),
    "tasks": frozenset({"task", "robot"}),
    "records": frozenset({"base", "task"}),
    "signatures": frozenset({"base", "records"}),
    "solution": frozenset({"base", "records"}),
    "sandbox": frozenset({"base", "robots"}),
    "sim": frozenset({"base", "robots", "task"}),
    "verify": frozenset({"base", "sandbox", "sim", "solution", "task", "tasks"}),
    "planner": frozenset({"base", "records", "robots", "solution", "task", "verify"}),
    "robot": frozenset({"base", "robots", "task", "sim", "planner"}),
    "program": frozenset({"base", "records", "signatures", "robots", "sandbox", "solution", "task", "verify"}),
    "render": frozenset({"base", "robots", "sandbox", "sim", "task", "verify"}),
    "report_page": frozenset({"base", "eval", "render", "solution", "task", "verify"}),
    "eval": frozenset(
        {"base", "planner", "program", "render", "report_page", "robots", "sandbox", "sim", "solution", "task"}
        | {"tasks", "verify"}
    ),
    "optimize": frozenset(
        {"base", "eval", "planner", "program", "robots", "sandbox", "solution", "task", "tasks", "verify"}
    ),
    "cli": frozenset(
        {"base", "eval", "optimize", "planner", "program", "render", "report_page", "robots", "sandbox", "sim"}
        | {"solution", "task", "tasks", "verify"}
    ),
}
"""Layer -> the layers its modules may import (see :func:`layer` for which modules make up each). Read as: the task
model knows robots only through their contract; the records of the LM stages are DSPy-free; the sandbox, the
simulator and the LM-free planner never import the LM path (``signatures``, ``program``), the evaluator, the optimiser
or the command line; a robot (``robots/<name>/``) plugs into the contract, the simulator and the planner; the
contract names simulator and planner types only for its typed hooks. ``eval`` and ``report_page`` use each other:
the report page draws the evaluator's records and the evaluator writes the page. The package's ``__init__`` and every
``__main__`` are entry points and may import anything. docs/architecture.md shows this table; keep them in step."""

LM_FREE_LAYERS = frozenset(
    {"base", "task", "robots", "tasks", "records", "solution", "sandbox", "sim", "verify", "planner", "robot"}
)
"""Layers that must never load DSPy, however deep the import."""


def layer(module: str) -> str:
    """The layer a module belongs to (the table's key): its top-level package, with the exceptions named above."""
    parts = module.split(".")
    if module == "robotool" or parts[-1] == "__main__":
        return "entry"
    if len(parts) == 2 and parts[1] in BASE_MODULES:
        return "base"
    if len(parts) == 2 and parts[1] == "execute":
        return "verify"
    if parts[1] == "robots":
        return "robots" if len(parts) == 2 or parts[2] in ROBOT_CONTRACT else "robot"
    if parts[1] == "signatures" and len(parts) > 2 and parts[2] in DSPY_FREE_RECORDS:
        return "records"
    return parts[1]


def layer_violations(graph: dict[str, set[str]]) -> list[str]:
    """Every import that crosses layers against the table, and every module whose layer the table lacks."""
    found = []
    for module, imports in sorted(graph.items()):
        own = layer(module)
        if own == "entry":
            continue
        if own not in LAYERS:
            found.append(f"{module}: layer {own!r} is not in LAYERS (add it, with what it may import)")
            continue
        for imported in sorted(imports):
            other = layer(imported)
            if other != own and other not in LAYERS[own]:
                found.append(f"{module} ({own}) imports {imported} ({other})")
    return found


def _imports_dspy(path: Path) -> bool:
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import) and any(a.name.partition(".")[0] == "dspy" for a in node.names):
            return True
        if isinstance(node, ast.ImportFrom) and not node.level and (node.module or "").partition(".")[0] == "dspy":
            return True
    return False


def dspy_chains(graph: dict[str, set[str]], modules: dict[str, Path], starts: list[str]) -> list[str]:
    """For each start module that reaches a module importing DSPy, the chain of imports that gets there."""
    importers = {module for module, path in modules.items() if _imports_dspy(path)}
    chains = []
    for start in starts:
        parent: dict[str, str] = {}
        seen, stack = {start}, [start]
        while stack:
            node = stack.pop()
            if node in importers:
                chain = [node]
                while chain[-1] in parent:
                    chain.append(parent[chain[-1]])
                chains.append(" <- ".join(["dspy", *chain]))
                break
            for child in sorted(graph[node] - seen):
                seen.add(child)
                parent[child] = node
                stack.append(child)
    return chains


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


def test_every_import_keeps_to_the_layer_table() -> None:
    assert layer_violations(import_graph()) == []


def test_the_layer_table_names_a_violation_and_an_unknown_layer() -> None:
    graph = {
        "robotool.planner.search": {"robotool.sim.lockstep", "robotool.task.scene"},
        "robotool.sim.build": {"robotool.program.lm"},
        "robotool.robots.arm.controller": {"robotool.sim.backend", "robotool.robots.registry"},
        "robotool.newthing": set(),
        "robotool.eval.__main__": {"robotool.cli.eval_command"},
    }
    assert layer_violations(graph) == [
        "robotool.newthing: layer 'newthing' is not in LAYERS (add it, with what it may import)",
        "robotool.planner.search (planner) imports robotool.sim.lockstep (sim)",
        "robotool.sim.build (sim) imports robotool.program.lm (program)",
    ]
    assert layer("robotool.signatures.models") == "records" != layer("robotool.signatures.repair")
    assert layer("robotool.robots.registry") == "robots" != layer("robotool.robots.quadruped.terrain") == "robot"


def test_every_layer_in_the_table_may_only_import_layers_in_the_table() -> None:
    assert {name for allowed in LAYERS.values() for name in allowed} - set(LAYERS) == set()


def test_the_lm_free_layers_never_reach_dspy() -> None:
    modules = _modules()
    starts = [m for m in modules if layer(m) in LM_FREE_LAYERS]
    assert dspy_chains(import_graph(), modules, starts) == []


def test_the_dspy_chain_finder_names_the_chain(tmp_path: Path) -> None:
    root = _write(
        tmp_path,
        {"__init__.py": "", "a.py": "from pkg import b\n", "b.py": "def f():\n    import dspy\n", "c.py": ""},
    )
    modules = _modules(root)
    assert dspy_chains(import_graph(root), modules, ["pkg.a", "pkg.c"]) == ["dspy <- pkg.b <- pkg.a"]


def test_importing_the_planner_does_not_load_dspy() -> None:
    code = (
        "import sys; import robotool.planner, robotool.planner.search, robotool.signatures.traces; "
        "assert 'dspy' not in sys.modules, sorted(m for m in sys.modules if m.startswith('robotool'))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr


def documented_layers(text: str) -> dict[str, frozenset[str]]:
    """The layer table of docs/architecture.md's "Layers" section: layer -> the layers it may import."""
    section = text.split("\n## Layers\n", 1)[1].split("\n## ", 1)[0]
    table = {}
    for line in section.splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) == 2 and line.startswith("|") and cells[0] not in ("layer", "---"):
            allowed = "" if cells[1] == "(nothing)" else cells[1]
            table[cells[0]] = frozenset(name.strip() for name in allowed.split(",") if name.strip())
    return table


def test_the_architecture_doc_shows_the_layer_table_as_it_is() -> None:
    doc = (PACKAGE.parent / "docs" / "architecture.md").read_text(encoding="utf-8")
    assert documented_layers(doc) == LAYERS
