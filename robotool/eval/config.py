"""What an evaluation is asked to do, its defaults, and where its results go.

Output folder: ``--out DIR``, or by default ``results/<model>-k<K>-w<R>-s<seed>`` (``-r<N>`` after ``k<K>``
with N repair rounds; ``<model>`` is the LM's model string made path-safe, ``no-lm`` without one), so the
same command always writes to, and resumes in, the same folder. The folder holds ``settings.json`` (the
:class:`Request` that last wrote it: a different request is refused unless ``--resume`` is given),
``journal.jsonl`` (one line per finished run, keyed by the content of its inputs) and at the end
``results.json``, ``report.md`` and the plots, which cover exactly the runs the last command asked for.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from robotool.errors import LMUnavailableError, RobotoolError
from robotool.vocabulary import BackendName

TIME_BUDGET_S = 300.0
"""The default run (no LM: the LM-free methods on every built-in task and the default generated
instances, one run each) must finish within this many seconds on a 2-core machine. Measured: 62 runs
(10 built-in tasks + 21 solvable generated instances at seeds 0-2, x search and no_tool) took 119-167 s."""

DEFAULT_RESULTS = Path("results")
DEFAULT_WORKERS = 4
"""Runs of LM methods in flight at once (their LM calls overlap; LM-free runs take turns)."""


class EvalError(ValueError):
    """The evaluation cannot be set up as asked; the message says why (exit status 2)."""


class RunsNotAttempted(RobotoolError):
    """Some runs could not be attempted (the language model was unavailable); nothing was recorded for them.

    ``missing`` of ``total`` runs were not attempted because of ``cause``; the runs that finished are in the
    journal, and the same command retries the others.
    """

    def __init__(self, missing: int, total: int, cause: LMUnavailableError) -> None:
        super().__init__(
            f"{missing} of {total} run(s) could not be attempted: {cause} ({cause.kind}); "
            "nothing was recorded for them: fix this and rerun the same command "
            "(finished runs are kept)"
        )
        self.missing, self.total, self.cause = missing, total, cause


class Settings(BaseModel):
    """The settings that decide a run's result: resuming with other settings is refused."""

    lm: str | None = None
    temperature: float | None = None
    candidates: int = Field(1, ge=1, description="candidate programs per run (LM methods)")
    worlds: int = Field(3, ge=1, description="perturbed worlds per candidate")
    backend: BackendName | None = None
    seed: int = Field(0, ge=0, description="base seed of the perturbed worlds")
    adapter: Literal["chat", "json"] | None = Field(None, description="answer format asked of the LM (None: chat)")
    repair: int = Field(0, ge=0, description="repair rounds after a verification with no full success (LM methods)")


class Request(BaseModel):
    """What an evaluation asked for: which runs, with which settings (``settings.json`` of a results folder)."""

    model_config = ConfigDict(extra="forbid")

    tasks: list[str] | None = None
    families: list[str] | None = None
    seeds: list[int] | None = None
    methods: list[str] | None = None
    programs: list[str] | None = None
    runs: int = 1
    settings: Settings = Field(default_factory=Settings)
    api_base: str | None = None

    def differences(self, other: Request) -> list[str]:
        """``field: other -> self`` for each field that differs (settings field by field)."""
        mine, theirs = self.model_dump(), other.model_dump()
        mine |= {f"settings.{k}": v for k, v in mine.pop("settings").items()}
        theirs |= {f"settings.{k}": v for k, v in theirs.pop("settings").items()}
        return [
            f"{k.removeprefix('settings.')}: {_shown(theirs.get(k))} -> {_shown(v)}"
            for k, v in mine.items()
            if theirs.get(k) != v
        ]


def _shown(value: object) -> str:
    if value is None:
        return "default"
    return ",".join(map(str, value)) if isinstance(value, list) else str(value)


class EvalConfig(BaseModel):
    """One evaluation: what to run (None: the defaults), with which settings, and where to write."""

    tasks: list[str] | None = Field(None, description="built-in task names or task files")
    families: list[str] | None = None
    seeds: list[int] | None = None
    methods: list[str] | None = Field(None, description="None: every method that can run here")
    programs: list[Path] | None = Field(
        None, description="compiled programs (robotool optimize), each a method named after its file"
    )
    allow_train: bool = Field(False, description="evaluate a compiled program on its own training instances")
    runs: int = Field(1, ge=1, description="runs per task instance and method")
    settings: Settings = Field(default_factory=Settings)
    api_base: str | None = None
    api_key_env: str | None = None
    workers: int = Field(DEFAULT_WORKERS, ge=1)
    out: Path | None = None
    resume: bool = Field(False, description="reuse a folder whose settings.json holds a different request")
    pictures: bool = Field(True, description="draw each task's scene and representative failures for the report")
    videos: int = Field(0, ge=0, description="film the first N failed worlds of each task and method for report.html")
    cache: bool = Field(True, description="reuse DSPy's cached LM replies")
    timeout: float | None = Field(None, gt=0, description="seconds to wait for each LM reply")
    log_prompts: Path | None = Field(None, description="JSONL file that receives every LM request and reply")

    @property
    def request(self) -> Request:
        """What this evaluation asks for, as ``settings.json`` records it."""
        return Request(
            tasks=self.tasks,
            families=self.families,
            seeds=self.seeds,
            methods=self.methods,
            programs=[str(p) for p in self.programs] if self.programs else None,
            runs=self.runs,
            settings=self.settings,
            api_base=self.api_base,
        )

    @property
    def out_dir(self) -> Path:
        """The output folder (see the module docstring)."""
        if self.out is not None:
            return self.out
        s = self.settings
        model = re.sub(r"[^A-Za-z0-9_.]+", "-", s.lm).strip("-") if s.lm else "no-lm"
        repair = f"-r{s.repair}" if s.repair else ""
        return DEFAULT_RESULTS / f"{model}-k{s.candidates}{repair}-w{s.worlds}-s{s.seed}"

    def world_seed(self, run: int) -> int:
        """Seed of run ``run``'s worlds: runs never share a perturbed world."""
        return self.settings.seed + run * self.settings.worlds
