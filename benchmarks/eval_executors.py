"""Runs per minute of the evaluator with the local executor and with the Ray executor, on the same sweep.

Both evaluate the same LM-free runs (the search planner and the no-tool floor) into fresh folders; the
table gives each executor's wall time, runs per minute, and for Ray the time to start (or connect to)
Ray, which a sweep pays once. The last line checks that both executors recorded the same runs with the
same outcomes.

    python benchmarks/eval_executors.py                               # the default sweep, Ray with 2 CPUs here
    python benchmarks/eval_executors.py --families milk_reaching --seeds 0-9 --worlds 3
    python benchmarks/eval_executors.py --address ray://HEAD:10001    # Ray executor on a cluster
"""

from __future__ import annotations

import argparse
import io
import logging
import os
import tempfile
import time
from pathlib import Path

from rich.console import Console

from robotool.cli.options import DEFAULT_WORLDS, cluster_address, positive_int
from robotool.eval import EvalConfig, Results, Settings, evaluate
from robotool.eval.config import DEFAULT_WORKERS
from robotool.eval.executor import Executor, LocalExecutor
from robotool.eval.instances import parse_seeds


def timed(config: EvalConfig, executor: Executor) -> tuple[Results, float]:
    """One evaluation and its wall time in seconds."""
    began = time.perf_counter()
    results = evaluate(config, console=Console(file=io.StringIO()), executor=executor)
    return results, time.perf_counter() - began


def outcomes(results: Results) -> list[tuple[str, float, str | None]]:
    """What must not depend on the executor: each run's key, success rate and failure class."""
    return [(r.key.id, r.success_rate, r.failure_class) for r in results.records]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tasks", nargs="+", help="built-in tasks or task files (default: the evaluator's default sweep)")
    p.add_argument("--families", nargs="+", help="task families (with --seeds)")
    p.add_argument("--seeds", type=parse_seeds, help="seeds of generated instances, e.g. 0-9")
    p.add_argument("--worlds", type=positive_int, default=DEFAULT_WORLDS)
    p.add_argument("--num-cpus", type=positive_int, default=2, help="CPUs of the Ray started here")
    p.add_argument("--address", type=cluster_address, help="a Ray cluster instead of a Ray started here")
    args = p.parse_args()
    import ray

    from robotool.eval.ray_executor import RayExecutor

    seeds = list(args.seeds) if args.seeds else None
    with tempfile.TemporaryDirectory() as folder:

        def config(name: str) -> EvalConfig:
            return EvalConfig(out=Path(folder) / name, tasks=args.tasks, families=args.families, seeds=seeds,
                              methods=["search", "no_tool"], settings=Settings(worlds=args.worlds))

        local, local_s = timed(config("local"), LocalExecutor(DEFAULT_WORKERS))
        began = time.perf_counter()
        if args.address is None:
            ray.init(num_cpus=args.num_cpus, include_dashboard=False, logging_level=logging.ERROR,
                     log_to_driver=False)
        with RayExecutor(args.address) as executor:
            start_s = time.perf_counter() - began
            on_ray, ray_s = timed(config("ray"), executor)
            cpus = int(ray.cluster_resources().get("CPU", 0))
        ray.shutdown()

    runs = len(local.records)
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    print(f"{runs} runs (search, no_tool; {args.worlds} worlds each); {os.cpu_count()} cores, load average {load}\n")
    print("| executor | wall s | runs / min | start s |")
    print("| --- | --- | --- | --- |")
    print(f"| local (runs take turns) | {local_s:.1f} | {60 * runs / local_s:.1f} | - |")
    print(f"| ray ({cpus} CPUs) | {ray_s:.1f} | {60 * runs / ray_s:.1f} | {start_s:.1f} |")
    same = outcomes(local) == outcomes(on_ray)
    print(f"\nsame runs and outcomes on both executors: {'yes' if same else 'NO'}")


if __name__ == "__main__":
    main()
