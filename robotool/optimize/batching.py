"""A batching service for verification: concurrent requests for the same task run as one batched rollout.

An optimiser evaluates examples on several threads (``num_threads``); each metric call verifies a few
programs in a few perturbed worlds. Stepping each call's small batch on its own wastes the simulator,
whose cost per step hardly grows with the batch. :class:`RolloutBatcher` is a :class:`~robotool.verify.CodeRunner`:
the first caller to arrive waits :attr:`~RolloutBatcher.window` seconds for others, then runs every
pending request, those of the same task (and backend) merged into one batch, and hands each caller its
own worlds; callers that arrive meanwhile are served by the next round. Each world is perturbed from its
own seed, so a merged batch gives every request the rollouts it would have got alone. Requests for
different tasks cannot share a batch (they are different simulated scenes) and run one after the other.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

from robotool.rollout import Rollout
from robotool.task.task_model import Task
from robotool.verify import run_worlds
from robotool.vocabulary import BackendName

DEFAULT_WINDOW = 0.05
"""Seconds the first request waits for concurrent ones before its batch runs."""


@dataclass
class _BatchRequest:
    task: Task
    codes: list[str]
    worlds: int
    seed: int
    backend: BackendName | None
    result: list[list[Rollout]] | None = None
    error: BaseException | None = None
    done: bool = False
    key: tuple[str, str | None] = field(init=False)

    def __post_init__(self) -> None:
        self.key = (self.task.model_dump_json(), self.backend)

    @property
    def programs(self) -> list[str]:
        return [code for code in self.codes for _ in range(self.worlds)]

    @property
    def world_seeds(self) -> list[int]:
        return [self.seed + r for _ in self.codes for r in range(self.worlds)]


class RolloutBatcher:
    """Merges concurrent :meth:`run_codes` calls for the same task into one batch (see the module docstring)."""

    def __init__(self, window: float = DEFAULT_WINDOW):
        if window < 0:
            raise ValueError(f"window must be at least 0 s, got {window}")
        self.window = window
        self.batches: list[int] = []
        """How many requests each batch run so far merged (for reports and tests)."""
        self._pending: list[_BatchRequest] = []
        self._busy = False
        self._changed = threading.Condition()

    def __call__(
        self, task: Task, codes: Sequence[str], *, worlds: int, seed: int = 0, backend: BackendName | None = None
    ) -> list[list[Rollout]]:
        """Like :func:`robotool.verify.run_codes`: each program in ``worlds`` perturbed worlds."""
        return self.run_codes(task, codes, worlds=worlds, seed=seed, backend=backend)

    def run_codes(
        self, task: Task, codes: Sequence[str], *, worlds: int, seed: int = 0, backend: BackendName | None = None
    ) -> list[list[Rollout]]:
        """Like :func:`robotool.verify.run_codes`, merged with concurrent calls for the same task."""
        if not codes:
            return []
        request = _BatchRequest(task, list(codes), worlds, seed, backend)
        with self._changed:
            self._pending.append(request)
            while not request.done and self._busy:
                self._changed.wait()
            if not request.done:
                self._busy = True  # this caller runs the next round
        if not request.done:
            self._lead()
        if request.error is not None:
            raise request.error
        assert request.result is not None
        return request.result

    def _lead(self) -> None:
        """Collect for the window, run every pending request, and wake the callers."""
        try:
            time.sleep(self.window)
            with self._changed:
                taken, self._pending = self._pending, []
            groups: dict[tuple[str, str | None], list[_BatchRequest]] = {}
            for request in taken:
                groups.setdefault(request.key, []).append(request)
            for group in groups.values():
                self._run(group)
        finally:
            with self._changed:
                self._busy = False
                self._changed.notify_all()

    def _run(self, group: list[_BatchRequest]) -> None:
        """One batch for requests of the same task; each request gets its own slice of the worlds back."""
        try:
            rollouts = run_worlds(
                group[0].task,
                [p for r in group for p in r.programs],
                [s for r in group for s in r.world_seeds],
                backend=group[0].backend,
            )
        except BaseException as e:  # every caller of this batch learns why it failed
            for request in group:
                request.error, request.done = e, True
            return
        self.batches.append(len(group))
        start = 0
        for request in group:
            mine = rollouts[start : start + len(request.programs)]
            start += len(request.programs)
            request.result = [mine[i * request.worlds : (i + 1) * request.worlds] for i in range(len(request.codes))]
            for k, world in enumerate(w for worlds in request.result for w in worlds):
                world.world = k  # numbered within the request, as a batch of its own would number it
            request.done = True
