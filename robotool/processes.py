"""Pools of worker processes for CPU-bound simulation (the interpreter lock keeps threads to one core)."""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor

PRELOAD = (
    "robotool.planner",
    "robotool.verify",
    "robotool.eval.work",
    "robotool.eval.pictures",
    "robotool.render.painter",
    "robotool.render.still",
    "robotool.render.run_videos",
)
"""Modules the fork server imports once, before it forks any pool process, so that no pool process imports
them again (about a second of CPU each); none starts a thread. One that is missing is skipped."""


def cores() -> int:
    """The CPU cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def process_pool(processes: int, initializer: Callable[[], None] | None = None) -> ProcessPoolExecutor:
    """``processes`` fresh worker processes, started from a fork server (the caller may have threads, so no
    plain fork) that has already imported :data:`PRELOAD`; each starts its own sandbox when it needs one."""
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["__main__", *PRELOAD])  # only before the fork server starts
    return ProcessPoolExecutor(max_workers=processes, mp_context=context, initializer=initializer)
