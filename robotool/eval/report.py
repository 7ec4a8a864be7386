"""The tables as ``report.md`` and on the console."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from robotool.eval.records import Picture, Results, RunRecord
from robotool.eval.tables import TextTable
from robotool.program.methods import runs_analyzer
from robotool.safe_text import markdown_text, one_line


def _markdown_table(table: TextTable) -> str:
    def line(cells: Sequence[str]) -> str:
        return "| " + " | ".join(markdown_text(c) for c in cells) + " |"

    lines = [f"## {markdown_text(table.title)}", "", line(table.columns), line(["---"] * len(table.columns))]
    lines += [line(row) for row in table.rows]
    if table.note:
        lines += ["", markdown_text(table.note)]
    return "\n".join(lines)


def preamble(results: Results, escape: Callable[[str], str] = markdown_text) -> list[str]:
    """What ran, with which settings, and what did not run and why (``escape``: for the sink the lines go to)."""
    s = results.config.settings
    lines = [
        f"- LM: {s.lm or 'none'}; candidates per run: {s.candidates}; worlds per candidate: {s.worlds}; "
        f"backend: {s.backend or 'default'}; base seed: {s.seed}",
        f"- runs recorded: {len(results.records)}; wall time of the last command: {results.wall_s:.0f} s",
    ]
    calls = sum(r.lm_calls for r in results.records)
    cached = sum(r.cached_replies for r in results.records)
    if cached:
        lines.append(
            f"- {cached} of {calls} LM replies came from DSPy's cache, not the model (--no-cache asks the model again)"
        )
    lines += [f"- {escape(line)}" for line in skipped_lines(results.skipped)]
    lines += [f"- note: {escape(note)}" for note in results.notes]
    lines += [f"- {escape(line)}" for line in internal_error_lines(results.records)]
    if not any(r.concepts.correct is not None or runs_analyzer(r.key.method) for r in results.records):
        lines.append(
            "- key-concept accuracy (Table 2) is graded only for methods with an Analyzer, which need an LM; none ran"
        )
    return lines


INTERNAL_ERRORS_SHOWN = 10
"""Runs with an internal error that the report names one by one (the others are counted)."""


def internal_error_lines(records: Sequence[RunRecord]) -> list[str]:
    """The runs a bug in robotool ended, apart from the results: how many, then each one's reason and where its
    traceback is (the record's place in ``results.json``)."""
    broken = [(i, r.key.id, r.internal_error) for i, r in enumerate(records) if r.internal_error is not None]
    if not broken:
        return []
    lines = [
        f"internal errors: {len(broken)} run(s) ended by a bug in robotool, neither successes nor failures: left out "
        "of the tables but the cost (their tracebacks were logged and are in results.json)"
    ]
    for i, run, error in broken[:INTERNAL_ERRORS_SHOWN]:
        lines.append(f"run {run}: {error} (its traceback: records[{i}].internal_error in results.json)")
    if len(broken) > INTERNAL_ERRORS_SHOWN:
        lines.append(f"... and {len(broken) - INTERNAL_ERRORS_SHOWN} more run(s) with an internal error")
    return lines


def skipped_lines(skipped: Mapping[str, str]) -> list[str]:
    """One line per reason: which methods did not run and why."""
    methods: dict[str, list[str]] = {}
    for method, why in skipped.items():
        methods.setdefault(why, []).append(method)
    return [f"skipped {', '.join(names)}: {why}" for why, names in methods.items()]


def markdown(results: Results, tables: Sequence[TextTable], plots: Sequence[str]) -> str:
    """The whole ``report.md``."""
    parts = ["# robotool evaluation", "", *preamble(results), ""]
    parts += [_markdown_table(t) + "\n" for t in tables]
    parts += [f"![{name}]({name})" for name in plots]
    parts += _pictures_section(results.pictures)
    return "\n".join(parts).rstrip() + "\n"


def _pictures_section(pictures: Sequence[Picture]) -> list[str]:
    """Per task: its scene, then the end state of one failed world per failure class."""
    if not pictures:
        return []
    lines = [
        "",
        "## Pictures",
        "",
        "Each task's scene, then the end of one failed world per failure class "
        "(simulated again from its program and seed).",
    ]
    by_task: dict[str, list[Picture]] = {}
    for picture in pictures:
        by_task.setdefault(picture.task, []).append(picture)
    for task, shown in by_task.items():
        lines += ["", f"### {markdown_text(task)}", ""]
        for picture in shown:
            lines += [f"![{markdown_text(picture.caption)}]({picture.file})", ""]
    return lines


def print_tables(results: Results, tables: Sequence[TextTable], console: Console) -> None:
    """The preamble and every table, reference rows dimmed."""
    for line in preamble(results):
        console.print(line, markup=False, highlight=False)
    for t in tables:
        table = Table(title=one_line(t.title), caption=one_line(t.note) or None)
        for i, column in enumerate(t.columns):
            header = column if i == 0 else column.replace("_", "\n")  # task names wrap at underscores
            table.add_column(header, justify="left" if i == 0 else "right", no_wrap=i == 0)
        for i, row in enumerate(t.rows):
            cells = [escape(one_line(cell)) for cell in row]
            table.add_row(*cells, style="dim" if i >= len(t.rows) - t.reference else None)
        console.print(table)
