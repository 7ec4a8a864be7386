"""Pydantic output models of the LM stages, validated against the task being solved.

DSPy does not enforce constraints written on output fields, so validation lives here. A stage's
reply must name real skills of the embodiment and real objects of the scene; the scene is made
known to the validators with :func:`scene_context` around the stage calls.
"""

from __future__ import annotations

import contextvars
import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from pydantic import BaseModel, Field, field_validator, model_validator

from robotool.concepts import KeyConcept
from robotool.embodiments import skill_names
from robotool.scene import Task

__all__ = ["KeyConcept", "ObjectRole", "PlanStep", "StepParameters", "scene_context"]


@dataclass(frozen=True)
class _Scene:
    skills: frozenset[str]
    objects: frozenset[str]


_SCENE: contextvars.ContextVar[_Scene | None] = contextvars.ContextVar("robotool_scene", default=None)


@contextmanager
def scene_context(task: Task) -> Iterator[None]:
    """Validate stage outputs against ``task`` (its skills and object names) inside this block."""
    token = _SCENE.set(_Scene(skill_names(task.embodiment), frozenset(task.object_names) | {"robot"}))
    try:
        yield
    finally:
        _SCENE.reset(token)


def _check_objects(names: list[str]) -> list[str]:
    scene = _SCENE.get()
    if scene is not None:
        unknown = [n for n in names if n not in scene.objects]
        if unknown:
            raise ValueError(f"unknown object(s) {unknown}; the scene has {sorted(scene.objects)}")
    return names


class ObjectRole(BaseModel):
    """What an object is like and what it could do for the task."""

    name: str = Field(description="an object of the scene")
    properties: str = Field(description="its relevant physical and geometric properties")
    role: str = Field(description="its possible role: target, tool (how), obstacle, or none")

    @field_validator("name")
    @classmethod
    def _known(cls, name: str) -> str:
        return _check_objects([name])[0]


class PlanStep(BaseModel):
    """One step of the plan: one skill call, the objects it involves and why."""

    skill: str = Field(description="the name of one of the robot's skills")
    objects: list[str] = Field(default_factory=list, description="objects this step involves")
    intent: str = Field(description="what the step achieves")

    @field_validator("skill")
    @classmethod
    def _real_skill(cls, skill: str) -> str:
        scene = _SCENE.get()
        if scene is not None and skill not in scene.skills:
            raise ValueError(f"unknown skill {skill!r}; the robot's skills are {sorted(scene.skills)}")
        return skill

    @field_validator("objects")
    @classmethod
    def _real_objects(cls, objects: list[str]) -> list[str]:
        return _check_objects(objects)


class StepParameters(BaseModel):
    """The numbers of one plan step: an absolute target, or an offset from an object's current centre."""

    step: int = Field(ge=1, description="the plan step these parameters belong to, counting from 1")
    object: str | None = Field(None, description="the object the skill acts on, if any")
    target: list[float] | None = Field(None, description="absolute target [x, y, z] in metres")
    relative_to: str | None = Field(
        None, description="an object whose centre, queried when the step runs, the offset is added to"
    )
    offset: list[float] | None = Field(None, description="[dx, dy, dz] in metres from relative_to's centre")
    explanation: str = Field("", description="how the numbers were derived")

    @field_validator("target", "offset")
    @classmethod
    def _vector(cls, value: list[float] | None) -> list[float] | None:
        if value is not None and (len(value) != 3 or not all(math.isfinite(v) for v in value)):
            raise ValueError(f"must be three finite numbers [x, y, z], got {value}")
        return value

    @model_validator(mode="after")
    def _names(self) -> StepParameters:
        _check_objects([n for n in (self.object, self.relative_to) if n is not None])
        if self.relative_to is not None and self.offset is None:
            raise ValueError("relative_to needs an offset")
        return self
