"""Procedural task families: seeded variations of the built-in tasks with their ground truth.

``generate(family, seed)`` builds one :class:`Instance` deterministically from
``numpy.random.default_rng(seed)``: a valid task file plus whether it needs a tool (decided by the
geometry, :func:`robotool.task.concepts.needs_tool`), whether it is solvable, which object(s) a solution uses,
its decoys and a sentence on what was varied. Each family's module documents its randomizations.

The built-in families are registered below; :func:`register_family` adds another (a plug-in, or a program that
embeds robotool) and :func:`registered_families` adds some for a block only (tests).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from robotool.tasks.families import (
    button_pressing,
    can_grasping,
    cube_lifting,
    milk_reaching,
    sofa_climbing,
    sofa_traversing,
    vase_lowering,
)
from robotool.tasks.families._common import Draft, Instance, finish

__all__ = [
    "Builder",
    "Draft",
    "Instance",
    "families",
    "generate",
    "register_family",
    "registered_families",
    "write_instance",
]

Builder = Callable[[np.random.Generator], Draft]
"""A family: draws one instance's task and its ground truth from a seeded generator."""

_BUILDERS: dict[str, Builder] = {}


def register_family(name: str, build: Builder) -> None:
    """Add a task family (as robots are added to their registry); the same builder again does nothing, another
    under a taken name fails."""
    taken = _BUILDERS.get(name)
    if taken is not None and taken is not build:
        raise ValueError(f"a task family named {name!r} is already registered; choose another name")
    _BUILDERS[name] = build


@contextmanager
def registered_families(**builders: Builder) -> Iterator[None]:
    """Register ``name=build`` families for the block only; afterwards the families are as before."""
    saved = dict(_BUILDERS)
    try:
        for name, build in builders.items():
            register_family(name, build)
        yield
    finally:
        _BUILDERS.clear()
        _BUILDERS.update(saved)


for _module in (
    milk_reaching,
    can_grasping,
    button_pressing,
    sofa_traversing,
    sofa_climbing,
    cube_lifting,
    vase_lowering,
):
    register_family(_module.__name__.rsplit(".", 1)[1], _module.build)


def families() -> list[str]:
    """Names of the task families, sorted."""
    return sorted(_BUILDERS)


def generate(family: str, seed: int) -> Instance:
    """The instance of ``family`` for ``seed`` (the same pair always gives the same task)."""
    if family not in _BUILDERS:
        raise ValueError(f"unknown task family {family!r}; families: {', '.join(families())}")
    if seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed}")
    return finish(family, seed, _BUILDERS[family](np.random.default_rng(seed)))


def write_instance(instance: Instance, path: str | Path) -> Path:
    """Write the instance's task file (YAML), its ground truth in a comment header; returns the path."""
    truth = (
        f"# generated: family {instance.family}, seed {instance.seed}\n"
        f"# needs_tool: {str(instance.needs_tool).lower()}, solvable: {str(instance.solvable).lower()}, "
        f"tool: {', '.join(instance.tools) or 'none'}, decoys: {', '.join(instance.decoys) or 'none'}\n"
        f"# {instance.description}\n"
    )
    path = Path(path)
    path.write_text(truth + instance.task.to_yaml(), encoding="utf-8")
    return path
