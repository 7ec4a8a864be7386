"""Candidates -> sandboxed programs -> one batch of perturbed rollouts -> outcomes -> the best.

Every candidate runs in the same ``worlds`` perturbed copies of the scene (world ``r`` of each
candidate is perturbed with the same seed), all candidates in one batch of the simulator.
:func:`select` is verified best-of-K: a :class:`~robotool.solution.Proposal` in, a
:class:`~robotool.solution.Solution` out.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import NamedTuple, Protocol

from robotool.rollout import Event, Rollout
from robotool.sandbox import ProgramRejected, extract, start_sessions, validate
from robotool.sim import run_sessions
from robotool.sim.backend import default_backend
from robotool.sim.recorder import StateRecorder
from robotool.solution import Candidate, CandidateFailure, Proposal, Solution, rank, usage_by_stage
from robotool.task.task_model import Task
from robotool.vocabulary import BackendName


class PreparedCode(NamedTuple):
    """An LM reply's program (None when none was found), why it cannot run, and what extraction left out."""

    code: str | None
    rejection: str | None
    note: str | None = None


def prepare_code(text: str, task: Task) -> PreparedCode:
    """Extract the program from an LM reply and validate it against the task's embodiment."""
    try:
        extraction = extract(text)
    except ProgramRejected as e:
        return PreparedCode(None, str(e))
    try:
        validate(extraction.code, task.embodiment)
    except ProgramRejected as e:
        return PreparedCode(extraction.code, str(e), extraction.note)
    return PreparedCode(extraction.code, None, extraction.note)


def run_worlds(
    task: Task,
    programs: Sequence[str],
    world_seeds: Sequence[int],
    *,
    backend: BackendName | None = None,
    recorder: StateRecorder | None = None,
) -> list[Rollout]:
    """Run ``programs[w]`` in world ``w`` perturbed from ``world_seeds[w]``, all worlds in one batch."""
    sessions = start_sessions(list(programs), task.embodiment)
    return run_sessions(
        task, sessions, world_seeds=list(world_seeds), backend=backend or default_backend(), recorder=recorder
    )


def run_codes(
    task: Task,
    codes: Sequence[str],
    *,
    worlds: int,
    seed: int = 0,
    backend: BackendName | None = None,
    recorder: StateRecorder | None = None,
) -> list[list[Rollout]]:
    """Run each (validated) program in ``worlds`` perturbed worlds, all in one batch.

    World ``r`` of program ``i`` is world ``i * worlds + r`` of the batch (the index a ``recorder`` names).
    """
    return run_seeded(task, [(code, range(seed, seed + worlds)) for code in codes], backend=backend, recorder=recorder)


def run_seeded(
    task: Task,
    runs: Sequence[tuple[str, Sequence[int]]],
    *,
    backend: BackendName | None = None,
    recorder: StateRecorder | None = None,
) -> list[list[Rollout]]:
    """Run each (validated) program in the perturbed worlds of its own seeds, all in one batch: one list of
    rollouts per run, in its seeds' order (each rollout's ``world`` is its index in the batch)."""
    if not runs:
        return []
    programs = [code for code, seeds in runs for _ in seeds]
    world_seeds = [s for _, seeds in runs for s in seeds]
    rollouts = run_worlds(task, programs, world_seeds, backend=backend, recorder=recorder)
    out, start = [], 0
    for _, seeds in runs:
        out.append(rollouts[start : start + len(seeds)])
        start += len(seeds)
    return out


class CodeRunner(Protocol):
    """Runs programs in perturbed worlds like :func:`run_codes` (which is one; a batching service is another)."""

    def __call__(
        self, task: Task, codes: Sequence[str], *, worlds: int, seed: int = 0, backend: BackendName | None = None
    ) -> list[list[Rollout]]: ...


def verify(
    task: Task,
    candidates: Sequence[Candidate],
    *,
    worlds: int,
    seed: int = 0,
    backend: BackendName | None = None,
    runner: CodeRunner | None = None,
) -> None:
    """Simulate every candidate that has valid code; record rollouts and a failure reason in place.

    Candidates with the same program are simulated once and share its rollouts (a note says so).
    ``runner`` runs the programs (default: :func:`run_codes`, one batch per call).
    """
    runnable = [c for c in candidates if c.code is not None and c.failure is None]
    first: dict[str, Candidate] = {}
    for candidate in runnable:
        first.setdefault(candidate.code or "", candidate)
    codes = list(first)
    run = runner or run_codes
    results = dict(zip(codes, run(task, codes, worlds=worlds, seed=seed, backend=backend), strict=True))
    for candidate in runnable:
        code = candidate.code or ""
        candidate.rollouts = [r.model_copy(deep=True) for r in results[code]]
        if first[code] is not candidate:
            candidate.notes.append(f"same program as candidate {first[code].index}; simulated once")
        if candidate.success_rate < 1.0:
            candidate.failure = failure_reason(candidate.rollouts)


def select(
    task: Task,
    proposal: Proposal,
    *,
    worlds: int,
    seed: int = 0,
    backend: BackendName | None = None,
    runner: CodeRunner | None = None,
) -> Solution:
    """Verify a proposal's candidates (see :func:`verify`) and return the best as a :class:`Solution`.

    The proposal is not changed: the solution holds verified copies of its candidates; ``runner`` as for
    :func:`verify`.
    """
    started = time.perf_counter()
    candidates = [c.model_copy(deep=True) for c in proposal.candidates]
    verify(task, candidates, worlds=worlds, seed=seed, backend=backend, runner=runner)
    return chosen(proposal, candidates, proposal.timings | {"verify": time.perf_counter() - started})


def chosen(proposal: Proposal, candidates: list[Candidate], timings: dict[str, float]) -> Solution:
    """The best of a proposal's verified ``candidates`` (repaired ones included) as a :class:`Solution`;
    ``timings``: seconds by phase, to which their total is added."""
    ranked = rank(candidates)
    best = ranked[0] if ranked and ranked[0].rollouts else None
    calls = proposal.lm_calls + [call for c in candidates for call in c.lm_calls]
    timings = timings | {"total": sum(timings.values())}
    return Solution(
        task=proposal.task,
        method=proposal.method,
        code=best.code if best else None,
        best=best.index if best else None,
        success_rate=best.success_rate if best else 0.0,
        candidates=candidates,
        stages=best.stages if best else proposal.shared,
        usage=usage_by_stage(calls),
        lm_calls=calls,
        timings=timings,
        notes=list(proposal.notes),
    )


def failure_reason(rollouts: Sequence[Rollout]) -> CandidateFailure | None:
    """Why the first failed world failed, with how many worlds failed (None when every world succeeded)."""
    failed = [(k, r) for k, r in enumerate(rollouts) if not r.success]
    if not failed:
        return None
    k, first = failed[0]
    return CandidateFailure(
        stage="simulation",
        kind="worlds_failed",
        reason=world_failure(first) or "",
        failed_worlds=len(failed),
        worlds=len(rollouts),
        world=k,
    )


MAX_TOLD_EVENTS = 4  # events a one-line failure reason tells, besides what failed


def world_failure(rollout: Rollout) -> str | None:
    """Why one world failed: its error or the goal conditions not met, then the most telling events before it.

    The events (clamps, grasps that held nothing, objects pushed away, stalls, refusals, falls) are
    rendered from the rollout's typed records, in time order; repeats of an event on the same object
    and limit are told once (the last grasp failure, the first of the others).
    """
    if rollout.success:
        return None
    if rollout.error:
        head = rollout.error
    else:
        unmet = [name for name, ok in rollout.conditions.items() if not ok]
        head = "goal not reached: " + ", ".join(unmet) if unmet else "goal not reached"
    told = telling_events(rollout.events or _call_events(rollout))
    if not told:
        return head
    return head + "; before that: " + "; ".join(e.describe(rollout.calls) for e in told)


def _call_events(rollout: Rollout) -> list[Event]:
    """Events read from the calls' outcomes, for rollouts recorded without events (older results)."""
    return [
        Event(kind=c.outcome, call=k, time=c.ended, measured=c.measured, detail=c.reason)
        for k, c in enumerate(rollout.calls)
        if c.outcome in ("stalled", "timeout", "refused")
    ]


def telling_events(events: Sequence[Event]) -> list[Event]:
    """The events worth telling in a failure reason (see :func:`world_failure`), at most :data:`MAX_TOLD_EVENTS`."""
    chosen: dict[tuple[str, str | None, str | None], int] = {}
    for k, event in enumerate(events):
        if event.kind == "grasped":
            continue
        key = (event.kind, event.object, event.limit)
        if key not in chosen or event.kind == "grasp_failed":
            chosen[key] = k
    picked = sorted(chosen.values())
    if len(picked) > MAX_TOLD_EVENTS:  # keep the last one (closest to the failure) and the earliest others
        picked = [*picked[: MAX_TOLD_EVENTS - 1], picked[-1]]
    return [events[k] for k in picked]
