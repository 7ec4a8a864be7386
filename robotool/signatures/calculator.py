"""The Calculator: the numeric parameters of each plan step."""

from __future__ import annotations

import dspy

from robotool.signatures.models import KeyConcept, PlanStep, StepParameters


class Calculate(dspy.Signature):
    """Compute the numeric parameters of each plan step that needs them.

    Give target positions in metres. Where an object may have moved by the time the step runs, give
    the target as an offset from that object's centre (relative_to + offset), to be queried then;
    otherwise give an absolute target. Account for object sizes: push from the far side, stand fully
    on a surface, leave clearance so parts do not collide.
    """

    description: str = dspy.InputField(desc="the scene with its numbers, the robot's limits and skills, the task")
    key_concepts: list[KeyConcept] = dspy.InputField(desc="the analysis of feasibility; may be empty")
    steps: list[PlanStep] = dspy.InputField(desc="the plan steps, numbered from 1 in order")
    calculation: str | None = dspy.OutputField(desc="how the numbers were derived")
    parameters: list[StepParameters] = dspy.OutputField(desc="parameters of each step that needs numbers")
