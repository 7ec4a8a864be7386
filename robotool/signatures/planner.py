"""The Planner: object roles, an abstract plan, and one plan step per skill call."""

from __future__ import annotations

import dspy

from robotool.signatures.models import KeyConcept, ObjectRole, PlanStep


class Plan(dspy.Signature):
    """Plan how the robot completes the task with its skills.

    First describe each object's properties and the role it could play. Where a key concept shows a
    limit that makes the direct way impossible, use objects in the scene as tools: as a stepping
    stone, a bridge, a hook to pull with, a stick to push with, parts to assemble into a longer tool,
    a lever. Use as few objects as the task needs, and none when the direct way works. Then give an
    abstract plan and the plan steps, one skill call each, in order.
    """

    description: str = dspy.InputField(desc="the scene with its numbers, the robot's limits and skills, the task")
    key_concepts: list[KeyConcept] = dspy.InputField(desc="the analysis of feasibility; may be empty")
    object_roles: list[ObjectRole] | None = dspy.OutputField(desc="every relevant object's properties and role")
    abstract_plan: str | None = dspy.OutputField(desc="the plan in a few sentences")
    steps: list[PlanStep] = dspy.OutputField(desc="one skill call per step, in order")
