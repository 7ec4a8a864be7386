"""The Repair stage: a failed candidate, what the simulator measured when it ran, and the fix."""

from __future__ import annotations

from typing import Any

import dspy

from robotool.rollout import SkillCall
from robotool.safe_text import model_text
from robotool.signatures.models import PlanStep, StepParameters
from robotool.signatures.traces import FailureTrace


class ShownTrace(dspy.Type):
    """A :class:`FailureTrace` as the Repair prompt shows it: numbered lines a person (and a model) can read."""

    trace: FailureTrace

    def format(self) -> str:
        t = self.trace
        lines = [f"The program ran in {t.worlds} perturbed world(s); the goal was missed in {t.failed_worlds}."]
        lines.append(f"World {t.world}, its skill calls up to the first that did not end 'done':")
        for call in t.calls:
            line = f"  {call.number}. {call.skill}({', '.join(_shown(a) for a in call.args)}) -> {call.outcome}"
            if call.reason:
                line += f": {model_text(call.reason)}"
            if call.measured:
                line += "; measured " + ", ".join(f"{k} = {_shown(v)}" for k, v in call.measured.items())
            if call.result is not None:
                line += f"; returned {_shown(call.result)}"
            lines.append(line)
        if not t.calls:
            lines.append("  (no skill call)")
        if t.events:
            shown = [SkillCall(skill=c.skill, args=c.args, outcome="done") for c in t.calls]
            lines.append("What the simulator recorded during them:")
            lines += [f"  - {event.describe(shown)}" for event in t.events]
        lines.append(f"The program made {t.calls_made} skill call(s) in that world in all.")
        if t.error:
            lines.append(f"The world ended with an error: {model_text(t.error)}")
        lines.append(f"Goal sub-conditions missed: {', '.join(t.conditions_missed) or 'none'}.")
        lines.append(f"Goal sub-conditions met: {', '.join(t.conditions_met) or 'none'}.")
        scope = (
            "parameters: the calls ran as planned and the failure is in the numbers; keep the plan steps"
            if t.scope == "parameters"
            else "plan: the plan steps may change"
        )
        lines.append(f"Scope of the repair: {scope}.")
        return "\n".join(lines)


def _shown(value: Any) -> str:
    """Numbers to the millimetre (or gram), lists in brackets, names quoted."""
    if isinstance(value, bool):
        return str(value)
    if isinstance(value, int | float):
        return f"{round(float(value), 3):g}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_shown(v) for v in value) + "]"
    return model_text(repr(value))


class Repair(dspy.Signature):
    """Repair a robot program that failed in simulation, using what the simulator measured.

    The trace shows the skill calls of a failed world up to the first one that did not work, with the
    values the simulator measured (for example a gap still too wide after a push, a distance a motion
    stopped short of its goal, a target outside the workspace) and the goal sub-conditions that were
    missed. Find the cause in the numbers, then give the revised plan steps and parameters and the
    complete new program. When the scope is 'parameters', keep the plan steps and change only the
    numbers. Call the skills as plain functions as in the description; only `import numpy as np` and
    `import math` are available. Helper functions (def) are allowed; classes, try/except, with statements
    and generators are not.
    """

    description: str = dspy.InputField(desc="the scene with its numbers, the robot's limits and skills, the task")
    failed_steps: list[PlanStep] = dspy.InputField(desc="the plan steps of the failed program; may be empty")
    failed_parameters: list[StepParameters] = dspy.InputField(desc="its step parameters; may be empty")
    failed_code: str = dspy.InputField(desc="the failed program")
    trace: ShownTrace = dspy.InputField(desc="what the simulator recorded when the program ran")
    diagnosis: str | None = dspy.OutputField(desc="what went wrong, in terms of the measured values")
    revised_steps: list[PlanStep] | None = dspy.OutputField(
        desc="the revised plan steps; leave empty when the scope is 'parameters'"
    )
    revised_parameters: list[StepParameters] | None = dspy.OutputField(desc="the revised step parameters")
    code: str = dspy.OutputField(desc="the complete revised Python program, and nothing else")
