"""The Analyzer: the key concepts that decide whether the task is feasible without tools."""

from __future__ import annotations

import dspy

from robotool.signatures.models import AnalyzedConcept


class Analyze(dspy.Signature):
    """Analyze a robot task before any planning.

    Identify the key concepts that decide whether the robot can complete the task directly, without
    using other objects as tools: distances, heights to climb, gaps to cross, masses to push, reach
    outside the workspace, heights something would fall. Use the numbers given, and compute implicit
    ones (for example the gap between two objects from their centres and sizes). Compare each value
    with the robot or object limit it must respect and say whether the limit is met.
    """

    description: str = dspy.InputField(desc="the scene with its numbers, the robot's limits and skills, the task")
    analysis: str | None = dspy.OutputField(desc="short reasoning that leads to the key concepts")
    key_concepts: list[AnalyzedConcept] = dspy.OutputField(desc="the quantities that decide feasibility")
