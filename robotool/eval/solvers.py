"""The methods the evaluator compares, and how each one solves a task.

LM methods are the RoboTool program and the paper's ablations (:data:`robotool.program.methods.STAGES_BY_METHOD`):
each run gets its own ``rollout_id`` so that, at a temperature above 0, runs are fresh samples rather
than cached replies. LM-free methods come from the search planner (``robotool.planner.solve``):
``search`` with every object, ``no_tool`` restricted to the target object (the floor).
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Literal, Protocol

from pydantic import BaseModel

from robotool.eval.records import EqualBudget
from robotool.program.methods import STAGES_BY_METHOD
from robotool.solution import Solution
from robotool.task.task_model import Task
from robotool.vocabulary import PLANNER_METHODS, BackendName, MethodName, PlannerMethod

if TYPE_CHECKING:
    import dspy

    from robotool.program.lm_program import RoboTool


class Solver(Protocol):
    """Solves one task for one run; ``seed`` seeds the run's perturbed worlds."""

    def __call__(self, task: Task, *, seed: int, run: int) -> Solution | Compared: ...


@dataclass
class Compared:
    """A run with repair rounds (``solution``) and plain sampling at the same number of LM calls."""

    solution: Solution
    equal_budget: EqualBudget


class MethodInfo(BaseModel):
    """A method's name as the CLI and records spell it, its label in tables, and what it needs."""

    name: str
    label: str
    uses_lm: bool


_LABELS: dict[MethodName | PlannerMethod, str] = {
    "robotool": "RoboTool",
    "no_analyzer": "RoboTool w/o Analyzer",
    "no_calculator": "RoboTool w/o Calculator",
    "planner_coder": "Planner-Coder",
    "coder": "Coder",
    "search": "Search planner (no LM)",
    "no_tool": "No tool (floor)",
}

METHODS: dict[str, MethodInfo] = {
    name: MethodInfo(name=name, label=_LABELS[name], uses_lm=name in STAGES_BY_METHOD)
    for name in (*STAGES_BY_METHOD, *PLANNER_METHODS)
}
"""Every method, in table order: the LM program and its ablations, then the LM-free planner's two."""


def method_label(method: str) -> str:
    """How tables and plots name a method."""
    info = METHODS.get(method)
    return info.label if info else method


class SolverSettings(BaseModel):
    """What every solver shares: worlds per candidate, backend; for LM methods candidates per run, the
    temperature of every call, the answer format, the file that logs requests and replies, and repair rounds."""

    candidates: int = 1
    worlds: int = 3
    backend: BackendName | None = None
    temperature: float | None = None
    adapter: Literal["chat", "json"] | None = None
    log_prompts: Path | None = None
    repair: int = 0


def lm_solver(method: str, lm: dspy.LM, settings: SolverSettings) -> Solver:
    """The RoboTool program or an ablation, sampling from ``lm``."""
    from robotool.program.lm_program import RoboTool

    return _sampling_solver(lambda **options: RoboTool.method(method, **options), lm, settings)


def compiled_solver(path: Path, lm: dspy.LM, settings: SolverSettings) -> Solver:
    """A compiled program file (``robotool optimize``) as a method, sampling from ``lm``.

    The file is read and checked now (:class:`~robotool.program.compiled.CompiledProgramError` when it cannot be
    used) and loaded afresh for each run.
    """
    from robotool.program.lm_program import RoboTool

    RoboTool.from_compiled(path)
    return _sampling_solver(lambda **options: RoboTool.from_compiled(path, **options), lm, settings)


def _sampling_solver(make: Callable[..., RoboTool], lm: dspy.LM, settings: SolverSettings) -> Solver:
    """Runs of the program ``make(**options)`` builds; with repair rounds, also plain sampling at equal LM calls."""

    def solve(task: Task, *, seed: int, run: int) -> Solution | Compared:
        import dspy

        def sampled(candidates: int, repair: int) -> Solution:
            program = make(
                candidates=candidates,
                worlds_per_candidate=settings.worlds,
                backend=settings.backend,
                seed=seed,
                rollout_base=run * settings.candidates,
                temperature=settings.temperature,
                adapter=settings.adapter,
                log_prompts=settings.log_prompts,
                repair_rounds=repair,
            )
            with dspy.context(lm=lm.copy(rollout_id=run) if run else lm):
                return program(task=task).solution

        solution = sampled(settings.candidates, settings.repair)
        if not settings.repair:
            return solution
        return Compared(solution, equal_budget(solution, lambda k: sampled(k, 0)))

    return solve


def program_stages(path: Path) -> str:
    """The method (stages) a compiled program file was made for."""
    from robotool.program.compiled import read_compiled

    _, info = read_compiled(path)
    return info.method if info else "robotool"


def equal_budget(solution: Solution, plain: Callable[[int], Solution]) -> EqualBudget:
    """``solution`` (with repairs) against ``plain(k)``, plain best-of-k with as many LM calls as it spent."""
    first = [c for c in solution.candidates if c.repaired_from is None]
    repair_calls = sum(len(c.lm_calls) for c in solution.candidates if c.repaired_from is not None)
    first_calls = len(solution.lm_calls) - repair_calls
    per_candidate = max(1.0, sum(len(c.lm_calls) for c in first) / max(len(first), 1))
    extra = math.ceil(repair_calls / per_candidate)
    sampled_success = max((c.success_rate for c in first), default=0.0)
    other = plain(len(first) + extra) if extra else solution
    return EqualBudget(
        sampled=len(first),
        sampled_calls=first_calls,
        sampled_success=sampled_success,
        repair_calls=len(solution.lm_calls),
        repair_success=solution.success_rate,
        plain=len(first) + extra,
        plain_calls=len(other.lm_calls) if extra else first_calls,
        plain_success=other.success_rate if extra else sampled_success,
    )


@dataclass(frozen=True)
class PlannerSolver:
    """The LM-free search planner, with every object (``tools``) or the target only; a plain value, so that it
    can be sent to another process."""

    tools: bool
    settings: SolverSettings

    def __call__(self, task: Task, *, seed: int, run: int) -> Solution:
        planner = importlib.import_module("robotool.planner")
        s = self.settings
        return planner.solve(task, worlds=s.worlds, seed=seed, backend=s.backend, tools=self.tools)


def planner_solver(tools: bool, settings: SolverSettings) -> Solver:
    """The LM-free search planner, with every object (``tools``) or the target only."""
    return PlannerSolver(tools, settings)


def planner_missing() -> str | None:
    """Why the search planner cannot be used here, or None when it can."""
    try:
        planner = importlib.import_module("robotool.planner")
    except ImportError as e:
        return f"the search planner is not available ({e})"
    if not callable(getattr(planner, "solve", None)):
        return "the search planner is not available (robotool.planner has no solve())"
    return None


def make_solvers(
    methods: list[str],
    settings: SolverSettings,
    lm: dspy.LM | None,
    overrides: Mapping[str, Solver] | None = None,
) -> tuple[dict[str, Solver], dict[str, str]]:
    """Solvers for the methods that can run, and the reason for each that cannot."""
    overrides = overrides or {}
    solvers: dict[str, Solver] = {}
    skipped: dict[str, str] = {}
    factories: dict[str, Callable[[], Solver]] = {
        "search": lambda: planner_solver(True, settings),
        "no_tool": lambda: planner_solver(False, settings),
    }
    missing = None if all(m in overrides for m in factories) else planner_missing()
    for name in methods:
        if name in overrides:
            solvers[name] = overrides[name]
        elif METHODS[name].uses_lm:
            if lm is None:
                skipped[name] = "no language model is configured (pass --lm MODEL or set ROBOTOOL_LM)"
            else:
                solvers[name] = lm_solver(name, lm, settings)
        elif missing is not None:
            skipped[name] = missing
        else:
            solvers[name] = factories[name]()
    return solvers, skipped
