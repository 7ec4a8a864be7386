"""Procedural task families: seeded variations of the built-in tasks with their ground truth.

``generate(family, seed)`` builds one :class:`Instance` deterministically from
``numpy.random.default_rng(seed)``: a valid task file plus whether it needs a tool (decided by the
geometry, :func:`robotool.task.concepts.needs_tool`), whether it is solvable, which object(s) a solution uses,
its decoys and a sentence on what was varied. Each family's module documents its randomizations.
"""

from __future__ import annotations

from collections.abc import Callable
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

__all__ = ["Instance", "families", "generate", "write_instance"]

_BUILDERS: dict[str, Callable[[np.random.Generator], Draft]] = {
    module.__name__.rsplit(".", 1)[1]: module.build
    for module in (
        milk_reaching,
        can_grasping,
        button_pressing,
        sofa_traversing,
        sofa_climbing,
        cube_lifting,
        vase_lowering,
    )
}


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
