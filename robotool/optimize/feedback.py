"""Feedback for each stage from typed evidence: ground-truth key concepts, candidates and rollout traces.

Nothing here reads reason text back: the Analyzer is graded concept by concept against
:func:`robotool.task.concepts.key_concepts` (kind, value, verdict); each failed world is attributed to the
stage whose output it points at, from its :class:`~robotool.rollout.SkillCall` outcomes, measured values
and the tools it used (:func:`robotool.eval.failure_classes.classify`); programs the sandbox refuses are checked
again for their line. Texts the simulator or sandbox wrote (a refusal's reason) are quoted, never parsed.

Attribution of a failed world: a program that raised or made a call that errored -> Coder; the wrong
tools (one needed and none used, or one used where none was needed) -> Planner; a refused call -> Planner
(a step out of order or a limit ignored), except a refusal that measured what a tool's placement leaves (the
robot's ``placement_measures``: a step, gap or drop) after a tool was used -> Calculator (the tool was placed
where it leaves that gap); a stall, a timeout, a target clamped to the workspace or a call the robot reads as
a numerical miss (its ``numerical_hint``: a grasp that closed on nothing) -> Calculator; no abnormal call: no
motion or a needed tool
left unused -> Planner, else the goal missed by distance -> Calculator.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from robotool import robots
from robotool.eval.failure_classes import TaskFacts, classify, tools_used
from robotool.eval.grading import ABSOLUTE_TOLERANCE, RELATIVE_TOLERANCE, matches
from robotool.rollout import Rollout, SkillCall
from robotool.sandbox import ProgramRejected, validate
from robotool.solution import Candidate, Solution
from robotool.task.concepts import KeyConcept
from robotool.task.task_model import Task
from robotool.vocabulary import Stage, is_stage


@dataclass(frozen=True)
class StageFinding:
    """One piece of evidence about a stage's output, in a sentence a model can act on."""

    stage: Stage
    text: str


def _number(value: float, unit: str) -> str:
    return f"{value:.3g} {unit}"


def _verdict(concept: KeyConcept) -> str:
    return "within the limit" if concept.satisfied else "beyond the limit (a tool is needed)"


def concept_findings(truth: Sequence[KeyConcept], predicted: Sequence[KeyConcept] | None) -> list[StageFinding]:
    """The Analyzer's key concepts against the ground truth: what was missed, misjudged or misread."""
    if not truth:
        return []
    if not predicted:
        return [
            StageFinding("analyzer", f"no key concepts were given; the deciding quantity is {_truth(t)}") for t in truth
        ]
    findings = []
    for t in truth:
        if any(matches(t, p) for p in predicted):
            continue
        same_kind = [p for p in predicted if p.kind == t.kind]
        if not same_kind:
            findings.append(StageFinding("analyzer", f"missed a deciding quantity: {_truth(t)}"))
            continue
        p = min(same_kind, key=lambda c: abs(c.value - t.value))
        tolerance = max(RELATIVE_TOLERANCE * abs(t.value), ABSOLUTE_TOLERANCE.get(t.unit, 0.0))
        if abs(p.value - t.value) > tolerance:
            findings.append(
                StageFinding(
                    "analyzer",
                    f"wrong value for {t.kind} ('{p.name}'): you gave "
                    f"{_number(p.value, p.unit)}, the scene's geometry gives {_truth(t)}",
                )
            )
        if p.satisfied != t.satisfied:
            findings.append(
                StageFinding(
                    "analyzer",
                    f"misjudged the limit for {t.kind} ('{p.name}'): you said {_verdict(p)}, but {_truth(t)}",
                )
            )
    return findings


def _truth(t: KeyConcept) -> str:
    return f"{t.name} = {_number(t.value, t.unit)} against {t.limit_name} {_number(t.limit, t.unit)}, {_verdict(t)}"


def _call(call: SkillCall, index: int) -> str:
    args = ", ".join(repr(a) if isinstance(a, str) else str(a) for a in call.args)
    return f"call {index + 1}, {call.skill}({args})"


def _measured(call: SkillCall) -> str:
    shown = {k: v for k, v in call.measured.items() if not k.startswith(("target_", "clamped_"))}
    return ", ".join(f"{k} {v:.3f}" for k, v in shown.items())


def world_finding(rollout: Rollout, facts: TaskFacts) -> StageFinding | None:
    """The stage a failed world points at, with the evidence (None for a world that reached the goal)."""
    kind = classify(rollout, facts)
    if kind is None:
        return None
    where = f"world {rollout.world}"
    if kind == "invalid":
        bad = next((k for k, c in enumerate(rollout.calls) if c.outcome == "error"), None)
        if bad is not None:
            call = rollout.calls[bad]
            return StageFinding("coder", f"{where}: {_call(call, bad)} failed: {call.reason}")
        return StageFinding("coder", f"{where}: the program stopped with an error: {rollout.error}")
    used = tools_used(rollout, facts)
    robot = robots.get(facts.robot)
    if kind == "tool_use":
        if facts.needs_tool:
            needed = sorted(facts.needed or facts.tools)
            return StageFinding(
                "planner",
                f"{where}: the task needs a tool but the program used none of "
                f"{', '.join(needed) or 'the movable objects'}",
            )
        extra = sorted(used - (facts.needed or frozenset()))
        return StageFinding(
            "planner",
            f"{where}: a tool was used where none was needed ({', '.join(extra)}); "
            "the direct way is within the robot's limits",
        )
    for k, call in enumerate(rollout.calls):
        if call.outcome == "refused":
            values = _measured(call)
            evidence = f"{_call(call, k)} was refused: {call.reason}" + (f" (measured: {values})" if values else "")
            left_by_tool = bool(used) and any(m in call.measured for m in robot.feedback.placement_measures)
            stage: Stage = "calculator" if left_by_tool else "planner"
            placed = "; the tool was placed so that this is left" if stage == "calculator" else ""
            return StageFinding(stage, f"{where}: {evidence}{placed}")
        if call.outcome in ("stalled", "timeout") or call.measured.get("outside_workspace", 0.0) > 0.0:
            values = _measured(call)
            return StageFinding(
                "calculator",
                f"{where}: {_call(call, k)} ended {call.outcome}: {call.reason}"
                + (f" (measured: {values})" if values else ""),
            )
        hint = robot.feedback.numerical_hint(call) if kind == "numerical" and call.outcome == "done" else None
        if hint is not None:
            return StageFinding("calculator", f"{where}: {_call(call, k)} {hint}")
    unmet = [name for name, ok in rollout.conditions.items() if not ok]
    if kind == "logical":
        missing = sorted((facts.needed or frozenset()) - used)
        what = f"the needed tool(s) {', '.join(missing)} were never used" if missing else "no motion was made"
        return StageFinding("planner", f"{where}: a step is missing: {what}")
    return StageFinding(
        "calculator",
        f"{where}: every step ran but the goal was missed by distance; unmet: {', '.join(unmet) or 'the goal'}",
    )


def candidate_findings(task: Task, candidate: Candidate, facts: TaskFacts) -> list[StageFinding]:
    """Evidence from one candidate: the stage that gave no usable reply, a refused program, failed worlds."""
    failure = candidate.failure
    if failure is not None and failure.kind in ("no_reply", "fault") and is_stage(failure.stage):
        stage = failure.stage
        if stage == "coder" and candidate.code is not None:
            try:
                validate(candidate.code, task.embodiment)
            except ProgramRejected as e:
                line = f"line {e.line} (`{e.construct}`)" if e.line else f"`{e.construct}`"
                return [StageFinding("coder", f"the sandbox refused the program at {line}: {e.reason}")]
        return [StageFinding(stage, f"the {stage} gave no usable reply: {candidate.failure}")]
    return [f for r in candidate.rollouts if (f := world_finding(r, facts)) is not None]


def findings(
    task: Task, solution: Solution, facts: TaskFacts, truth: Sequence[KeyConcept], analyzed: bool
) -> list[StageFinding]:
    """Every finding of a verified proposal: the Analyzer's concepts (when it ran), then the chosen candidate's."""
    found = concept_findings(truth, solution.stages.key_concepts) if analyzed else []
    chosen = solution.candidates[solution.best] if solution.best is not None else None
    candidates = [chosen] if chosen is not None else solution.candidates
    return found + [f for c in candidates for f in candidate_findings(task, c, facts)]


NAMES: dict[Stage, str] = {"analyzer": "Analyzer", "planner": "Planner", "calculator": "Calculator", "coder": "Coder"}
DUTY: dict[Stage, str] = {
    "analyzer": "the key concepts that decide whether a tool is needed",
    "planner": "which objects to use and the order of the steps",
    "calculator": "the numbers of each step",
    "coder": "the program text",
}


def stage_feedback(stage: Stage, score: float, worlds: int, found: Sequence[StageFinding]) -> str:
    """The feedback for one stage: the outcome, then the evidence about its output, then the rest in brief."""
    outcome = (
        f"The best program reached the goal in {round(score * worlds)} of {worlds} perturbed simulated "
        f"world(s) (score {score:.2f})."
    )
    mine = [f.text for f in found if f.stage == stage]
    others = [f for f in found if f.stage != stage]
    lines = [outcome]
    if mine:
        lines.append(f"About the {NAMES[stage]}'s output ({DUTY[stage]}):")
        lines += [f"- {text}" for text in dict.fromkeys(mine)]
    elif score < 1.0:
        lines.append(f"Nothing points at the {NAMES[stage]}'s output ({DUTY[stage]}).")
    else:
        lines.append(f"The {NAMES[stage]}'s output worked; keep what made it work.")
    if others:
        blamed = sorted({NAMES[f.stage] for f in others})
        lines.append(
            f"Other failures point at the {', '.join(blamed)}: " + "; ".join(dict.fromkeys(f.text for f in others[:3]))
        )
    return "\n".join(lines)
