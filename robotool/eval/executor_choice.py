"""Which executor the evaluator's command line names: ``local`` (threads here) or ``ray`` (a Ray cluster)."""

from __future__ import annotations

from typing import Literal

from robotool.eval.config import EvalError
from robotool.eval.executor import Executor, LocalExecutor

ExecutorName = Literal["local", "ray"]
EXECUTORS: tuple[ExecutorName, ...] = ("local", "ray")

RAY_MISSING = "the Ray executor needs Ray, which is not installed: pip install 'robotool[ray]'"


def make_executor(name: ExecutorName, *, workers: int, processes: int = 1, address: str | None = None) -> Executor:
    """The executor the command line names; ``address`` is the Ray cluster's (None: a Ray on this machine).

    Raises :class:`~robotool.eval.config.EvalError` when Ray is asked for and not installed, or cannot connect.
    """
    if name == "local":
        if address is not None:
            raise EvalError("--address needs --executor ray")
        return LocalExecutor(workers, processes)
    try:
        import ray  # noqa: F401
    except ImportError:
        raise EvalError(RAY_MISSING) from None
    from robotool.eval.ray_executor import RayExecutor  # imports Ray

    return RayExecutor(address)
