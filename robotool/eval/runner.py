"""``evaluate``: methods x task instances x runs -> journal -> results folder.

Runs are keyed by (task, seed, method, run). Each finished run is appended to the folder's journal
by the thread that ran it, so an interrupted evaluation resumes where it stopped: rerunning the
same command skips every run already in the journal. Runs go through a thread pool; LM-free runs
(pure simulation on the CPU) take turns on a lock, while LM runs overlap their LM calls.
"""

from __future__ import annotations

import contextlib
import contextvars
import threading
import time
from collections.abc import Mapping
from concurrent.futures import Future, ThreadPoolExecutor, as_completed
from typing import TYPE_CHECKING

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from robotool.eval.config import EvalConfig, EvalError, Settings
from robotool.eval.instances import TaskInstance, select
from robotool.eval.journal import Journal, write_atomic
from robotool.eval.judge import crashed, judge
from robotool.eval.metrics import summarize
from robotool.eval.plots import write_plots
from robotool.eval.records import Results, RunKey, RunRecord
from robotool.eval.report import markdown, print_tables, skipped_lines
from robotool.eval.solvers import METHODS, Solver, SolverSettings, make_solvers
from robotool.eval.tables import all_tables

if TYPE_CHECKING:
    import dspy

SETTINGS = "settings.json"


def _lm(config: EvalConfig, lm: dspy.LM | None) -> dspy.LM | None:
    """The LM given, or the one the configuration names (None without either)."""
    if lm is not None:
        return lm
    from robotool.lm import make_lm

    return make_lm(config.settings.lm, api_base=config.api_base, api_key_env=config.api_key_env,
                   temperature=config.settings.temperature)


def _methods(
    config: EvalConfig, lm: dspy.LM | None, overrides: Mapping[str, Solver] | None
) -> tuple[dict[str, Solver], dict[str, str]]:
    """Solvers to run and methods skipped; a method asked for by name that cannot run is an error."""
    names = config.methods or list(METHODS)
    unknown = [m for m in names if m not in METHODS]
    if unknown:
        raise EvalError(f"unknown method {', '.join(unknown)}; methods: {', '.join(METHODS)}")
    settings = SolverSettings(candidates=config.settings.candidates, worlds=config.settings.worlds,
                              backend=config.settings.backend)
    solvers, skipped = make_solvers(names, settings, lm, overrides)
    if config.methods is not None and skipped:
        method, why = next(iter(skipped.items()))
        raise EvalError(f"cannot run {method}: {why}")
    if not solvers:
        raise EvalError("no method can run here: " + "; ".join(skipped_lines(skipped)))
    return solvers, skipped


def _check_settings(config: EvalConfig) -> None:
    """Refuse to mix results made with other settings into the output folder."""
    folder = config.out_dir
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / SETTINGS
    current = config.settings.model_dump_json(indent=2)
    if path.exists():
        before = Settings.model_validate_json(path.read_text())
        if before != config.settings:
            raise EvalError(f"{folder} holds results made with other settings ({before.model_dump()}); "
                            "choose another --out")
    else:
        write_atomic(path, current)


def evaluate(
    config: EvalConfig,
    *,
    lm: dspy.LM | None = None,
    solvers: Mapping[str, Solver] | None = None,
    console: Console | None = None,
) -> Results:
    """Run every (instance, method, run) not yet in the journal, then write the results folder.

    ``lm`` replaces the LM the configuration names; ``solvers`` replaces methods' solvers (tests).
    """
    started = time.perf_counter()
    console = console or Console()
    lm = _lm(config, lm)
    if lm is not None and config.settings.lm is None:
        config = config.model_copy(update={"settings": config.settings.model_copy(update={"lm": lm.model})})
    instances, notes = select(config.tasks, config.families, config.seeds)
    chosen, skipped = _methods(config, lm, solvers)
    _check_settings(config)
    journal = Journal(config.out_dir)
    plan = [(instance, RunKey(task=instance.name, seed=instance.seed, method=method, run=run))
            for instance in instances for method in chosen for run in range(config.runs)]
    for line in skipped_lines(skipped):
        console.print(line, style="yellow", highlight=False)
    _run(config, chosen, [(i, k) for i, k in plan if k.id not in journal], journal, len(plan), console)
    results = Results(config=config, skipped=skipped, notes=notes,
                      records=[journal.records[k.id] for _, k in plan], wall_s=time.perf_counter() - started)
    _write(results, console)
    return results


def _run(
    config: EvalConfig, solvers: Mapping[str, Solver], pending: list[tuple[TaskInstance, RunKey]],
    journal: Journal, total: int, console: Console,
) -> None:
    """Run the pending runs in a thread pool, journaling each as it finishes."""
    sim_turn = threading.Lock()

    def one(instance: TaskInstance, key: RunKey) -> RunRecord:
        seed = config.world_seed(key.run)
        with contextlib.nullcontext() if METHODS[key.method].uses_lm else sim_turn:
            begun = time.perf_counter()
            try:
                solution = solvers[key.method](instance.task, seed=seed, run=key.run)
            except Exception as e:  # a method that raises fails its run, not the evaluation
                record = crashed(instance, key, seed, e, time.perf_counter() - begun)
            else:
                record = judge(instance, key, seed, solution, time.perf_counter() - begun)
        journal.append(record)
        return record

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    any_lm = any(METHODS[m].uses_lm for m in solvers)
    with Progress(*columns, console=console) as progress, ThreadPoolExecutor(
            max_workers=config.workers if any_lm else 1) as pool:
        bar = progress.add_task("evaluating", total=total, completed=total - len(pending))
        futures: list[Future[RunRecord]] = [
            pool.submit(contextvars.copy_context().run, one, instance, key) for instance, key in pending]
        try:
            for future in as_completed(futures):
                record = future.result()
                outcome = f"{record.success_rate:.0%}" if record.failure_class is None else record.failure_class
                progress.update(bar, advance=1, description=f"{record.key.id}: {outcome}")
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)
            raise


def _write(results: Results, console: Console) -> None:
    """results.json, the plots, report.md; then the tables on the console."""
    folder = results.config.out_dir
    write_atomic(folder / "results.json", results.model_dump_json(indent=1))
    summary = summarize(results.records, list(METHODS))
    tables = all_tables(summary)
    plots = write_plots(summary, folder)
    write_atomic(folder / "report.md", markdown(results, tables, plots))
    print_tables(results, tables, console)
    console.print(f"wrote {folder}/results.json, report.md and {len(plots)} plot(s)", highlight=False)
