"""Prompt optimisation of the RoboTool program against simulator-verified success.

Modules, one job each: :mod:`~robotool.optimize.data` (examples and disjoint splits),
:mod:`~robotool.optimize.verified_metric` (verification and the score), :mod:`~robotool.optimize.feedback` (what
each stage is told), :mod:`~robotool.optimize.batching` (concurrent verifications merged into one batch),
:mod:`~robotool.optimize.demos` (offline demonstrations from the search planner),
:mod:`~robotool.optimize.run` (one optimisation run), :mod:`~robotool.cli.optimize_command` (the command line).
"""

from robotool.optimize.batching import RolloutBatcher
from robotool.optimize.data import SEED_RANGES, DatasetError, Splits, dataset, splits
from robotool.optimize.run import OPTIMIZERS, OptimizeError, OptimizerBudget, OptimizeSettings, optimize
from robotool.optimize.verified_metric import Metric, metric

__all__ = [
    "OPTIMIZERS",
    "SEED_RANGES",
    "DatasetError",
    "Metric",
    "OptimizeError",
    "OptimizeSettings",
    "OptimizerBudget",
    "RolloutBatcher",
    "Splits",
    "dataset",
    "metric",
    "optimize",
    "splits",
]
