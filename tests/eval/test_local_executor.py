"""The local executor: simulation-only jobs run in a process per core on the mujoco backend, LM jobs in threads."""

from __future__ import annotations

import os
import signal
import threading
import time

import pytest

from robotool.eval.executor import LocalExecutor, WorkerLost


def _where(job: int) -> tuple[int, int]:
    """TEST FIXTURE work: (the job, the process that ran it), slow enough that two jobs overlap."""
    time.sleep(0.3)
    return job, os.getpid()


def _dies_in_a_pool_process(job: tuple[int, int]) -> tuple[int, int]:
    """TEST FIXTURE work on (job, the parent's pid): a pool process is killed on it (as by the OOM killer)."""
    if os.getpid() != job[1]:
        os.kill(os.getpid(), signal.SIGKILL)
    return job[0], os.getpid()


def _run(work, jobs: list, *, exclusive: bool, backend: str = "mujoco", processes: int = 2) -> dict:
    outcomes: dict = {}
    lock = threading.Lock()

    def done(job: object, outcome: tuple[int, int] | WorkerLost) -> None:
        with lock:
            outcomes[job] = outcome

    with LocalExecutor(workers=4, processes=processes) as executor:
        executor.run(jobs, work, done, skip=lambda _: False, exclusive=lambda _: exclusive, backend=backend)
    return outcomes


@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="one core: nothing to run side by side")
def test_simulation_jobs_run_in_other_processes_side_by_side() -> None:
    outcomes = _run(_where, list(range(4)), exclusive=True)
    assert sorted(outcomes) == [0, 1, 2, 3] and all(o[0] == j for j, o in outcomes.items())
    processes = {o[1] for o in outcomes.values()}
    assert os.getpid() not in processes and len(processes) >= 2


def test_simulation_jobs_on_another_backend_take_turns_here() -> None:
    outcomes = _run(_where, [0, 1], exclusive=True, backend="warp")
    assert {o[1] for o in outcomes.values()} == {os.getpid()}


def test_without_processes_asked_for_simulation_jobs_take_turns_here() -> None:
    outcomes = _run(_where, [0, 1], exclusive=True, processes=1)
    assert {o[1] for o in outcomes.values()} == {os.getpid()}


def test_lm_jobs_run_in_this_process() -> None:
    outcomes = _run(_where, [0, 1, 2], exclusive=False)
    assert {o[1] for o in outcomes.values()} == {os.getpid()}


def test_work_that_cannot_go_to_another_process_runs_here() -> None:
    outcomes = _run(lambda job: (job, os.getpid()), [0, 1, 2], exclusive=True)
    assert {o[1] for o in outcomes.values()} == {os.getpid()}


@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="one core: no pool")
def test_a_job_whose_process_died_runs_again_here() -> None:
    jobs = [(k, os.getpid()) for k in range(3)]
    outcomes = _run(_dies_in_a_pool_process, jobs, exclusive=True)
    assert sorted(outcomes) == jobs and {o[1] for o in outcomes.values()} == {os.getpid()}


def test_the_evaluators_lm_free_work_can_go_to_another_process() -> None:
    # The main job's runs reach the process pool only if the work pickles (a closure once kept them on one core).
    import pickle

    from robotool.eval.solvers import SolverSettings, planner_solver
    from robotool.eval.work import RunWork

    work = RunWork(
        {"search": planner_solver(True, SolverSettings()), "no_tool": planner_solver(False, SolverSettings())}
    )
    assert pickle.loads(pickle.dumps(work)) == work
