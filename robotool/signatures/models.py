"""Pydantic output models of the LM stages, validated against the task being solved.

DSPy does not enforce constraints written on output fields, so validation lives here. It is lenient
where a reply's meaning is clear and strict where it matters:

- numbers may carry a unit (``"0.4 m"``, ``"40 cm"``, ``"2 kg"``); lengths become metres, masses kilograms;
  numbers that are not finite are rejected;
- a 2-D ``[x, y]`` target or offset for a robot whose motions ignore z (``RobotType.rules.planar``) gets z = 0; for
  the others it is rejected, since its height matters;
- object names match case-, space- and separator-insensitively when exactly one scene object fits
  (``"Yoga Roller"`` is ``yoga_roller``), with a note;
- names that a plan step or an object role mentions only for information (``"gap"``, ``"floor"``) and that are
  not objects of the scene are ignored with a note;
- a key concept's kind is read by meaning (``"gap"`` is ``gap_width``) with a note, and one that names no known
  kind is rejected; a missing ``limit_name`` is left empty and a missing ``satisfied`` is read from
  ``value <= limit``;
- known synonyms of a step parameter's fields (``"position"`` for ``"target"``) are read as the field with a
  note; a step with no numbers (no target and no offset) is rejected, naming the fields that were not read;
- skills that do not exist, and unknown objects in the parameters a skill acts on, are rejected.

The scene is made known to the validators with :func:`scene_context` around the stage calls; the notes
about what was repaired or ignored are collected by :func:`validation_notes`.
"""

from __future__ import annotations

import contextvars
import math
import numbers
import re
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Annotated, Any, Protocol, get_args

from pydantic import BaseModel, BeforeValidator, Field, field_validator, model_validator

from robotool.task.key_concept import ConceptKind, KeyConcept
from robotool.task.task_model import Task

__all__ = [
    "AnalyzedConcept",
    "KeyConcept",
    "ObjectRole",
    "PlanStep",
    "StepParameters",
    "parse_quantity",
    "scene_context",
    "validation_notes",
]


@dataclass(frozen=True)
class _Scene:
    planar: bool
    skills: frozenset[str]
    objects: frozenset[str]


_SCENE: contextvars.ContextVar[_Scene | None] = contextvars.ContextVar("robotool_scene", default=None)
_NOTES: contextvars.ContextVar[list[str] | None] = contextvars.ContextVar("robotool_notes", default=None)


class MotionFacts(Protocol):
    """Whether a robot's motions ignore z (a 2-D target gets z = 0): its :class:`robotool.robots.TaskRules`."""

    @property
    def planar(self) -> bool: ...


class RobotFacts(Protocol):
    """What validation needs of the task's robot (a :class:`robotool.robots.RobotType` has it)."""

    @property
    def rules(self) -> MotionFacts:
        """Its task rules (whether its motions ignore z)."""

    @property
    def skill_names(self) -> frozenset[str]:
        """Its skills' names."""


@contextmanager
def scene_context(task: Task, robot: RobotFacts) -> Iterator[None]:
    """Validate stage outputs against ``task`` (its robot's skills, its object names) inside this block;
    ``robot`` is the task's robot type (``robotool.robots.get(task.embodiment)``)."""
    scene = _Scene(robot.rules.planar, robot.skill_names, frozenset(task.object_names) | {"robot"})
    token = _SCENE.set(scene)
    try:
        yield
    finally:
        _SCENE.reset(token)


@dataclass
class NoteSink:
    """Notes on what validation repaired or ignored, in the order they arose."""

    notes: list[str] = field(default_factory=list)


@contextmanager
def validation_notes() -> Iterator[NoteSink]:
    """Collect the notes that validators write inside this block."""
    sink = NoteSink()
    token = _NOTES.set(sink.notes)
    try:
        yield sink
    finally:
        _NOTES.reset(token)


def _note(text: str) -> None:
    notes = _NOTES.get()
    if notes is not None and text not in notes:
        notes.append(text)


def _squashed(name: str) -> str:
    return re.sub(r"[\s_\-.]+", "", name.lower())


def _scene_name(name: str, scene: _Scene) -> str:
    """The scene object ``name`` means: itself, or the one object whose name is the same once case, spaces and
    separators are ignored (with a note); else ``name`` unchanged."""
    if name in scene.objects:
        return name
    fits = [o for o in scene.objects if _squashed(o) == _squashed(name)]
    if len(fits) == 1:
        _note(f"object {name!r} read as {fits[0]!r}")
        return fits[0]
    return name


def _check_objects(names: list[str]) -> list[str]:
    """``names`` as scene objects (see :func:`_scene_name`); raises ValueError naming every unknown one."""
    scene = _SCENE.get()
    if scene is None:
        return names
    names = [_scene_name(n, scene) for n in names]
    unknown = [n for n in names if n not in scene.objects]
    if unknown:
        raise ValueError(f"unknown object(s) {unknown}; the scene has {sorted(scene.objects)}")
    return names


def _informational(names: list[str], where: str) -> list[str]:
    """Names of scene objects among ``names`` (see :func:`_scene_name`); the others are dropped with a note."""
    scene = _SCENE.get()
    if scene is None:
        return names
    names = [_scene_name(n, scene) for n in names]
    unknown = [n for n in names if n not in scene.objects]
    if unknown:
        _note(f"{where} names {', '.join(map(repr, unknown))}, not object(s) of the scene; ignored")
    return [n for n in names if n in scene.objects]


_UNITS: dict[str, tuple[str, float]] = {
    "m": ("m", 1.0),
    "meter": ("m", 1.0),
    "meters": ("m", 1.0),
    "metre": ("m", 1.0),
    "metres": ("m", 1.0),
    "cm": ("m", 0.01),
    "centimeter": ("m", 0.01),
    "centimeters": ("m", 0.01),
    "centimetre": ("m", 0.01),
    "centimetres": ("m", 0.01),
    "mm": ("m", 0.001),
    "millimeter": ("m", 0.001),
    "millimeters": ("m", 0.001),
    "millimetre": ("m", 0.001),
    "millimetres": ("m", 0.001),
    "kg": ("kg", 1.0),
    "kilogram": ("kg", 1.0),
    "kilograms": ("kg", 1.0),
    "g": ("kg", 0.001),
    "gram": ("kg", 0.001),
    "grams": ("kg", 0.001),
}
_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z]*)\s*$")


def parse_quantity(value: Any) -> tuple[float, str | None]:
    """A finite number and its SI unit (None when none was written) from a number or text like ``"40 cm"``."""
    if isinstance(value, bool):
        raise ValueError(f"expected a number, got {value!r}")
    if isinstance(value, numbers.Real):
        number, unit = float(value), None
    elif isinstance(value, str):
        match = _QUANTITY.match(value.replace(",", ""))
        if match is None and value.strip().lower().lstrip("+-") in ("inf", "infinity", "nan"):
            raise ValueError(f"must be a finite number, got {value!r}")
        if match is None:
            raise ValueError(f"expected a number, optionally with a unit such as m, cm or kg; got {value!r}")
        number, written = float(match.group(1)), match.group(2).lower()
        if written and written not in _UNITS:
            raise ValueError(f"unknown unit {match.group(2)!r} in {value!r}; use m, cm, mm, kg or g")
        unit, scale = _UNITS[written] if written else (None, 1.0)
        number *= scale
    else:
        raise ValueError(f"expected a number, got {value!r}")
    if not math.isfinite(number):
        raise ValueError(f"must be a finite number, got {value!r}")
    return number, unit


def _number(value: Any) -> float:
    return parse_quantity(value)[0]


Number = Annotated[float, BeforeValidator(_number)]
"""A finite float that may be written with a unit; the unit is converted to SI."""


class AnalyzedConcept(KeyConcept):
    """A key concept as the Analyzer states it: numbers may carry units; ``limit_name`` and ``satisfied``
    may be left out (``satisfied`` then means ``value <= limit``)."""

    value: Number = Field(description="the measured value")
    limit: Number = Field(description="the robot or object limit it is compared with")
    limit_name: str = Field("", description="which limit, e.g. 'max_gap' or 'workspace'")

    @model_validator(mode="before")
    @classmethod
    def _lenient(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        data = dict(data)
        if isinstance(data.get("kind"), str):
            data["kind"] = _concept_kind(data["kind"])
        try:
            numbers = {key: parse_quantity(data[key]) for key in ("value", "limit") if data.get(key) is not None}
        except ValueError:
            return data  # the field validators say which number is wrong
        written = {unit for _, unit in numbers.values() if unit is not None}
        if len(written) > 1:
            raise ValueError(f"value and limit are in different units ({', '.join(sorted(written))})")
        data |= {key: number for key, (number, _) in numbers.items()}
        if written:
            data["unit"] = written.pop()
        elif isinstance(data.get("unit"), str) and data["unit"].strip().lower() in _UNITS:
            unit, scale = _UNITS[data["unit"].strip().lower()]  # plain numbers in the unit the field names
            data |= {key: number * scale for key, (number, _) in numbers.items()} | {"unit": unit}
        if data.get("satisfied") is None and len(numbers) == 2:
            data["satisfied"] = data["value"] <= data["limit"]
            _note(f"key concept {data.get('name', '?')!r} gave no verdict; read as value <= limit")
        return data


_KINDS: frozenset[str] = frozenset(get_args(ConceptKind))


_KIND_WORDS: dict[str, frozenset[str]] = {
    "workspace_excess": frozenset({"workspace", "reach", "reachability", "reachable", "arm_reach"}),
    "climb_height": frozenset({"climb", "climbing", "step_up", "stepup", "step"}),
    "drop_height": frozenset({"drop", "step_down", "stepdown", "descent", "descend"}),
    "gap_width": frozenset({"gap", "gaps", "width", "span", "crossing"}),
    "mass": frozenset({"mass", "weight", "payload", "heavy"}),
    "fall_height": frozenset({"fall", "falling"}),
    "lift_height": frozenset({"lift", "lifting"}),
}
"""Words that name each kind by meaning; a kind written otherwise is read as the one kind its words name."""


def _concept_kind(text: str) -> str:
    """``"Gap width"`` -> ``gap_width``, ``"gap"`` -> ``gap_width`` (with a note); raises ValueError for a kind
    whose words name no known kind, or several."""
    kind = re.sub(r"[\s\-]+", "_", text.strip().lower())
    if kind in _KINDS:
        return kind
    words = set(kind.split("_")) | {kind}
    meant = [known for known, synonyms in _KIND_WORDS.items() if words & synonyms]
    if len(meant) == 1:
        _note(f"key concept kind {text!r} read as {meant[0]!r}")
        return meant[0]
    raise ValueError(f"kind {text!r} is not one of {', '.join(sorted(_KINDS))} (use 'other' if none fits)")


class ObjectRole(BaseModel):
    """What an object is like and what it could do for the task."""

    name: str = Field(description="an object of the scene")
    properties: str = Field("", description="its relevant physical and geometric properties")
    role: str = Field("", description="its possible role: target, tool (how), obstacle, or none")

    @field_validator("name")
    @classmethod
    def _known(cls, name: str) -> str:
        known = _informational([name], "an object role")
        return known[0] if known else name


class PlanStep(BaseModel):
    """One step of the plan: one skill call, the objects it involves and why."""

    skill: str = Field(description="the name of one of the robot's skills")
    objects: list[str] = Field(default_factory=list, description="objects this step involves")
    intent: str = Field("", description="what the step achieves")

    @field_validator("skill", mode="before")
    @classmethod
    def _call_to_name(cls, skill: Any) -> Any:
        """``"move_to_position(p)"`` or ``" open_gripper() "`` names the skill."""
        call = re.fullmatch(r"\s*([A-Za-z_]\w*)\s*(?:\(.*\))?\s*", skill, re.DOTALL) if isinstance(skill, str) else None
        return call.group(1) if call else skill

    @field_validator("skill")
    @classmethod
    def _real_skill(cls, skill: str) -> str:
        scene = _SCENE.get()
        if scene is not None and skill not in scene.skills:
            raise ValueError(f"unknown skill {skill!r}; the robot's skills are {sorted(scene.skills)}")
        return skill

    @field_validator("objects", mode="before")
    @classmethod
    def _one_or_many(cls, objects: Any) -> Any:
        return [objects] if isinstance(objects, str) else objects

    @field_validator("objects")
    @classmethod
    def _scene_objects(cls, objects: list[str]) -> list[str]:
        return _informational(objects, "a plan step")


class StepParameters(BaseModel):
    """The numbers of one plan step: an absolute target, or an offset from an object's current centre."""

    step: int = Field(ge=1, description="the plan step these parameters belong to, counting from 1")
    object: str | None = Field(None, description="the object the skill acts on, if any")
    target: list[Number] | None = Field(None, description="absolute target [x, y, z] in metres")
    relative_to: str | None = Field(
        None, description="an object whose centre, queried when the step runs, the offset is added to"
    )
    offset: list[Number] | None = Field(None, description="[dx, dy, dz] in metres from relative_to's centre")
    explanation: str = Field("", description="how the numbers were derived")

    @field_validator("target", "offset")
    @classmethod
    def _vector(cls, value: list[float] | None) -> list[float] | None:
        if value is None:
            return None
        scene = _SCENE.get()
        if len(value) == 2 and scene is not None and scene.planar:
            return [*value, 0.0]  # the robot's motions ignore z
        if len(value) != 3:
            raise ValueError(f"must be three numbers [x, y, z] in metres, got {value}")
        return value

    @model_validator(mode="wrap")
    @classmethod
    def _numbers_and_names(cls, data: Any, handler: Any) -> StepParameters:
        """Known synonyms of the fields are read as the fields (with a note); a step must carry numbers and name
        scene objects (see :func:`_check_objects`)."""
        ignored: list[str] = []
        if isinstance(data, dict):
            data = {re.sub(r"[\s\-]+", "_", str(k).strip().lower()): v for k, v in data.items()}
            for synonym in [k for k in data if k in _PARAMETER_SYNONYMS]:
                field_name = _PARAMETER_SYNONYMS[synonym]
                if data.get(field_name) is not None:
                    raise ValueError(f"both {field_name!r} and {synonym!r} are given; give only {field_name!r}")
                data[field_name] = data.pop(synonym)
                _note(f"step parameter {synonym!r} read as {field_name!r}")
            ignored = sorted(k for k in data if k not in cls.model_fields)
        self = handler(data)
        if self.target is None and self.offset is None:
            unread = f"; the field(s) {', '.join(map(repr, ignored))} are not parameters" if ignored else ""
            raise ValueError(
                f"step {self.step} has no numbers: target and offset are both empty{unread}; give target "
                "[x, y, z], or relative_to and offset"
            )
        if ignored:
            _note(f"step {self.step}: field(s) {', '.join(map(repr, ignored))} are not parameters; ignored")
        if self.object is not None:
            self.object = _check_objects([self.object])[0]
        if self.relative_to is not None:
            self.relative_to = _check_objects([self.relative_to])[0]
        if self.relative_to is not None and self.offset is None:
            raise ValueError("relative_to needs an offset")
        return self


_PARAMETER_SYNONYMS: dict[str, str] = {
    **dict.fromkeys(
        ("position", "target_position", "goal", "goal_position", "coordinates", "point", "location", "xyz"), "target"
    ),
    **dict.fromkeys(("delta", "displacement", "relative_offset"), "offset"),
    **dict.fromkeys(("reference", "reference_object", "relative_object", "relative", "anchor"), "relative_to"),
    **dict.fromkeys(("object_name", "obj", "target_object", "item"), "object"),
    **dict.fromkeys(("step_number", "step_index", "step_id"), "step"),
    **dict.fromkeys(("reason", "reasoning", "rationale", "derivation"), "explanation"),
}
"""Field names real models write for the step parameters' fields."""
