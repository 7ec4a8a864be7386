"""Where the evaluator's runs are carried out: the :class:`Executor` protocol and the local executor.

An executor applies one function (``work``) to a list of jobs and hands every finished job's outcome to
a callback (``done``) as soon as it finishes, so that the caller can record it durably before anything
else happens. The jobs and the function must be picklable for executors that run them elsewhere
(:class:`~robotool.eval.ray_executor.RayExecutor` ships both to its workers), and one job is one unit of
work: the evaluator submits one run (its K x R worlds verified in one batch), and any other batched
verification can be submitted the same way. A job whose worker was lost (killed, out of memory, its
machine gone) is retried once; a second loss is handed to ``done`` as :class:`WorkerLost`.

The local executor runs the jobs on a thread pool in this process, where the LM runs overlap. Jobs marked
``exclusive`` (pure simulation on the CPU, such as the LM-free planner's runs) would only take turns on
Python's interpreter lock there: asked for ``processes`` > 1 (the command line asks for one per core), it
runs them on the ``mujoco`` backend in that many pool processes, each with its own sandbox; otherwise, or when
the work cannot be sent to another process, they take turns on a lock. A job whose process died is run again
once in this process.
"""

from __future__ import annotations

import contextvars
import functools
import pickle
import threading
import warnings
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from types import TracebackType
from typing import Protocol, Self, TypeVar

from robotool.processes import process_pool
from robotool.vocabulary import BackendName

PRELOAD = (
    "robotool.planner",
    "robotool.verify",
    "robotool.eval.work",
    "robotool.eval.pictures",
    "robotool.render.painter",
    "robotool.render.still",
    "robotool.render.run_videos",
)
"""What the evaluator's pool processes (runs and pictures) import, imported once by the fork server before it
forks them (about a second and a half of CPU per process otherwise)."""

J = TypeVar("J")
R = TypeVar("R")


class WorkerLost(RuntimeError):
    """A job's worker was lost on every attempt (killed, out of memory, its machine gone); the message says how."""


class Executor(Protocol):
    """Runs jobs somewhere and reports each outcome as it comes in."""

    def backend(self, asked: BackendName | None) -> BackendName:
        """The simulator backend the jobs will use: ``asked``, or what the workers have (warp with a GPU)."""
        ...

    def run(
        self,
        jobs: Sequence[J],
        work: Callable[[J], R],
        done: Callable[[J, R | WorkerLost], None],
        *,
        skip: Callable[[J], bool],
        exclusive: Callable[[J], bool],
        backend: BackendName,
    ) -> None:
        """Apply ``work`` to every job and call ``done`` with each outcome (from any thread).

        ``skip(job)`` is asked just before a job would start: True leaves it out (``done`` is not called
        for it). ``exclusive(job)`` marks jobs that must not share this machine's CPU with each other
        (executors with workers of their own may ignore it). ``backend`` is the backend the jobs use (see
        :meth:`backend`). An exception that is not an outcome (e.g. ``KeyboardInterrupt``) stops the jobs
        not yet started and propagates; jobs already finished have been handed to ``done``.
        """
        ...

    def close(self) -> None:
        """Release what the executor started."""
        ...

    def __enter__(self) -> Self: ...

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None: ...


class LocalExecutor:
    """Jobs on a thread pool in this process, ``workers`` at once; exclusive jobs in ``processes`` pool processes
    on the ``mujoco`` backend, or one at a time here."""

    def __init__(self, workers: int, processes: int = 1) -> None:
        self.workers = workers
        self.processes = processes

    def backend(self, asked: BackendName | None) -> BackendName:
        """``asked``, or this machine's default backend."""
        from robotool.sim.backend import default_backend

        return asked or default_backend()

    def run(
        self,
        jobs: Sequence[J],
        work: Callable[[J], R],
        done: Callable[[J, R | WorkerLost], None],
        *,
        skip: Callable[[J], bool],
        exclusive: Callable[[J], bool],
        backend: BackendName,
    ) -> None:
        """See :meth:`Executor.run`; ``done`` is called from the thread that ran the job."""
        turn = threading.Lock()
        simulations = sum(1 for job in jobs if exclusive(job))
        lanes = _simulation_lanes(work, min(simulations, self.processes), backend)
        processes = _simulation_pool(lanes) if lanes > 1 else None

        def simulate(job: J) -> R:
            if processes is not None:
                try:
                    return processes.submit(work, job).result()
                except BrokenProcessPool:  # its process died (killed, out of memory): once more, here
                    pass
            with turn:
                return work(job)

        def one(job: J) -> None:
            if skip(job):
                return
            outcome = simulate(job) if exclusive(job) else work(job)
            done(job, outcome)

        parallel = lanes if simulations == len(jobs) else max(self.workers, lanes)
        try:
            with ThreadPoolExecutor(max_workers=parallel) as pool:
                futures: list[Future[None]] = [pool.submit(contextvars.copy_context().run, one, job) for job in jobs]
                try:
                    for future in as_completed(futures):
                        future.result()
                except BaseException:
                    pool.shutdown(wait=False, cancel_futures=True)
                    raise
        finally:
            if processes is not None:
                processes.shutdown(wait=True, cancel_futures=True)

    def close(self) -> None:
        """Nothing to release: the pool lives only as long as :meth:`run`."""

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        self.close()


def _simulation_lanes(work: Callable[..., object], wanted: int, backend: BackendName) -> int:
    """How many simulation-only jobs run at once: ``wanted`` on the ``mujoco`` backend when ``work`` can be sent
    to another process, else 1."""
    if backend != "mujoco" or wanted < 2:
        return 1
    try:
        pickle.dumps(work)
    except (pickle.PicklingError, TypeError, AttributeError):
        return 1
    return wanted


def _simulation_pool(processes: int) -> ProcessPoolExecutor:
    """``processes`` pool processes, each with its own sandbox, for simulation-only jobs."""
    from robotool.sandbox.zygote import zygote

    zygote().layers()  # the sandbox's layers, learnt (and a missing one warned of) once, here
    return process_pool(processes, initializer=functools.partial(_start_pool_process, processes), preload=PRELOAD)


def _start_pool_process(processes: int) -> None:
    """In a pool process: the parent already warned about a missing sandbox layer; the cores are shared with the
    pool's other ``processes``."""
    from robotool.sandbox.jail import SandboxWarning
    from robotool.sim.backend_mujoco import share_cores

    warnings.simplefilter("ignore", SandboxWarning)
    share_cores(processes)
