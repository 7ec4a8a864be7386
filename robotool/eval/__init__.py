"""The offline evaluator (``python -m robotool.eval``): methods x tasks x runs -> tables, plots, report.

Modules, one job each: :mod:`~robotool.eval.config` (what to run, defaults, output folder),
:mod:`~robotool.eval.instances` (which tasks), :mod:`~robotool.eval.solvers` (the methods),
:mod:`~robotool.eval.sweep` (the resumable loop), :mod:`~robotool.eval.work` (one run as a job),
:mod:`~robotool.eval.executor` (where runs are carried out: threads here) and
:mod:`~robotool.eval.ray_executor` (Ray tasks on a cluster), :mod:`~robotool.eval.executor_choice` (which one the
command line names), :mod:`~robotool.eval.journal` (durable records),
:mod:`~robotool.eval.judge` (a solution -> its record), :mod:`~robotool.eval.failure_classes` (failure classes),
:mod:`~robotool.eval.grading` (key-concept accuracy), :mod:`~robotool.eval.metrics`,
:mod:`~robotool.eval.tables`, :mod:`~robotool.eval.report`, :mod:`~robotool.eval.plots`,
:mod:`~robotool.eval.reference` (the paper's numbers). The command line is
:mod:`~robotool.cli.eval_command`.
"""

from robotool.eval.config import TIME_BUDGET_S, EvalConfig, EvalError, RunsNotAttempted, Settings
from robotool.eval.failure_classes import FailureClass, TaskFacts, classify, tools_used
from robotool.eval.grading import ConceptGrade, grade
from robotool.eval.records import Results, RunKey, RunRecord
from robotool.eval.solvers import METHODS, Solver
from robotool.eval.sweep import evaluate

__all__ = [
    "METHODS",
    "TIME_BUDGET_S",
    "ConceptGrade",
    "EvalConfig",
    "EvalError",
    "FailureClass",
    "Results",
    "RunKey",
    "RunRecord",
    "RunsNotAttempted",
    "Settings",
    "Solver",
    "TaskFacts",
    "classify",
    "evaluate",
    "grade",
    "tools_used",
]
