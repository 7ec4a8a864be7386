"""Pools of worker processes for CPU-bound simulation (the interpreter lock keeps threads to one core)."""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor


def cores() -> int:
    """The CPU cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def process_pool(
    processes: int, initializer: Callable[[], None] | None = None, preload: Sequence[str] = ()
) -> ProcessPoolExecutor:
    """``processes`` fresh worker processes, started from a fork server (the caller may have threads, so no
    plain fork); each starts its own sandbox when it needs one. The fork server is one per process: the first pool
    starts it, after importing ``preload`` (modules its pool processes would each import again otherwise; none may
    start a thread, and one that is missing is skipped)."""
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["__main__", *preload])  # no effect once the fork server runs
    return ProcessPoolExecutor(max_workers=processes, mp_context=context, initializer=initializer)
