"""``RoboTool``: the four-stage DSPy program, its ablations, and candidates checked in simulation.

The Analyzer runs once; the Planner, Calculator and Coder run once per candidate, concurrently,
each candidate with its own ``rollout_id`` and temperature. Every candidate's code is validated by
the sandbox and run in ``worlds_per_candidate`` perturbed worlds, all candidates in one batch, and
the candidates are ranked (success rate, then fewer objects touched, then fewer skill calls).
The paper's ablations are the same module with stages switched off: see :data:`METHODS`. Repeated
runs that should sample afresh set ``rollout_base`` (candidate ``k`` uses rollout id ``rollout_base + k``).
"""

from __future__ import annotations

import contextvars
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import dspy

from robotool.describe import describe
from robotool.methods import METHODS
from robotool.scene import Task
from robotool.signatures import Analyze, Calculate, Code, Plan, scene_context
from robotool.solution import Candidate, Solution, StageOutputs, TokenUsage, rank
from robotool.verify import prepare_code, verify


class RoboTool(dspy.Module):
    """Description -> Analyzer -> Planner -> Calculator -> Coder -> K candidates verified in simulation."""

    def __init__(
        self,
        *,
        analyzer: bool = True,
        planner: bool = True,
        calculator: bool = True,
        candidates: int = 1,
        worlds_per_candidate: int = 3,
        backend: str | None = None,
        seed: int = 0,
        temperature: float = 0.7,
        max_temperature: float = 1.0,
        rollout_base: int = 0,
    ):
        super().__init__()
        if calculator and not planner:
            raise ValueError("the Calculator needs the Planner's steps")
        if candidates < 1 or worlds_per_candidate < 1:
            raise ValueError("candidates and worlds_per_candidate must be at least 1")
        self.analyze = dspy.Predict(Analyze) if analyzer else None
        self.plan = dspy.Predict(Plan) if planner else None
        self.calculate = dspy.Predict(Calculate) if calculator else None
        self.code = dspy.Predict(Code)
        self.candidates = candidates
        self.worlds_per_candidate = worlds_per_candidate
        self.backend = backend
        self.seed = seed
        self.temperature = temperature
        self.max_temperature = max_temperature
        self.rollout_base = rollout_base

    @classmethod
    def method(cls, name: str, **options: Any) -> RoboTool:
        """The full program or an ablation by name (see :data:`METHODS`)."""
        if name not in METHODS:
            raise ValueError(f"unknown method {name!r}; methods: {', '.join(METHODS)}")
        return cls(**METHODS[name], **options)

    @property
    def method_name(self) -> str:
        stages = {"analyzer": self.analyze is not None, "planner": self.plan is not None,
                  "calculator": self.calculate is not None}
        return next(name for name, switches in METHODS.items() if switches == stages)

    def forward(self, task: Task) -> dspy.Prediction:
        """Solve ``task``; the prediction carries the :class:`Solution` and the best code."""
        started = time.perf_counter()
        description = describe(task)
        shared = StageOutputs()
        usage: dict[str, TokenUsage] = {}
        analysis_failure = None
        with scene_context(task):
            if self.analyze is not None:
                try:
                    out, usage["analyzer"] = _tracked(lambda: self.analyze(description=description))
                    shared = StageOutputs(analysis=out.analysis, key_concepts=out.key_concepts)
                except Exception as e:
                    analysis_failure = f"analyzer: {_reason(e)}"
        lm_started = time.perf_counter()
        if analysis_failure is not None:
            candidates = [Candidate(index=k, stages=shared, failure=analysis_failure)
                          for k in range(self.candidates)]
        else:
            candidates = self._sample(task, description, shared)
        lm_done = time.perf_counter()
        verify(task, candidates, worlds=self.worlds_per_candidate, seed=self.seed, backend=self.backend)
        ranked = rank(candidates)
        best = ranked[0] if ranked[0].rollouts else None
        for candidate in candidates:
            for stage, tokens in candidate.usage.items():
                usage[stage] = usage.get(stage, TokenUsage()) + tokens
        solution = Solution(
            task=task.name,
            method=self.method_name,
            code=best.code if best else None,
            best=best.index if best else None,
            success_rate=best.success_rate if best else 0.0,
            candidates=candidates,
            stages=best.stages if best else shared,
            usage=usage,
            timings={"analyzer": lm_started - started, "candidates": lm_done - lm_started,
                     "verify": time.perf_counter() - lm_done, "total": time.perf_counter() - started},
        )
        return dspy.Prediction(solution=solution, code=solution.code)

    def _sample(self, task: Task, description: str, shared: StageOutputs) -> list[Candidate]:
        """Run the per-candidate stages for every candidate concurrently."""
        with ThreadPoolExecutor(max_workers=self.candidates) as pool:
            futures = []
            for k in range(self.candidates):
                context = contextvars.copy_context()  # carries dspy.context overrides into the thread
                futures.append(pool.submit(context.run, self._candidate, task, description, shared, k))
            return [f.result() for f in futures]

    def _config(self, k: int) -> dict[str, Any]:
        if self.candidates == 1:
            return {}
        spread = (self.max_temperature - self.temperature) * k / (self.candidates - 1)
        return {"rollout_id": self.rollout_base + k, "temperature": self.temperature + spread}

    def _candidate(self, task: Task, description: str, shared: StageOutputs, k: int) -> Candidate:
        candidate = Candidate(index=k, stages=shared.model_copy())
        stages, config = candidate.stages, self._config(k)
        concepts = shared.key_concepts or []
        stage = "planner"
        try:
            with scene_context(task):
                if self.plan is not None:
                    out, candidate.usage["planner"] = _tracked(
                        lambda: self.plan(description=description, key_concepts=concepts, config=config))
                    stages.object_roles, stages.abstract_plan, stages.steps = (
                        out.object_roles, out.abstract_plan, out.steps)
                stage = "calculator"
                if self.calculate is not None:
                    out, candidate.usage["calculator"] = _tracked(lambda: self.calculate(
                        description=description, key_concepts=concepts, steps=stages.steps, config=config))
                    stages.calculation, stages.parameters = out.calculation, out.parameters
                stage = "coder"
                out, candidate.usage["coder"] = _tracked(lambda: self.code(
                    description=description, steps=stages.steps or [], parameters=stages.parameters or [],
                    config=config))
        except Exception as e:
            candidate.failure = f"{stage}: {_reason(e)}"
            return candidate
        candidate.code, rejection = prepare_code(out.code, task)
        if rejection is not None:
            candidate.failure = f"coder: {rejection}"
        return candidate


def _tracked(call: Callable[[], dspy.Prediction]) -> tuple[dspy.Prediction, TokenUsage]:
    """Run one stage call and count its tokens."""
    with dspy.track_usage() as tracker:
        out = call()
    usage = TokenUsage()
    for entry in tracker.get_total_tokens().values():
        usage = usage + TokenUsage(prompt_tokens=int(entry.get("prompt_tokens") or 0),
                                   completion_tokens=int(entry.get("completion_tokens") or 0))
    return out, usage


def _reason(error: Exception) -> str:
    """One readable line for a failed LM stage."""
    if isinstance(error, dspy.utils.exceptions.AdapterParseError):
        text = " ".join(str(error).split())
        return f"the reply could not be parsed ({text[:300]})"
    first = " ".join(str(error).split())
    return f"{type(error).__name__}: {first[:300]}"

