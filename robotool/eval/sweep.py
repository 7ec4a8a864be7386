"""``evaluate``: methods x task instances x runs -> journal -> results folder.

A run is keyed by (task, seed, method, run) and a digest of the content of its inputs (the task itself,
the method, the LM and its settings, the seeds, the robotool version), so a changed input is a new run.
Each finished run is appended to the folder's journal as soon as its record is back, so an interrupted
evaluation resumes where it stopped: rerunning the same command reuses every run already in the journal
and says how many. A run that could not be attempted because the language model was unavailable is not
a result and is never journalled. Runs go through an executor (:mod:`robotool.eval.executor`): by default
a thread pool here, where LM-free runs (pure simulation on the CPU) take turns on a lock while LM runs
overlap their LM calls; or Ray tasks on a cluster (:mod:`robotool.eval.ray_executor`). Either way the
journal is written here, as each run's record comes back, so the results folder is the same.
"""

from __future__ import annotations

import hashlib
import logging
import threading
import time
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, NamedTuple, Self

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from robotool import robots
from robotool.errors import LMUnavailableError
from robotool.eval.config import EvalConfig, EvalError, Request, RunsNotAttempted
from robotool.eval.executor import Executor, LocalExecutor, WorkerLost
from robotool.eval.instances import TaskInstance, select
from robotool.eval.journal import Journal, write_atomic
from robotool.eval.judge import crashed
from robotool.eval.metrics import summarize
from robotool.eval.plots import write_plots
from robotool.eval.records import Results, RunKey, RunRecord, inputs_digest
from robotool.eval.report import markdown, print_tables, skipped_lines
from robotool.eval.solvers import (
    METHODS,
    Solver,
    SolverSettings,
    compiled_solver,
    make_solvers,
    program_stages,
)
from robotool.eval.tables import all_tables
from robotool.eval.work import NotAttempted, RunJob, RunWork
from robotool.processes import cores
from robotool.safe_text import TerminalConsole, console_plain, json_text
from robotool.version import version
from robotool.vocabulary import BackendName

logger = logging.getLogger(__name__)

if TYPE_CHECKING:
    import dspy

SETTINGS = "settings.json"


def _lm(config: EvalConfig, lm: dspy.LM | None) -> dspy.LM | None:
    """The LM given, or the one the configuration names (None without either)."""
    if lm is not None:
        return lm
    from robotool.program.lm import make_lm

    return make_lm(
        config.settings.lm,
        api_base=config.api_base,
        api_key_env=config.api_key_env,
        temperature=config.settings.temperature,
        cache=config.cache,
        timeout=config.timeout,
    )


class Methods(NamedTuple):
    """The solvers to run, the methods skipped and why, and for each compiled program the method of its stages."""

    solvers: dict[str, Solver]
    skipped: dict[str, str]
    stages: dict[str, str]


def _methods(
    config: EvalConfig, lm: dspy.LM | None, overrides: Mapping[str, Solver] | None, backend: BackendName
) -> Methods:
    """Solvers to run and methods skipped; a method asked for by name that cannot run is an error."""
    names = config.methods or ([] if config.programs else list(METHODS))
    unknown = [m for m in names if m not in METHODS]
    if unknown:
        raise EvalError(f"unknown method {', '.join(unknown)}; methods: {', '.join(METHODS)}")
    settings = SolverSettings(
        candidates=config.settings.candidates,
        worlds=config.settings.worlds,
        backend=backend,
        temperature=config.settings.temperature,
        adapter=config.settings.adapter,
        log_prompts=config.log_prompts,
        repair=config.settings.repair,
    )
    solvers, skipped = make_solvers(names, settings, lm, overrides)
    if config.methods is not None and skipped:
        method, why = next(iter(skipped.items()))
        raise EvalError(f"cannot run {method}: {why}")
    stages = _programs(config, lm, settings, solvers)
    if not solvers:
        raise EvalError("no method can run here: " + "; ".join(skipped_lines(skipped)))
    return Methods(solvers, skipped, stages)


def _programs(
    config: EvalConfig, lm: dspy.LM | None, settings: SolverSettings, solvers: dict[str, Solver]
) -> dict[str, str]:
    """Add a solver per compiled program (a method named after its file); returns each one's stages."""
    from robotool.program.compiled import CompiledProgramError, read_compiled

    stages: dict[str, str] = {}
    for path in config.programs or []:
        name = path.stem
        if name in METHODS or name in stages:
            raise EvalError(f"--program {path}: its name {name!r} is already a method's; rename the file")
        try:
            read_compiled(path)  # a file that is not there or not a program is said before what running it needs
            if lm is None:
                raise EvalError(
                    f"--program {path} runs its stages on a language model: pass --lm MODEL or set ROBOTOOL_LM"
                )
            solvers[name] = compiled_solver(path, lm, settings)
            stages[name] = program_stages(path)
        except CompiledProgramError as e:
            raise EvalError(str(e)) from None
    return stages


def held_out_warnings(config: EvalConfig, instances: list[TaskInstance]) -> list[str]:
    """Warnings about compiled programs evaluated on instances they were validated on (or, with
    ``allow_train``, trained on); raises :class:`EvalError` for training instances without ``allow_train``."""
    from robotool.program.compiled import read_compiled

    warnings: list[str] = []
    labels = [i.label for i in instances]
    for path in config.programs or []:
        _, info = read_compiled(path)
        if info is None:
            continue
        trained = [label for label in labels if label in info.train]
        validated = [label for label in labels if label in info.val]
        if trained and not config.allow_train:
            raise EvalError(
                f"--program {path} was trained on {', '.join(trained)}: its score there is not held out; leave "
                "them out of --tasks/--seeds, or pass --allow-train"
            )
        if trained:
            warnings.append(f"{path.stem} was trained on {', '.join(trained)}: those scores are not held out")
        if validated:
            warnings.append(
                f"{path.stem} was validated on {', '.join(validated)} while it was optimised: those scores are not "
                "held out"
            )
    return warnings


def uses_lm(method: str) -> bool:
    """Whether a method's runs call a language model (compiled programs always do)."""
    return METHODS[method].uses_lm if method in METHODS else True


MAX_RUNS = 100_000
"""Runs one evaluation may ask for (task instances x methods x runs), refused before the first is planned."""


def _check_size(instances: int, methods: int, runs: int) -> None:
    """Refuse an evaluation of more than :data:`MAX_RUNS` runs, saying what multiplied to it."""
    if instances * methods * runs > MAX_RUNS:
        raise EvalError(
            f"{instances} task instance(s) x {methods} method(s) x {runs} run(s) is {instances * methods * runs} runs; "
            f"one evaluation runs at most {MAX_RUNS}: ask for fewer --tasks, --seeds, --methods or --runs"
        )


def _check_folder(config: EvalConfig) -> None:
    """Create the output folder; refuse one that holds a different request unless ``--resume``."""
    folder = config.out_dir
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise EvalError(f"cannot create the output folder {folder}: {e.strerror or e}") from None
    path = folder / SETTINGS
    request = config.request
    if path.exists() and not config.resume:
        try:
            before = Request.model_validate_json(path.read_text(encoding="utf-8"))
        except ValueError:  # pydantic.ValidationError included: an older or foreign settings.json
            raise EvalError(
                f"{folder} holds results of an unknown request; pass --resume to reuse its "
                "matching runs, or choose another --out"
            ) from None
        if before != request:
            changes = "; ".join(request.differences(before))
            raise EvalError(
                f"{folder} holds an evaluation with other settings ({changes}); pass --resume to "
                "reuse its matching runs and add these, or choose another --out"
            )
    try:
        write_atomic(path, json_text(request, indent=2))
    except OSError as e:
        raise EvalError(f"cannot write into the output folder {folder}: {e.strerror or e}") from None


def _plan(
    config: EvalConfig, instances: list[TaskInstance], methods: list[str], backend: BackendName
) -> list[tuple[TaskInstance, RunKey]]:
    """Every run asked for, keyed by the content of its inputs (``backend``: the one the runs use; a compiled
    program's runs also by its file's content)."""
    shared = {"api_base": config.api_base, "backend": backend, "robotool": version()}
    programs = {p.stem: hashlib.sha256(p.read_bytes()).hexdigest()[:16] for p in config.programs or []}
    contexts = {m: shared | ({"program": programs[m]} if m in programs else {}) for m in methods}
    return [
        (
            instance,
            RunKey(
                task=instance.name,
                seed=instance.seed,
                method=method,
                run=run,
                inputs=inputs_digest(instance.task, method, run, config.settings, contexts[method]),
            ),
        )
        for instance in instances
        for method in methods
        for run in range(config.runs)
    ]


def _say_reuse(config: EvalConfig, plan: list[tuple[TaskInstance, RunKey]], journal: Journal, console: Console) -> None:
    """Say out loud how many runs come from the folder's journal, and how many of its runs are left out."""
    reused = sum(key.id in journal for _, key in plan)
    if not journal.records:
        return
    wanted = {key.id for _, key in plan}
    other = sum(key_id not in wanted for key_id in journal.records)
    line = f"reusing {reused} of {len(plan)} runs from {config.out_dir}"
    if other:
        line += f"; {other} other run(s) in its journal (other inputs or settings) are not in this report"
    console.print(line, highlight=False, markup=False)


def evaluate(
    config: EvalConfig,
    *,
    lm: dspy.LM | None = None,
    solvers: Mapping[str, Solver] | None = None,
    console: Console | None = None,
    executor: Executor | None = None,
) -> Results:
    """Run every run asked for that is not yet in the journal, then write the results folder.

    ``lm`` replaces the LM the configuration names; ``solvers`` replaces methods' solvers (tests);
    ``executor`` carries out the runs (default: a :class:`LocalExecutor` with ``config.workers``).
    Raises :class:`RunsNotAttempted` (after the other runs finished) when the language model was
    unavailable for some runs: they are not journalled, and no report is written.
    """
    started = time.perf_counter()
    console = console or TerminalConsole()  # emoji codes in a program's text stay text; paths' controls escaped
    lm = _lm(config, lm)
    if lm is not None and config.settings.lm is None:
        config = config.model_copy(update={"settings": config.settings.model_copy(update={"lm": lm.model})})
    instances, notes = select(config.tasks, config.families, config.seeds)
    executor = executor or LocalExecutor(config.workers)
    backend = executor.backend(config.settings.backend)
    chosen, skipped, stages = _methods(config, lm, solvers, backend)
    notes = [*notes, *held_out_warnings(config, instances)]
    _check_size(len(instances), len(chosen), config.runs)
    _check_folder(config)
    journal = Journal(config.out_dir)
    plan = _plan(config, instances, list(chosen), backend)
    for line in skipped_lines(skipped):
        console.print(console_plain(line), style="yellow", highlight=False, markup=False)  # may quote an LM error
    _say_reuse(config, plan, journal, console)
    pending = longest_first([RunJob(i, k, config.world_seed(k.run)) for i, k in plan if k.id not in journal])
    drawers = executor.processes if isinstance(executor, LocalExecutor) else cores()
    with _Pictures(config, instances, plan, journal, backend, drawers) as pictures:
        _run(executor, RunWork(chosen, stages), pending, journal, len(plan), backend, console, pictures.recorded)
        results = Results(
            config=config,
            skipped=skipped,
            notes=notes,
            records=[journal.records[k.id] for _, k in plan],
        )
        results = pictures.into(results)
    results = _with_videos(results, instances, backend)
    results.wall_s = time.perf_counter() - started
    _write(results, console)
    return results


def longest_first(jobs: list[RunJob]) -> list[RunJob]:
    """The runs in the order they start, those expected to take longest first, so that no long run starts last
    while the other processes sit idle: the planner with every object (``search``) before the floor, and the runs
    of robots whose runs cost more (their registry's ``sim.run_cost``) first; otherwise in plan order. Only the
    order changes, not what runs: records are reported in plan order."""
    return sorted(
        jobs, key=lambda job: (job.key.method != "search", -robots.get(job.instance.task.embodiment).sim.run_cost)
    )


def _run(
    executor: Executor,
    work: RunWork,
    pending: list[RunJob],
    journal: Journal,
    total: int,
    backend: BackendName,
    console: Console,
    recorded_hook: Callable[[RunJob], None],
) -> None:
    """Carry out the pending runs with ``executor``, journaling each record as it comes back (then telling
    ``recorded_hook``).

    A run that could not be attempted because the language model was unavailable is not journalled, the
    LM runs not yet started are not attempted, and :class:`RunsNotAttempted` is raised once the others
    end. A run whose worker was lost on every attempt is journalled as failed, with the reason.
    """
    unavailable: list[LMUnavailableError] = []
    recorded: list[str] = []

    def done(job: RunJob, outcome: RunRecord | NotAttempted | WorkerLost) -> None:
        if isinstance(outcome, NotAttempted):
            unavailable.append(outcome.error())
            return
        if isinstance(outcome, WorkerLost):  # nothing of the run came back: an internal error, not a failure
            logger.error("internal error in run %s: %s", job.key.id, outcome)
            ran = work.stages.get(job.key.method)
            outcome = crashed(job.instance, job.key, job.world_seed, outcome, 0.0, stages=ran)
        journal.append(outcome)
        recorded.append(job.key.id)
        recorded_hook(job)
        progress.update(bar, advance=1)

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    with Progress(*columns, console=console) as progress:
        bar = progress.add_task("evaluating", total=total, completed=total - len(pending))
        executor.run(
            pending,
            work,
            done,
            skip=lambda job: uses_lm(job.key.method) and bool(unavailable),
            exclusive=lambda job: not uses_lm(job.key.method),
            backend=backend,
        )
    if unavailable:
        raise RunsNotAttempted(len(pending) - len(recorded), total, unavailable[0])


class _Pictures:
    """The report's pictures, each instance's drawn in ``processes`` processes as soon as its last run is recorded
    (so that drawing overlaps the runs still going), failed worlds simulated again on ``backend`` (the one the runs
    used); or a note saying why there are none."""

    def __init__(
        self,
        config: EvalConfig,
        instances: list[TaskInstance],
        plan: list[tuple[TaskInstance, RunKey]],
        journal: Journal,
        backend: BackendName,
        processes: int,
    ) -> None:
        self.journal = journal
        self.lock = threading.Lock()
        self.keys = {id(i): [k.id for j, k in plan if j is i] for i in instances}
        self.waiting = {id(i): {key for key in self.keys[id(i)] if key not in journal} for i in instances}
        self.order = {i.label: n for n, i in enumerate(instances)}
        self.drawer = None
        if config.pictures:
            from robotool.eval.pictures import PictureDrawer

            self.drawer = PictureDrawer(len(instances), config.out_dir, backend, processes)
            for instance in instances:
                if not self.waiting[id(instance)]:
                    self._draw(instance)

    def _draw(self, instance: TaskInstance) -> None:
        assert self.drawer is not None
        self.drawer.draw(instance, [self.journal.records[key] for key in self.keys[id(instance)]])

    def recorded(self, job: RunJob) -> None:
        """A run's record is in the journal: draw its instance once its last run is."""
        if self.drawer is None:
            return
        with self.lock:
            waiting = self.waiting[id(job.instance)]
            waiting.discard(job.key.id)
            if not waiting:
                self._draw(job.instance)

    def into(self, results: Results) -> Results:
        """``results`` with the pictures in instance order, or a note saying why there are none."""
        if self.drawer is None:
            return results
        from robotool.errors import RobotoolError

        try:
            pictures = self.drawer.pictures()
        except RobotoolError as e:
            return results.model_copy(update={"notes": [*results.notes, f"no pictures: {e}"]})
        pictures.sort(key=lambda picture: self.order[picture.task])  # instance order, however they finished
        return results.model_copy(update={"pictures": pictures})

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        if self.drawer is not None:
            self.drawer.close()


def _with_videos(results: Results, instances: list[TaskInstance], backend: BackendName) -> Results:
    """The results with the videos ``--videos N`` asked for, or a note saying why there are none."""
    if not results.config.videos:
        return results
    from robotool.errors import RobotoolError
    from robotool.eval.recordings import write_run_videos

    try:
        videos = write_run_videos(instances, results.records, results.config.out_dir, results.config.videos, backend)
    except (RobotoolError, ImportError) as e:
        return results.model_copy(update={"notes": [*results.notes, f"no videos: {e}"]})
    return results.model_copy(update={"videos": videos})


def _write(results: Results, console: Console) -> None:
    """results.json, the plots, report.md and report.html; then the tables on the console."""
    from robotool.report_page import evaluation_page  # it reads the evaluator's records: imported once they are

    folder = results.config.out_dir
    write_atomic(folder / "results.json", json_text(results, indent=1))
    summary = summarize(results.records, [*METHODS, *(p.stem for p in results.config.programs or [])])
    tables = all_tables(summary)
    plots = write_plots(summary, folder)
    write_atomic(folder / "report.md", markdown(results, tables, plots))
    write_atomic(folder / "report.html", evaluation_page(results, tables, plots))
    print_tables(results, tables, console)
    console.print(
        f"wrote {folder}/results.json, report.md, report.html and {len(plots)} plot(s)", highlight=False, markup=False
    )
