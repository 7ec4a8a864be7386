"""Which task instances an evaluation covers: built-in tasks, task files and generated instances.

A built-in task or a task file is keyed by its name (seed None); a generated instance by its family
and seed (``robotool.tasks.generate(family, seed)``). Unsolvable generated instances are left out:
success on them measures nothing.
"""

from __future__ import annotations

from collections.abc import Sequence

from pydantic import BaseModel, ConfigDict

from robotool import tasks
from robotool.eval.config import EvalError
from robotool.eval.reference import BUILTIN_TOOLS, PAPER_TASKS
from robotool.safe_text import capped
from robotool.task.concepts import needs_tool
from robotool.task.task_model import Task

DEFAULT_SEEDS: tuple[int, ...] = (0, 1, 2)
"""Seeds per family in the default run, sized so that it fits :data:`~robotool.eval.config.TIME_BUDGET_S`."""


class TaskInstance(BaseModel):
    """One task to evaluate, with what grading needs to know about it."""

    model_config = ConfigDict(frozen=True)

    name: str
    seed: int | None = None
    family: str | None = None
    task: Task
    needs_tool: bool
    tools: frozenset[str] | None = None

    @property
    def label(self) -> str:
        """How tables and the progress bar name it: ``name`` or ``family#seed``."""
        return self.name if self.seed is None else f"{self.name}#{self.seed}"


def builtin(name_or_path: str) -> TaskInstance:
    """A built-in task by name, or a task file by path (TaskFileError when neither)."""
    task = tasks.load(name_or_path)
    return TaskInstance(name=task.name, task=task, needs_tool=needs_tool(task), tools=BUILTIN_TOOLS.get(name_or_path))


def builtin_names() -> list[str]:
    """The built-in tasks, the paper's six first in its order."""
    names = tasks.names()
    return [n for n in PAPER_TASKS if n in names] + [n for n in names if n not in PAPER_TASKS]


def families() -> list[str] | None:
    """The procedural task families, or None when this install has none."""
    listing = getattr(tasks, "families", None)
    return list(listing()) if callable(listing) and callable(getattr(tasks, "generate", None)) else None


def generated(family: str, seed: int) -> TaskInstance | None:
    """A generated instance, or None when it is unsolvable."""
    instance = tasks.generate(family, seed)
    if not getattr(instance, "solvable", True):
        return None
    return TaskInstance(
        name=family,
        seed=seed,
        family=family,
        task=instance.task,
        needs_tool=bool(instance.needs_tool),
        tools=frozenset(instance.tools),
    )


def _edited_copy(given: str, instance: TaskInstance) -> str | None:
    """The note for a task file given by path that holds a task named like a built-in task that it is not (an
    edited copy: the tables show it under that name), or None."""
    if given in tasks.names() or instance.name not in tasks.names() or instance.task == tasks.load(instance.name):
        return None
    where = ", beside the paper's published numbers" if instance.name in PAPER_TASKS else ""
    copy = f"{given} is an edited copy of the built-in task {instance.name!r}"
    return f"{copy}: its runs are shown under that name{where}"


def _distinct(chosen: list[TaskInstance], notes: list[str]) -> list[TaskInstance]:
    """The tasks given, each once (a task given twice is noted); EvalError for two different tasks of one name, which
    the tables and pictures would take for one."""
    by_name: dict[str, TaskInstance] = {}
    for instance in chosen:
        seen = by_name.setdefault(instance.name, instance)
        if seen.task != instance.task:
            raise EvalError(
                f"two different tasks are named {instance.name!r}: rename one (the tables and pictures know a task by "
                "its name)"
            )
    if len(by_name) < len(chosen):
        notes.append(f"{len(chosen) - len(by_name)} task(s) given more than once, evaluated once")
    return list(by_name.values())


MAX_SEEDS = 1000
"""Seeds one ``--seeds`` may name (each is an instance of every family): counted before a range is expanded, so
``0-99999999999`` is refused at once rather than filling the memory."""


def parse_seeds(text: str) -> tuple[int, ...]:
    """``"A-B"`` (inclusive), ``"A"`` or ``"A,B,C"`` -> seeds, at most :data:`MAX_SEEDS` of them; ValueError with a
    readable message."""
    ranges: list[range] = []
    for part in text.split(","):
        low, dash, high = part.strip().partition("-")
        try:
            first, last = int(low), int(high) if dash else int(low)
        except ValueError:  # also a number of more digits than Python converts
            raise ValueError(f"seeds must look like 0-9 or 1,4,7, got {capped(text, 60)!r}") from None
        if first < 0 or last < first:
            raise ValueError(f"seed range {capped(part.strip(), 60)!r} must be A-B with 0 <= A <= B")
        ranges.append(range(first, last + 1))
        if sum(r.stop - r.start for r in ranges) > MAX_SEEDS:  # len() of a range fails past 2**63
            raise ValueError(f"at most {MAX_SEEDS} seeds at once, got more in {capped(text, 60)!r}")
    return tuple(dict.fromkeys(seed for r in ranges for seed in r))


def select(
    task_names: Sequence[str] | None, family_names: Sequence[str] | None, seeds: Sequence[int] | None
) -> tuple[list[TaskInstance], list[str]]:
    """The instances to evaluate and notes for the user.

    With nothing given: every built-in task plus every family at :data:`DEFAULT_SEEDS`. With only
    tasks: those tasks. Families or seeds given: those families (default all) at those seeds
    (default :data:`DEFAULT_SEEDS`), after the tasks given.
    """
    notes: list[str] = []
    everything = task_names is None and family_names is None and seeds is None
    given = builtin_names() if everything else list(task_names or [])
    chosen = [builtin(name) for name in given]
    notes += [note for name, i in zip(given, chosen, strict=True) if (note := _edited_copy(name, i)) is not None]
    chosen = _distinct(chosen, notes)
    if everything or family_names is not None or seeds is not None:
        available = families()
        if available is None:
            if not everything:
                raise EvalError("procedural task families are not available in this install")
            notes.append("no generated instances: procedural task families are not available in this install")
            return chosen, notes
        unknown = sorted(set(family_names or ()) - set(available))
        if unknown:
            raise EvalError(f"unknown task family {', '.join(unknown)}; families: {', '.join(available)}")
        skipped = 0
        for family in family_names or available:
            for seed in seeds if seeds is not None else DEFAULT_SEEDS:
                instance = generated(family, seed)
                if instance is None:
                    skipped += 1
                else:
                    chosen.append(instance)
        if skipped:
            notes.append(f"left out {skipped} unsolvable generated instance(s)")
    if not chosen:
        raise EvalError("no tasks to evaluate")
    return chosen, notes
