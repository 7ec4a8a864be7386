"""Metrics over hand-made records, task selection, seeds, and the journal's durability rules."""

from __future__ import annotations

from pathlib import Path

import pytest

from robotool import tasks
from robotool.eval.config import EvalError
from robotool.eval.failure_classes import FailureClass
from robotool.eval.grading import ConceptGrade
from robotool.eval.instances import DEFAULT_SEEDS, parse_seeds, select
from robotool.eval.journal import JOURNAL, Journal
from robotool.eval.metrics import RepairComparison, summarize
from robotool.eval.plots import write_plots
from robotool.eval.records import RunKey, RunRecord, WorldResult
from robotool.eval.tables import all_tables
from robotool.solution import TokenUsage


def record(
    task: str,
    method: str,
    run: int,
    worlds: list[tuple[FailureClass | None, bool]],
    *,
    seed: int | None = None,
    needs_tool: bool = True,
    correct: bool | None = None,
) -> RunRecord:
    """A hand-made record: one (failure class, used a tool) pair per world."""
    results = [
        WorldResult(world=i, seed=i, success=c is None, failure_class=c, tools_used=["t"] if used else [])
        for i, (c, used) in enumerate(worlds)
    ]
    return RunRecord(
        key=RunKey(task=task, seed=seed, method=method, run=run),
        embodiment="arm",
        needs_tool=needs_tool,
        world_seed=0,
        success_rate=sum(w.success for w in results) / len(results) if results else 0.0,
        worlds=results,
        concepts=ConceptGrade(correct=correct),
        wall_s=2.0,
        usage={"coder": TokenUsage(prompt_tokens=100, completion_tokens=10)},
    )


RECORDS = [
    record("milk_reaching", "robotool", 0, [(None, True), ("numerical", True)], correct=True),
    record("milk_reaching", "robotool", 1, [], correct=False),  # nothing ran
    record("milk_reaching_near", "robotool", 0, [("tool_use", True), (None, False)], needs_tool=False),
    record("sofa_traversing", "robotool", 0, [(None, True)], seed=3),
    record("milk_reaching", "coder", 0, [("logical", False)]),
]


def test_summary_means_breakdown_and_discrimination() -> None:
    summary = summarize(RECORDS, ["robotool", "no_analyzer", "coder"])
    assert summary.methods == ["robotool", "coder"]
    robotool = summary.success[0]
    assert robotool.cells["milk_reaching"].value == pytest.approx(0.25) and robotool.cells["milk_reaching"].n == 2
    assert summary.generated[0].cells["sofa_traversing"].value == 1.0
    shares = summary.errors[0].shares
    assert sum(shares.values()) == pytest.approx(1.0)
    assert shares["invalid"] == pytest.approx(0.25) and shares["numerical"] == pytest.approx(0.125)
    assert shares["success"] == pytest.approx((0.5 + 0 + 0.5 + 1) / 4)
    d = summary.discrimination[0]
    assert d.needed.value == pytest.approx(1.0) and d.needed.n == 2  # the run that ran nothing is left out
    assert d.not_needed.value == pytest.approx(0.5)
    assert summary.concepts[0].cells["milk_reaching"].value == pytest.approx(0.5)
    assert summary.cost[0].prompt_tokens == 100 and summary.cost[0].total_wall_s == 8.0


def test_tables_show_measured_rows_and_paper_references() -> None:
    tables = {t.title: t for t in all_tables(summarize(RECORDS, ["robotool", "coder"]))}
    table1 = tables["Success rate (paper Table 1)"]
    assert table1.columns == ["method", "milk_reaching", "average"]
    assert table1.rows[0] == ["RoboTool", "0.25", "0.25"]
    assert table1.rows[-table1.reference] == ["paper: RoboTool", "0.90", "0.90"]
    table2 = tables["Key-concept accuracy (paper Table 2)"]
    assert table2.columns == ["task", "RoboTool", "paper: RoboTool"]  # tasks as rows, as in the paper
    assert table2.rows == [["milk_reaching", "0.50", "1.00"]]


@pytest.mark.parametrize(("text", "seeds"), [("0-3", (0, 1, 2, 3)), ("7", (7,)), ("1,4,2-3", (1, 4, 2, 3))])
def test_parse_seeds(text: str, seeds: tuple[int, ...]) -> None:
    assert parse_seeds(text) == seeds


@pytest.mark.parametrize("text", ["a-b", "3-1", "-2", ""])
def test_parse_seeds_rejects(text: str) -> None:
    with pytest.raises(ValueError):
        parse_seeds(text)


def test_select_defaults_and_families() -> None:
    chosen, _ = select(None, None, None)
    builtins = [i for i in chosen if i.seed is None]
    assert [i.name for i in builtins][:2] == ["milk_reaching", "can_grasping"]  # the paper's order first
    assert len(builtins) == len(tasks.names())
    generated = [i for i in chosen if i.seed is not None]
    assert generated and {i.seed for i in generated} <= set(DEFAULT_SEEDS)
    only, _ = select(["sofa_traversing"], None, None)
    assert [i.label for i in only] == ["sofa_traversing"] and only[0].tools == frozenset({"surfboard"})
    family, _ = select(None, ["sofa_traversing"], [0, 2])
    assert [i.label for i in family] == ["sofa_traversing#0", "sofa_traversing#2"]
    with pytest.raises(EvalError, match="unknown task family"):
        select(None, ["juggling"], None)


def test_two_different_tasks_of_one_name_are_refused_and_one_given_twice_runs_once(tmp_path: Path) -> None:
    """Found by an adversarial run: a task file named like a built-in task (milk_reaching_near renamed
    milk_reaching) was pooled with it in one column of the paper's table, and its scene picture was written over
    the other's. Alone, an edited copy of a built-in task runs under its name, and the notes say so."""
    renamed = tmp_path / "renamed.yaml"
    renamed.write_text(tasks.source("milk_reaching_near").replace("name: milk_reaching_near", "name: milk_reaching"))
    with pytest.raises(EvalError, match="two different tasks are named 'milk_reaching'"):
        select([str(renamed), "milk_reaching"], None, None)
    _, notes = select([str(renamed)], None, None)
    assert notes == [
        f"{renamed} is an edited copy of the built-in task 'milk_reaching': its runs are shown under that name, "
        "beside the paper's published numbers"
    ]
    other = tmp_path / "other.yaml"
    other.write_text(tasks.source("milk_reaching_near").replace("name: milk_reaching_near", "name: my_milk"))
    moved = tmp_path / "moved.yaml"
    moved.write_text(tasks.source("milk_reaching").replace("name: milk_reaching", "name: my_milk"))
    with pytest.raises(EvalError, match="two different tasks are named 'my_milk'"):
        select([str(other), str(moved)], None, None)
    copy = tmp_path / "copy.yaml"
    copy.write_text(tasks.source("milk_reaching"))  # the built-in task itself, from a file: the same task
    chosen, notes = select(["milk_reaching", str(copy)], None, None)
    assert [i.name for i in chosen] == ["milk_reaching"] and notes == ["1 task(s) given more than once, evaluated once"]


def test_journal_cuts_a_torn_line_and_never_duplicates(tmp_path: Path) -> None:
    journal = Journal(tmp_path)
    assert journal.append(RECORDS[0]) and not journal.append(RECORDS[0])
    with (tmp_path / JOURNAL).open("a") as f:
        f.write(RECORDS[1].model_dump_json()[:40])
    reopened = Journal(tmp_path)
    assert list(reopened.records) == [RECORDS[0].key.id]
    assert reopened.append(RECORDS[1])
    assert len((tmp_path / JOURNAL).read_text().splitlines()) == 2
    assert list(Journal(tmp_path).records) == [RECORDS[0].key.id, RECORDS[1].key.id]


def test_journal_refuses_a_corrupt_middle_line(tmp_path: Path) -> None:
    (tmp_path / JOURNAL).write_text("not json\n" + RECORDS[0].model_dump_json() + "\n")
    with pytest.raises(EvalError, match="line 1"):
        Journal(tmp_path)


def test_only_an_analyzer_is_graded_on_key_concepts() -> None:
    """The search planner copies the ground-truth concepts; grading it would always give 1.0."""
    from robotool.eval.instances import builtin
    from robotool.eval.judge import judge
    from robotool.solution import Solution, StageOutputs
    from robotool.task.concepts import key_concepts

    instance = builtin("sofa_traversing")
    truth = key_concepts(instance.task)
    solution = Solution(task="sofa_traversing", method="search", stages=StageOutputs(key_concepts=truth))
    searched = judge(instance, RunKey(task="sofa_traversing", method="search", run=0), 0, solution, 0.1)
    analyzed = judge(instance, RunKey(task="sofa_traversing", method="robotool", run=0), 0, solution, 0.1)
    assert searched.concepts.correct is None
    assert analyzed.concepts.correct is True


def test_every_run_of_a_method_with_an_analyzer_is_graded() -> None:
    """A run whose Analyzer gave no usable reply, or whose method raised, predicted nothing: it counts as wrong."""
    from robotool.eval.instances import builtin
    from robotool.eval.judge import crashed, judge
    from robotool.solution import Solution, StageOutputs

    instance = builtin("sofa_traversing")
    no_concepts = Solution(task="sofa_traversing", method="robotool", stages=StageOutputs(key_concepts=None))
    key = RunKey(task="sofa_traversing", method="robotool", run=0)
    assert judge(instance, key, 0, no_concepts, 0.1).concepts.correct is False
    assert crashed(instance, key, 0, RuntimeError("boom"), 0.1).concepts.correct is False
    coder = RunKey(task="sofa_traversing", method="coder", run=0)
    assert crashed(instance, coder, 0, RuntimeError("boom"), 0.1).concepts.correct is None
    records = [judge(instance, key, 0, no_concepts, 0.1)]
    assert summarize(records, ["robotool"]).concepts[0].cells["sofa_traversing"].value == 0.0


def test_a_run_with_an_internal_error_is_left_out_of_every_table_but_the_cost() -> None:
    """A bug in robotool (a controller or the method raised) is neither a success nor a failure: the tables leave
    the run out of their means and say how many runs they left out; the cost still counts it."""
    from robotool.bugs import InternalError

    broken = record("milk_reaching", "robotool", 2, [("invalid", False)]).model_copy(
        update={"internal_error": InternalError(where="the arm controller, in open_gripper, world 0", reason="E: x")}
    )
    summary = summarize([*RECORDS, broken], ["robotool", "coder"])
    assert summary.internal_errors == {"robotool": 1}
    assert summary.success == summarize(RECORDS, ["robotool", "coder"]).success  # the denominator leaves it out
    assert summary.errors[0].runs == 4 and summary.cost[0].runs == 5
    tables = {t.title: t for t in all_tables(summary)}
    assert tables["Success rate (paper Table 1)"].rows[0] == ["RoboTool", "0.25", "0.25"]
    for title in ("Success rate (paper Table 1)", "Outcomes and error breakdown (share of runs)"):
        assert "1 run(s) with an internal error (a bug in robotool, not a failure) left out." in tables[title].note
    only_broken = summarize([broken], ["robotool"])
    assert only_broken.success == [] and only_broken.errors == [] and only_broken.internal_errors == {"robotool": 1}


def test_plots_show_a_method_name_with_its_controls_and_mathtext_escaped(tmp_path: Path, monkeypatch) -> None:
    """Found by an adversarial run: a compiled program's file name (its method's name) reached the plots' legends and
    tick labels raw, so ``$a$`` was drawn as mathtext and an ESC as a missing glyph."""
    import matplotlib.figure
    import matplotlib.text

    hostile = "x\x1b[31m $a$ \u202eevil.json"
    records = [r.model_copy(update={"key": r.key.model_copy(update={"method": hostile})}) for r in RECORDS]
    summary = summarize(records, [hostile])
    comparison = RepairComparison(
        method=hostile, runs=1, sampled=1, sampled_calls=4, sampled_success=0.5, repair_calls=5, repair_success=1.0,
        plain=2, plain_calls=8, plain_success=0.5,
    )  # fmt: skip
    summary = summary.model_copy(update={"repair": [comparison]})
    drawn: list[str] = []
    savefig = matplotlib.figure.Figure.savefig

    def keep_texts(fig: matplotlib.figure.Figure, *args, **kwargs) -> None:
        drawn.extend(t.get_text() for t in fig.findobj(matplotlib.text.Text))
        savefig(fig, *args, **kwargs)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", keep_texts)
    assert write_plots(summary, tmp_path) == ["success.png", "errors.png", "discrimination.png", "repair.png"]
    named = [text for text in drawn if "evil" in text]
    assert len(named) >= 5, drawn  # the legends of success and repair (2), the ticks of errors and discrimination
    assert all("\x1b" not in text and "\u202e" not in text and "$a" not in text.replace("\\$", "") for text in named)
    assert all("\\x1b[31m \\$a\\$ \\u202eevil.json" in text for text in named), named
