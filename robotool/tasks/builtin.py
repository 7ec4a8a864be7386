"""The built-in task files shipped in ``robotool/tasks/data``: their names, their text, loading one by name or path."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from robotool.task.task_file import Problem, TaskFileError, load_task
from robotool.task.task_model import Task

_DATA = resources.files("robotool.tasks").joinpath("data")


def names() -> list[str]:
    """Names of the built-in tasks, sorted."""
    return sorted(p.name.removesuffix(".yaml") for p in _DATA.iterdir() if p.name.endswith(".yaml"))


def load(name_or_path: str | Path) -> Task:
    """Load a built-in task by name, or a task file by path."""
    text = str(name_or_path)
    if text in names():
        with resources.as_file(_DATA.joinpath(f"{text}.yaml")) as path:
            return load_task(path)
    if not text.strip():  # (Path("") is the current folder)
        raise TaskFileError(repr(text), [Problem(path="", message="give a built-in task name or a task file")])
    path = Path(name_or_path)
    if path.suffix.lower() in (".yaml", ".yml", ".json") or path.exists():
        return load_task(path)
    raise TaskFileError(
        text, [Problem(path="", message=f"no built-in task or file by that name; built-in tasks: {', '.join(names())}")]
    )


def source(name: str) -> str:
    """The YAML text of a built-in task, as shipped (TaskFileError naming the built-in tasks otherwise)."""
    if name not in names():
        raise TaskFileError(
            name, [Problem(path="", message=f"no built-in task by that name; built-in tasks: {', '.join(names())}")]
        )
    return _DATA.joinpath(f"{name}.yaml").read_text(encoding="utf-8")
