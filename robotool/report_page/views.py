"""What ``report.html`` shows, as typed views built from the evaluator's records, a solve's
:class:`~robotool.solution.Solution` or a run's :class:`~robotool.execute.RunReport`."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from pydantic import BaseModel, Field

from robotool.eval.grading import ConceptGrade
from robotool.eval.records import Picture, RunRecord, Video
from robotool.eval.tables import TextTable
from robotool.rollout import Rollout, SkillCall, notable_distances
from robotool.solution import Candidate, RepairRound, Solution, StageOutputs
from robotool.verify import world_failure


class Media(BaseModel):
    """A picture or a video on the page: ``src`` is a path relative to the page, or a ``data:`` URI."""

    src: str
    caption: str = ""


class CallView(BaseModel):
    """One skill call of a world's trace."""

    number: int
    skill: str
    args: str
    outcome: str
    reason: str | None = None
    measured: str = ""
    notable: bool = Field(False, description="refused, or a measured distance that says something went wrong")


class WorldView(BaseModel):
    """One perturbed world of a candidate: how it ended, its skill-call trace, and its video if one was filmed."""

    world: int
    seed: int
    success: bool
    internal_error: bool = Field(False, description="a bug in robotool ended it: neither a success nor a failure")
    failure_class: str | None = None
    failure: str | None = None
    calls: list[CallView] = Field(default_factory=list)
    events: list[str] = Field(default_factory=list)
    output: str = ""
    video: Media | None = None
    plan: Media | None = Field(None, description="the world from above, when it was filmed")


class CandidateView(BaseModel):
    """One candidate program: chosen or not, how it did and why it failed."""

    index: int
    chosen: bool
    success_rate: float | None = None
    failure: str | None = None
    repaired_from: int | None = None
    code: str | None = None
    worlds: list[WorldView] = Field(default_factory=list, description="its worlds, when it is not the chosen one")


class RunView(BaseModel):
    """One run's drill-down."""

    anchor: str = Field(description="the id of its <details> element")
    title: str
    success_rate: float | None = Field(description="None: an internal error left the run out of the results")
    failure_class: str | None = None
    error: str | None = None
    internal_error: str | None = Field(None, description="the bug in robotool met in the run, in one line")
    scene: Media | None = None
    concepts: ConceptGrade = Field(default_factory=ConceptGrade)
    stages: StageOutputs = Field(default_factory=StageOutputs)
    code: str | None = None
    worlds: list[WorldView] = Field(default_factory=list, description="the chosen candidate's worlds")
    candidates: list[CandidateView] = Field(default_factory=list)
    repairs: list[RepairRound] = Field(default_factory=list)
    stills: list[Media] = Field(default_factory=list)
    notes: list[str] = Field(default_factory=list)
    cost: str = ""


class PageView(BaseModel):
    """The whole page."""

    title: str
    preamble: list[str] = Field(default_factory=list)
    tables: list[TextTable] = Field(default_factory=list)
    plots: list[Media] = Field(default_factory=list)
    runs: list[RunView] = Field(default_factory=list)


def _value(value: object) -> str:
    if isinstance(value, float):
        return f"{value:.3f}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    return repr(value) if isinstance(value, str) else str(value)


def _call(number: int, call: SkillCall) -> CallView:
    return CallView(
        number=number,
        skill=call.skill,
        args=", ".join(_value(a) for a in call.args),
        outcome=call.outcome,
        reason=call.reason,
        measured=", ".join(f"{k} {v:.3f}" for k, v in call.measured.items()),
        notable=call.outcome != "done" or bool(notable_distances(call.measured)),
    )


def world_view(
    rollout: Rollout, failure_class: str | None = None, video: Media | None = None, plan: Media | None = None
) -> WorldView:
    """A world's view from its full trace."""
    return WorldView(
        world=rollout.world,
        seed=rollout.seed,
        success=rollout.success,
        internal_error=rollout.internal_error is not None,
        failure_class=failure_class,
        failure=world_failure(rollout),
        calls=[_call(i + 1, c) for i, c in enumerate(rollout.calls)],
        events=[e.describe(rollout.calls) for e in rollout.events],
        output=rollout.output,
        video=video,
        plan=plan,
    )


def _candidate(candidate: Candidate, chosen: bool) -> CandidateView:
    return CandidateView(
        index=candidate.index,
        chosen=chosen,
        success_rate=candidate.success_rate if candidate.rollouts else None,
        failure=str(candidate.failure) if candidate.failure else None,
        repaired_from=candidate.repaired_from,
        code=None if chosen else candidate.code,
        worlds=[] if chosen else [world_view(r) for r in candidate.rollouts],
    )


def _anchor(text: str) -> str:
    return "run-" + "".join(c if c.isalnum() else "-" for c in text)


def record_view(record: RunRecord, pictures: Sequence[Picture], videos: Sequence[Video]) -> RunView:
    """An evaluated run's view; ``pictures`` and ``videos``: the results folder's, paths relative to the page."""
    key = record.key
    task = key.task if key.seed is None else f"{key.task}#{key.seed}"
    classes = {w.world: w.failure_class for w in record.worlds}
    mine = [v for v in videos if v.run == key.id]
    filmed = {v.world: Media(src=v.file, caption=f"world {v.world}, simulated again") for v in mine}
    plans = {v.world: Media(src=v.plan, caption=f"world {v.world} from above") for v in mine if v.plan}
    scene = next((p for p in pictures if p.kind == "scene" and p.task == task), None)
    tokens = sum(u.prompt_tokens + u.completion_tokens for u in record.usage.values())
    return RunView(
        anchor=_anchor(key.id),
        title=f"{task} / {key.method} / run {key.run}",
        success_rate=None if record.internal_error else record.success_rate,
        failure_class=record.failure_class,
        error=record.error,
        internal_error=str(record.internal_error) if record.internal_error else None,
        scene=Media(src=scene.file, caption=scene.caption) if scene else None,
        concepts=record.concepts,
        stages=record.stages,
        code=record.code,
        worlds=[world_view(r, classes.get(r.world), filmed.get(r.world), plans.get(r.world)) for r in record.rollouts],
        candidates=[
            CandidateView(index=i, chosen=i == record.best, failure=failure)
            for i, failure in enumerate(record.candidate_failures)
        ],
        repairs=record.repairs,
        stills=[Media(src=p.file, caption=p.caption) for p in pictures if p.kind == "failure" and p.run == key.id],
        notes=record.notes,
        cost=f"{record.lm_calls} LM call(s), {tokens} tokens, {record.wall_s:.1f} s",
    )


def solution_view(
    solution: Solution, scene: Media | None, concepts: ConceptGrade, videos: Mapping[int, Media]
) -> RunView:
    """A solve's view: every candidate, the chosen one's worlds (``videos``: world -> its video) and the repairs."""
    best = solution.candidates[solution.best] if solution.best is not None else None
    failure = best.failure if best is not None else None
    tokens = sum(u.prompt_tokens + u.completion_tokens for u in solution.usage.values())
    return RunView(
        anchor=_anchor(f"{solution.task}-{solution.method}"),
        title=f"{solution.task} / {solution.method}",
        success_rate=solution.success_rate,
        error=str(failure) if failure and not solution.success else None,
        scene=scene,
        concepts=concepts,
        stages=solution.stages,
        code=solution.code,
        worlds=[world_view(r, video=videos.get(r.world)) for r in best.rollouts] if best else [],
        candidates=[_candidate(c, c is best) for c in solution.candidates],
        repairs=solution.repairs,
        notes=solution.notes,
        cost=f"{len(solution.lm_calls)} LM call(s), {tokens} tokens",
    )


def rollouts_view(
    task: str, code: str, rollouts: Sequence[Rollout], scene: Media | None, videos: Mapping[int, Media]
) -> RunView:
    """A program run's view (``robotool run``): its worlds and their traces."""
    rate = sum(r.success for r in rollouts) / len(rollouts) if rollouts else 0.0
    return RunView(
        anchor=_anchor(task),
        title=f"{task} / program",
        success_rate=rate,
        scene=scene,
        code=code,
        worlds=[world_view(r, video=videos.get(r.world)) for r in rollouts],
    )
