"""One optimisation run: examples -> validation before -> an optimiser compiles the proposing program ->
validation after -> a compiled program file.

The student is a :class:`~robotool.program.lm_program.Proposer` (the four stages, one candidate per task): optimisers
see exactly its predictors, and the :class:`~robotool.optimize.verified_metric.Metric` verifies what it proposes in
simulation. The log folder holds ``settings.json`` (what the run was asked to do), the optimiser's own
checkpoints (GEPA resumes from them; MIPROv2 writes its trials there), the planner's solved instances
(``planner-demos`` reuses them) and the validation scores; DSPy's LM cache makes a rerun of the LM calls
already made cost nothing.
"""

from __future__ import annotations

import contextlib
import contextvars
import logging
import sys
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any, Literal

import dspy
from dspy.utils.exceptions import AdapterParseError
from pydantic import BaseModel, Field

from robotool.optimize.data import Splits, check_training, splits
from robotool.optimize.demos import Say, planner_demonstrations
from robotool.optimize.verified_metric import Metric
from robotool.program.compiled import CompiledInfo, DemoSource, Validation, save_compiled
from robotool.program.lm_program import Proposer
from robotool.safe_text import json_text
from robotool.vocabulary import BackendName

Optimizer = Literal["gepa", "mipro", "bootstrap", "simba", "planner-demos"]
OPTIMIZERS: tuple[Optimizer, ...] = ("gepa", "mipro", "bootstrap", "simba", "planner-demos")


DEMO_OPTIMIZERS: frozenset[str] = frozenset({"bootstrap"})
"""Optimisers whose only change is demonstrations (zero kept means an unchanged program)."""
FROZEN_REPAIR = "the Repair stage is left as it is: the metric verifies proposals and never runs repair rounds"


class OptimizeError(ValueError):
    """The run cannot be set up as asked; the message says why."""


class OptimizerBudget(BaseModel):
    """How much an optimiser may spend (each applies to the optimisers named)."""

    auto: Literal["light", "medium", "heavy"] | None = Field(None, description="gepa, mipro: DSPy's preset")
    max_metric_calls: int | None = Field(None, ge=1, description="gepa: metric calls (default 60 without auto)")
    trials: int = Field(6, ge=1, description="mipro: trials without auto")
    candidates: int = Field(3, ge=1, description="mipro, simba: instruction candidates per round")
    steps: int = Field(4, ge=1, description="simba: steps")
    demos: int = Field(2, ge=0, description="bootstrap, mipro, simba, planner-demos: demonstrations per stage")


class OptimizeSettings(BaseModel):
    """Everything that decides a run's result (``settings.json``; recorded in the compiled program)."""

    optimizer: Optimizer
    families: list[str]
    train: int = Field(ge=1)
    val: int = Field(ge=0)
    method: str = "robotool"
    worlds: int = Field(3, ge=1)
    seed: int = Field(0, ge=0)
    backend: BackendName | None = None
    threads: int = Field(4, ge=1)
    lm: str | None = None
    reflection_lm: str | None = None
    temperature: float | None = None
    adapter: Literal["chat", "json"] | None = None
    budget: OptimizerBudget = Field(default_factory=OptimizerBudget)


class OptimizeResult(BaseModel):
    """What a run produced."""

    info: CompiledInfo
    out: Path
    train: list[str]
    val: list[str]


def student(settings: OptimizeSettings) -> Proposer:
    """The program an optimiser compiles: the method's stages, one candidate per task."""
    return Proposer.method(settings.method, temperature=settings.temperature, adapter=settings.adapter)


def validate(program: Proposer, examples: Sequence[dspy.Example], metric: Metric, threads: int) -> float:
    """Mean verified success of ``program`` on ``examples``; an unavailable LM stops it (the error propagates)."""

    def one(example: dspy.Example) -> float:
        return float(metric(example, program(**example.inputs())))

    with ThreadPoolExecutor(max_workers=threads) as pool:
        futures = [pool.submit(contextvars.copy_context().run, one, e) for e in examples]
        scores = [f.result() for f in futures]
    return sum(scores) / len(scores)


def _compile(
    settings: OptimizeSettings,
    program: Proposer,
    data: Splits,
    metric: Metric,
    log: Path,
    reflection_lm: dspy.LM | None,
    say: Say,
    notes: list[str],
) -> tuple[Proposer, list[DemoSource]]:
    """The compiled program and where its demonstrations came from; what the optimiser could not do is added to
    ``notes`` (and said)."""
    b = settings.budget
    name = settings.optimizer
    if name == "planner-demos":
        say(f"solving {len(data.train)} training instance(s) with the search planner")
        sources = planner_demonstrations(
            program,
            data.train,
            per_stage=b.demos,
            worlds=settings.worlds,
            seed=settings.seed,
            backend=settings.backend,
            log=log,
            say=say,
        )
        if not sources:
            raise OptimizeError(
                "the search planner verified no training instance: no demonstration to keep; "
                "try more --train examples or other --families"
            )
        return program, sources
    valset = data.val or None
    if name == "gepa":
        if reflection_lm is None:
            raise OptimizeError("gepa needs a reflection model: pass --reflection-lm (or --lm)")
        budget: dict[str, Any] = {"auto": b.auto} if b.auto else {"max_metric_calls": b.max_metric_calls or 60}
        optimizer = dspy.GEPA(
            metric=metric,
            reflection_lm=reflection_lm,
            num_threads=settings.threads,
            log_dir=str(log / "gepa"),
            seed=settings.seed,
            **budget,
        )
        return optimizer.compile(program, trainset=data.train, valset=valset), []
    if name == "bootstrap":
        optimizer = dspy.BootstrapFewShot(
            metric=metric, metric_threshold=1.0, max_bootstrapped_demos=b.demos, max_labeled_demos=0, max_rounds=1
        )
        return optimizer.compile(program, trainset=data.train), []
    if name == "mipro":
        mipro = _MIPRO(
            notes.append,
            metric=metric,
            prompt_model=reflection_lm,
            auto=b.auto,
            num_candidates=None if b.auto else b.candidates,
            num_threads=settings.threads,
            max_bootstrapped_demos=b.demos,
            max_labeled_demos=0,
            seed=settings.seed,
            log_dir=str(log / "mipro"),
            metric_threshold=1.0,
        )
        trials = {} if b.auto else {"num_trials": b.trials}
        if not b.auto:  # DSPy's log numbers the default program's evaluation as trial 1 of the trials asked for
            say(f"mipro: the default program is evaluated, then {b.trials} trial(s) of proposed prompts")
        compiled = mipro.compile(
            program, trainset=data.train, valset=valset, minibatch=False, data_aware_proposer=False, **trials
        )
        for note in notes:
            say(note)
        return compiled, []
    simba = dspy.SIMBA(
        metric=metric,
        bsize=min(len(data.train), 8),
        num_candidates=b.candidates,
        max_steps=b.steps,
        max_demos=b.demos,
        prompt_model=reflection_lm,
        num_threads=settings.threads,
    )
    return simba.compile(program, trainset=data.train, seed=settings.seed), []


class _MIPRO(dspy.MIPROv2):
    """MIPROv2 that survives a proposer reply it cannot read: the stages then keep their own instructions as the
    only candidates (the search still chooses among the demonstrations), and ``note`` is told why."""

    def __init__(self, note: Callable[[str], None], **options: Any):
        super().__init__(**options)
        self._note = note

    def _propose_instructions(self, program: Any, *args: Any, **kwargs: Any) -> dict[int, list[str]]:
        try:
            return super()._propose_instructions(program, *args, **kwargs)
        except (AdapterParseError, ValueError) as e:
            reason = " ".join(str(e).split())[:200]
            self._note(
                f"mipro: the proposer's reply could not be read ({type(e).__name__}: {reason}); the stages keep "
                "their instructions and only demonstrations were searched"
            )
            return {i: [predictor.signature.instructions] for i, predictor in enumerate(program.predictors())}


def optimize(
    settings: OptimizeSettings,
    *,
    out: Path,
    log: Path,
    lm: dspy.LM | None = None,
    reflection_lm: dspy.LM | None = None,
    say: Say = print,
    data: Splits | None = None,
) -> OptimizeResult:
    """Run one optimisation (see the module docstring) and write the compiled program to ``out``.

    ``data`` replaces the examples drawn from ``settings.families`` (its training set is checked the same way).
    """
    if settings.optimizer != "planner-demos" and lm is None:
        raise OptimizeError(f"{settings.optimizer} runs the stages on a language model: pass --lm MODEL")
    _claim(log, settings, say)
    if data is None:
        data = splits(settings.families, train=settings.train, val=settings.val, paper_tasks=False)
    check_training(data.train)
    say(f"{len(data.train)} training and {len(data.val)} validation example(s) from {', '.join(settings.families)}")
    metric = Metric(worlds=settings.worlds, seed=settings.seed, backend=settings.backend)
    program = student(settings)
    notes = [FROZEN_REPAIR]  # the metric verifies proposals and never runs repair rounds
    say(FROZEN_REPAIR)
    with dspy.context(lm=lm) if lm is not None else contextlib.nullcontext():
        before = _measure(program, data, metric, settings, lm, "before", say)
        program.repair_frozen = True
        say(f"the optimiser's own log lines and progress bars go to {log / NOISE_LOG}")
        with noise_to(log / NOISE_LOG, say) as loud:
            compiled, sources = _compile(settings, program, data, metric, log, reflection_lm or lm, loud, notes)
        compiled.repair_frozen = program.repair_frozen = False
        after = _measure(compiled, data, metric, settings, lm, "after", say)
    if settings.optimizer in DEMO_OPTIMIZERS and not any(p.demos for _, p in compiled.named_predictors()):
        kept = (
            f"{settings.optimizer} kept no demonstration: no training instance's proposal succeeded in every world, "
            "so the stages' demonstrations are unchanged"
        )
        notes.append(kept)
        say(kept)
    validation = Validation(
        examples=len(data.val),
        before=before,
        after=after,
        note=None
        if lm is not None and data.val
        else "not measured: "
        + ("no validation examples" if not data.val else "no language model (pass --lm to measure the stages on one)"),
    )
    info = CompiledInfo(
        optimizer=settings.optimizer,
        method=settings.method,
        settings=settings.model_dump(mode="json"),
        validation=validation,
        demonstrations=sources,
        train=[instance_label(e) for e in data.train],
        val=[instance_label(e) for e in data.val],
        notes=notes,
    )
    save_compiled(compiled, out, info)
    (log / "validation.json").write_text(json_text(validation, indent=1), encoding="utf-8")
    return OptimizeResult(info=info, out=out, train=[e.name for e in data.train], val=[e.name for e in data.val])


NOISE_LOG = "dspy.log"
"""The file in the log folder that receives DSPy's (and GEPA's, Optuna's) log lines and progress bars."""


@contextlib.contextmanager
def noise_to(path: Path, say: Say) -> Iterator[Say]:
    """Send what the optimisers write to stdout and stderr (DSPy's INFO lines and tracebacks, progress bars,
    Optuna's trial lines) to ``path`` instead of the console, inside this block; yields ``say`` writing to the
    console still."""
    try:
        f = path.open("a", encoding="utf-8")
    except OSError as e:
        raise OptimizeError(f"cannot write {path}: {e.strerror or e}") from None
    console = sys.stdout

    def loud(line: str) -> None:
        with contextlib.redirect_stdout(console):
            say(line)

    optuna = logging.getLogger("optuna")
    handlers = optuna.handlers[:]
    optuna.handlers = [logging.StreamHandler(f)]
    try:
        with f, contextlib.redirect_stderr(f), contextlib.redirect_stdout(f):
            yield loud
    finally:
        optuna.handlers = handlers


def instance_label(example: dspy.Example) -> str:
    """How the evaluation names an example's task instance: ``family#seed`` when generated, else its name."""
    return f"{example.family}#{example.seed}" if example.get("seed") is not None else example.name


def _claim(log: Path, settings: OptimizeSettings, say: Say) -> None:
    """Create the log folder, or resume in it when it holds a run with the same settings, or a GEPA run that
    this one extends with a larger metric-call budget (else refuse)."""
    path = log / "settings.json"
    if path.exists():
        try:
            before = OptimizeSettings.model_validate_json(path.read_text(encoding="utf-8"))
        except ValueError:
            raise OptimizeError(f"{log} holds a run this version cannot read; choose another --log") from None
        if (grown := _grown_budget(before, settings)) is not None:
            say(f"resuming the GEPA run in {log} with a larger budget: {grown[0]} -> {grown[1]} metric calls")
        elif before != settings:
            mine, theirs = settings.model_dump(), before.model_dump()
            changed = ", ".join(k for k in mine if mine[k] != theirs[k])
            raise OptimizeError(f"{log} holds a run with other settings ({changed}); choose another --log")
    try:
        log.mkdir(parents=True, exist_ok=True)
        path.write_text(json_text(settings, indent=1), encoding="utf-8")
    except OSError as e:
        raise OptimizeError(f"cannot write the log folder {log}: {e.strerror or e}") from None


def _grown_budget(before: OptimizeSettings, now: OptimizeSettings) -> tuple[int, int] | None:
    """(old, new) metric-call budgets when ``now`` is the GEPA run ``before`` with only a larger budget, else None."""
    if now.optimizer != "gepa" or before.model_copy(update={"budget": now.budget}) != now:
        return None
    if before.budget.model_copy(update={"max_metric_calls": now.budget.max_metric_calls}) != now.budget:
        return None
    if before.budget.auto or now.budget.auto:
        return None
    old, new = before.budget.max_metric_calls or 60, now.budget.max_metric_calls or 60
    return (old, new) if new > old else None


def _measure(
    program: Proposer, data: Splits, metric: Metric, settings: OptimizeSettings, lm: dspy.LM | None, when: str, say: Say
) -> float | None:
    if lm is None or not data.val:
        return None
    say(f"validating {when}: {len(data.val)} example(s) x {settings.worlds} world(s)")
    return validate(program, data.val, metric, settings.threads)
