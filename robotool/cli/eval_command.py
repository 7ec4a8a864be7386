"""``python -m robotool.eval``: the command line of the offline evaluator.

Mistakes in the arguments end with a one-line message and exit status 2, never a traceback.
Runs that could not be attempted because the language model was unavailable (no key, unreachable
server, authentication, quota) are reported and not recorded: exit status 3, and the same command
retries them. Interrupting (Ctrl-C) keeps every finished run; the same command resumes (130).
``--executor ray [--address ADDR]`` runs the runs as Ray tasks (:mod:`robotool.eval.ray_executor`).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from rich.console import Console

from robotool.cli.command import UsageError, check_batch, run_line, set_command
from robotool.cli.internal_error import report_broken_runs, report_internal_error
from robotool.cli.options import (
    EXIT_INTERRUPTED,
    EXIT_USAGE,
    MAX_PROCESSES,
    MAX_RUNS,
    MAX_THREADS,
    MAX_WORLDS,
    Parser,
    Verbs,
    add_candidate_options,
    add_lm_options,
    add_world_options,
    cluster_address,
    count,
    output_folder,
    positive_int,
    print_error,
)
from robotool.cli.verbs import add_verb
from robotool.errors import RobotoolError
from robotool.eval.config import DEFAULT_WORKERS, EvalConfig, EvalError, RunsNotAttempted, Settings
from robotool.eval.executor_choice import EXECUTORS, make_executor
from robotool.eval.instances import DEFAULT_SEEDS, parse_seeds
from robotool.eval.solvers import METHODS
from robotool.processes import cores
from robotool.program.lm import LMConfigError
from robotool.task.task_file import TaskFileError
from robotool.version import version

EXIT_NOT_ATTEMPTED = 3
"""Some runs could not be attempted (the language model was unavailable); they were not recorded."""


def _seeds(text: str) -> list[int]:
    try:
        return list(parse_seeds(text))
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


DESCRIPTION = (
    "Evaluate methods on tasks: success (paper Table 1), key-concept accuracy (Table 2), error breakdown, "
    "discriminative tool use, cost. Resumable: rerun the same command."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The evaluator's arguments."""
    p.add_argument("--version", action="version", version=f"robotool {version()}")
    p.add_argument(
        "--tasks",
        nargs="+",
        metavar="TASK",
        help="built-in task names or task files "
        "(default: every built-in task, plus generated instances when no --families/--seeds is given)",
    )
    p.add_argument("--families", nargs="+", metavar="FAMILY", help="procedural task families (default: all)")
    default_seeds = f"{DEFAULT_SEEDS[0]}-{DEFAULT_SEEDS[-1]}"
    p.add_argument(
        "--seeds",
        type=_seeds,
        metavar="A-B",
        help=f"seeds of generated instances, e.g. 0-9 or 1,4 (default: {default_seeds})",
    )
    p.add_argument(
        "--methods",
        nargs="+",
        choices=list(METHODS),
        metavar="METHOD",
        help=f"methods to compare: {', '.join(METHODS)} (default: every method that can run here)",
    )
    p.add_argument(
        "--program",
        dest="programs",
        nargs="+",
        type=Path,
        metavar="PROGRAM.json",
        help="compiled programs (robotool optimize), each evaluated as a method named after its file; "
        "with --program and no --methods only the programs run",
    )
    p.add_argument(
        "--allow-train",
        action="store_true",
        help="evaluate a --program on instances it was trained on (refused by default; warned about)",
    )
    p.add_argument("--runs", type=positive_int(MAX_RUNS), default=1, help="runs per task and method (the paper: 10)")
    add_lm_options(
        p,
        temperature_help="sampling temperature of every LM call (above 0 for runs that differ; default: the "
        "model's for one candidate, 0.7 to 1.0 spread over several)",
    )
    add_candidate_options(p)
    add_world_options(p, seed_help="base seed of the perturbed worlds")
    p.add_argument(
        "--workers", type=positive_int(MAX_THREADS), default=DEFAULT_WORKERS, help="LM runs in flight at once"
    )
    p.add_argument(
        "--processes",
        type=positive_int(MAX_PROCESSES),
        default=cores(),
        help="LM-free runs (pure simulation) in flight at once with --executor local and the mujoco backend, "
        "each in a process of its own (default: one per core, here %(default)s)",
    )
    p.add_argument(
        "--executor",
        choices=EXECUTORS,
        default="local",
        help="where runs are carried out: threads here, or Ray tasks (pip install 'robotool[ray]')",
    )
    p.add_argument(
        "--address",
        type=cluster_address,
        help="the Ray cluster to use with --executor ray, e.g. auto or ray://HOST:10001 "
        "(default: $RAY_ADDRESS, else start Ray here)",
    )
    p.add_argument(
        "--out", type=output_folder, help="output folder (default: results/<model>-k<K>[-r<N>]-w<R>-s<seed>)"
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="reuse an output folder that holds an evaluation with other settings: its runs with the "
        "same inputs are reused, the rest are run, and the report covers exactly this command's runs",
    )
    p.add_argument(
        "--no-pictures",
        action="store_true",
        help="leave out the report's pictures (each task's scene and one failed world per failure class)",
    )
    p.add_argument(
        "--videos",
        type=count(MAX_WORLDS),
        default=0,
        metavar="N",
        help="film the first N failed worlds of each task and method (MP4s under videos/, shown in report.html)",
    )


def config_from(args: argparse.Namespace) -> EvalConfig:
    """The evaluation the parsed arguments ask for."""
    settings = Settings(
        lm=args.lm,
        temperature=args.temperature,
        candidates=args.candidates,
        worlds=args.worlds,
        backend=args.backend,
        seed=args.seed,
        adapter=args.adapter,
        repair=args.repair,
    )
    return EvalConfig(
        tasks=args.tasks,
        families=args.families,
        seeds=args.seeds,
        methods=args.methods,
        programs=args.programs,
        allow_train=args.allow_train,
        runs=args.runs,
        settings=settings,
        api_base=args.api_base,
        api_key_env=args.api_key_env,
        workers=args.workers,
        out=args.out,
        resume=args.resume,
        pictures=not args.no_pictures,
        videos=args.videos,
        cache=not args.no_cache,
        timeout=args.timeout,
        log_prompts=args.log_prompts,
    )


def cmd_eval(args: argparse.Namespace, console: Console, errors: Console) -> int:
    """Run the evaluation the arguments ask for; returns the exit status."""
    from robotool.eval.sweep import evaluate

    if args.executor == "ray" and args.log_prompts is not None:  # the file would be written on the workers
        raise UsageError("--log-prompts writes a file on this machine, so it needs --executor local")
    check_batch(args.candidates, args.worlds)
    folder: Path | None = None  # where an internal error's traceback goes, once known
    try:
        config = config_from(args)
        folder = config.out
        with make_executor(
            args.executor, workers=args.workers, processes=args.processes, address=args.address
        ) as executor:
            results = evaluate(config, console=console, executor=executor)
    except RunsNotAttempted as e:  # before RobotoolError, which it is
        print_error(errors, str(e))
        return EXIT_NOT_ATTEMPTED
    except (EvalError, TaskFileError, LMConfigError, RobotoolError) as e:
        print_error(errors, " ".join(str(e).split()))
        return EXIT_USAGE
    except KeyboardInterrupt:
        errors.print(
            "interrupted: finished runs are kept in the journal; run the same command to resume",
            markup=False,
            highlight=False,
        )
        return EXIT_INTERRUPTED
    except Exception as e:  # anything else is a bug in robotool, not the user's mistake
        return report_internal_error(errors, e, args.prog, folder)
    broken = sum(r.internal_error is not None for r in results.records)
    if broken:  # recorded and reported, but a bug in robotool all the same
        return report_broken_runs(errors, broken, config.out_dir / "results.json")
    return 0


def register(verbs: Verbs) -> None:
    """Add ``eval`` to the ``robotool`` verbs."""
    p = add_verb(verbs, "eval", description=DESCRIPTION)
    add_arguments(p)
    set_command(p, cmd_eval)


def main(argv: Sequence[str] | None = None, prog: str = "python -m robotool.eval") -> int:
    """Run the evaluator as ``prog``; returns the exit status."""
    parser = Parser(prog=prog, description=DESCRIPTION)
    add_arguments(parser)
    set_command(parser, cmd_eval)
    return run_line(parser, argv)


if __name__ == "__main__":
    sys.exit(main())
