"""The budgets one sandboxed program runs under."""

from __future__ import annotations

import os

from pydantic import BaseModel, ConfigDict, Field


class BatchTooLarge(ValueError):
    """A batch of more programs than the sandbox's memory can give each one its MiB (see
    :meth:`SandboxLimits.for_batch`); the command line refuses it before anything runs."""

    def __init__(self, programs: int, batch_mb: int) -> None:
        super().__init__(
            f"a batch of {programs} programs does not fit in {batch_mb} MiB of sandbox memory "
            f"(at least 1 MiB each: at most {batch_mb} programs at once)"
        )
        self.programs, self.batch_mb = programs, batch_mb


class SandboxLimits(BaseModel):
    """Per-program limits. Time spent waiting for the simulator to answer a skill call counts
    against none of them: ``cpu_s`` is the worker's own CPU time (it does not grow while 256 workers
    share two cores, only their wall time does), and ``wall_s`` only runs while the worker owes the
    runner an answer: from ``resume`` until its next skill call or its end begins to arrive (the runner
    watches every world at once), and while ``wait`` then reads it. A message that has already arrived
    is always accepted, so ``wall_s`` is a backstop for a worker that is stuck without using CPU, set
    well above ``cpu_s``."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    cpu_s: float = Field(2.0, gt=0, description="CPU seconds for the whole program (SIGPROF timer)")
    wall_s: float = Field(
        30.0, gt=0, description="wall seconds while the runner waits on the program, summed over its run"
    )
    memory_mb: int = Field(256, gt=0, description="address space the program may add to the worker, MiB")
    batch_memory_mb: int | None = Field(
        None,
        gt=0,
        description="address space all programs of one batch may add together, MiB (default: half of this "
        "machine's physical memory); each of N programs gets at most batch_memory_mb / N",
    )
    max_output_chars: int = Field(20_000, gt=0, description="characters the program may print")
    max_batch_output_chars: int = Field(
        1_000_000, gt=0, description="characters kept from the output of all programs of one batch together"
    )
    max_skill_calls: int = Field(500, gt=0, description="skill calls (queries and motions) per program")

    def for_batch(self, programs: int) -> SandboxLimits:
        """The limits of each program of a batch of ``programs`` that run at once: ``memory_mb`` cut to
        an equal share of the batch's memory, so that the batch together cannot exhaust the machine
        (the worker's address-space limit is what enforces it). Raises :class:`BatchTooLarge` (a ``ValueError``)
        when a share would be under 1 MiB."""
        batch_mb = self.batch_memory_mb or default_batch_memory_mb()
        share = batch_mb // max(programs, 1)
        if share < 1:
            raise BatchTooLarge(programs, batch_mb)
        return self.model_copy(update={"memory_mb": min(self.memory_mb, share)})

    def skill_calls_exceeded(self) -> str:
        return f"skill call limit exceeded (more than {self.max_skill_calls} calls)"


def default_batch_memory_mb() -> int:
    """Half of this machine's physical memory, in MiB: what all sandboxed programs may hold by default."""
    return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") // 2 // 2**20
