"""Generate-and-test: order candidate programs, verify them in the batched simulator round by round.

Programs are ordered by what the planner predicts from geometry (predicted-feasible first), then by
how many objects they use, then by how many motion steps they take; each round verifies the next
``beam`` of them (from one tier: tool-free programs come as their own first tier when the
geometry says no tool is needed) in one batch of perturbed worlds, and the search stops at the first round with a
program that succeeded in every world (or when the rounds or the time budget run out).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from robotool.planner.codegen import Program
from robotool.solution import Candidate, CandidateFailure, StageOutputs
from robotool.task.task_model import Task
from robotool.verify import failure_reason, prepare_code, run_codes
from robotool.vocabulary import BackendName


@dataclass(frozen=True)
class Budget:
    """How much verifying one search may do."""

    beam: int  # programs per round (one simulator batch)
    rounds: int  # rounds at most
    seconds: float  # no new round starts after this much time


@dataclass
class Tried:
    """One verified (or rejected) program and its candidate record."""

    program: Program
    candidate: Candidate


def order(programs: Iterable[Program]) -> list[Program]:
    """Distinct programs, best guess first: predicted feasible, then fewer less likely choices, then fewer
    objects, then fewer steps."""
    seen: set[str] = set()
    unique = []
    for prog in programs:
        if prog.code not in seen:
            seen.add(prog.code)
            unique.append(prog)
    return sorted(unique, key=lambda p: (p.doubt is not None, p.late, *p.cost))


def search(
    task: Task,
    tiers: list[list[Program]],
    stages: Callable[[Program], StageOutputs],
    *,
    worlds: int,
    seed: int,
    backend: BackendName | None,
    budget: Budget,
    start: int = 0,
) -> tuple[list[Tried], int]:
    """Verify programs in rounds, tier by tier (a round never mixes tiers; each tier already ordered).

    Candidates are numbered from ``start``. Returns what was tried and how many rounds ran."""
    started = time.perf_counter()
    tried: list[Tried] = []
    rounds = 0
    queue = [(k, p) for k, tier in enumerate(tiers) for p in tier]
    while rounds < budget.rounds and len(tried) < len(queue):
        if rounds and time.perf_counter() - started > budget.seconds:
            break
        tier = queue[len(tried)][0]
        batch = [
            Tried(p, Candidate(index=start + len(tried) + k, stages=stages(p)))
            for k, (t, p) in enumerate(queue[len(tried) : len(tried) + budget.beam])
            if t == tier
        ]
        runnable, codes = [], []
        for item in batch:
            item.candidate.code, rejection, _ = prepare_code(item.program.code, task)
            if rejection is not None:
                item.candidate.failure = CandidateFailure(stage="search", kind="rejected", reason=rejection)
            elif item.candidate.code is not None:  # always, without a rejection
                runnable.append(item)
                codes.append(item.candidate.code)
        results = run_codes(task, codes, worlds=worlds, seed=seed, backend=backend)
        for item, rollouts in zip(runnable, results, strict=True):
            item.candidate.rollouts = rollouts
            item.candidate.failure = failure_reason(rollouts)
        tried += batch
        rounds += 1
        if any(t.candidate.rollouts and t.candidate.success_rate == 1.0 for t in batch):
            break
    return tried, rounds
