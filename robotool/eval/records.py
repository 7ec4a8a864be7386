"""The evaluator's records: one :class:`RunRecord` per run (keyed by its inputs' content), and the results file."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from robotool.bugs import InternalError
from robotool.eval.config import EvalConfig, Settings
from robotool.eval.failure_classes import FailureClass
from robotool.eval.grading import ConceptGrade
from robotool.rollout import Rollout
from robotool.solution import RepairRound, StageOutputs, TokenUsage
from robotool.task.task_model import Task


class RunKey(BaseModel):
    """What identifies a run: the task (a family for generated instances), its seed, method, run index,
    and ``inputs``, a digest of the content of everything its result depends on (see :func:`inputs_digest`)."""

    model_config = ConfigDict(frozen=True)

    task: str
    seed: int | None = None
    method: str
    run: int
    inputs: str = Field("", description="digest of the run's inputs; '' in journals written before it existed")

    @property
    def id(self) -> str:
        """One string for the key, e.g. ``sofa_traversing#3/robotool/0@1f0c...``."""
        task = self.task if self.seed is None else f"{self.task}#{self.seed}"
        return f"{task}/{self.method}/{self.run}@{self.inputs}"


def inputs_digest(task: Task, method: str, run: int, settings: Settings, context: Mapping[str, object]) -> str:
    """A digest of what decides a run's result: the task's content (every field of the validated task, so an
    edited task file is a new run), the method, the run index, the settings (LM model, temperature,
    candidates, worlds, backend, seed, repair rounds: left out when 0, so runs journalled before the setting
    existed keep their digest) and ``context`` (e.g. the API base URL, the resolved backend and the robotool
    version)."""
    payload = {
        "task": task.model_dump(mode="json"),
        "method": method,
        "run": run,
        "settings": settings.model_dump(mode="json", exclude={"repair"} if not settings.repair else None),
        "context": dict(context),
    }
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]


class WorldResult(BaseModel):
    """One perturbed world of the chosen candidate, summarized and classified."""

    world: int
    seed: int
    success: bool
    failure_class: FailureClass | None = None
    failure: str | None = Field(None, description="why it failed, in one line")
    internal_error: bool = Field(False, description="a bug in robotool ended it: neither a success nor a failure")
    tools_used: list[str] = Field(default_factory=list)
    calls: int = 0
    sim_time: float = 0.0


class EqualBudget(BaseModel):
    """A run with repair rounds against plain sampling at the same number of LM calls (``--repair N``).

    ``sampled_*``: the run's K sampled candidates alone (plain best-of-K, before any repair); ``repair_*``:
    the run as returned, repairs included; ``plain_*``: a second solve sampling K' candidates without repair,
    K' chosen so that its LM calls match the run's (K' = K when no repair round ran, and nothing is solved again).
    """

    sampled: int = Field(description="K")
    sampled_calls: int
    sampled_success: float
    repair_calls: int
    repair_success: float
    plain: int = Field(description="K'")
    plain_calls: int
    plain_success: float


class RunRecord(BaseModel):
    """Everything about one run: the instance, the program, its worlds, its grades and its cost."""

    key: RunKey
    family: str | None = None
    embodiment: str
    needs_tool: bool
    world_seed: int
    success_rate: float = Field(description="share of the chosen candidate's worlds that reached the goal")
    failure_class: FailureClass | None = Field(None, description="the run's most common failure; None: no failure")
    worlds: list[WorldResult] = Field(default_factory=list)
    concepts: ConceptGrade = Field(default_factory=ConceptGrade)
    code: str | None = None
    stages: StageOutputs = Field(default_factory=StageOutputs)
    candidate_failures: list[str | None] = Field(default_factory=list)
    best: int | None = Field(None, description="the index of the chosen candidate (None: none ran)")
    repairs: list[RepairRound] = Field(default_factory=list, description="repair rounds, in order")
    rollouts: list[Rollout] = Field(default_factory=list, description="the chosen candidate's full traces")
    usage: dict[str, TokenUsage] = Field(default_factory=dict, description="LM tokens by stage")
    lm_calls: int = Field(0, description="LM requests the run made, failed ones included")
    cached_replies: int = Field(0, description="of those, replies that came from DSPy's cache")
    timings: dict[str, float] = Field(default_factory=dict, description="the method's own phases, seconds")
    wall_s: float = Field(0.0, description="wall time of the whole run as the evaluator measured it")
    notes: list[str] = Field(default_factory=list)
    error: str | None = Field(None, description="the method raised instead of returning a solution")
    internal_error: InternalError | None = Field(
        None,
        description="a bug in robotool met in the run (a controller or the method raised; the first one, with its "
        "traceback): the run is neither a success nor a failure, and the success tables leave it out",
    )
    equal_budget: EqualBudget | None = Field(None, description="with repair rounds: plain sampling at equal LM calls")

    @property
    def tokens(self) -> int:
        """LM tokens of the run, prompt and completion."""
        return sum(u.prompt_tokens + u.completion_tokens for u in self.usage.values())

    @property
    def tool_use_rate(self) -> float | None:
        """Share of its worlds in which the program used a tool (None when nothing ran)."""
        return sum(bool(w.tools_used) for w in self.worlds) / len(self.worlds) if self.worlds else None


class Picture(BaseModel):
    """One picture in the results folder: a task's scene, or the end of a failed world."""

    kind: Literal["scene", "failure"]
    task: str = Field(description="the instance: task name, or family#seed")
    file: str = Field(description="path relative to the results folder")
    failure_class: FailureClass | None = None
    run: str | None = Field(None, description="the key of the run the world belongs to (task/method/run@inputs)")
    world: int | None = None
    caption: str = ""
    reproduced: bool | None = Field(
        None, description="the failed world simulated again failed the same way (None: nothing to simulate)"
    )


class Video(BaseModel):
    """One video in the results folder: a failed world of a run, simulated again from its program and seed."""

    run: str = Field(description="the key of the run the world belongs to (task/method/run@inputs)")
    world: int
    file: str = Field(description="path relative to the results folder")
    plan: str | None = Field(None, description="its plan view from above (PNG), path relative to the results folder")


class Results(BaseModel):
    """``results.json``: the configuration, the methods left out and why, and every run's record."""

    config: EvalConfig
    skipped: dict[str, str] = Field(default_factory=dict, description="method -> why it did not run")
    notes: list[str] = Field(default_factory=list)
    records: list[RunRecord] = Field(default_factory=list)
    wall_s: float = Field(0.0, description="wall time of the command that wrote this file")
    pictures: list[Picture] = Field(default_factory=list, description="the report's pictures (files in the folder)")
    videos: list[Video] = Field(default_factory=list, description="videos of failed worlds (files in the folder)")
