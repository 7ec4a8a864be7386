"""What an evaluation is asked to do, its defaults, and where its results go.

Output folder: ``--out DIR``, or by default ``results/<model>-k<K>-w<R>-s<seed>`` (``<model>`` is the
LM's model string made path-safe, ``no-lm`` without one), so the same command always writes to, and
resumes in, the same folder while different settings never mix. The folder holds ``settings.json``
(the settings that decide results, checked when resuming), ``journal.jsonl`` (one line per finished
run), and at the end ``results.json``, ``report.md`` and the plots.
"""

from __future__ import annotations

import re
from pathlib import Path

from pydantic import BaseModel, Field

TIME_BUDGET_S = 300.0
"""The default run (no LM: the LM-free methods on every built-in task and the default generated
instances, one run each) must finish within this many seconds on a 2-core machine. Measured: 62 runs
(10 built-in tasks + 21 solvable generated instances at seeds 0-2, x search and no_tool) took 119-167 s."""

DEFAULT_RESULTS = Path("results")
DEFAULT_WORKERS = 4
"""Runs of LM methods in flight at once (their LM calls overlap; LM-free runs take turns)."""


class EvalError(ValueError):
    """The evaluation cannot be set up as asked; the message says why (exit status 2)."""


class Settings(BaseModel):
    """The settings that decide a run's result: resuming with other settings is refused."""

    lm: str | None = None
    temperature: float | None = None
    candidates: int = Field(1, ge=1, description="candidate programs per run (LM methods)")
    worlds: int = Field(3, ge=1, description="perturbed worlds per candidate")
    backend: str | None = None
    seed: int = Field(0, ge=0, description="base seed of the perturbed worlds")


class EvalConfig(BaseModel):
    """One evaluation: what to run (None: the defaults), with which settings, and where to write."""

    tasks: list[str] | None = Field(None, description="built-in task names or task files")
    families: list[str] | None = None
    seeds: list[int] | None = None
    methods: list[str] | None = Field(None, description="None: every method that can run here")
    runs: int = Field(1, ge=1, description="runs per task instance and method")
    settings: Settings = Field(default_factory=Settings)
    api_base: str | None = None
    api_key_env: str | None = None
    workers: int = Field(DEFAULT_WORKERS, ge=1)
    out: Path | None = None

    @property
    def out_dir(self) -> Path:
        """The output folder (see the module docstring)."""
        if self.out is not None:
            return self.out
        s = self.settings
        model = re.sub(r"[^A-Za-z0-9_.]+", "-", s.lm).strip("-") if s.lm else "no-lm"
        return DEFAULT_RESULTS / f"{model}-k{s.candidates}-w{s.worlds}-s{s.seed}"

    def world_seed(self, run: int) -> int:
        """Seed of run ``run``'s worlds: runs never share a perturbed world."""
        return self.settings.seed + run * self.settings.worlds
