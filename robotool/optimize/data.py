"""Training, validation and test examples for prompt optimisation, from task families and built-in tasks.

An example's input is the task; its labels are the ground truth an optimiser's metric grades with: the
key concepts (:func:`robotool.task.concepts.key_concepts`), whether a tool is needed, the tools a reference
solution uses, and the family. Generated instances come from disjoint seed ranges per split
(:data:`SEED_RANGES`), so no instance is in two splits; unsolvable instances are left out (success on them
measures nothing). The paper's six tasks are never training examples: :func:`splits` puts them in the
test split, and :func:`check_training` refuses a training set that holds one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import dspy

from robotool import tasks
from robotool.eval.reference import BUILTIN_TOOLS, PAPER_TASKS
from robotool.task.concepts import key_concepts, needs_tool
from robotool.task.task_model import Task

Split = Literal["train", "val", "test"]
SEED_RANGES: dict[Split, range] = {
    "train": range(0, 100_000),
    "val": range(100_000, 200_000),
    "test": range(200_000, 300_000),
}
"""Seeds of generated instances by split: disjoint, so an instance belongs to one split only."""
MAX_DRAWS = 20
"""Seeds tried per requested example before giving up on a family (unsolvable instances are skipped)."""


class DatasetError(ValueError):
    """The examples cannot be built as asked; the message says why."""


def example(
    task: Task, *, family: str | None = None, seed: int | None = None, tools: frozenset[str] | None = None
) -> dspy.Example:
    """One example: ``task`` as the input, its ground truth as labels."""
    return dspy.Example(
        task=task,
        name=task.name,
        family=family,
        seed=seed,
        key_concepts=key_concepts(task),
        needs_tool=needs_tool(task),
        tools=sorted(tools) if tools is not None else None,
    ).with_inputs("task")


def generated(family: str, seed: int) -> dspy.Example | None:
    """The example of a family's instance, or None when the instance is unsolvable."""
    instance = tasks.generate(family, seed)
    if not instance.solvable:
        return None
    return example(instance.task, family=family, seed=seed, tools=frozenset(instance.tools))


def builtin(name: str) -> dspy.Example:
    """The example of a built-in task."""
    return example(tasks.load(name), tools=BUILTIN_TOOLS.get(name))


def split_of(seed: int) -> Split:
    """The split a generated instance's seed belongs to."""
    return next(name for name, seeds in SEED_RANGES.items() if seed in seeds)


def check_families(families: Sequence[str]) -> None:
    """Refuse an empty or unknown family name, naming the families there are."""
    if not families:
        raise DatasetError("no task families given")
    unknown = sorted(set(families) - set(tasks.families()))
    if unknown:
        raise DatasetError(f"unknown task family {', '.join(unknown)}; families: {', '.join(tasks.families())}")


def dataset(families: Sequence[str], seeds: Sequence[int]) -> list[dspy.Example]:
    """Examples of ``families`` at ``seeds`` (unsolvable instances left out), family by family."""
    check_families(families)
    return [e for family in families for seed in seeds if (e := generated(family, seed)) is not None]


def draw(families: Sequence[str], count: int, split: Split) -> list[dspy.Example]:
    """``count`` solvable examples from ``split``'s seed range, taking the families in turn."""
    check_families(families)
    chosen: list[dspy.Example] = []
    next_seed = {family: SEED_RANGES[split].start for family in families}
    for attempt in range(MAX_DRAWS * count):
        if len(chosen) == count:
            break
        family = families[attempt % len(families)]
        found = generated(family, next_seed[family])
        next_seed[family] += 1
        if found is not None:
            chosen.append(found)
    if len(chosen) < count:
        raise DatasetError(f"too few solvable instances of {', '.join(families)} for {count} examples")
    return chosen


@dataclass(frozen=True)
class Splits:
    """Training, validation and test examples; disjoint by construction."""

    train: list[dspy.Example]
    val: list[dspy.Example]
    test: list[dspy.Example]


def splits(families: Sequence[str], *, train: int, val: int, test: int = 0, paper_tasks: bool = True) -> Splits:
    """``train``/``val``/``test`` generated examples of ``families``; the paper's six tasks join the test split."""
    if train < 1:
        raise DatasetError("an optimiser needs at least one training example")
    held_out = [builtin(name) for name in PAPER_TASKS] if paper_tasks else []
    result = Splits(
        train=draw(families, train, "train"),
        val=draw(families, val, "val") if val else [],
        test=(draw(families, test, "test") if test else []) + held_out,
    )
    check_training(result.train)
    return result


def check_training(examples: Sequence[dspy.Example]) -> None:
    """Refuse a training set holding one of the paper's tasks or an instance from another split's seeds."""
    for e in examples:
        if e.name in PAPER_TASKS and e.family is None:
            raise DatasetError(f"{e.name} is one of the paper's tasks, held out of training")
        if e.seed is not None and split_of(e.seed) != "train":
            raise DatasetError(f"{e.family} seed {e.seed} belongs to the {split_of(e.seed)} split, not train")
