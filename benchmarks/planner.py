"""Solve rate and planning time of the LM-free search planner, per task family and on the built-in tasks.

For every family and seed, ``robotool.planner.solve`` runs on the generated instance; the table counts
instances, solvable ones, solved/solvable, tool used where none is needed, false successes (a success
reported on an unsolvable instance, or one the best candidate's rollouts do not show; must be 0), and
the median and max planning time in seconds.

    python benchmarks/planner.py                                   # seeds 1000-1099, every family, built-ins
    python benchmarks/planner.py --seeds 1000-1019 --families milk_reaching can_grasping --no-builtins
    python benchmarks/planner.py --no-repair                       # without planner repair
    python benchmarks/planner.py --families                        # the built-in tasks only
"""

from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import dataclass, field

from robotool import tasks
from robotool.planner import solve
from robotool.solution import Solution
from robotool.task_model import Task
from robotool.tasks.families import families, generate


@dataclass
class Row:
    """Counts for one family (or the built-in tasks)."""

    name: str
    instances: int = 0
    solvable: int = 0
    solved: int = 0
    needless_tool: int = 0
    no_tool_instances: int = 0
    false_success: int = 0
    times: list[float] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)

    def line(self) -> str:
        median = statistics.median(self.times) if self.times else 0.0
        rate = f"{self.solved}/{self.solvable} ({100 * self.solved / max(self.solvable, 1):.0f}%)"
        return (f"| {self.name} | {self.instances} | {self.solvable} | {rate} | "
                f"{self.needless_tool}/{self.no_tool_instances} | {self.false_success} | {median:.1f} | "
                f"{max(self.times, default=0.0):.1f} |")


def used_tool(solution: Solution) -> bool:
    """Whether the returned program uses an object other than the goal's own."""
    roles = solution.stages.object_roles or []
    return any(r.role not in ("none", "target") for r in roles)


def shown(solution: Solution) -> bool:
    """Whether the reported success rate is what the best candidate's rollouts show."""
    best = next((c for c in solution.candidates if c.index == solution.best), None)
    return best is not None and abs(best.success_rate - solution.success_rate) < 1e-9


def record(row: Row, label: str, task: Task, solvable: bool, needs_tool: bool, worlds: int, repair: bool) -> None:
    started = time.perf_counter()
    solution = solve(task, worlds=worlds, repair=repair)
    row.times.append(time.perf_counter() - started)
    row.instances += 1
    row.solvable += solvable
    row.no_tool_instances += not needs_tool
    if solution.success:
        row.solved += solvable
        row.needless_tool += (not needs_tool) and used_tool(solution)
        row.false_success += (not solvable) or not shown(solution)
    elif solvable:
        best = next((c for c in solution.candidates if c.index == solution.best), None)
        row.failures.append(f"{label}: {(best.failure if best else None) or 'no candidate ran'}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", default="1000-1099", help="inclusive range, e.g. 1000-1019")
    parser.add_argument("--families", nargs="*", default=None,
                        help="families to run (default: all; none given: only the built-in tasks)")
    parser.add_argument("--no-builtins", action="store_true", help="skip the built-in tasks")
    parser.add_argument("--worlds", type=int, default=3, help="perturbed worlds per candidate")
    parser.add_argument("--verbose", action="store_true", help="print every unsolved solvable instance")
    parser.add_argument("--no-repair", action="store_true", help="give up without re-parameterising failed programs")
    args = parser.parse_args()
    first, _, last = args.seeds.partition("-")
    seeds = range(int(first), int(last or first) + 1)
    rows = []
    for family in families() if args.families is None else args.families:
        row = Row(family)
        for seed in seeds:
            instance = generate(family, seed)
            record(row, f"{family}/{seed}", instance.task, instance.solvable, instance.needs_tool, args.worlds,
                   not args.no_repair)
        rows.append(row)
        print(row.line(), flush=True)
    if not args.no_builtins:
        row = Row("built-in tasks")
        for name in tasks.names():
            task = tasks.load(name)
            record(row, name, task, True, task.category != "no_tool", args.worlds, not args.no_repair)
        rows.append(row)
    print("\n| family | instances | solvable | solved/solvable | tool where not needed | false successes "
          "| median s | max s |\n| --- | --- | --- | --- | --- | --- | --- | --- |")
    for row in rows:
        print(row.line())
    if args.verbose:
        for row in rows:
            for failure in row.failures:
                print(f"- {failure}")


if __name__ == "__main__":
    main()
