"""Offline compilation: the search planner's verified solutions become demonstrations of every stage.

For each training example the LM-free planner (:func:`robotool.planner.solve`) searches for a program; a
solution whose code reached the goal in every perturbed world becomes one demonstration per stage, typed
as the stage's signature outputs: the Analyzer's key concepts (the ground truth the planner reads from
the geometry), the Planner's object roles, abstract plan and steps, the Calculator's parameters and the
Coder's program. A stage's demonstration gets the inputs that stage receives in this program (a program
without an Analyzer gives its Planner no key concepts, and so on). Solutions that failed in any world are
never kept. Each solved instance is written to the log folder, so a rerun reuses it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import dspy
from pydantic import BaseModel

from robotool.program.compiled import DemoSource
from robotool.program.lm_program import Proposer
from robotool.safe_text import json_text, prompt_block
from robotool.solution import Solution
from robotool.task.describe import describe
from robotool.vocabulary import BackendName

Say = Callable[[str], None]


class SolvedInstance(BaseModel):
    """One training instance as the planner solved it (the log folder keeps these)."""

    task: str
    family: str | None
    seed: int | None
    solution: Solution


def _solved(
    example: dspy.Example, *, worlds: int, seed: int, backend: BackendName | None, log: Path | None
) -> Solution:
    """The planner's solution of an example, from the log folder when an earlier run solved it."""
    from robotool.planner import solve

    path = log / f"planner-{example.name}-w{worlds}-s{seed}.json" if log is not None else None
    if path is not None and path.exists():
        return SolvedInstance.model_validate_json(path.read_text(encoding="utf-8")).solution
    solution = solve(example.task, worlds=worlds, seed=seed, backend=backend)
    if path is not None:
        record = SolvedInstance(task=example.name, family=example.family, seed=example.seed, solution=solution)
        path.write_text(json_text(record), encoding="utf-8")
    return solution


def stage_demos(program: Proposer, example: dspy.Example, solution: Solution) -> dict[str, dspy.Example]:
    """One demonstration per stage predictor of ``program`` from a verified solution (none for the Repair
    stage: a solution shows no failed program and its fix)."""
    stages = solution.stages
    description = prompt_block(describe(example.task))  # as the program reads it (lm_program)
    concepts = (stages.key_concepts or []) if program.analyze is not None else []
    steps = (stages.steps or []) if program.plan is not None else []
    parameters = (stages.parameters or []) if program.calculate is not None else []
    demos = {
        "analyze": dspy.Example(
            description=description, analysis=stages.analysis, key_concepts=stages.key_concepts or []
        ),
        "plan": dspy.Example(
            description=description,
            key_concepts=concepts,
            object_roles=stages.object_roles,
            abstract_plan=stages.abstract_plan,
            steps=stages.steps or [],
        ),
        "calculate": dspy.Example(
            description=description,
            key_concepts=concepts,
            steps=steps,
            calculation=stages.calculation,
            parameters=stages.parameters or [],
        ),
        "code": dspy.Example(description=description, steps=steps, parameters=parameters, code=solution.code),
    }
    return {
        name: demos[name].with_inputs(*_inputs(predictor))
        for name, predictor in program.named_predictors()
        if name in demos
    }


def _inputs(predictor: dspy.Predict) -> list[str]:
    return list(predictor.signature.input_fields)


def planner_demonstrations(
    program: Proposer,
    trainset: Sequence[dspy.Example],
    *,
    per_stage: int,
    worlds: int,
    seed: int = 0,
    backend: BackendName | None = None,
    log: Path | None = None,
    say: Say = lambda _: None,
) -> list[DemoSource]:
    """Give every stage of ``program`` up to ``per_stage`` demonstrations from verified planner solutions.

    Returns where each kept demonstration came from. Examples are tried in order until ``per_stage``
    solutions succeeded in all ``worlds`` worlds.
    """
    kept: list[DemoSource] = []
    demos: dict[str, list[dspy.Example]] = {name: [] for name, _ in program.named_predictors()}
    for example in trainset:
        if len(kept) == per_stage:
            break
        solution = _solved(example, worlds=worlds, seed=seed, backend=backend, log=log)
        if solution.code is None or solution.success_rate < 1.0:
            say(f"{example.name}: the planner found no program that succeeded in all {worlds} world(s); not kept")
            continue
        for name, demo in stage_demos(program, example, solution).items():
            demos[name].append(demo)
        kept.append(
            DemoSource(
                task=example.name,
                family=example.family,
                seed=example.seed,
                code=solution.code,
                success_rate=solution.success_rate,
            )
        )
        say(f"{example.name}: verified in {worlds} world(s); kept as demonstration {len(kept)} of every stage")
    for name, predictor in program.named_predictors():
        predictor.demos = demos[name]
    return kept
