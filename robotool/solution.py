"""What solving a task returns: the best program, every candidate with its rollouts, and the stages."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field, computed_field

from robotool.rollout import Rollout
from robotool.signatures.models import KeyConcept, ObjectRole, PlanStep, StepParameters
from robotool.signatures.traces import FailureTrace, RepairScope
from robotool.vocabulary import CallingStage, FailureStage

FailureKind = Literal["no_reply", "fault", "rejected", "worlds_failed"]


class CandidateFailure(BaseModel):
    """Why a candidate failed, as a typed record; ``str()`` renders it for people, and nothing reads that back.

    ``kind`` says what happened at ``stage``: an LM stage or the repair stage gave no usable reply
    (``no_reply``) or raised (``fault``); the sandbox rejected the search planner's code (``rejected``, stage
    ``search``); or the program ran and ``failed_worlds`` of its ``worlds`` perturbed worlds missed the goal
    (``worlds_failed``, stage ``simulation``; ``world`` is the first that did). ``reason`` is the words: the
    stage's problem, the sandbox's rejection, or why the first failed world failed.
    """

    stage: FailureStage
    kind: FailureKind
    reason: str
    failed_worlds: int | None = None
    worlds: int | None = None
    world: int | None = None

    def __str__(self) -> str:
        if self.kind == "worlds_failed":
            return f"{self.failed_worlds}/{self.worlds} worlds failed; world {self.world}: {self.reason}"
        if self.kind == "rejected":
            return f"planner produced invalid code: {self.reason}"
        return f"{self.stage}: {self.reason}"


class StageOutputs(BaseModel):
    """The typed outputs of the stages that ran (None for a stage that did not)."""

    analysis: str | None = None
    key_concepts: list[KeyConcept] | None = None
    object_roles: list[ObjectRole] | None = None
    abstract_plan: str | None = None
    steps: list[PlanStep] | None = None
    calculation: str | None = None
    parameters: list[StepParameters] | None = None


class TokenUsage(BaseModel):
    """Tokens a stage used, summed over its LM calls."""

    prompt_tokens: int = 0
    completion_tokens: int = 0

    def __add__(self, other: TokenUsage) -> TokenUsage:
        return TokenUsage(
            prompt_tokens=self.prompt_tokens + other.prompt_tokens,
            completion_tokens=self.completion_tokens + other.completion_tokens,
        )


class LMCall(BaseModel):
    """One request to the language model: which stage and attempt made it, what it cost, how it ended."""

    stage: CallingStage
    candidate: int | None = Field(None, description="the candidate it belongs to; None for the shared Analyzer")
    attempt: int = Field(1, ge=1, description="1 for the first try, 2+ for format repairs")
    prompt_tokens: int = 0
    completion_tokens: int = 0
    seconds: float = 0.0
    cached: bool = Field(False, description="answered from DSPy's cache (costs no tokens)")
    error: str | None = Field(None, description="why this reply was not used, if it was not")

    @property
    def usage(self) -> TokenUsage:
        return TokenUsage(prompt_tokens=self.prompt_tokens, completion_tokens=self.completion_tokens)


def usage_by_stage(calls: list[LMCall]) -> dict[str, TokenUsage]:
    """Tokens summed per stage over ``calls``, failed ones included."""
    usage: dict[str, TokenUsage] = {}
    for call in calls:
        usage[call.stage] = usage.get(call.stage, TokenUsage()) + call.usage
    return usage


class Candidate(BaseModel):
    """One candidate program: how it was made, and how it did in its perturbed worlds."""

    index: int
    code: str | None = None
    stages: StageOutputs = Field(default_factory=StageOutputs)
    failure: CandidateFailure | None = Field(None, description="why it failed: no usable reply, rejected code, worlds")
    rollouts: list[Rollout] = Field(default_factory=list)
    lm_calls: list[LMCall] = Field(default_factory=list, description="its LM requests, failed ones included")
    notes: list[str] = Field(default_factory=list, description="what was repaired or ignored in its replies")
    repaired_from: int | None = Field(None, description="the failed candidate a repair round made this one from")

    # prop-decorator: mypy cannot type a decorator over @property; pydantic's documentation uses this ignore
    @computed_field  # type: ignore[prop-decorator]
    @property
    def usage(self) -> dict[str, TokenUsage]:
        """Tokens by stage over every LM call it made, failed attempts included."""
        return usage_by_stage(self.lm_calls)

    @property
    def success_rate(self) -> float:
        """Share of its worlds in which the goal was reached."""
        return sum(r.success for r in self.rollouts) / len(self.rollouts) if self.rollouts else 0.0

    @property
    def objects_touched(self) -> float:
        """Mean number of objects it touched per world."""
        return sum(len(r.touched) for r in self.rollouts) / len(self.rollouts) if self.rollouts else 0.0

    @property
    def skill_calls(self) -> float:
        """Mean number of skill calls per world."""
        return sum(len(r.calls) for r in self.rollouts) / len(self.rollouts) if self.rollouts else 0.0

    @property
    def conditions_met(self) -> float:
        """Mean share of the goal's sub-conditions met at the end of a world."""
        shares = [
            sum(r.conditions.values()) / len(r.conditions) if r.conditions else float(r.success) for r in self.rollouts
        ]
        return sum(shares) / len(shares) if shares else 0.0

    @property
    def calls_completed_in_failures(self) -> float:
        """Mean number of skill calls that completed in its failed worlds (how far it got; 0 if none failed)."""
        failed = [r for r in self.rollouts if not r.success]
        done = sum(sum(call.outcome == "done" for call in r.calls) for r in failed)
        return done / len(self.rollouts) if self.rollouts else 0.0

    def rank_key(self) -> tuple[float, ...]:
        """Sort key, best first: success rate, then more worlds succeeded (at the same rate, one verified in more
        worlds), then how far failed worlds got (goal sub-conditions met, skill calls completed), then fewer objects
        touched, then fewer skill calls."""
        return (
            -self.success_rate,
            -sum(r.success for r in self.rollouts),
            -self.conditions_met,
            -self.calls_completed_in_failures,
            self.objects_touched,
            self.skill_calls,
            self.index,
        )


class Proposal(BaseModel):
    """What the LM stages proposed for one task, before anything was simulated."""

    task: str
    method: str
    shared: StageOutputs = Field(default_factory=StageOutputs, description="the Analyzer's outputs")
    candidates: list[Candidate] = Field(default_factory=list)
    lm_calls: list[LMCall] = Field(default_factory=list, description="the Analyzer's LM requests")
    notes: list[str] = Field(default_factory=list)
    timings: dict[str, float] = Field(default_factory=dict, description="seconds by phase")


class RepairAttempt(BaseModel):
    """One failed candidate repaired: what the model was shown, what it changed, and how the new one did."""

    source: int = Field(description="the failed candidate shown to the model")
    candidate: int = Field(description="the candidate the repair made")
    shown: FailureTrace = Field(description="the failure trace in the repair prompt")
    scope: RepairScope
    diagnosis: str | None = None
    changed: list[str] = Field(
        default_factory=list, description="what differs from the source: steps, parameters or code"
    )
    success_rate: float = 0.0
    failure: CandidateFailure | None = Field(None, description="why the repaired candidate failed, if it did")


class RepairRound(BaseModel):
    """One repair round: the failures repaired concurrently and re-verified in one batch."""

    round: int = Field(ge=1)
    attempts: list[RepairAttempt] = Field(default_factory=list)
    prompt_tokens: int = 0
    completion_tokens: int = 0


class Solution(BaseModel):
    """The result of solving a task: the best code and everything behind the choice."""

    task: str
    method: str
    code: str | None = Field(None, description="the best candidate's program (None if none ran)")
    best: int | None = Field(None, description="index of the best candidate")
    success_rate: float = 0.0
    candidates: list[Candidate] = Field(default_factory=list)
    stages: StageOutputs = Field(default_factory=StageOutputs, description="the best candidate's stages")
    usage: dict[str, TokenUsage] = Field(default_factory=dict, description="tokens by stage, all candidates")
    lm_calls: list[LMCall] = Field(default_factory=list, description="every LM request, failed ones included")
    timings: dict[str, float] = Field(default_factory=dict, description="seconds by phase")
    repairs: list[RepairRound] = Field(default_factory=list, description="repair rounds, in order")
    notes: list[str] = Field(default_factory=list, description="what the user should know (e.g. which planner)")

    @property
    def success(self) -> bool:
        return self.best is not None and self.success_rate > 0

    @property
    def cached_replies(self) -> int:
        """How many LM replies came from DSPy's cache rather than the model."""
        return sum(call.cached for call in self.lm_calls)


def rank(candidates: list[Candidate]) -> list[Candidate]:
    """Candidates best first; ones that never ran come last."""
    return sorted(candidates, key=lambda c: (c.code is None or not c.rollouts, *c.rank_key()))
