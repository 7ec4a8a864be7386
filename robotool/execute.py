"""Run one skill program against a task in perturbed worlds: ``robotool.run`` and ``robotool run``.

The program is parsed strictly (Python as written: a syntax error anywhere stops it before it runs)
and then goes through the same sandbox as generated code, so it is checked and confined exactly like a
model's.
"""

from __future__ import annotations

from pathlib import Path

from pydantic import BaseModel, Field

from robotool import tasks
from robotool.rollout import Rollout
from robotool.sandbox.strict import check_user_program
from robotool.sim.backend import default_backend
from robotool.sim.recorder import StateRecorder
from robotool.task.task_model import Task
from robotool.verify import run_codes
from robotool.vocabulary import BackendName


class RunReport(BaseModel):
    """Everything ``robotool run`` reports; ``--json`` writes this model."""

    task: str
    worlds: int
    seed: int
    backend: BackendName
    success: bool = Field(description="true when the goal was reached in every world")
    success_rate: float = Field(description="share of worlds in which the goal was reached")
    code: str
    rollouts: list[Rollout]


def run(
    task: Task | str | Path,
    code: str,
    *,
    worlds: int = 1,
    seed: int = 0,
    backend: BackendName | None = None,
    recorder: StateRecorder | None = None,
) -> RunReport:
    """Check ``code`` strictly in the sandbox and run it in ``worlds`` perturbed worlds of ``task``.

    A ``recorder`` keeps the states of the worlds it names (for videos).

    Raises :class:`~robotool.sandbox.ProgramRejected` for a program the sandbox refuses and
    :class:`~robotool.task.task_file.TaskFileError` for a bad task.
    """
    if worlds < 1:
        raise ValueError(f"worlds must be at least 1, got {worlds}")
    task = task if isinstance(task, Task) else tasks.load(task)
    program = check_user_program(code, task.embodiment)
    rollouts = run_codes(task, [program], worlds=worlds, seed=seed, backend=backend, recorder=recorder)[0]
    successes = sum(r.success for r in rollouts)
    return RunReport(
        task=task.name,
        worlds=worlds,
        seed=seed,
        backend=backend or default_backend(),
        success=successes == worlds,
        success_rate=successes / worlds,
        code=program,
        rollouts=rollouts,
    )
