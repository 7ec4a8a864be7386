"""Each registered robot type's limits model, for a task to apply its overrides (filled by the registry).

A task model reads limits from here rather than from the registry, whose records refer back to the task model.
"""

from __future__ import annotations

from pydantic import BaseModel

LIMITS_MODELS: dict[str, type[BaseModel]] = {}
"""Robot type name -> its limits model; :func:`robotool.robots.register` adds each robot's."""


def limits_model(robot_type: str) -> type[BaseModel]:
    """The limits model of a registered robot type (KeyError naming the registered ones otherwise)."""
    try:
        return LIMITS_MODELS[robot_type]
    except KeyError:
        known = ", ".join(sorted(LIMITS_MODELS))
        raise KeyError(f"robot type {robot_type!r} is not registered; registered: {known}") from None


def add(robot_type: str, model: type[BaseModel]) -> None:
    """Record a robot type's limits model (called by :func:`robotool.robots.register`)."""
    LIMITS_MODELS[robot_type] = model
