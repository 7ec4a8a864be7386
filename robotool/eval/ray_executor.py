"""The Ray executor: jobs as Ray tasks on a cluster (or on a Ray started on this machine).

Each job is one Ray task that asks for one CPU, and a share of a GPU (:data:`JOBS_PER_GPU` jobs per GPU)
when the jobs simulate on the warp backend and the cluster has GPUs: Ray shows a task a GPU only when it
asks for one. Without ``--backend`` the backend is warp when the cluster has GPUs, else mujoco, so every
run of a sweep uses the same backend whichever worker it lands on. The job and the work function travel
with the task (pickled by Ray), nothing is read from this machine's files on the workers, and the
outcomes come back here, where the caller records them: a worker that dies loses only the job it was
running. That job is submitted again once (Ray starts a fresh worker process, on another machine when
the first one is gone); when its worker is lost again the job's outcome is :class:`WorkerLost` with
the reason. Any other failure of a Ray task (e.g. a worker that cannot import robotool, or runs another
version of it) stops the sweep with an :class:`~robotool.eval.config.EvalError`.
"""

from __future__ import annotations

import logging
import socket
from collections import deque
from collections.abc import Callable, Sequence
from types import TracebackType
from typing import Any, Self, TypeVar

import ray
from ray import exceptions as ray_errors

from robotool.eval.config import EvalError
from robotool.eval.executor import WorkerLost
from robotool.version import version
from robotool.vocabulary import BackendName

J = TypeVar("J")
R = TypeVar("R")

JOBS_PER_GPU = 4
"""Jobs that share one GPU when they simulate on the warp backend."""
CONNECT_TIMEOUT_S = 10.0
"""How long to wait for a cluster's address to answer before giving up (Ray itself retries for minutes)."""
RETRIES = 1
"""Times a job whose worker was lost is submitted again."""
LOST: tuple[type[Exception], ...] = (
    ray_errors.WorkerCrashedError,
    ray_errors.NodeDiedError,
    ray_errors.OutOfMemoryError,
    ray_errors.ObjectLostError,
)
"""How Ray reports a job whose worker process or machine went away (killed, out of memory, node lost)."""


class VersionMismatchError(RuntimeError):
    """A worker runs another robotool version than the driver: its results would not match their keys."""


def _attempt(work: Callable[[Any], Any], job: Any, driver_version: str) -> Any:
    """What a Ray worker runs for one job (after checking that it runs the driver's robotool)."""
    mine = version()
    if mine != driver_version:
        raise VersionMismatchError(f"a Ray worker runs robotool {mine}, this machine {driver_version}")
    return work(job)


def _one_line(error: BaseException, limit: int = 300) -> str:
    """An error in one line: its first line, whitespace collapsed."""
    text = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
    return " ".join(text.split())[:limit]


def _check_reachable(address: str) -> None:
    """Fail fast when ``HOST:PORT`` (or ``ray://HOST:PORT``) does not accept connections (``auto`` is Ray's)."""
    host, colon, port = address.removeprefix("ray://").rpartition(":")
    if not colon or not port.isdigit():
        if address != "auto":
            raise EvalError(f"a Ray cluster address is auto, HOST:PORT or ray://HOST:PORT, got {address!r}")
        return
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=CONNECT_TIMEOUT_S).close()
    except OSError as e:
        raise EvalError(f"cannot reach the Ray cluster at {address}: {e.strerror or e}") from None


def task_options(backend: BackendName, resources: dict[str, float]) -> dict[str, float]:
    """What one job's Ray task asks for on a cluster with ``resources``: a CPU, and a share of a GPU when
    it simulates on warp and the cluster has GPUs; no automatic retry (a lost job is submitted again here)."""
    gpu = 1 / JOBS_PER_GPU if backend == "warp" and resources.get("GPU", 0) > 0 else 0
    return {"num_cpus": 1, "num_gpus": gpu, "max_retries": 0}


class RayExecutor:
    """Jobs as Ray tasks: on the cluster at ``address`` (None: ``$RAY_ADDRESS``, else a Ray started here and
    shut down by :meth:`close`), or on the Ray this process is already connected to."""

    def __init__(self, address: str | None = None) -> None:
        if address is not None:
            _check_reachable(address)
        self._owns_ray = not ray.is_initialized()
        if self._owns_ray:
            try:
                ray.init(address=address, include_dashboard=False, logging_level=logging.ERROR, log_to_driver=False)
            except (ConnectionError, ValueError, RuntimeError) as e:
                where = f"the Ray cluster at {address}" if address else "a Ray on this machine"
                raise EvalError(f"cannot connect to {where}: {_one_line(e)}") from None

    def _resources(self) -> dict[str, float]:
        return dict(ray.cluster_resources())

    def backend(self, asked: BackendName | None) -> BackendName:
        """``asked``, or warp when the cluster has GPUs, else mujoco."""
        return asked or ("warp" if self._resources().get("GPU", 0) > 0 else "mujoco")

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
        """See :meth:`~robotool.eval.executor.Executor.run`: ``done`` is called here, in the calling thread.

        Each job asks for a worker of its own, so ``exclusive`` needs nothing more. At most twice as many
        jobs as the cluster has CPUs are submitted at a time, so that ``skip`` is asked shortly before a
        job starts.
        """
        resources = self._resources()
        task = ray.remote(_attempt).options(**task_options(backend, resources))
        window = max(2, 2 * int(resources.get("CPU", 1)))
        work_ref = ray.put(work)
        driver_version = version()
        waiting = deque(jobs)
        running: dict[ray.ObjectRef, tuple[J, int]] = {}

        def submit(job: J, attempt: int) -> None:
            running[task.remote(work_ref, job, driver_version)] = (job, attempt)

        try:
            while waiting or running:
                while waiting and len(running) < window:
                    job = waiting.popleft()
                    if not skip(job):
                        submit(job, 1)
                if not running:
                    continue
                (ref,), _ = ray.wait(list(running), num_returns=1)
                job, attempt = running.pop(ref)
                try:
                    outcome: R | WorkerLost = ray.get(ref)
                except LOST as e:
                    if attempt <= RETRIES:
                        submit(job, attempt + 1)
                        continue
                    outcome = WorkerLost(f"its Ray worker was lost on all {attempt} attempts ({_one_line(e)})")
                except ray_errors.RayTaskError as e:
                    raise EvalError(f"a Ray task failed: {_one_line(e.cause or e)}") from None
                except ray_errors.RayError as e:
                    raise EvalError(f"a Ray task failed: {type(e).__name__}: {_one_line(e)}") from None
                done(job, outcome)
        except BaseException:
            for ref in running:
                ray.cancel(ref, force=True)
            raise

    def close(self) -> None:
        """Shut down the Ray this executor started (a cluster it connected to keeps running)."""
        if self._owns_ray and ray.is_initialized():
            ray.shutdown()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        self.close()
