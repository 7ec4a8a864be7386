"""Concurrent metric calls merged into one batched rollout: world-steps per second of 8 concurrent metric
calls (R worlds each, through the metric's batching service) against one metric call with 8 x R worlds.

An optimiser with ``num_threads`` makes metric calls in parallel; :class:`~robotool.optimize.RolloutBatcher`
merges the ones for the same task into one batch. The program verified is the search planner's solution
of the task, each concurrent call's a little different (so each is simulated, none shared). A world-step
is one physics step of one world (its simulated time over the model's timestep). For comparison the same
8 calls are also made without merging (each its own batch).

    python benchmarks/metric_batching.py [--task milk_reaching_near] [--worlds 3] [--calls 8] [--repeats 2]

Target: merged / single >= 0.8.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor

os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")

import dspy

from robotool import tasks
from robotool.optimize import Metric, RolloutBatcher
from robotool.optimize.data import example
from robotool.planner import solve
from robotool.rollout import Rollout
from robotool.sim import build
from robotool.solution import Candidate, Proposal
from robotool.task.task_model import Task
from robotool.verify import run_codes


def _prediction(task_name: str, code: str) -> dspy.Prediction:
    proposal = Proposal(task=task_name, method="coder", candidates=[Candidate(index=0, code=code)])
    return dspy.Prediction(proposal=proposal)


def _world_steps(metric: Metric, gold: dspy.Example, preds: list[dspy.Prediction], timestep: float) -> float:
    worlds = [r for p in preds for c in metric.verdict(gold, p).candidates for r in c.rollouts]
    return sum(r.sim_time for r in worlds) / timestep


def _calls(metric: Metric, gold: dspy.Example, preds: list[dspy.Prediction]) -> None:
    """The metric calls, all at once (as an optimiser's threads make them)."""
    with ThreadPoolExecutor(max_workers=len(preds)) as pool:
        list(pool.map(lambda p: metric(gold, p), preds))


class _Unmerged:
    """A runner that gives every call its own batch (what the metric would do without the batching service)."""

    def __call__(
        self, task: Task, codes: Sequence[str], *, worlds: int, seed: int = 0, backend: str | None = None
    ) -> list[list[Rollout]]:
        return run_codes(task, codes, worlds=worlds, seed=seed, backend=backend)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--task", default="milk_reaching_near")
    parser.add_argument("--worlds", type=int, default=3)
    parser.add_argument("--calls", type=int, default=8)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--backend", choices=["mujoco", "warp"])
    args = parser.parse_args()
    task = tasks.load(args.task)
    gold = example(task)
    timestep = build(task).model.opt.timestep
    base = solve(task, worlds=1, backend=args.backend).code
    if base is None:
        raise SystemExit(f"the search planner found no program for {args.task}")
    codes = [base + f"x = {k}\n" for k in range(args.calls)]  # distinct programs, the same motions

    def rate(make_metric: Callable[[], Metric], preds_of: Callable[[], list[dspy.Prediction]]) -> float:
        best = 0.0
        for _ in range(args.repeats):
            metric, preds = make_metric(), preds_of()
            started = time.perf_counter()
            _calls(metric, gold, preds)
            wall = time.perf_counter() - started
            best = max(best, _world_steps(metric, gold, preds, timestep) / wall)
        return best

    merged = rate(lambda: Metric(worlds=args.worlds, backend=args.backend, batcher=RolloutBatcher()),
                  lambda: [_prediction(task.name, c) for c in codes])
    unmerged = rate(lambda: Metric(worlds=args.worlds, backend=args.backend, batcher=_Unmerged()),
                    lambda: [_prediction(task.name, c) for c in codes])
    single = rate(lambda: Metric(worlds=args.worlds * args.calls, backend=args.backend),
                  lambda: [_prediction(task.name, codes[0])])
    print(f"task {task.name}, {args.calls} calls x {args.worlds} worlds, best of {args.repeats}")
    print(f"one call with {args.calls * args.worlds} worlds:        {single:12.0f} world-steps/s")
    for label, value in (("merged", merged), ("unmerged", unmerged)):
        share = f"({value / single:.2f} of single)"
        print(f"{args.calls} concurrent calls, {label + ':':10} {value:12.0f} world-steps/s  {share}")


if __name__ == "__main__":
    main()
