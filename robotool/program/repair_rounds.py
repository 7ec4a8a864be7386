"""Repair rounds: when no candidate succeeds in every world, show the model what the simulator measured.

After verification, the best-progressing failures (ranked as candidates are: goal sub-conditions met,
skill calls completed) are each given to the Repair stage with a compact :class:`FailureTrace` built from
their typed rollout records (never from reason text): the calls of the first failed world up to the first
that did not end ``done`` with their measured values, the goal sub-conditions missed, and in how many
worlds. The repairs of one round run concurrently; the repaired programs are verified together in one
batch; the loop stops at the first candidate that succeeds in every world, or when the rounds or the
token budget are spent. Repaired candidates join the others, so ranking never prefers a repair that did
worse over a better earlier candidate.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import dspy

from robotool import robots
from robotool.program.lm_calls import CallSettings, Salvage, StageFailed, call_stage, run_concurrently
from robotool.signatures.models import scene_context
from robotool.signatures.repair import ShownTrace
from robotool.signatures.traces import failure_trace
from robotool.solution import Candidate, CandidateFailure, RepairAttempt, RepairRound, rank
from robotool.task.task_model import Task
from robotool.verify import prepare_code


@dataclass(frozen=True)
class RepairBudget:
    """How much repairing one solve may do."""

    rounds: int
    width: int = 1
    """failures repaired per round (concurrently)"""
    tokens: int | None = None
    """no new round starts once the repair calls have used this many tokens"""


Propose = Callable[[Candidate, int], tuple[Candidate, RepairAttempt]]
"""Makes the repaired candidate with index ``index`` from a failed one (an LM call; not yet verified)."""


def repair_rounds(
    candidates: list[Candidate],
    propose: Propose,
    verify: Callable[[list[Candidate]], None],
    budget: RepairBudget,
) -> list[RepairRound]:
    """Run repair rounds (see the module docstring); repaired candidates are appended to ``candidates``."""
    rounds: list[RepairRound] = []
    repaired: set[int] = set()
    used = 0
    while len(rounds) < budget.rounds and not _solved(candidates):
        if budget.tokens is not None and used >= budget.tokens:
            break
        sources = _to_repair(candidates, repaired, budget.width)
        if not sources:
            break
        repaired |= {c.index for c in sources}
        first = max(c.index for c in candidates) + 1
        made = run_concurrently([functools.partial(propose, source, first + k) for k, source in enumerate(sources)])
        new = [candidate for candidate, _ in made]
        candidates += new
        verify(new)
        record = RepairRound(round=len(rounds) + 1)
        for candidate, attempt in made:
            attempt.success_rate, attempt.failure = candidate.success_rate, candidate.failure
            record.attempts.append(attempt)
            record.prompt_tokens += sum(call.prompt_tokens for call in candidate.lm_calls)
            record.completion_tokens += sum(call.completion_tokens for call in candidate.lm_calls)
        used += record.prompt_tokens + record.completion_tokens
        rounds.append(record)
    return rounds


def _solved(candidates: Sequence[Candidate]) -> bool:
    return any(c.rollouts and c.success_rate == 1.0 for c in candidates)


def _to_repair(candidates: list[Candidate], repaired: set[int], width: int) -> list[Candidate]:
    """The best-progressing failures with simulator evidence that were not repaired yet."""
    failures = [c for c in candidates if c.rollouts and c.success_rate < 1.0 and c.index not in repaired]
    return rank(failures)[:width]


def propose_repair(
    predictor: dspy.Predict,
    task: Task,
    description: str,
    source: Candidate,
    index: int,
    *,
    settings: CallSettings,
    config: dict[str, Any],
    salvage: Salvage | None = None,
) -> tuple[Candidate, RepairAttempt]:
    """Ask the Repair stage to fix ``source``; the new candidate keeps what the repair did not change.

    ``salvage`` reads the program from a reply that did not follow the answer format.
    """
    trace = failure_trace(source.rollouts)
    if trace is None:
        raise ValueError(f"candidate {source.index} has no failed world to repair")
    candidate = Candidate(index=index, stages=source.stages.model_copy(deep=True), repaired_from=source.index)
    attempt = RepairAttempt(source=source.index, candidate=index, shown=trace, scope=trace.scope)
    stages = candidate.stages

    def program_problem(out: dspy.Prediction) -> str | None:
        candidate.code, rejection, dropped = prepare_code(out.code, task)
        if dropped and f"repair: {dropped}" not in candidate.notes:
            candidate.notes.append(f"repair: {dropped}")
        return rejection

    inputs = {
        "description": description,
        "failed_steps": stages.steps or [],
        "failed_parameters": stages.parameters or [],
        "failed_code": source.code or "",
        "trace": ShownTrace(trace=trace),
    }
    try:
        with scene_context(task, robots.get(task.embodiment)):
            result = call_stage(
                predictor,
                "repair",
                inputs,
                settings=settings,
                candidate=index,
                config=config,
                salvage=salvage,
                check=program_problem,
            )
    except StageFailed as e:
        candidate.lm_calls += e.calls
        candidate.failure = CandidateFailure(stage="repair", kind="no_reply", reason=e.reason)
        return candidate, attempt
    candidate.lm_calls += result.calls
    candidate.notes += [f"repair: {note}" for note in result.notes]
    out = result.outputs
    attempt.diagnosis = out.get("diagnosis")
    revised_steps, revised_parameters = out.get("revised_steps"), out.get("revised_parameters")
    if revised_steps and trace.scope == "plan" and revised_steps != stages.steps:
        stages.steps = revised_steps
        attempt.changed.append("steps")
    elif revised_steps and revised_steps != stages.steps:
        candidate.notes.append("repair: the failure was numerical; the revised plan steps were not used")
    if revised_parameters and revised_parameters != stages.parameters:
        stages.parameters = revised_parameters
        attempt.changed.append("parameters")
    if candidate.code != source.code:
        attempt.changed.append("code")
    candidate.notes.append(f"repair of candidate {source.index}")
    return candidate, attempt
