"""What a skill is, and the checks every skill call's arguments pass, whichever robot it belongs to.

Each robot lists its skills as :class:`SkillSpec` records in its own package (``robotool/robots/<name>/``);
the sandbox, the description, the simulator and the signatures' validation all read that one list through
the registry (:mod:`robotool.robots.registry`).
"""

from __future__ import annotations

import math
import numbers
import reprlib
from dataclasses import dataclass
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field


class SkillSpec(BaseModel):
    """One parameterized skill: its Python signature and its exact meaning."""

    model_config = ConfigDict(frozen=True)

    name: str
    params: tuple[tuple[str, str], ...] = Field(
        description="(parameter name, type) pairs; types are 'name', 'position' or 'angle' (degrees)"
    )
    returns: str
    kind: Literal["query", "motion"]
    semantics: str

    @property
    def signature(self) -> str:
        """The call as a user writes it, e.g. ``walk_to_position(position)``."""
        return f"{self.name}({', '.join(p for p, _ in self.params)})"


QUERY_NAME = (("name", "name"),)
"""The parameters of a query about one object."""
POSITION = (("position", "position"),)
"""The parameters of a motion to one position."""
HEADING = (("heading", "angle"),)
"""The parameters of a turn to one heading (degrees about z)."""


class SkillArgumentError(ValueError):
    """A skill was called with arguments it cannot take; the message says which and why."""


MAX_DISTANCE_FROM_SCENE = 5.0
"""How far (m) a position argument may lie outside the box around the scene's objects, the robot and
its workspace: farther is refused as a mistake (a wrong unit, a runaway computation), never simulated."""


@dataclass(frozen=True)
class SceneBox:
    """The axis-aligned box (m) around a scene: its objects, the robot's start and what the robot can reach."""

    lo: tuple[float, float, float]
    hi: tuple[float, float, float]

    def distance(self, point: tuple[float, float, float]) -> float:
        """How far ``point`` lies outside the box (0 inside)."""
        gaps = (max(lo - p, 0.0, p - hi) for p, lo, hi in zip(point, self.lo, self.hi, strict=True))
        return math.sqrt(sum(g * g for g in gaps))


def check_arguments(spec: SkillSpec, args: tuple[object, ...], scene: SceneBox | None = None) -> tuple[object, ...]:
    """Check a call of ``spec``'s arguments and return them normalized (positions as 3 floats).

    Raises :class:`SkillArgumentError` for a wrong argument count, a name that is not a string, an angle that
    is not one finite number, a position that is not three finite numbers, or (given the ``scene``'s box) a
    position more than :data:`MAX_DISTANCE_FROM_SCENE` outside it. A 2-number position gets z = 0.
    """
    name = spec.name
    if len(args) != len(spec.params):
        raise SkillArgumentError(f"{spec.signature} takes {len(spec.params)} argument(s), got {len(args)}")
    out: list[object] = []
    for (param, kind), value in zip(spec.params, args, strict=True):
        if kind == "name":
            if not isinstance(value, str):
                raise SkillArgumentError(f"{name}: {param} must be an object name, got {_shown(value)}")
            out.append(value)
            continue
        if kind == "angle":
            out.append(_angle(name, param, value))
            continue
        position = _position(name, param, value)
        if scene is not None and scene.distance(position) > MAX_DISTANCE_FROM_SCENE:
            shown = ", ".join(f"{v:.4g}" for v in position)
            raise SkillArgumentError(
                f"{name}: {param} [{shown}] is {scene.distance(position):.3g} m outside the scene (more than "
                f"{MAX_DISTANCE_FROM_SCENE:g} m); positions are in metres"
            )
        out.append(position)
    return tuple(out)


def _shown(value: object) -> str:
    """A short repr of a program's argument; an integer too long for decimal text is described instead."""
    try:
        return reprlib.repr(value)
    except ValueError:  # Python refuses to turn an integer of more than 4300 digits into text
        return f"a {type(value).__name__} too large to show"


def _angle(skill: str, param: str, value: object) -> float:
    """An angle argument in degrees: one finite real number (not text or a truth value)."""
    if not isinstance(value, numbers.Real) or isinstance(value, bool | np.bool_):
        raise SkillArgumentError(f"{skill}: {param} must be a number of degrees, got {_shown(value)}")
    try:
        angle = float(value)
    except OverflowError:  # an integer beyond any float
        angle = math.inf
    if not math.isfinite(angle):
        raise SkillArgumentError(f"{skill}: {param} must be a finite number of degrees, got {_shown(value)}")
    return angle


def _position(skill: str, param: str, value: object) -> tuple[float, float, float]:
    """A position argument: a list, tuple or 1-D array of 2 or 3 numbers (not text, truth values, sets or
    mappings, which ``float`` would quietly accept or order at random)."""
    wrong = SkillArgumentError(f"{skill}: {param} must be [x, y, z] in metres, got {_shown(value)}")
    if isinstance(value, np.ndarray) and value.ndim != 1:
        raise wrong
    if not isinstance(value, list | tuple | np.ndarray) or len(value) not in (2, 3):
        raise wrong
    if not all(isinstance(v, numbers.Real) and not isinstance(v, bool | np.bool_) for v in value):
        raise wrong
    try:
        items = [float(v) for v in value]
    except OverflowError:  # an integer beyond any float
        raise wrong from None
    if not all(math.isfinite(v) for v in items):
        raise SkillArgumentError(f"{skill}: {param} must be finite, got {items}")
    if len(items) == 2:
        items.append(0.0)
    return (items[0], items[1], items[2])
