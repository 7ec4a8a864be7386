"""What every robotool command line shares: the option groups (language model, worlds, candidates) declared once,
one-line argument errors, checked numbers and output paths, consoles that keep their width when piped, and error
lines that print text exactly as it is.

A user mistake ends as one line on stderr and exit status :data:`EXIT_USAGE`, never a traceback.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, TypeAlias

from rich.console import Console
from rich.text import Text

from robotool.errors import RobotoolWarning
from robotool.program.lm import DEFAULT_TIMEOUT, MAX_TIMEOUT
from robotool.safe_text import TerminalConsole, capped, console_plain, one_line
from robotool.vocabulary import BACKENDS, BackendName

if TYPE_CHECKING:
    import dspy

EXIT_USAGE = 2
EXIT_INTERRUPTED = 130  # Ctrl-C: 128 + SIGINT, as shells report it
DEFAULT_WORLDS = 3
"""Perturbed worlds per candidate for ``solve`` and ``eval``: enough to rank candidates."""
BACKEND_HELP = "simulator (default: warp with a CUDA GPU, else mujoco)"
ADAPTERS = ["chat", "json"]
TIMEOUT_HELP = f"how long to wait for each LM reply, at most {MAX_TIMEOUT:g} s (default: {DEFAULT_TIMEOUT:g})"
ADAPTER_HELP = "answer format asked of the model: chat (field markers, default) or json"
LOG_PROMPTS_HELP = "append every LM request and reply to this JSONL file"
TEMPERATURE_HELP = (
    "sampling temperature of every LM call (default: the model's for one candidate, 0.7 to 1.0 spread over several)"
)
TASK_HELP = "a built-in task name (see robotool tasks) or a YAML/JSON task file"
REPAIR_HELP = (
    "repair rounds (LM methods): while no candidate succeeds in every world, the best failures are shown what "
    "the simulator measured and rewritten by the model, then verified again"
)
CAPTURED_WIDTH = 120
"""Console width when the output goes to a file or a pipe (rich would squeeze tables to 80 columns)."""


class HelpFormatter(argparse.HelpFormatter):
    """Appends ``(default: X)`` to an option's help when it has a default and the help does not say it."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if (
            default is None
            or default is False
            or default is argparse.SUPPRESS
            or "default" in text
            or action.option_strings == []
            or not text
        ):
            return text
        shown = " ".join(map(str, default)) if isinstance(default, list | tuple) else default
        return f"{text} (default: {shown})"


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line on stderr with exit status 2."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        """The message on one line, its control characters escaped (it quotes the argument, e.g. a path)."""
        self.exit(EXIT_USAGE, f"error: {one_line(message)} (see {one_line(self.prog)} --help)\n")


Verbs: TypeAlias = "argparse._SubParsersAction[Parser]"
"""A parser's verbs (what ``add_subparsers`` returns): each command module registers its own."""


MAX_WORLDS = 1000
"""Perturbed worlds per candidate: each world's program runs in a sandboxed worker of its own, all at once."""
MAX_CANDIDATES = 100
"""Candidate programs per solve or run (each is verified in every world: K x R workers at once)."""
MAX_REPAIRS = 100
"""Repair rounds, and times a stage is asked again after a reply that does not parse."""
MAX_RUNS = 1000
"""Runs per task and method of an evaluation (the paper: 10)."""
MAX_THREADS = 256
"""Threads that keep language-model calls in flight at once."""
MAX_PROCESSES = 1024
"""Processes that simulate at once (one per core is the default)."""
MAX_SEED = 2**63 - 1
"""The largest seed: seeds are added to and hashed, and a number of thousands of digits is a mistake."""
SHOWN_CHARS = 40
"""How much of an argument that is not a number an error quotes."""


def _whole_number(text: str, minimum: int, maximum: int, expected: str) -> int:
    """``text`` as a whole number from ``minimum`` to ``maximum``; the argument error says it ``expected`` one (and
    the bound it broke)."""
    try:
        value = int(text)
    except ValueError:  # also a number of more digits than Python converts
        raise argparse.ArgumentTypeError(f"expected {expected}, got {capped(text, SHOWN_CHARS)!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"expected {expected}, got {value}")
    if value > maximum:
        raise argparse.ArgumentTypeError(f"expected {expected} of at most {maximum}, got {capped(text, SHOWN_CHARS)}")
    return value


def positive_int(maximum: int) -> Callable[[str], int]:
    """An argument that must be a whole number from 1 to ``maximum`` (every count has a bound: a count far beyond
    any real use would hang the command or exhaust the machine's memory before it said anything)."""

    def positive(text: str) -> int:
        return _whole_number(text, 1, maximum, "a positive integer")

    return positive


def count(maximum: int) -> Callable[[str], int]:
    """A count that may be zero: a whole number from 0 to ``maximum``."""

    def whole(text: str) -> int:
        return _whole_number(text, 0, maximum, "a whole number >= 0")

    return whole


def seed(text: str) -> int:
    """A seed: a whole number from 0 to :data:`MAX_SEED`."""
    return _whole_number(text, 0, MAX_SEED, "a seed (a whole number >= 0)")


def seconds(text: str) -> float:
    """A wait for one LM reply: a finite number of seconds above 0, at most :data:`~robotool.program.lm.MAX_TIMEOUT`."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds > 0, got {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"expected a finite number of seconds > 0, got {text!r}")
    if value > MAX_TIMEOUT:
        raise argparse.ArgumentTypeError(f"expected a number of seconds of at most {MAX_TIMEOUT:g}, got {text!r}")
    return value


def variable_name(text: str) -> str:
    """The name of an environment variable: not empty, with no ``=`` or NUL in it (no variable could have it)."""
    if not text or "=" in text or "\0" in text:
        raise argparse.ArgumentTypeError(f"expected the name of an environment variable, got {text!r}")
    return text


def temperature(text: str) -> float:
    """A sampling temperature: a finite number of at least 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text!r}")
    return value


def cluster_address(text: str) -> str:
    """A cluster's address as its client takes it (``auto``, ``HOST:PORT``, ``ray://HOST:PORT``): one word."""
    value = text.strip()
    if not value or any(c.isspace() for c in value):
        raise argparse.ArgumentTypeError(f"expected a cluster address such as auto or ray://HOST:10001, got {text!r}")
    return value


def output_file(text: str) -> Path:
    """A file the command will write: its folder must exist and be writable, and it must not be a folder."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a file name, got an empty one")
    path = Path(text)
    folder = path.parent
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{path} is a folder; give a file name")
    if not folder.is_dir():
        raise argparse.ArgumentTypeError(f"cannot write {path}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK) or (path.exists() and not os.access(path, os.W_OK)):
        raise argparse.ArgumentTypeError(f"cannot write {path}: permission denied")
    return path


def compiled_program_file(text: str) -> Path:
    """A file a compiled program will be saved to (:func:`output_file`): a ``.json`` file, the only kind that
    ``--program`` loads."""
    path = output_file(text)
    if path.suffix.lower() != ".json":
        raise argparse.ArgumentTypeError(f"{path}: a compiled program is saved as a .json file, which --program loads")
    return path


def output_folder(text: str) -> Path:
    """A folder the command will create or write into: it must not be a file, and it must be creatable."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a folder name, got an empty one")
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{path} is a file, not a folder")
    existing = next(p for p in (path, *path.parents) if p.exists())
    if not existing.is_dir():
        raise argparse.ArgumentTypeError(f"cannot create {path}: {existing} is a file")
    if not os.access(existing, os.W_OK):
        raise argparse.ArgumentTypeError(f"cannot write into {path}: permission denied on {existing}")
    return path


def add_lm_options(
    parser: argparse.ArgumentParser, *, temperature_help: str = TEMPERATURE_HELP, log_prompts: bool = True
) -> argparse._ArgumentGroup:
    """The language-model options every LM command takes; returns their group, for a command's own LM options.

    ``log_prompts``: also ``--log-prompts FILE`` (commands that can write every request and reply)."""
    group = parser.add_argument_group("language model")
    group.add_argument("--lm", help="model string DSPy accepts, e.g. openai/gpt-4o-mini (default: $ROBOTOOL_LM)")
    group.add_argument("--api-base", help="base URL of an OpenAI-compatible server, e.g. http://127.0.0.1:8000/v1")
    group.add_argument("--api-key-env", type=variable_name, help="environment variable holding the API key")
    group.add_argument("--temperature", type=temperature, help=temperature_help)
    group.add_argument("--adapter", choices=ADAPTERS, help=ADAPTER_HELP)
    group.add_argument("--timeout", type=seconds, metavar="SECONDS", help=TIMEOUT_HELP)
    group.add_argument("--no-cache", action="store_true", help="do not reuse cached LM replies")
    if log_prompts:
        group.add_argument("--log-prompts", type=output_file, metavar="FILE", help=LOG_PROMPTS_HELP)
    return group


def lm_from(args: argparse.Namespace, *, max_tokens: int | None = None) -> dspy.LM | None:
    """The model the LM options name (None when none is configured), with a token limit per reply if given."""
    from robotool.program.lm import make_lm

    return make_lm(
        args.lm,
        api_base=args.api_base,
        api_key_env=args.api_key_env,
        temperature=args.temperature,
        cache=not args.no_cache,
        timeout=args.timeout,
        max_tokens=max_tokens,
    )


def add_world_options(
    parser: argparse.ArgumentParser,
    *,
    worlds: int = DEFAULT_WORLDS,
    worlds_help: str = "perturbed worlds per candidate (R)",
    seed_help: str = "seed of the world perturbations",
) -> argparse._ArgumentGroup:
    """The simulated worlds' options every command that runs programs takes: how many, which simulator, the seed."""
    group = parser.add_argument_group("worlds")
    group.add_argument("--worlds", type=positive_int(MAX_WORLDS), default=worlds, help=worlds_help)
    group.add_argument("--backend", choices=BACKENDS, help=BACKEND_HELP)
    group.add_argument("--seed", type=seed, default=0, help=seed_help)
    return group


def add_candidate_options(parser: argparse.ArgumentParser) -> argparse._ArgumentGroup:
    """How many programs the LM path proposes (K) and how many repair rounds it may run."""
    group = parser.add_argument_group("candidates")
    group.add_argument(
        "--candidates", type=positive_int(MAX_CANDIDATES), default=1, help="candidate programs to sample (K)"
    )
    group.add_argument("--repair", type=count(MAX_REPAIRS), default=0, metavar="N", help=REPAIR_HELP)
    return group


def make_console(*, stderr: bool = False) -> Console:
    """A console for output; when it is not a terminal (and ``COLUMNS`` is not a positive width), tables keep
    :data:`CAPTURED_WIDTH` columns instead of rich's 80. A :class:`~robotool.safe_text.TerminalConsole`: whatever
    reaches it (an output path the user typed included) shows its control characters as escapes, and emoji codes stay
    text (``:white_check_mark:`` in a program's string must not paint a tick in the host's tables)."""
    stream = sys.stderr if stderr else sys.stdout
    columns = os.environ.get("COLUMNS", "").strip()
    if columns.isdigit() and int(columns) > 0:  # the user's width (rich reads it)
        return TerminalConsole(stderr=stderr)
    if stream.isatty():  # (rich would take COLUMNS=0 for a width of nothing, and print nothing at all)
        return TerminalConsole(stderr=stderr, width=shutil.get_terminal_size().columns)
    return TerminalConsole(stderr=stderr, width=CAPTURED_WIDTH)


def warnings_in_one_line() -> None:
    """Show robotool's own warnings as one ``warning: ...`` line on stderr (no file, line or source)."""
    python_format = warnings.formatwarning

    def formatted(
        message: Warning | str, category: type[Warning], filename: str, lineno: int, line: str | None = None
    ) -> str:
        if issubclass(category, RobotoolWarning):
            return f"warning: {one_line(str(message))}\n"
        return python_format(message, category, filename, lineno, line)

    warnings.formatwarning = formatted


def print_error(errors: Console, message: str) -> None:
    """``error: message``, the message printed exactly (square brackets and all, never read as markup), its control
    characters escaped (it can quote a program)."""
    errors.print(Text.assemble(("error:", "bold red"), " ", console_plain(message)), highlight=False, soft_wrap=True)


def warn_if_warp_on_cpu(backend: BackendName | None, errors: Console) -> None:
    """Say once that ``--backend warp`` without a CUDA GPU runs on the CPU, much slower than mujoco."""
    if backend != "warp":
        return
    from robotool.sim.backend import default_backend

    if default_backend() != "warp":
        errors.print(
            Text.assemble(
                ("warning:", "yellow"),
                " no CUDA GPU found: --backend warp runs on the CPU, much slower than --backend mujoco",
            ),
            highlight=False,
            soft_wrap=True,
        )
