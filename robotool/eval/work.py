"""One evaluation run as a job any executor can carry: what it needs travels with it, its record comes back.

A :class:`RunJob` holds the task itself (not a path), so a worker needs no files of this machine; a
:class:`RunWork` holds the methods' solvers (with their LM and settings). Applying the work to a job
solves the task (the method verifies its K x R worlds in one batch) and judges the solution where it
ran, returning the run's :class:`~robotool.eval.records.RunRecord`, or :class:`NotAttempted` when the
language model was unavailable (not a result: the evaluator does not record it).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping
from dataclasses import dataclass, field

from robotool.bugs import describe
from robotool.errors import LMFailureKind, LMUnavailableError
from robotool.eval.instances import TaskInstance
from robotool.eval.judge import crashed, judge
from robotool.eval.records import RunKey, RunRecord
from robotool.eval.solvers import Compared, Solver
from robotool.safe_text import one_line

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class RunJob:
    """One run to carry out: the task instance, the run's key, and the seed of its perturbed worlds."""

    instance: TaskInstance
    key: RunKey
    world_seed: int


@dataclass(frozen=True)
class NotAttempted:
    """A run that could not be attempted because the language model was unavailable."""

    kind: LMFailureKind
    message: str

    def error(self) -> LMUnavailableError:
        """The error as the LM path raised it."""
        return LMUnavailableError(self.kind, self.message)


@dataclass(frozen=True)
class RunWork:
    """Solve and judge one run with the solver of its method; ``stages`` names, for each compiled program,
    the method whose stages it has (its Analyzer's key concepts are graded)."""

    solvers: Mapping[str, Solver]
    stages: Mapping[str, str] = field(default_factory=dict)

    def __call__(self, job: RunJob) -> RunRecord | NotAttempted:
        begun = time.perf_counter()
        key = job.key
        ran = self.stages.get(key.method)
        try:
            result = self.solvers[key.method](job.instance.task, seed=job.world_seed, run=key.run)
        except LMUnavailableError as e:  # nothing was attempted: not a result
            return NotAttempted(e.kind, str(e))
        except Exception as e:  # a bug in robotool: an internal error of this run, not of the evaluation
            logger.error(  # one line: the traceback is kept in the run's record (results.json)
                "internal error in run %s: the %s method raised %s", key.id, key.method, one_line(describe(e))
            )
            return crashed(job.instance, key, job.world_seed, e, time.perf_counter() - begun, stages=ran)
        solution = result.solution if isinstance(result, Compared) else result
        record = judge(job.instance, key, job.world_seed, solution, time.perf_counter() - begun, stages=ran)
        if isinstance(result, Compared):  # a run with repair rounds, and plain sampling at its LM calls
            record.equal_budget = result.equal_budget
        return record
