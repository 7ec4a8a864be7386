"""The rules every robot's ``robot.limits`` overrides follow, whatever the robot (:func:`limit_problems`).

A robot's limits model gives each limit's type and its own bounds; a task file's numbers are bounded as the objects'
are. A limit is a positive quantity (a size, length or mass, or a tuple of them such as a body's size), between
:data:`MIN_LIMIT` and :data:`~robotool.task.scene.MAX_LENGTH`, or an end of a range (``<x>_min``, ``<x>_max``, such
as a workspace's corners), a coordinate within :data:`~robotool.task.scene.MAX_COORDINATE` and below its other end
on every axis. Every number is finite and none is true or false.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from pydantic import BaseModel

from robotool.task.scene import MAX_COORDINATE, MAX_LENGTH
from robotool.task.task_problem import Problem

MIN_LIMIT = 0.001
"""The smallest positive limit (1 mm, 1 g): a robot's body of this size and mass still builds in the simulator."""
LOW, HIGH = "_min", "_max"


def limit_problems(overrides: Mapping[str, Any], limits: BaseModel) -> list[Problem]:
    """Problems with ``robot.limits`` as a task file gives them (``overrides``), once the robot's limits model read
    them (``limits``)."""
    problems = []
    for key, given in overrides.items():
        for suffix, raw, number in _numbers(given, getattr(limits, key)):
            message = _number_problem(raw, number, is_end=key.endswith((LOW, HIGH)))
            if message is not None:
                problems.append(Problem(path=f"robot.limits.{key}{suffix}", message=message))
    return problems or _range_problems(overrides, limits)


def _numbers(given: Any, value: Any) -> list[tuple[str, Any, float]]:
    """A limit's numbers, each with its index (``[1]``, or empty for a single number) and as the file gave it."""
    if _is_number(value):
        return [("", given, float(value))]
    if isinstance(value, tuple) and all(_is_number(v) for v in value):
        return [(f"[{i}]", raw, float(v)) for i, (raw, v) in enumerate(zip(given, value, strict=False))]
    return []


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _number_problem(raw: Any, number: float, is_end: bool) -> str | None:
    if isinstance(raw, bool):
        return f"a number is needed, not a boolean (got {str(raw).lower()})"
    if not math.isfinite(number):
        return f"must be a finite number (got {number})"
    if is_end and abs(number) > MAX_COORDINATE:
        return f"an end of a range lies within ±{MAX_COORDINATE:g} m (got {number:g})"
    if not is_end and not MIN_LIMIT <= number <= MAX_LENGTH:
        return f"a limit lies between {MIN_LIMIT:g} and {MAX_LENGTH:g} (m or kg; got {number:g})"
    return None


def _range_problems(overrides: Mapping[str, Any], limits: BaseModel) -> list[Problem]:
    """A range's low end (``<x>_min``) below its high end (``<x>_max``) on every axis, where the file gives either."""
    problems = []
    fields = type(limits).model_fields
    for low in (k for k in fields if k.endswith(LOW)):
        high = low.removesuffix(LOW) + HIGH
        if high not in fields or (low not in overrides and high not in overrides):
            continue
        low_end, high_end = getattr(limits, low), getattr(limits, high)
        if isinstance(low_end, tuple) and isinstance(high_end, tuple):
            pairs = [(f"[{i}]", a, b) for i, (a, b) in enumerate(zip(low_end, high_end, strict=False))]
        else:
            pairs = [("", low_end, high_end)]
        for suffix, a, b in pairs:
            if _is_number(a) and _is_number(b) and not a < b:
                message = f"must be below {high}{suffix} ({a:g} is not below {b:g})"
                problems.append(Problem(path=f"robot.limits.{low}{suffix}", message=message))
    return problems
