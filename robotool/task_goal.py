"""A task's goal: exactly one condition on one object (:class:`Goal`); which goals a robot has is its own
(``RobotType.goals``)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from robotool.scene import Name, PositiveLength, StrictModel

GoalKind = Literal["robot_on", "grasped", "pressed", "lifted", "lowered"]


class LiftGoal(StrictModel):
    object: Name
    height: PositiveLength


class LowerGoal(StrictModel):
    object: Name
    height: Annotated[float, Field(ge=0, allow_inf_nan=False)]


class Goal(StrictModel):
    """Exactly one goal condition."""

    robot_on: Name | None = None
    grasped: Name | None = None
    pressed: Name | None = None
    lifted: LiftGoal | None = None
    lowered: LowerGoal | None = None

    @model_validator(mode="after")
    def _exactly_one(self) -> Goal:
        given = [k for k in type(self).model_fields if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(
                "give exactly one of robot_on, grasped, pressed, lifted, lowered "
                f"(got {', '.join(sorted(given)) or 'none'})"
            )
        return self

    @property
    def kind(self) -> GoalKind:
        """Which goal this is."""
        for k in ("robot_on", "grasped", "pressed", "lifted", "lowered"):
            if getattr(self, k) is not None:
                return k
        raise AssertionError("validated goal has no kind")

    @property
    def object(self) -> str:
        """The object the goal is about."""
        value = getattr(self, self.kind)
        return value if isinstance(value, str) else value.object
