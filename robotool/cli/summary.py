"""Readable console summaries of a :class:`~robotool.solution.Solution`."""

from __future__ import annotations

from rich import box
from rich.console import Console, RenderableType
from rich.markup import escape
from rich.padding import Padding
from rich.panel import Panel
from rich.syntax import Syntax
from rich.table import Table
from rich.text import Text

from robotool.execute import RunReport
from robotool.rollout import Rollout, notable_distances
from robotool.safe_text import CUT, console_markup, console_plain, mask_addresses, terminal_safe
from robotool.sandbox import layers_in_use
from robotool.solution import Solution
from robotool.verify import world_failure


def _labelled(label: str, markup: str) -> RenderableType:
    """``label`` then ``markup`` (text from a program or an LM, escaped): its lines, wrapped ones included,
    stay in a column right of the label, so none can pose as one of the report's own (its verdict)."""
    grid = Table.grid()
    grid.add_column(no_wrap=True)
    grid.add_column(overflow="fold")
    grid.add_row(label, markup)
    return grid


def _framed(title: str, text: str) -> RenderableType:
    """What a program printed or raised, in a frame: every line, wrapped ones included, starts with its
    border, so none can pose as one of the report's own (its verdict)."""
    shown = Text(console_plain(mask_addresses(text)), overflow="fold")
    panel = Panel(shown, title=title, title_align="left", box=box.SQUARE, expand=False, border_style="dim")
    return Padding(panel, (0, 0, 0, 2))


def print_sandbox_layers(console: Console) -> None:
    """Which OS layers confined the generated programs of this run; a loud warning if seccomp was missing."""
    layers = layers_in_use()
    if layers is None:
        return
    console.print(layers.summary(), markup=False, highlight=False)
    warning = layers.warning()
    if warning:
        console.print(f"[bold red]WARNING:[/] {escape(warning)}")


def print_solution(solution: Solution, console: Console) -> None:
    """Key concepts, the chosen plan, every candidate's outcome, and the best code
    (:func:`print_solution_verdict` prints the verdict, last)."""
    for note in solution.notes:
        console.print(_labelled("[yellow]note:[/] ", console_markup(note)))
    stages = solution.stages
    if stages.key_concepts:
        table = Table(title="Key concepts")
        for column in ("concept", "value", "limit", "met"):
            table.add_column(column)
        for c in stages.key_concepts:
            table.add_row(
                console_markup(c.name),
                console_markup(f"{c.value:g} {c.unit}"),
                console_markup(f"{c.limit:g} ({c.limit_name})"),
                "yes" if c.satisfied else "[red]no[/]",
            )
        console.print(table)
    if stages.abstract_plan:
        console.print(_labelled("[bold]Plan:[/] ", console_markup(stages.abstract_plan)))
    for i, step in enumerate(stages.steps or [], start=1):
        objects = f" [{', '.join(step.objects)}]" if step.objects else ""
        console.print(_labelled(f"  {i}. ", console_markup(f"{step.skill}{objects}: {step.intent}")))
    table = Table(title=f"Candidates ({solution.method})")
    for column in ("#", "success", "objects", "calls", "outcome"):
        table.add_column(column, overflow="fold")
    for candidate in solution.candidates:
        ran = bool(candidate.rollouts)
        failure = str(candidate.failure) if candidate.failure else "solved in every world"
        table.add_row(
            str(candidate.index) + (" *" if candidate.index == solution.best else ""),
            f"{candidate.success_rate:.0%}" if ran else "-",
            f"{candidate.objects_touched:.1f}" if ran else "-",
            f"{candidate.skill_calls:.1f}" if ran else "-",
            console_markup("; ".join([failure, *candidate.notes])),
        )
    console.print(table if solution.candidates else f"Candidates ({solution.method}): none was made (see the notes)")
    print_repairs(solution, console)
    if solution.code:
        # numbered lines: a long line of the model's code wraps right of the numbers, never at column 0
        console.print(Syntax(terminal_safe(solution.code), "python", line_numbers=True, word_wrap=True))
    if solution.cached_replies:
        console.print(
            f"[yellow]note:[/] {solution.cached_replies} of {len(solution.lm_calls)} LM replies came from "
            "DSPy's cache, not the model (--no-cache asks the model again)"
        )
    print_sandbox_layers(console)


def print_solution_verdict(solution: Solution, console: Console) -> None:
    """The last line of ``solve``: solved or not (as the exit status says), the success rate and the cost; a best
    program that failed in some of its perturbed worlds is said to be solved in those it did only, with how many."""
    verdict = "[green]solved[/]" if solution.success else "[red]not solved[/]"
    rate = f"best success rate {solution.success_rate:.0%}"
    if solution.success and solution.success_rate < 1.0 and solution.best is not None:
        rollouts = solution.candidates[solution.best].rollouts
        verdict = "[yellow]solved in some worlds only[/]"
        rate += f" ({sum(r.success for r in rollouts)} of {len(rollouts)} perturbed worlds: not a plan to trust as is)"
    tokens = sum(u.prompt_tokens + u.completion_tokens for u in solution.usage.values())
    calls = f" in {len(solution.lm_calls)} LM call(s)" if solution.lm_calls else ""
    console.print(f"{verdict}: {rate}; {tokens} LM tokens{calls}; {solution.timings.get('total', 0.0):.1f} s")


def print_repairs(solution: Solution, console: Console) -> None:
    """Each repair round: which failure was shown what, what the model changed, and how the repair did."""
    for record in solution.repairs:
        tokens = record.prompt_tokens + record.completion_tokens
        table = Table(title=f"Repair round {record.round} ({tokens} LM tokens)")
        for column in ("repaired", "shown", "changed", "result"):
            table.add_column(column, overflow="fold")
        for attempt in record.attempts:
            shown = attempt.shown
            evidence = [f"{shown.failed_worlds}/{shown.worlds} worlds failed"]
            notable = next((c for c in shown.calls if c.outcome != "done" or notable_distances(c.measured)), None)
            if shown.error:
                evidence.append(shown.error)
            elif notable is not None:
                values = notable_distances(notable.measured) or notable.measured
                measured = ", ".join(f"{k} {v:.3g}" for k, v in values.items())
                what = f"call {notable.number} {notable.skill} {notable.outcome}"
                evidence.append(what + (f" ({measured})" if measured else ""))
            if shown.conditions_missed:
                evidence.append("missed " + ", ".join(shown.conditions_missed))
            result = f"{attempt.success_rate:.0%}" + (f": {attempt.failure}" if attempt.failure else "")
            changed = ", ".join(attempt.changed) or "nothing"
            table.add_row(
                f"{attempt.source} -> {attempt.candidate}",
                console_markup("; ".join(evidence) + f"; scope {attempt.scope}"),
                console_markup(changed + (f"; {attempt.diagnosis}" if attempt.diagnosis else "")),
                console_markup(result),
            )
        console.print(table)


def _format_args(args: list[object]) -> str:
    parts = []
    for a in args:
        if isinstance(a, list | tuple):
            parts.append("[" + ", ".join(f"{v:.3f}" if isinstance(v, float) else str(v) for v in a) + "]")
        else:
            parts.append(repr(a))
    return ", ".join(parts)


def print_trace(rollout: Rollout, console: Console) -> None:
    """One world's skill calls: arguments, outcome, duration, reasons and measured values."""
    status = "[green]success[/]" if rollout.success else "[red]failed[/]"
    table = Table(title=f"World {rollout.world} ({status}, {rollout.sim_time:.2f} s simulated)")
    for column in ("#", "call", "outcome", "time (s)", "reason / measured"):
        table.add_column(column, overflow="fold")
    for i, call in enumerate(rollout.calls, start=1):
        outcome = call.outcome if call.outcome == "done" else f"[red]{call.outcome}[/]"
        measured = "" if call.outcome == "done" else ", ".join(f"{k} {v:.3g}" for k, v in call.measured.items())
        details = " ".join(part for part in (call.reason or "", f"({measured})" if measured else "") if part)
        table.add_row(
            str(i),
            console_markup(f"{call.skill}({_format_args(call.args)})"),
            outcome,
            f"{call.ended - call.started:.2f}",
            console_markup(details),
        )
    console.print(table)
    conditions = ", ".join(
        f"{console_markup(name)} {'[green]yes[/]' if ok else '[red]no[/]'}" for name, ok in rollout.conditions.items()
    )
    touched = console_markup(", ".join(rollout.touched)) or "nothing"
    console.print(f"  goal: {conditions or 'no conditions'}; touched: {touched}")
    if rollout.error:
        console.print(_framed("[red]error[/]", rollout.error))
    if rollout.output:
        console.print(_framed("printed by the program", output_shown(rollout.output.strip())))


OUTPUT_SHOWN = 500  # characters of a program's output a summary shows


def output_shown(text: str) -> str:
    """The first :data:`OUTPUT_SHOWN` characters of what a program printed, a cut marked with how much is left out
    (the run's JSON report keeps all of it)."""
    if len(text) <= OUTPUT_SHOWN:
        return text
    return f"{text[:OUTPUT_SHOWN]}{CUT} ({len(text) - OUTPUT_SHOWN} more characters, in the JSON report)"


def print_run(report: RunReport, console: Console, *, traces: int = 3) -> None:
    """A run's summary over worlds, then the traces of the first world and of failed worlds
    (:func:`print_run_verdict` prints the verdict, last)."""
    title = f"{console_markup(report.task)}: {report.worlds} world(s), seed {report.seed}, {report.backend} backend"
    table = Table(title=title)
    for column in ("world", "success", "sim time (s)", "calls", "touched", "why it failed"):
        table.add_column(column, overflow="fold")
    for r in report.rollouts:
        table.add_row(
            str(r.world),
            "yes" if r.success else "[red]no[/]",
            f"{r.sim_time:.2f}",
            str(len(r.calls)),
            str(len(r.touched)),
            console_markup(world_failure(r) or ""),
        )
    console.print(table)
    shown = [report.rollouts[0], *[r for r in report.rollouts[1:] if not r.success]][:traces]
    for rollout in shown:
        print_trace(rollout, console)
    print_sandbox_layers(console)


def print_run_verdict(report: RunReport, console: Console) -> None:
    """The last line of ``run``: whether every world succeeded (as the exit status says) and the success rate."""
    verdict = "[green]every world succeeded[/]" if report.success else "[red]some worlds failed[/]"
    console.print(f"{verdict}: success rate {report.success_rate:.0%}")
