"""A task's goal: exactly one condition on one object (:class:`Goal`); which goals a robot has is its own
(``RobotType.goals``)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from robotool.task.scene import MAX_LENGTH, NOT_BOOLEAN, Name, PositiveLength, StrictModel, number_text

GoalKind = Literal["robot_on", "grasped", "pressed", "lifted", "lowered"]


class LiftGoal(StrictModel):
    object: Name
    height: PositiveLength


class LowerGoal(StrictModel):
    object: Name
    height: Annotated[float, Field(ge=0, le=MAX_LENGTH, allow_inf_nan=False), NOT_BOOLEAN]


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

    def text(self) -> str:
        """The goal in a few words, for tables and pictures: ``robot on sofa_2``, ``vase lowered to <= 0.05 m``."""
        if self.lifted is not None:
            return f"{self.lifted.object} lifted to >= {number_text(self.lifted.height)} m"
        if self.lowered is not None:
            return f"{self.lowered.object} lowered to <= {number_text(self.lowered.height)} m"
        verbs = {"robot_on": "robot on", "grasped": "grasp", "pressed": "press"}
        return f"{verbs[self.kind]} {self.object}"

    def sentence(self, *, unbroken: bool = False) -> str:
        """The goal as the task's description states it to the model (``unbroken``: a fragile object must not
        break)."""
        if self.robot_on is not None:
            return f"The robot stands on top of {self.robot_on} at the end."
        if self.grasped is not None:
            return f"The gripper holds {self.grasped} at the end."
        if self.pressed is not None:
            return f"{self.pressed} is pressed at some moment."
        if self.lifted is not None:
            return (
                f"The bottom of {self.lifted.object} is at least {number_text(self.lifted.height)} m above where it "
                "started, at the end."
            )
        assert self.lowered is not None
        return (
            f"The bottom of {self.lowered.object} is at most {number_text(self.lowered.height)} m above the ground "
            f"at the end{', unbroken' if unbroken else ''}."
        )
