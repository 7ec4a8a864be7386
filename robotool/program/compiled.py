"""Compiled programs: a :class:`~robotool.program.lm_program.Proposer`'s optimised prompts and demonstrations in one
JSON file, with a record of how they were made.

The file is DSPy's own state file (``module.save``: each predictor's instructions and demonstrations)
plus a ``robotool`` entry, :class:`CompiledInfo`: the robotool version that compiled it, the optimiser,
its settings, the method (which stages the program has), the validation score before and after, and
where each demonstration came from. :func:`read_compiled` checks a file before anything uses it;
:func:`check_fits` says exactly what does not fit a program (its stages), and :func:`version_note` says
when the robotool version differs.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel, Field, ValidationError

from robotool.errors import RobotoolError
from robotool.task.task_file import read_at_most
from robotool.version import version

if TYPE_CHECKING:
    import dspy

KEY = "robotool"


class CompiledProgramError(RobotoolError):
    """A compiled program file cannot be used as asked; the message says why and what to do."""


class DemoSource(BaseModel):
    """Where one stored demonstration came from: the instance, and its code's verified success rate."""

    task: str
    family: str | None = None
    seed: int | None = None
    code: str
    success_rate: float


class Validation(BaseModel):
    """Validation success of the program before and after optimisation (mean over the examples)."""

    examples: int
    before: float | None = None
    after: float | None = None
    note: str | None = Field(None, description="why a score is missing, if one is")


class CompiledInfo(BaseModel):
    """How a compiled program was made."""

    robotool_version: str = Field(default_factory=version)
    optimizer: str
    method: str = Field(description="the stages the program has (robotool.program.methods.STAGES_BY_METHOD)")
    settings: dict[str, Any] = Field(default_factory=dict)
    validation: Validation | None = None
    demonstrations: list[DemoSource] = Field(default_factory=list)
    train: list[str] = Field(default_factory=list, description="the task instances it was trained on")
    val: list[str] = Field(default_factory=list, description="the task instances it was validated on")
    notes: list[str] = Field(default_factory=list, description="what the optimiser did not do, and why")


MAX_COMPILED_BYTES = 64 * 2**20
"""A compiled program file's largest size (its prompts and demonstrations take some hundreds of kB)."""


def save_compiled(program: dspy.Module, path: Path, info: CompiledInfo) -> None:
    """Write the program's state and ``info`` to ``path`` (JSON)."""
    state = program.dump_state()
    state[KEY] = info.model_dump(mode="json")
    path.write_text(json.dumps(state, indent=1, default=str), encoding="utf-8")


def read_compiled(path: Path) -> tuple[dict[str, Any], CompiledInfo | None]:
    """The state in a compiled program file and its record (None for a plain DSPy state file)."""
    if path.suffix.lower() != ".json":
        raise CompiledProgramError(f"{path}: a compiled program is a .json file")
    try:
        data = read_at_most(path, MAX_COMPILED_BYTES)
        if len(data) > MAX_COMPILED_BYTES:
            raise CompiledProgramError(
                f"{path} is larger than {MAX_COMPILED_BYTES // 2**20} MiB: not a compiled program"
            )
        state = json.loads(data.decode("utf-8"))
    except FileNotFoundError:
        raise CompiledProgramError(f"compiled program not found: {path}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise CompiledProgramError(f"cannot read {path}: {getattr(e, 'strerror', None) or e}") from None
    except json.JSONDecodeError as e:
        raise CompiledProgramError(f"{path} is not JSON (line {e.lineno}, column {e.colno}: {e.msg})") from None
    except ValueError as e:  # a number of thousands of digits
        raise CompiledProgramError(f"{path} cannot be read: {str(e).split(';')[0]}") from None
    if not isinstance(state, dict):
        raise CompiledProgramError(f"{path} is not a compiled program (expected a JSON object)")
    info = None
    if KEY in state:
        try:
            info = CompiledInfo.model_validate(state.pop(KEY))
        except ValidationError as e:
            problem = e.errors(include_url=False)[0]
            where = ".".join(map(str, problem["loc"]))
            raise CompiledProgramError(f"{path}: its robotool record is damaged ({where}: {problem['msg']})") from None
    for name, entry in state.items():
        if name != "metadata" and not (isinstance(entry, dict) and "signature" in entry and "demos" in entry):
            raise CompiledProgramError(f"{path}: entry {name!r} is not a DSPy predictor's state")
    return state, info


def check_fits(path: Path, state: dict[str, Any], info: CompiledInfo | None, predictors: list[str]) -> list[str]:
    """Refuse a file that lacks one of the program's stages (it would silently keep its default prompt);
    notes on stages of the file that the program does not have (they are not used)."""
    missing = [p for p in predictors if p not in state]
    extra = sorted(k for k in state if k != "metadata" and k not in predictors)
    compiled_for = f" (compiled for method {info.method})" if info else ""
    if missing:
        raise CompiledProgramError(
            f"{path}{compiled_for} has no stage {', '.join(missing)}, which this program (stages "
            f"{', '.join(predictors)}) has; use the method it was compiled for"
        )
    return [f"{path}{compiled_for}: its stage(s) {', '.join(extra)} are not used by this program"] if extra else []


def version_note(path: Path, info: CompiledInfo | None) -> str | None:
    """A note when the file was compiled by another robotool version (or records none)."""
    if info is None:
        return f"{path} has no robotool record (a plain DSPy state file): its origin is unknown"
    if info.robotool_version != version():
        return (
            f"{path} was compiled with robotool {info.robotool_version}; this is {version()}: "
            "its prompts may not match this version's stages"
        )
    return None
