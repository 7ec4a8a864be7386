"""One run's :class:`~robotool.solution.Solution` -> its :class:`RunRecord`: classified and graded."""

from __future__ import annotations

from robotool.bugs import InternalError
from robotool.eval.failure_classes import TaskFacts, classify, run_class, tools_used
from robotool.eval.grading import grade
from robotool.eval.instances import TaskInstance
from robotool.eval.records import RunKey, RunRecord, WorldResult
from robotool.program.methods import runs_analyzer
from robotool.solution import Solution
from robotool.task.concepts import KeyConcept, key_concepts
from robotool.verify import world_failure


def _empty(instance: TaskInstance, key: RunKey, world_seed: int, wall_s: float) -> RunRecord:
    """A run in which nothing ran: success 0, class ``invalid``."""
    return RunRecord(
        key=key,
        family=instance.family,
        embodiment=instance.task.embodiment,
        needs_tool=instance.needs_tool,
        world_seed=world_seed,
        wall_s=wall_s,
        success_rate=0.0,
        failure_class="invalid",
    )


def _predicted_concepts(stages: str, solution: Solution) -> list[KeyConcept] | None:
    """The Analyzer's concepts (none when it failed, which grades as wrong); None for methods without one
    (the search planner copies the ground truth)."""
    return (solution.stages.key_concepts or []) if runs_analyzer(stages) else None


def judge(
    instance: TaskInstance, key: RunKey, world_seed: int, solution: Solution, wall_s: float, stages: str | None = None
) -> RunRecord:
    """Classify the chosen candidate's worlds and grade the key concepts of a finished run.

    ``stages``: the method whose stages ran (default: the run's method; a compiled program's differs)."""
    facts = TaskFacts.of(instance.task, needs_tool=instance.needs_tool, needed=instance.tools)
    chosen = solution.candidates[solution.best] if solution.best is not None else None
    rollouts = chosen.rollouts if chosen is not None else []
    worlds = [
        WorldResult(
            world=r.world,
            seed=r.seed,
            success=r.success,
            failure_class=classify(r, facts),
            failure=world_failure(r),
            internal_error=r.internal_error is not None,
            tools_used=sorted(tools_used(r, facts)),
            calls=len(r.calls),
            sim_time=r.sim_time,
        )
        for r in rollouts
    ]
    update = {
        "worlds": worlds,
        "concepts": grade(key_concepts(instance.task), _predicted_concepts(stages or key.method, solution)),
        "code": solution.code,
        "stages": solution.stages,
        "candidate_failures": [str(c.failure) if c.failure else None for c in solution.candidates],
        "rollouts": rollouts,
        "best": solution.best,
        "repairs": solution.repairs,
        "usage": solution.usage,
        "lm_calls": len(solution.lm_calls),
        "cached_replies": solution.cached_replies,
        "timings": solution.timings,
        "notes": solution.notes,
        "internal_error": first_internal_error(solution),
    }
    if worlds:
        update |= {
            "success_rate": sum(w.success for w in worlds) / len(worlds),
            "failure_class": run_class([w.failure_class for w in worlds]),
        }
    return _empty(instance, key, world_seed, wall_s).model_copy(update=update)


def first_internal_error(solution: Solution) -> InternalError | None:
    """The first bug in robotool met by any candidate's worlds, the chosen candidate's first (None: none was)."""
    chosen = [solution.candidates[solution.best]] if solution.best is not None else []
    rollouts = (r for c in [*chosen, *solution.candidates] for r in c.rollouts)
    return next((r.internal_error for r in rollouts if r.internal_error is not None), None)


def crashed(
    instance: TaskInstance, key: RunKey, world_seed: int, error: Exception, wall_s: float, stages: str | None = None
) -> RunRecord:
    """The record of a run whose method raised (or whose worker was lost): nothing ran, and that is a bug in
    robotool, not the method's failure: an internal error, with no class (``stages`` as for :func:`judge`)."""
    found = InternalError.of(error, f"the {key.method} method")
    update: dict[str, object] = {"error": found.reason, "internal_error": found, "failure_class": None}
    if runs_analyzer(stages or key.method):  # the run's Analyzer produced nothing: graded as wrong
        update["concepts"] = grade(key_concepts(instance.task), [])
    return _empty(instance, key, world_seed, wall_s).model_copy(update=update)
