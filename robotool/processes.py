"""Pools of worker processes for CPU-bound simulation (the interpreter lock keeps threads to one core)."""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor


def cores() -> int:
    """The CPU cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def process_pool(processes: int, initializer: Callable[[], None] | None = None) -> ProcessPoolExecutor:
    """``processes`` fresh worker processes, started from a fork server (the caller may have threads, so no
    plain fork); each imports robotool and starts its own sandbox when it needs one."""
    return ProcessPoolExecutor(
        max_workers=processes, mp_context=multiprocessing.get_context("forkserver"), initializer=initializer
    )
