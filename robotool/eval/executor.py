"""Where the evaluator's runs are carried out: the :class:`Executor` protocol and the local executor.

An executor applies one function (``work``) to a list of jobs and hands every finished job's outcome to
a callback (``done``) as soon as it finishes, so that the caller can record it durably before anything
else happens. The jobs and the function must be picklable for executors that run them elsewhere
(:class:`~robotool.eval.ray_executor.RayExecutor` ships both to its workers), and one job is one unit of
work: the evaluator submits one run (its K x R worlds verified in one batch), and any other batched
verification can be submitted the same way. A job whose worker was lost (killed, out of memory, its
machine gone) is retried once; a second loss is handed to ``done`` as :class:`WorkerLost`.

The local executor runs the jobs on a thread pool in this process: jobs marked ``exclusive`` (pure
simulation on the CPU) take turns on a lock, the others (LM runs) overlap.
"""

from __future__ import annotations

import contextlib
import contextvars
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor, as_completed
from types import TracebackType
from typing import Protocol, Self, TypeVar

J = TypeVar("J")
R = TypeVar("R")


class WorkerLost(RuntimeError):
    """A job's worker was lost on every attempt (killed, out of memory, its machine gone); the message says how."""


class Executor(Protocol):
    """Runs jobs somewhere and reports each outcome as it comes in."""

    def backend(self, asked: str | None) -> str:
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
        backend: str,
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
    """Jobs on a thread pool in this process: exclusive jobs one at a time, the others ``workers`` at once."""

    def __init__(self, workers: int) -> None:
        self.workers = workers

    def backend(self, asked: str | None) -> str:
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
        backend: str,
    ) -> None:
        """See :meth:`Executor.run`; ``done`` is called from the thread that ran the job."""
        turn = threading.Lock()

        def one(job: J) -> None:
            if skip(job):
                return
            with turn if exclusive(job) else contextlib.nullcontext():
                outcome = work(job)
            done(job, outcome)

        parallel = 1 if all(exclusive(job) for job in jobs) else self.workers
        with ThreadPoolExecutor(max_workers=parallel) as pool:
            futures: list[Future[None]] = [pool.submit(contextvars.copy_context().run, one, job) for job in jobs]
            try:
                for future in as_completed(futures):
                    future.result()
            except BaseException:
                pool.shutdown(wait=False, cancel_futures=True)
                raise

    def close(self) -> None:
        """Nothing to release: the pool lives only as long as :meth:`run`."""

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        self.close()
