"""``python -m robotool.eval``: the command line of the offline evaluator.

Mistakes in the arguments end with a one-line message and exit status 2, never a traceback.
Interrupting (Ctrl-C) keeps every finished run; the same command resumes.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

from rich.console import Console

from robotool.eval.config import DEFAULT_WORKERS, EvalConfig, EvalError, Settings
from robotool.eval.instances import DEFAULT_SEEDS, parse_seeds
from robotool.eval.solvers import METHODS
from robotool.lm import LMConfigError
from robotool.scene import TaskFileError

EXIT_USAGE = 2
EXIT_INTERRUPTED = 130
CAPTURED_WIDTH = 120  # console width when the output goes to a file or a pipe (rich would use 80)


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line on stderr and exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"error: {message} (see {self.prog} --help)\n")


def _positive(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def _seeds(text: str) -> list[int]:
    try:
        return list(parse_seeds(text))
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def build_parser(prog: str = "python -m robotool.eval") -> argparse.ArgumentParser:
    """The evaluator's arguments (``prog`` names the command in messages, e.g. ``robotool eval``)."""
    p = _Parser(prog=prog,
                description="Evaluate methods on tasks: success (paper Table 1), key-concept accuracy (Table 2), "
                            "error breakdown, discriminative tool use, cost. Resumable: rerun the same command.")
    p.add_argument("--tasks", nargs="+", metavar="TASK", help="built-in task names or task files "
                   "(default: every built-in task, plus generated instances when no --families/--seeds is given)")
    p.add_argument("--families", nargs="+", metavar="FAMILY", help="procedural task families (default: all)")
    default_seeds = f"{DEFAULT_SEEDS[0]}-{DEFAULT_SEEDS[-1]}"
    p.add_argument("--seeds", type=_seeds, metavar="A-B",
                   help=f"seeds of generated instances, e.g. 0-9 or 1,4 (default: {default_seeds})")
    p.add_argument("--methods", nargs="+", choices=list(METHODS), metavar="METHOD",
                   help=f"methods to compare: {', '.join(METHODS)} (default: every method that can run here)")
    p.add_argument("--runs", type=_positive, default=1, help="runs per task and method (the paper: 10)")
    p.add_argument("--lm", help="model string DSPy accepts, e.g. openai/gpt-4o-mini (default: $ROBOTOOL_LM)")
    p.add_argument("--api-base", help="base URL of an OpenAI-compatible server, e.g. http://127.0.0.1:8000/v1")
    p.add_argument("--api-key-env", help="environment variable holding the API key")
    p.add_argument("--temperature", type=float, help="LM sampling temperature (above 0 for runs that differ)")
    p.add_argument("--candidates", type=_positive, default=1, help="candidate programs per run, LM methods (K)")
    p.add_argument("--worlds", type=_positive, default=3, help="perturbed worlds per candidate (R)")
    p.add_argument("--backend", choices=["mujoco", "warp"], help="simulator (default: warp with a GPU, else mujoco)")
    p.add_argument("--seed", type=int, default=0, help="base seed of the perturbed worlds")
    p.add_argument("--workers", type=_positive, default=DEFAULT_WORKERS, help="LM runs in flight at once")
    p.add_argument("--out", type=Path, help="output folder (default: results/<model>-k<K>-w<R>-s<seed>)")
    return p


def config_from(args: argparse.Namespace) -> EvalConfig:
    """The evaluation the parsed arguments ask for."""
    if args.seed < 0:
        raise EvalError(f"--seed must be at least 0, got {args.seed}")
    settings = Settings(lm=args.lm, temperature=args.temperature, candidates=args.candidates, worlds=args.worlds,
                        backend=args.backend, seed=args.seed)
    return EvalConfig(tasks=args.tasks, families=args.families, seeds=args.seeds, methods=args.methods,
                      runs=args.runs, settings=settings, api_base=args.api_base, api_key_env=args.api_key_env,
                      workers=args.workers, out=args.out)


def main(argv: Sequence[str] | None = None, prog: str = "python -m robotool.eval") -> int:
    """Run the evaluator; returns the exit status."""
    from robotool.eval.runner import evaluate

    args = build_parser(prog).parse_args(argv)
    errors = Console(stderr=True)
    console = Console() if sys.stdout.isatty() else Console(width=CAPTURED_WIDTH)
    try:
        evaluate(config_from(args), console=console)
    except (EvalError, TaskFileError, LMConfigError) as e:
        errors.print(f"[bold red]error:[/] {' '.join(str(e).split())}", highlight=False, soft_wrap=True)
        return EXIT_USAGE
    except KeyboardInterrupt:
        errors.print("interrupted: finished runs are kept in the journal; run the same command to resume")
        return EXIT_INTERRUPTED
    return 0


if __name__ == "__main__":
    sys.exit(main())
