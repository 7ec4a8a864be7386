"""Solve rate and planning time of the LM-free search planner, per task family and on the built-in tasks.

For every family and seed, ``robotool.planner.solve`` runs on the generated instance; the table counts
instances, solvable ones, solved/solvable (the returned program succeeds in at least one world), solved in
every world/solvable (the returned program succeeds in every world the planner ran it in, planning and
verification worlds alike), the share of those worlds in which the returned programs succeed on solvable
instances, held in fresh worlds/solvable (the returned program, run again in ``--fresh`` perturbed worlds
whose seeds neither the planning nor the verification used, succeeds in every one of them; not counted in
the planning time), tool used where none is needed, false successes (a success reported on an unsolvable
instance, or one the best candidate's rollouts do not show; must be 0), and the median and max planning time
in seconds.

    python benchmarks/planner.py                                   # seeds 1000-1099, every family, built-ins
    python benchmarks/planner.py --seeds 1000-1019 --families milk_reaching can_grasping --no-builtins
    python benchmarks/planner.py --jobs 2                          # two instances at once
    python benchmarks/planner.py --no-repair                       # without planner repair
    python benchmarks/planner.py --families                        # the built-in tasks only
    python benchmarks/planner.py --fresh 0                         # skip the re-run in fresh worlds
    python benchmarks/planner.py --families --no-builtins --task-files held_out/   # task files kept elsewhere

Task files (``--task-files``: files or folders of ``*.yaml``) are counted as solvable instances in a row of their
own; a file that does not load is listed with its error and counted as not solved.
"""

from __future__ import annotations

import argparse
import statistics
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from robotool import tasks
from robotool.planner import solve
from robotool.sim.backend_mujoco import share_cores
from robotool.solution import Solution
from robotool.task.task_model import Task
from robotool.tasks.families import families, generate
from robotool.verify import failure_reason, run_codes

FRESH_SEED = 50_000  # first world seed of the re-run in fresh worlds, far from the planner's own seeds


@dataclass
class Row:
    """Counts for one family (or the built-in tasks)."""

    name: str
    instances: int = 0
    solvable: int = 0
    solved: int = 0
    solved_everywhere: int = 0
    held_fresh: int = 0
    needless_tool: int = 0
    no_tool_instances: int = 0
    false_success: int = 0
    times: list[float] = field(default_factory=list)
    world_rates: list[float] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)

    def line(self) -> str:
        median = statistics.median(self.times) if self.times else 0.0
        rate, everywhere, fresh = (
            f"{n}/{self.solvable} ({100 * n / max(self.solvable, 1):.0f}%)"
            for n in (self.solved, self.solved_everywhere, self.held_fresh)
        )
        worlds = f"{100 * statistics.fmean(self.world_rates):.0f}%" if self.world_rates else "-"
        return (
            f"| {self.name} | {self.instances} | {self.solvable} | {rate} | {everywhere} | {worlds} | {fresh} | "
            f"{self.needless_tool}/{self.no_tool_instances} | {self.false_success} | {median:.1f} | "
            f"{max(self.times, default=0.0):.1f} |"
        )


def used_tool(solution: Solution) -> bool:
    """Whether the returned program uses an object other than the goal's own."""
    roles = solution.stages.object_roles or []
    return any(r.role not in ("none", "target") for r in roles)


def shown(solution: Solution) -> bool:
    """Whether the reported success rate is what the best candidate's rollouts show."""
    best = next((c for c in solution.candidates if c.index == solution.best), None)
    return best is not None and abs(best.success_rate - solution.success_rate) < 1e-9


@dataclass(frozen=True)
class Attempt:
    """One planner run on one instance, as the table counts it."""

    label: str
    solvable: bool
    needs_tool: bool
    success: bool
    used_tool: bool
    shown: bool
    world_rate: float
    held_fresh: bool
    seconds: float
    failure: str


def attempt(label: str, task: Task, solvable: bool, needs_tool: bool, worlds: int, repair: bool, fresh: int) -> Attempt:
    """Run the planner on one instance, then its program again in ``fresh`` unseen perturbed worlds."""
    started = time.perf_counter()
    solution = solve(task, worlds=worlds, repair=repair)
    seconds = time.perf_counter() - started
    best = next((c for c in solution.candidates if c.index == solution.best), None)
    failure = "" if solution.success_rate == 1.0 else str((best.failure if best else None) or "no candidate ran")
    held = solution.success and solution.code is not None
    if held and fresh:
        reason = failure_reason(run_codes(task, [solution.code], worlds=fresh, seed=FRESH_SEED)[0])
        held = reason is None
        if reason is not None:
            failure = f"in fresh worlds, {reason}"
    return Attempt(
        label,
        solvable,
        needs_tool,
        solution.success,
        used_tool(solution),
        shown(solution),
        solution.success_rate,
        held,
        seconds,
        failure,
    )


def attempt_family(family: str, seed: int, worlds: int, repair: bool, fresh: int) -> Attempt:
    """Generate one family instance and run the planner on it (a picklable job for worker processes)."""
    instance = generate(family, seed)
    return attempt(f"{family}/{seed}", instance.task, instance.solvable, instance.needs_tool, worlds, repair, fresh)


def task_files(paths: list[Path]) -> dict[str, Task]:
    """The tasks of the YAML files named, and of those in the folders named in name order; exits naming every file
    that does not load."""
    files = [f for p in paths for f in (sorted(p.glob("*.yaml")) if p.is_dir() else [p])]
    loaded, problems = {}, []
    for f in files:
        try:
            loaded[str(f)] = tasks.load(f)
        except (OSError, ValueError) as e:
            problems.append(f"- {e}")
    if problems:
        raise SystemExit("task files that do not load:\n" + "\n".join(problems))
    return loaded


def add(row: Row, result: Attempt) -> None:
    row.times.append(result.seconds)
    row.instances += 1
    row.solvable += result.solvable
    row.no_tool_instances += not result.needs_tool
    if result.solvable:
        row.world_rates.append(result.world_rate)
    if result.success:
        row.solved += result.solvable
        row.solved_everywhere += result.solvable and result.world_rate == 1.0
        row.held_fresh += result.solvable and result.world_rate == 1.0 and result.held_fresh
        row.needless_tool += (not result.needs_tool) and result.used_tool
        row.false_success += (not result.solvable) or not result.shown
    if result.solvable and result.failure:
        row.failures.append(f"{result.label}: {result.failure}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", default="1000-1099", help="inclusive range, e.g. 1000-1019")
    parser.add_argument(
        "--families",
        nargs="*",
        default=None,
        help="families to run (default: all; none given: only the built-in tasks)",
    )
    parser.add_argument("--no-builtins", action="store_true", help="skip the built-in tasks")
    parser.add_argument("--worlds", type=int, default=3, help="perturbed worlds per candidate")
    parser.add_argument(
        "--verbose",
        action="store_true",
        help="print every instance as it is done, and every solvable one not solved in every world",
    )
    parser.add_argument("--jobs", type=int, default=1, help="instances planned at once, in worker processes")
    parser.add_argument(
        "--fresh",
        type=int,
        default=5,
        help="perturbed worlds, unseen by the planner, each returned program runs in again (0: none)",
    )
    parser.add_argument("--no-repair", action="store_true", help="give up without re-parameterising failed programs")
    parser.add_argument(
        "--task-files", nargs="*", type=Path, default=[], help="task files, or folders of them, run as solvable"
    )
    args = parser.parse_args()
    first, _, last = args.seeds.partition("-")
    seeds = range(int(first), int(last or first) + 1)
    files = task_files(args.task_files)
    rows = []
    names = families() if args.families is None else args.families
    # the worker processes simulate at once: each batch steps on its process's share of the cores
    with ProcessPoolExecutor(max_workers=args.jobs, initializer=share_cores, initargs=(args.jobs,)) as pool:
        pending = {
            family: [
                pool.submit(attempt_family, family, seed, args.worlds, not args.no_repair, args.fresh) for seed in seeds
            ]
            for family in names
        }
        for family in names:
            row = Row(family)
            for job in pending[family]:
                result = job.result()
                add(row, result)
                if args.verbose:
                    print(
                        f"  {result.label}: {result.seconds:.1f} s, {100 * result.world_rate:.0f}% of worlds"
                        f"{', held in fresh worlds' if result.held_fresh else ''}"
                        f"{'' if result.solvable else ', unsolvable'}",
                        flush=True,
                    )
            rows.append(row)
            print(row.line(), flush=True)
            for failure in row.failures if args.verbose else []:
                print(f"- {failure}", flush=True)
        if files:
            row = Row("task files")
            repair = not args.no_repair
            jobs = [
                pool.submit(attempt, name, task, True, task.category != "no_tool", args.worlds, repair, args.fresh)
                for name, task in files.items()
            ]
            for job in jobs:
                result = job.result()
                add(row, result)
                if args.verbose:
                    print(f"  {result.label}: {result.seconds:.1f} s, {100 * result.world_rate:.0f}% of worlds")
            rows.append(row)
            print(row.line(), flush=True)
    if not args.no_builtins:
        row = Row("built-in tasks")
        for name in tasks.names():
            task = tasks.load(name)
            add(row, attempt(name, task, True, task.category != "no_tool", args.worlds, not args.no_repair, args.fresh))
        rows.append(row)
    print(
        "\n| family | instances | solvable | solved/solvable | solved in every world | worlds succeeded "
        "| held in fresh worlds | tool where not needed | false successes | median s | max s |\n"
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    )
    for row in rows:
        print(row.line())
    if args.verbose:
        for row in rows:
            for failure in row.failures:
                print(f"- {failure}")


if __name__ == "__main__":
    main()
