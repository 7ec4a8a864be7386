"""Records -> the numbers the report shows: success (Table 1), key concepts (Table 2), error
breakdown, discriminative tool use, and cost.

Conventions. A run scores its chosen candidate's success rate over its perturbed worlds; a cell is
the mean over the cell's runs (generated instances: over every seed's runs of that family). The
error breakdown splits each run's weight of 1 evenly over its worlds, so a method's shares of
success, tool-use, logical, numerical and invalid sum to 1 and its success share equals its mean
success; a run that ran nothing counts 1 as invalid. A run with an internal error (a bug in robotool met in the
run: a controller or the method raised) is neither a success nor a failure: it is left out of every number but
the cost, and counted apart. The tool-use rate is the share of worlds whose
program used a tool (see :mod:`robotool.eval.failure_classes`), separately where the instance needs a tool
and where it does not.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable, Sequence
from statistics import mean

from pydantic import BaseModel, Field

from robotool.eval.failure_classes import FAILURE_CLASSES
from robotool.eval.records import RunRecord

OUTCOMES: tuple[str, ...] = ("success", *FAILURE_CLASSES)


class Cell(BaseModel):
    """A mean over ``n`` runs (None when no run was graded)."""

    value: float | None = None
    n: int = 0


class MethodRow(BaseModel):
    """One method's cells by column."""

    method: str
    cells: dict[str, Cell] = Field(default_factory=dict)


class Breakdown(BaseModel):
    """A method's share of outcomes over its runs (``OUTCOMES`` order)."""

    method: str
    shares: dict[str, float]
    runs: int


class Discrimination(BaseModel):
    """How often a method used a tool where one is needed and where none is."""

    method: str
    needed: Cell
    not_needed: Cell


class Cost(BaseModel):
    """A method's LM tokens and wall time: means per run and the total."""

    method: str
    runs: int
    prompt_tokens: float
    completion_tokens: float
    wall_s: float
    total_wall_s: float


class RepairComparison(BaseModel):
    """A method's mean success and LM calls: best-of-K, K plus repair, and plain best-of-K' at equal calls."""

    method: str
    runs: int
    sampled: float = Field(description="mean K")
    sampled_calls: float
    sampled_success: float
    repair_calls: float
    repair_success: float
    plain: float = Field(description="mean K'")
    plain_calls: float
    plain_success: float


class Summary(BaseModel):
    """Everything the tables and plots show. Runs with an internal error (a bug in robotool) are neither successes
    nor failures: every table but the cost leaves them out, and ``internal_errors`` counts them by method."""

    methods: list[str]
    success: list[MethodRow] = Field(description="built-in tasks and task files as columns")
    generated: list[MethodRow] = Field(description="task families as columns")
    concepts: list[MethodRow] = Field(description="methods that predicted key concepts; all tasks")
    errors: list[Breakdown]
    discrimination: list[Discrimination]
    cost: list[Cost]
    repair: list[RepairComparison] = Field(default_factory=list, description="runs with repair rounds only")
    internal_errors: dict[str, int] = Field(
        default_factory=dict, description="method -> runs left out because a bug in robotool ended them"
    )


def _cell(values: Sequence[float]) -> Cell:
    return Cell(value=mean(values) if values else None, n=len(values))


def _matrix(
    records: Sequence[RunRecord],
    methods: Sequence[str],
    column: Callable[[RunRecord], str | None],
    value: Callable[[RunRecord], float | None],
) -> list[MethodRow]:
    """Rows of per-column means; records whose column or value is None are left out."""
    groups: dict[str, dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
    columns: dict[str, None] = {}
    for r in records:
        name, v = column(r), value(r)
        if name is not None and v is not None:
            groups[r.key.method][name].append(v)
            columns[name] = None
    return [MethodRow(method=m, cells={c: _cell(groups[m][c]) for c in columns}) for m in methods if m in groups]


def _builtin_column(r: RunRecord) -> str | None:
    return r.key.task if r.key.seed is None else None


def _family_column(r: RunRecord) -> str | None:
    return r.key.task if r.key.seed is not None else None


def _any_column(r: RunRecord) -> str:
    return r.key.task if r.key.seed is None else f"{r.key.task} (generated)"


def _concept_score(r: RunRecord) -> float | None:
    return None if r.concepts.correct is None else float(r.concepts.correct)


def _breakdown(method: str, records: Sequence[RunRecord]) -> Breakdown:
    shares = dict.fromkeys(OUTCOMES, 0.0)
    for r in records:
        if not r.worlds:
            shares["invalid"] += 1.0
        for w in r.worlds:
            shares[w.failure_class or "success"] += 1.0 / len(r.worlds)
    return Breakdown(method=method, shares={k: v / len(records) for k, v in shares.items()}, runs=len(records))


def _discrimination(method: str, records: Sequence[RunRecord]) -> Discrimination:
    def rates(needed: bool) -> Cell:
        return _cell([rate for r in records if r.needs_tool == needed and (rate := r.tool_use_rate) is not None])

    return Discrimination(method=method, needed=rates(True), not_needed=rates(False))


def _cost(method: str, records: Sequence[RunRecord]) -> Cost:
    return Cost(
        method=method,
        runs=len(records),
        prompt_tokens=mean(sum(u.prompt_tokens for u in r.usage.values()) for r in records),
        completion_tokens=mean(sum(u.completion_tokens for u in r.usage.values()) for r in records),
        wall_s=mean(r.wall_s for r in records),
        total_wall_s=sum(r.wall_s for r in records),
    )


def _repair(method: str, records: Sequence[RunRecord]) -> RepairComparison | None:
    budgets = [r.equal_budget for r in records if r.equal_budget is not None]
    if not budgets:
        return None
    fields = [f for f in RepairComparison.model_fields if f not in ("method", "runs")]
    return RepairComparison(
        method=method, runs=len(budgets), **{f: mean(float(getattr(b, f)) for b in budgets) for f in fields}
    )


def summarize(records: Sequence[RunRecord], methods: Sequence[str]) -> Summary:
    """All the metrics of ``records``, rows in ``methods`` order (methods without records left out)."""
    by_method: dict[str, list[RunRecord]] = defaultdict(list)
    for r in records:
        by_method[r.key.method].append(r)
    graded = [r for r in records if r.internal_error is None]
    graded_by_method = {m: [r for r in rs if r.internal_error is None] for m, rs in by_method.items()}
    present = [m for m in methods if by_method[m]]
    scored = [m for m in present if graded_by_method[m]]
    return Summary(
        methods=present,
        success=_matrix(graded, scored, _builtin_column, lambda r: r.success_rate),
        generated=_matrix(graded, scored, _family_column, lambda r: r.success_rate),
        concepts=_matrix(graded, scored, _any_column, _concept_score),
        errors=[_breakdown(m, graded_by_method[m]) for m in scored],
        discrimination=[_discrimination(m, graded_by_method[m]) for m in scored],
        cost=[_cost(m, by_method[m]) for m in present],
        repair=[row for m in scored if (row := _repair(m, graded_by_method[m])) is not None],
        internal_errors={m: n for m in present if (n := len(by_method[m]) - len(graded_by_method[m]))},
    )
