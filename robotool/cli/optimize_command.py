"""``python -m robotool.optimize`` (also ``robotool optimize``): compile the proposing program.

Mistakes in the arguments end with one line and exit status 2; a language model that cannot be used
(no key, unreachable server) with one line and exit status 3; Ctrl-C with 130 (the log folder keeps what
was done: run the same command to resume).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from rich.console import Console
from rich.table import Table

from robotool import tasks
from robotool.cli.command import check_batch, run_line, set_command
from robotool.cli.internal_error import report_internal_error
from robotool.cli.options import (
    EXIT_INTERRUPTED,
    EXIT_USAGE,
    MAX_CANDIDATES,
    MAX_THREADS,
    Parser,
    Verbs,
    add_lm_options,
    add_world_options,
    compiled_program_file,
    count,
    lm_from,
    output_folder,
    positive_int,
    print_error,
)
from robotool.cli.verbs import add_verb
from robotool.errors import LMUnavailableError, RobotoolError
from robotool.optimize.data import DatasetError, check_families
from robotool.optimize.run import OPTIMIZERS, OptimizeError, OptimizerBudget, OptimizeResult, OptimizeSettings, optimize
from robotool.program.methods import STAGES_BY_METHOD
from robotool.safe_text import console_plain
from robotool.version import version

EXIT_LM_UNAVAILABLE = 3
MAX_EXAMPLES = 1000
"""Training or validation examples (each is generated, checked solvable and verified in simulation)."""
MAX_METRIC_CALLS = 100_000
MAX_STEPS = 1000
"""mipro's trials, simba's steps."""
MAX_DEMOS = 100
"""Demonstrations per stage (each goes into every prompt of its stage)."""


DESCRIPTION = (
    "Compile the RoboTool program: optimise its stages' prompts and demonstrations against simulator-verified "
    "success on generated task instances, and write a program file that solve, eval and RoboTool.load() use."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The optimiser's arguments."""
    p.add_argument("--version", action="version", version=f"robotool {version()}")
    p.add_argument(
        "--optimizer",
        required=True,
        choices=OPTIMIZERS,
        help="gepa (reflective prompt evolution), mipro (MIPROv2), bootstrap (BootstrapFewShot), simba, "
        "or planner-demos (no LM: verified search-planner solutions as demonstrations)",
    )
    p.add_argument(
        "--out", type=compiled_program_file, required=True, metavar="PROGRAM.json", help="the compiled program"
    )
    p.add_argument(
        "--log",
        type=output_folder,
        metavar="DIR",
        help="resumable log folder (default: the --out file's name with -log)",
    )
    p.add_argument(
        "--families",
        nargs="+",
        metavar="FAMILY",
        help="task families to draw examples from "
        "(default: all); the paper's six built-in tasks are never training examples",
    )
    p.add_argument("--train", type=positive_int(MAX_EXAMPLES), default=6, help="training examples")
    p.add_argument("--val", type=count(MAX_EXAMPLES), default=4, help="validation examples (scored before and after)")
    p.add_argument("--method", choices=list(STAGES_BY_METHOD), default="robotool", help="which stages the program has")
    lm = add_lm_options(p, temperature_help="sampling temperature of the stages' calls", log_prompts=False)
    lm.add_argument("--reflection-lm", help="model that proposes instructions (gepa, mipro, simba; default: --lm)")
    lm.add_argument("--reflection-api-base", help="base URL for the reflection model (default: --api-base)")
    add_world_options(
        p, worlds_help="perturbed worlds per verification", seed_help="seed of the perturbed worlds and the optimiser"
    )
    p.add_argument("--threads", type=positive_int(MAX_THREADS), default=4, help="metric calls in flight at once")
    budget = p.add_argument_group("budget")
    budget.add_argument("--auto", choices=["light", "medium", "heavy"], help="gepa, mipro: DSPy's budget preset")
    budget.add_argument(
        "--max-metric-calls", type=positive_int(MAX_METRIC_CALLS), help="gepa: metric calls (default: 60)"
    )
    budget.add_argument("--trials", type=positive_int(MAX_STEPS), default=6, help="mipro: trials")
    budget.add_argument(
        "--candidates", type=positive_int(MAX_CANDIDATES), default=3, help="mipro, simba: instruction candidates"
    )
    budget.add_argument("--steps", type=positive_int(MAX_STEPS), default=4, help="simba: steps")
    budget.add_argument("--demos", type=count(MAX_DEMOS), default=2, help="demonstrations per stage")


def settings_from(args: argparse.Namespace) -> OptimizeSettings:
    """The run the parsed arguments ask for."""
    families = args.families or tasks.families()
    check_families(families)
    if args.auto and args.max_metric_calls:
        raise OptimizeError("--auto and --max-metric-calls are two budgets; give one")
    return OptimizeSettings(
        optimizer=args.optimizer,
        families=families,
        train=args.train,
        val=args.val,
        method=args.method,
        worlds=args.worlds,
        seed=args.seed,
        backend=args.backend,
        threads=args.threads,
        lm=args.lm,
        reflection_lm=args.reflection_lm,
        temperature=args.temperature,
        adapter=args.adapter,
        budget=OptimizerBudget(
            auto=args.auto,
            max_metric_calls=args.max_metric_calls,
            trials=args.trials,
            candidates=args.candidates,
            steps=args.steps,
            demos=args.demos,
        ),
    )


def print_outcome(outcome: OptimizeResult, console: Console) -> None:
    """The before/after validation table and where the program went."""
    v = outcome.info.validation
    table = Table(title=f"Validation success ({outcome.info.optimizer}, method {outcome.info.method})")
    for column in ("examples", "before", "after"):
        table.add_column(column, justify="right")
    shown = [f"{s:.2f}" if s is not None else "-" for s in (v.before, v.after)] if v else ["-", "-"]
    table.add_row(str(v.examples if v else 0), *shown)
    console.print(table)
    if v is not None and v.note:
        console.print(console_plain(f"validation {v.note}"), style="yellow", markup=False, highlight=False)
    if outcome.info.demonstrations:
        console.print(
            f"{len(outcome.info.demonstrations)} verified demonstration(s) per stage from: "
            + ", ".join(d.task for d in outcome.info.demonstrations),
            markup=False,
            highlight=False,
        )
    console.print(f"wrote {outcome.out}", markup=False, highlight=False)


def cmd_optimize(args: argparse.Namespace, console: Console, errors: Console) -> int:
    """Run the optimisation the arguments ask for; returns the exit status."""
    from robotool.program.compiled import CompiledProgramError
    from robotool.program.lm import LMConfigError, make_lm

    check_batch(1, args.worlds)
    log = Path(args.log or args.out.with_name(f"{args.out.stem}-log"))
    try:
        settings = settings_from(args)
        lm = lm_from(args)
        reflection = (
            make_lm(
                args.reflection_lm,
                api_base=args.reflection_api_base or args.api_base,
                api_key_env=args.api_key_env,
                cache=not args.no_cache,
                timeout=args.timeout,
            )
            if args.reflection_lm
            else None
        )
        if lm is not None:
            settings = settings.model_copy(update={"lm": lm.model})
        outcome = optimize(
            settings,
            out=args.out,
            log=log,
            lm=lm,
            reflection_lm=reflection,
            say=lambda line: console.print(line, markup=False, highlight=False),
        )
    except LMUnavailableError as e:
        print_error(errors, str(e))
        return EXIT_LM_UNAVAILABLE
    except (OptimizeError, DatasetError, CompiledProgramError, LMConfigError, RobotoolError) as e:
        print_error(errors, " ".join(str(e).split()))
        return EXIT_USAGE
    except KeyboardInterrupt:
        errors.print("interrupted: run the same command to resume from the log folder", markup=False)
        return EXIT_INTERRUPTED
    except Exception as e:  # anything else is a bug in robotool, not the user's mistake
        return report_internal_error(errors, e, args.prog, log)
    print_outcome(outcome, console)
    return 0


def register(verbs: Verbs) -> None:
    """Add ``optimize`` to the ``robotool`` verbs."""
    p = add_verb(verbs, "optimize", description=DESCRIPTION)
    add_arguments(p)
    set_command(p, cmd_optimize)


def main(argv: Sequence[str] | None = None, prog: str = "python -m robotool.optimize") -> int:
    """Run the optimiser as ``prog``; returns the exit status."""
    parser = Parser(prog=prog, description=DESCRIPTION)
    add_arguments(parser)
    set_command(parser, cmd_optimize)
    return run_line(parser, argv)


if __name__ == "__main__":
    sys.exit(main())
