"""The report's tables as plain text cells, shared by the Markdown report and the console."""

from __future__ import annotations

from collections.abc import Sequence
from statistics import mean

from pydantic import BaseModel, Field

from robotool.eval.metrics import OUTCOMES, Cell, MethodRow, Summary
from robotool.eval.reference import (
    PAPER_SUCCESS,
    PAPER_SUCCESS_AVERAGE,
    PAPER_TASKS,
    paper_concept_accuracy,
    paper_success,
)
from robotool.eval.solvers import method_label

NONE = "–"


class TextTable(BaseModel):
    """A titled table of text cells; the last ``reference`` rows are the paper's published numbers.

    (Table 2 puts the paper's numbers in its last column instead, as the paper lays it out.)
    """

    title: str
    columns: list[str]
    rows: list[list[str]] = Field(default_factory=list)
    reference: int = 0
    note: str = ""


def _num(value: float | None) -> str:
    return NONE if value is None else f"{value:.2f}"


def _runs_note(rows: Sequence[MethodRow]) -> str:
    counts = sorted({c.n for row in rows for c in row.cells.values() if c.n})
    if not counts:
        return ""
    span = str(counts[0]) if len(counts) == 1 else f"{counts[0]}-{counts[-1]}"
    return f"Each cell is a mean over {span} run(s)."


def _left_out(summary: Summary, note: str) -> str:
    """``note``, then how many runs an internal error took out of the table (none: ``note`` alone)."""
    n = sum(summary.internal_errors.values())
    excluded = f"{n} run(s) with an internal error (a bug in robotool, not a failure) left out." if n else ""
    return " ".join(part for part in (note, excluded) if part)


def success_table(summary: Summary) -> TextTable:
    """Table 1: the paper's tasks as columns, methods as rows, the average, the paper's rows for reference."""
    columns = [c for c in PAPER_TASKS if any(c in row.cells for row in summary.success)]
    note = _left_out(summary, _runs_note(summary.success))
    table = _matrix_table("Success rate (paper Table 1)", columns, summary.success, note)
    if table.rows:
        for method in PAPER_SUCCESS:
            published = paper_success(method)
            average = (
                PAPER_SUCCESS_AVERAGE[method]
                if len(columns) == len(PAPER_TASKS)
                else mean(published[c] for c in columns)
            )
            table.rows.append([f"paper: {method_label(method)}", *(_num(published[c]) for c in columns), _num(average)])
        table.reference = len(PAPER_SUCCESS)
    return table


def other_tasks_table(summary: Summary) -> TextTable:
    """Success on the other built-in tasks and task files (discriminative variants, extra tasks)."""
    columns = [c for c in dict.fromkeys(c for row in summary.success for c in row.cells) if c not in PAPER_TASKS]
    note = _left_out(summary, _runs_note(summary.success))
    return _matrix_table("Success rate on other tasks", columns, summary.success, note)


def _matrix_table(title: str, columns: Sequence[str], rows: Sequence[MethodRow], note: str) -> TextTable:
    """Methods as rows, ``columns`` as columns, and the average over the columns with a value."""
    table = TextTable(title=title, columns=["method", *columns, "average"], note=note)
    for row in rows:
        values = [row.cells[c].value if c in row.cells else None for c in columns]
        known = [v for v in values if v is not None]
        if known:
            table.rows.append([method_label(row.method), *map(_num, values), _num(mean(known))])
    return table


def generated_table(summary: Summary) -> TextTable:
    """Success on generated instances: families as columns."""
    columns = list(dict.fromkeys(c for row in summary.generated for c in row.cells))
    return _matrix_table(
        "Success rate on generated instances",
        columns,
        summary.generated,
        _left_out(summary, _runs_note(summary.generated) + " A family's cell pools its seeds' runs."),
    )


def concepts_table(summary: Summary) -> TextTable:
    """Table 2 (tasks as rows, as in the paper): share of runs that recovered every ground-truth concept."""
    tasks = list(dict.fromkeys(c for row in summary.concepts for c in row.cells))
    published = paper_concept_accuracy()
    reference = any(t in published for t in tasks)
    table = TextTable(
        title="Key-concept accuracy (paper Table 2)",
        columns=[
            "task",
            *(method_label(r.method) for r in summary.concepts),
            *(["paper: RoboTool"] if reference else []),
        ],
        note=_left_out(summary, _runs_note(summary.concepts) + " Matching rule: robotool/eval/grading.py."),
    )
    for task in tasks:
        cells = [_num(r.cells[task].value if task in r.cells else None) for r in summary.concepts]
        table.rows.append([task, *cells, *([_num(published.get(task))] if reference else [])])
    return table


def errors_table(summary: Summary) -> TextTable:
    """Error breakdown: each method's share of outcomes."""
    table = TextTable(
        title="Outcomes and error breakdown (share of runs)",
        columns=["method", *OUTCOMES, "runs"],
        note=_left_out(summary, "Classes from rollout traces; rules in robotool/eval/failure_classes.py."),
    )
    for b in summary.errors:
        table.rows.append([method_label(b.method), *(_num(b.shares[o]) for o in OUTCOMES), str(b.runs)])
    return table


def _rate(cell: Cell) -> str:
    return NONE if cell.value is None else f"{cell.value:.2f} (n={cell.n})"


def discrimination_table(summary: Summary) -> TextTable:
    """Discriminative tool use: tool-use rate where a tool is needed and where none is."""
    table = TextTable(
        title="Discriminative tool use (share of worlds using a tool)",
        columns=["method", "tool needed", "no tool needed"],
        note=_left_out(summary, "Ideal: 1.00 where a tool is needed, 0.00 where none is. n: runs."),
    )
    for d in summary.discrimination:
        table.rows.append([method_label(d.method), _rate(d.needed), _rate(d.not_needed)])
    return table


def cost_table(summary: Summary) -> TextTable:
    """LM tokens and wall time per method."""
    table = TextTable(
        title="Cost per run",
        columns=["method", "runs", "prompt tokens", "completion tokens", "wall s / run", "wall s total"],
    )
    for c in summary.cost:
        table.rows.append(
            [
                method_label(c.method),
                str(c.runs),
                f"{c.prompt_tokens:.0f}",
                f"{c.completion_tokens:.0f}",
                f"{c.wall_s:.1f}",
                f"{c.total_wall_s:.1f}",
            ]
        )
    return table


def repair_table(summary: Summary) -> TextTable:
    """Success against LM calls spent: best-of-K, K plus repair rounds, and plain best-of-K' at equal calls."""
    table = TextTable(
        title="Repair against plain sampling at equal LM calls (mean success @ mean LM calls)",
        columns=["method", "runs", "best-of-K", "K + repair", "plain best-of-K'"],
        note="best-of-K: the run's sampled candidates before any repair; plain best-of-K': a second "
        "solve sampling K' candidates without repair, K' chosen to spend the LM calls the run "
        "with repair spent.",
    )
    for c in summary.repair:
        table.rows.append(
            [
                method_label(c.method),
                str(c.runs),
                f"{c.sampled_success:.2f} @ {c.sampled_calls:.1f} (K={c.sampled:.1f})",
                f"{c.repair_success:.2f} @ {c.repair_calls:.1f}",
                f"{c.plain_success:.2f} @ {c.plain_calls:.1f} (K'={c.plain:.1f})",
            ]
        )
    return table


def all_tables(summary: Summary) -> list[TextTable]:
    """Every table with at least one measured row, in report order."""
    tables = [
        success_table(summary),
        other_tasks_table(summary),
        generated_table(summary),
        concepts_table(summary),
        errors_table(summary),
        discrimination_table(summary),
        cost_table(summary),
        repair_table(summary),
    ]
    return [t for t in tables if len(t.rows) > t.reference]
