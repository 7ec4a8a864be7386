"""The Coder: a Python program that calls the robot's skills."""

from __future__ import annotations

import dspy

from robotool.signatures.models import PlanStep, StepParameters


class Code(dspy.Signature):
    """Write the Python program that completes the task by calling the robot's skills.

    Call the skills as plain functions, exactly as listed in the description. Query positions with the
    query skills right before a motion that depends on them, since objects move. Only `import numpy
    as np` and `import math` are available; no other imports, no file or network access. Helper functions
    (def) are allowed; classes, try/except, with statements and generators are not. Follow the plan steps
    and their parameters when they are given.
    """

    description: str = dspy.InputField(desc="the scene with its numbers, the robot's limits and skills, the task")
    steps: list[PlanStep] = dspy.InputField(desc="the plan steps; may be empty")
    parameters: list[StepParameters] = dspy.InputField(desc="numbers for the steps; may be empty")
    code: str = dspy.OutputField(desc="the Python program, and nothing else")
