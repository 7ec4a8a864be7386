"""The whole task file (format 1) as a model: the robot, the scene's objects and the goal (:class:`Task`)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

import yaml
from pydantic import BaseModel, BeforeValidator, Field, StringConstraints

from robotool.robots.limits_table import limits_model
from robotool.task.scene import Coordinate, Name, SceneObject, StrictModel
from robotool.task.task_goal import Goal

MAX_OBJECTS = 200
"""The most objects a task may hold. The built-in tasks hold 3 to 8 and the generated ones, distractors included, a
dozen; every object adds a body to the simulated scene and to each check of how objects rest and overlap, so a file of
thousands (3000 stacked boxes took minutes to load) is refused at once rather than loaded."""
WHY_MAX_OBJECTS = "a real task holds a few dozen at most"


def _integer(value: object) -> object:
    """The format is the integer 1: true and 1.0, which pydantic would read as 1, are refused."""
    if isinstance(value, bool | float):
        written = str(value).lower() if isinstance(value, bool) else value
        raise ValueError(f"the format is the integer 1 (got {written})")
    return value


Category = Literal["tool_selection", "sequential_tool_use", "tool_manufacturing", "no_tool"]


class Robot(StrictModel):
    """The robot: its type (a registered robot, see :mod:`robotool.robots`; the task-file checks refuse others),
    start position and limit overrides."""

    type: str
    position: tuple[Coordinate, Coordinate] | None = None
    limits: dict[str, Any] = Field(default_factory=dict)

    def required_position(self) -> tuple[float, float]:
        """The start position, for a robot type whose task-file checks require one (ValueError when absent)."""
        if self.position is None:
            raise ValueError(f"the {self.type} robot has no start position")
        return self.position


class Task(StrictModel):
    """A whole task file (format 1)."""

    format: Annotated[Literal[1], BeforeValidator(_integer)]
    name: Name
    category: Category
    instruction: Annotated[str, StringConstraints(min_length=1, strip_whitespace=True)]
    robot: Robot
    objects: list[SceneObject] = Field(max_length=MAX_OBJECTS)
    goal: Goal

    @property
    def embodiment(self) -> str:
        """The robot type's name."""
        return self.robot.type

    @property
    def limits(self) -> BaseModel:
        """The robot's limits with this task's overrides applied (its type's limits model)."""
        return limits_model(self.robot.type)(**self.robot.limits)

    def object(self, name: str) -> SceneObject:
        """The object with this name (KeyError naming the known objects otherwise)."""
        for obj in self.objects:
            if obj.name == name:
                return obj
        raise KeyError(f"no object named {name!r}; objects: {', '.join(self.object_names)}")

    @property
    def object_names(self) -> list[str]:
        return [o.name for o in self.objects]

    def to_yaml(self) -> str:
        """The task as a YAML task file."""
        data = self.model_dump(mode="json", exclude_defaults=True)
        data["format"] = 1
        return yaml.safe_dump(data, sort_keys=False)
