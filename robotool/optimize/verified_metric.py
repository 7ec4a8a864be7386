"""The simulator-verified metric: a proposal's candidates run in R perturbed worlds; the score is the best
candidate's success rate, and each stage gets feedback written for it from typed evidence.

:class:`Metric` accepts DSPy's GEPA signature ``(gold, pred, trace, pred_name, pred_trace)``. With a
``pred_name`` (GEPA asking for feedback on one predictor) it returns ``dspy.Prediction(score, feedback)``;
without one (evaluation, BootstrapFewShot, MIPROv2, SIMBA) the score alone. A proposal is verified once:
GEPA's per-predictor calls reuse the verdict. Verifications go through a
:class:`~robotool.optimize.batching.RolloutBatcher`, so concurrent metric calls for the same task share
one batched rollout.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from typing import Any

import dspy

from robotool.eval.failure_classes import TaskFacts
from robotool.optimize.batching import RolloutBatcher
from robotool.optimize.feedback import findings, stage_feedback
from robotool.solution import Proposal, Solution
from robotool.verify import select
from robotool.vocabulary import STAGES, BackendName, Stage

PREDICTOR_STAGES: dict[str, Stage] = {
    "analyze": "analyzer",
    "plan": "planner",
    "calculate": "calculator",
    "code": "coder",
}
"""Predictor name (as ``named_predictors()`` gives it) -> the stage it is."""
KEEP = 512
"""Verdicts kept for GEPA's per-predictor feedback calls on the same prediction."""


class Metric:
    """Verifies a :class:`~robotool.program.lm_program.Proposer`'s prediction; see the module docstring."""

    def __init__(
        self,
        *,
        worlds: int = 3,
        seed: int = 0,
        backend: BackendName | None = None,
        batcher: RolloutBatcher | None = None,
    ):
        if worlds < 1:
            raise ValueError("worlds must be at least 1")
        self.worlds, self.seed, self.backend = worlds, seed, backend
        self.batcher = batcher or RolloutBatcher()
        self._verdicts: OrderedDict[int, tuple[Proposal, Solution]] = OrderedDict()
        self._lock = threading.Lock()

    def __call__(
        self,
        gold: dspy.Example,
        pred: dspy.Prediction,
        trace: Any = None,
        pred_name: str | None = None,
        pred_trace: Any = None,
    ) -> float | dspy.Prediction:
        solution = self.verdict(gold, pred)
        if pred_name is None:
            return solution.success_rate
        return dspy.Prediction(score=solution.success_rate, feedback=self.feedback(gold, solution, pred_name))

    def verdict(self, gold: dspy.Example, pred: dspy.Prediction) -> Solution:
        """The proposal in ``pred`` verified in simulation (once per proposal)."""
        proposal = pred.get("proposal")
        if not isinstance(proposal, Proposal):
            raise TypeError(
                "the metric verifies what a robotool.program.lm_program.Proposer proposed; compile a Proposer "
                "(RoboTool verifies its own candidates)"
            )
        with self._lock:
            kept = self._verdicts.get(id(proposal))
            if kept is not None and kept[0] is proposal:
                return kept[1]
        solution = select(
            gold.task, proposal, worlds=self.worlds, seed=self.seed, backend=self.backend, runner=self.batcher
        )
        with self._lock:
            self._verdicts[id(proposal)] = (proposal, solution)
            while len(self._verdicts) > KEEP:
                self._verdicts.popitem(last=False)
        return solution

    def feedback(self, gold: dspy.Example, solution: Solution, pred_name: str) -> str:
        """The feedback for the predictor named ``pred_name`` (a stage's, or the whole program's)."""
        facts = TaskFacts.of(
            gold.task, needs_tool=gold.needs_tool, needed=frozenset(gold.tools) if gold.tools is not None else None
        )
        analyzed = any(call.stage == "analyzer" for call in solution.lm_calls)
        found = findings(gold.task, solution, facts, gold.key_concepts, analyzed)
        stage = PREDICTOR_STAGES.get(pred_name.rsplit(".", 1)[-1])
        if stage is None:  # a predictor this metric has no stage for: every finding, stage by stage
            return "\n\n".join(stage_feedback(s, solution.success_rate, self.worlds, found) for s in STAGES)
        return stage_feedback(stage, solution.success_rate, self.worlds, found)


metric = Metric()
"""The metric with its defaults: 3 perturbed worlds per candidate, seed 0, the default simulator."""
