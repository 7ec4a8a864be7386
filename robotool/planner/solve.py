"""``solve``: the LM-free planner end to end, returning the same :class:`Solution` as the RoboTool program.

Key concepts come from :func:`robotool.task.concepts.key_concepts`; candidate programs from the
embodiment's macros; verification from :mod:`robotool.planner.search`. When a key concept is
violated, programs that use no object besides the goal's own are skipped (the geometry already says
they cannot work); with ``tools=False`` only those are tried (the evaluator's no-tool floor).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from robotool import robots
from robotool.errors import RobotoolError
from robotool.planner.codegen import Program
from robotool.planner.reparameterise import repaired
from robotool.planner.search import (
    Budget,
    Pace,
    Tried,
    doomed,
    held,
    hopeless,
    mark_repaired,
    order,
    search,
    too_heavy,
)
from robotool.robots.registry import SearchMacros
from robotool.signatures.models import ObjectRole, scene_context
from robotool.signatures.traces import failure_trace
from robotool.solution import RepairAttempt, RepairRound, Solution, StageOutputs, rank
from robotool.task.concepts import KeyConcept, key_concepts, surface_under
from robotool.task.scene import SceneObject
from robotool.task.task_model import Task
from robotool.vocabulary import BackendName

KEEP_CALLS = 4  # failed candidates (best first) that keep their rollouts' skill-call traces
CALCULATION = (
    "Numbers come from the task file's geometry (object boxes, surfaces under vertical rays, graspable "
    "points, button faces) and the robot's limits; positions of objects that may have moved are queried "
    "when each step runs and the offsets are added to them."
)


def solve(
    task: Task,
    *,
    worlds: int = 3,
    verify: int | None = None,
    seed: int = 0,
    backend: BackendName | None = None,
    tools: bool = True,
    repair: bool = True,
) -> Solution:
    """Find the shortest program that the simulator shows reaching the goal, without a language model.

    Candidates are planned in ``worlds`` perturbed worlds; one that succeeds in all of them is verified in
    ``verify`` more (default ``worlds + 2``), fresh worlds whose seeds planning never uses, before it is returned
    (see :mod:`robotool.planner.search`). With ``repair``, when no program succeeds in every world, the best
    failures are re-parameterised from what the simulator measured and verified in one more round (see
    :mod:`robotool.planner.reparameterise`)."""
    started = time.perf_counter()
    planner = robot_planner(task)
    pace = Pace(planner.work)
    fresh = worlds + 2 if verify is None else verify
    budget = Budget(
        beam=planner.beam,
        rounds=planner.rounds,
        work=planner.work,
        first=planner.first,
        verify=fresh,
        doubted_rounds=planner.doubted_rounds,
    )
    concepts = key_concepts(task)
    allowed = goal_objects(task)
    generated = list(planner.candidates(task, tools))
    tool_free = [p for p in generated if set(p.objects) <= allowed]
    with_tool = [p for p in generated if not set(p.objects) <= allowed]
    needs_tool = any(not c.satisfied for c in concepts)
    if not tools:
        tiers = [order(tool_free)]
    elif needs_tool:
        tiers = [order(with_tool or generated)]
    else:  # the geometry says no tool is needed: try every tool-free program first
        tiers = [order(tool_free), order(with_tool)]
    programs = [p for tier in tiers for p in tier]
    generated_at = time.perf_counter()
    with scene_context(task, robots.get(task.embodiment)):
        tried, rounds = search(
            task,
            tiers,
            lambda p: stages_of(task, p, concepts),
            worlds=worlds,
            seed=seed,
            backend=backend,
            budget=budget,
            follow_up=(lambda batch: near_miss_repairs(task, batch, budget.beam)) if repair else None,
            pace=pace,
        )
        # a search that gave up on programs all predicted to fail repairs none: their variants are predicted to fail
        # too (unsolvable vase scenes spent a third of their 12-19 s on such repairs, none of which held)
        if repair and not any(held(t.candidate) for t in tried) and not hopeless(tried, rounds, budget):
            repair_round(
                task,
                tried,
                lambda p: stages_of(task, p, concepts),
                worlds=worlds,
                verify=fresh,
                seed=seed,
                backend=backend,
                beam=budget.beam,
                pace=pace,
            )
    verified_at = time.perf_counter()
    repairs = repair_record(tried)
    solution = _solution(task, tried, concepts, tools)
    solution.repairs = repairs
    solution.timings = {
        "generate": generated_at - started,
        "verify": verified_at - generated_at,
        "total": time.perf_counter() - started,
    }
    solution.notes = [
        "Produced by the LM-free search planner (robotool.planner): generate-and-test over geometric skill "
        "macros checked in the batched simulator; no language model was used.",
        f"{len(generated)} programs generated, {len(programs)} considered, {len(tried)} verified in {rounds} "
        f"round(s) of up to {budget.beam}, {worlds} perturbed world(s) each; a program that succeeded in all of "
        f"them was verified in {fresh} fresh perturbed world(s) before it counted as succeeding.",
    ]
    if not tools:
        solution.notes.append("tools=False: only the goal object (and what it rests on) and the robot were used.")
    if repairs:
        attempts = repairs[0].attempts
        solution.notes.append(
            f"{len(attempts)} failed program(s) re-parameterised from measured evidence and verified "
            f"again; {sum(a.success_rate == 1.0 for a in attempts)} succeeded in every world."
        )
    heavy = too_heavy(tried, worlds)
    verified = {t.program.code for t in tried}
    skipped = [p for p in programs if p.code not in verified and doomed(p, heavy) is not None]
    if skipped:
        solution.notes.append(
            f"{len(skipped)} program(s) not verified: each pushes an object that a push found too heavy to push in "
            f"a planning world ({', '.join(f'{name} in world {k}' for name, k in heavy.items())})."
        )
    unverified = len(programs) - len(verified & {p.code for p in programs}) - len(skipped)
    if unverified and pace.ran_out:
        solution.notes.append(
            f"The search stopped at its budget of {planner.work:g} simulated world-seconds with {unverified} "
            "program(s) not verified."
        )
    if not generated:
        solution.notes.append(
            f"The {task.robot.type}'s planner macros made no program for this layout (none of their approaches fits "
            f"where the objects and the robot stand{'' if tools else ' without a tool'}): nothing ran in simulation."
        )
    elif not solution.success:
        solution.notes.append("No candidate reached the goal in simulation; the best failed candidate is returned.")
    return solution


class NoPlannerError(RobotoolError):
    """The task's robot has no search-planner macros."""


def robot_planner(task: Task) -> SearchMacros:
    """The task's robot's macros and budget (:class:`NoPlannerError` when it has none)."""
    make = robots.get(task.embodiment).planner
    if make is None:
        raise NoPlannerError(
            f"the search planner has no macros for the {task.embodiment} robot; solve its tasks "
            "with a language model (robotool solve --lm ...) or run your own program (robotool run)"
        )
    return make()


NEAR_MISS_VARIANTS = 2  # variants made at once from a program that succeeded in some worlds but not all


def near_miss_repairs(task: Task, batch: list[Tried], limit: int) -> list[tuple[Program, Tried]]:
    """Variants of a round's near misses (programs that succeeded in some of their worlds but not all), the best
    first, :data:`NEAR_MISS_VARIANTS` each and ``limit`` in all: a best guess that mostly works is re-parameterised
    from what the simulator measured in the world it failed, in the second round, instead of after every other
    plan."""
    near = [t for t in batch if t.candidate.rollouts and 0.0 < t.candidate.success_rate < 1.0]
    tried = {t.program.code for t in batch}
    return _variants(task, sorted(near, key=lambda t: t.candidate.rank_key()), tried, limit, NEAR_MISS_VARIANTS)


def repair_round(
    task: Task,
    tried: list[Tried],
    stages: Callable[[Program], StageOutputs],
    *,
    worlds: int,
    verify: int,
    seed: int,
    backend: BackendName | None,
    beam: int,
    pace: Pace,
) -> None:
    """Re-parameterise the best ``beam`` failures from their measured evidence and verify up to ``2 * beam``
    variants not tried yet in one batch, one that holds in every world then in ``verify`` fresh ones (appended to
    ``tried``); not when ``pace`` says the batch would not end within the planning run's budget."""
    failures = sorted((t for t in tried if t.candidate.rollouts), key=lambda t: t.candidate.rank_key())[:beam]
    heavy = too_heavy(tried, worlds)
    variants = [
        (variant, source)
        for variant, source in _variants(task, failures, {t.program.code for t in tried}, 2 * beam, None)
        if doomed(variant, heavy) is None
    ]
    if not variants or not pace.fits():
        return
    new, _ = search(
        task,
        [[v for v, _ in variants]],
        stages,
        worlds=worlds,
        seed=seed,
        backend=backend,
        budget=Budget(beam=len(variants), rounds=1, work=float("inf"), verify=verify),
        start=len(tried),
        pace=pace,
    )
    for made, (_, source) in zip(new, variants, strict=True):
        mark_repaired(made.candidate, source.candidate)
    tried += new


def _variants(
    task: Task, sources: list[Tried], seen: set[str], limit: int, each: int | None
) -> list[tuple[Program, Tried]]:
    """Up to ``limit`` re-parameterised variants of ``sources`` (``each`` at most per source), none in ``seen``."""
    variants: list[tuple[Program, Tried]] = []
    for source in sources:
        made = 0
        for variant in repaired(task, source.program, source.candidate):
            if len(variants) == limit or made == each:
                break
            if variant.code not in seen:
                seen.add(variant.code)
                variants.append((variant, source))
                made += 1
    return variants


def repair_record(tried: list[Tried]) -> list[RepairRound]:
    """The re-parameterised candidates as the solution records them: one round of attempts, each with the failure
    it came from (none when nothing was re-parameterised)."""
    by_index = {t.candidate.index: t for t in tried}
    record = RepairRound(round=1)
    for made in tried:
        source_index = made.candidate.repaired_from
        if source_index is None:
            continue
        trace = failure_trace(by_index[source_index].candidate.rollouts)
        assert trace is not None  # a source has a failed world
        record.attempts.append(
            RepairAttempt(
                source=source_index,
                candidate=made.candidate.index,
                shown=trace,
                scope="parameters",
                diagnosis=made.program.sentences[-1],
                changed=["parameters", "code"],
                success_rate=made.candidate.success_rate,
                failure=made.candidate.failure,
            )
        )
    return [record] if record.attempts else []


def goal_objects(task: Task) -> set[str]:
    """What a program may use without using a tool: the goal object and, when it is to be lowered, its support."""
    target = task.object(task.goal.object)
    names = {target.name}
    if task.goal.kind == "lowered":
        support, _ = surface_under(task, np.asarray(target.center[:2]), exclude=target.name)
        names.add(support)
    return names


def stages_of(task: Task, prog: Program, concepts: list[KeyConcept]) -> StageOutputs:
    """The typed stage outputs of one program."""
    return StageOutputs(
        analysis=analysis(concepts),
        key_concepts=concepts,
        object_roles=[
            ObjectRole(name=o.name, properties=properties(o), role=_role(task, prog, o)) for o in task.objects
        ],
        abstract_plan=prog.abstract_plan,
        steps=prog.steps,
        calculation=CALCULATION,
        parameters=prog.parameters,
    )


def analysis(concepts: list[KeyConcept]) -> str:
    """The key concepts in words."""
    if not concepts:
        return "No limit is at stake: the goal is within the robot's reach."
    lines = [
        f"{c.name}: {c.value:g} {c.unit} against {c.limit_name} {c.limit:g} {c.unit} "
        f"({'within the limit' if c.satisfied else 'violated: a tool is needed'})"
        for c in concepts
    ]
    return "; ".join(lines) + "."


def properties(obj: SceneObject) -> str:
    """An object's relevant properties in words."""
    size = " x ".join(f"{v:g}" for v in obj.size)
    words = [f"{obj.shape}, {size} m, top at {obj.top:.3f} m"]
    words.append(f"movable, {obj.effective_mass:.2f} kg" if obj.movable else "fixed")
    words += [w for w, on in (("magnetic", obj.magnetic), ("soft", obj.soft)) if on]
    if obj.fragile is not None:
        words.append(f"fragile (max drop {obj.fragile.max_drop:g} m)")
    return ", ".join(words)


def _role(task: Task, prog: Program, obj: SceneObject) -> str:
    if obj.name == task.goal.object:
        return "target"
    return prog.roles.get(obj.name, "none")


def _solution(task: Task, tried: list[Tried], concepts: list[KeyConcept], tools: bool) -> Solution:
    candidates = [t.candidate for t in tried]
    ranked = rank(candidates)
    best = ranked[0] if ranked and ranked[0].rollouts else None
    for kept, candidate in enumerate(c for c in ranked if c is not best):
        if kept >= KEEP_CALLS:
            candidate.rollouts = [r.model_copy(update={"calls": []}) for r in candidate.rollouts]
    empty = StageOutputs(analysis=analysis(concepts), key_concepts=concepts)
    return Solution(
        task=task.name,
        method="search" if tools else "no_tool",
        code=best.code if best else None,
        best=best.index if best else None,
        success_rate=best.success_rate if best else 0.0,
        candidates=candidates,
        stages=best.stages if best else empty,
    )
