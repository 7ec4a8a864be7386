"""The evaluator serves only real, current results: runs keyed by their inputs' content, resuming said out
loud, folders with another request refused, and runs the LM could not attempt never journalled."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pytest
from fixtures.standin_solution import standin_solution
from rich.console import Console

from robotool import tasks
from robotool.cli.eval_command import main
from robotool.errors import LMUnavailableError
from robotool.eval import EvalConfig, EvalError, RunsNotAttempted, Settings, evaluate
from robotool.eval import solvers as eval_solvers
from robotool.eval.journal import JOURNAL
from robotool.solution import Solution
from robotool.task.task_model import Task


class Counting:
    """TEST FIXTURE: a solver that records which tasks it was asked to solve and answers with a stand-in."""

    def __init__(self) -> None:
        self.calls: list[str] = []

    def __call__(self, task: Task, *, seed: int, run: int) -> Solution:
        self.calls.append(task.name)
        return standin_solution(task, seed=seed, run=run)


def no_key(task: Task, *, seed: int, run: int) -> Solution:
    """TEST FIXTURE: a solver whose language model cannot be reached without a key."""
    raise LMUnavailableError("no_key", "no API key: set OPENAI_API_KEY or pass --api-key-env")


def _config(out: Path, **fields: object) -> EvalConfig:
    return EvalConfig(out=out, settings=Settings(worlds=1), **fields)  # type: ignore[arg-type]


def _console() -> Console:
    return Console(file=io.StringIO(), width=200)


def _printed(console: Console) -> str:
    return console.file.getvalue()  # type: ignore[attr-defined]


def _journal_lines(out: Path) -> list[dict[str, object]]:
    path = out / JOURNAL
    return [json.loads(line) for line in path.read_text().splitlines()] if path.exists() else []


def test_runs_the_lm_could_not_attempt_are_not_journalled_and_a_rerun_attempts_them(tmp_path: Path) -> None:
    out = tmp_path / "out"
    config = _config(out, tasks=["sofa_traversing", "milk_reaching"], methods=["robotool", "search"])
    search = Counting()
    with pytest.raises(RunsNotAttempted, match=r"2 of 4 run\(s\) could not be attempted: no API key.*\(no_key\)"):
        evaluate(config, solvers={"robotool": no_key, "search": search}, console=_console())
    assert sorted(line["key"]["method"] for line in _journal_lines(out)) == ["search", "search"]  # type: ignore[index]
    assert not (out / "report.md").exists()  # no report that leaves out runs it was asked for

    with_key, search_again = Counting(), Counting()
    console = _console()
    results = evaluate(config, solvers={"robotool": with_key, "search": search_again}, console=console)
    assert sorted(with_key.calls) == ["milk_reaching", "sofa_traversing"] and search_again.calls == []
    printed = _printed(console)
    assert f"reusing 2 of 4 runs from {out}" in printed
    assert "evaluating" in printed and "/robotool/" not in printed  # the bar shows progress, not a run's result
    assert [r.success_rate for r in results.records] == [1.0] * 4


def test_cli_reports_runs_the_lm_could_not_attempt_and_exits_3(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(eval_solvers, "lm_solver", lambda method, lm, settings: no_key)
    argv = [
        "--lm",
        "openai/some-model",
        "--tasks",
        "sofa_traversing",
        "--methods",
        "robotool",
        "--out",
        str(tmp_path / "out"),
    ]
    assert main(argv) == 3
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: 1 of 1 run(s) could not be attempted: no API key") and "\n" not in err
    assert _journal_lines(tmp_path / "out") == []

    answered = Counting()
    monkeypatch.setattr(eval_solvers, "lm_solver", lambda method, lm, settings: answered)
    assert main(argv) == 0
    assert answered.calls == ["sofa_traversing"]


def test_an_edited_task_file_is_run_again(tmp_path: Path) -> None:
    task_file = tmp_path / "milk.yaml"
    task_file.write_text(tasks.source("milk_reaching_near"))
    out = tmp_path / "out"
    config = _config(out, tasks=[str(task_file)], methods=["search"])
    solver = Counting()
    evaluate(config, solvers={"search": solver}, console=_console())
    evaluate(config, solvers={"search": solver}, console=_console())
    assert solver.calls == ["milk_reaching_near"]  # unchanged: reused

    task_file.write_text(task_file.read_text().replace("mass: 0.25", "mass: 0.3"))
    console = _console()
    results = evaluate(config, solvers={"search": solver}, console=console)
    assert solver.calls == ["milk_reaching_near", "milk_reaching_near"]  # edited: run again
    assert f"reusing 0 of 1 runs from {out}; 1 other run(s)" in _printed(console)
    assert len(results.records) == 1 and results.records[0].key.inputs != _journal_lines(out)[0]["key"]["inputs"]  # type: ignore[index]


def test_other_settings_change_the_run_identity(tmp_path: Path) -> None:
    solver = Counting()
    evaluate(
        _config(tmp_path / "a", tasks=["sofa_traversing"], methods=["search"]),
        solvers={"search": solver},
        console=_console(),
    )
    evaluate(
        EvalConfig(out=tmp_path / "b", tasks=["sofa_traversing"], methods=["search"], settings=Settings(worlds=2)),
        solvers={"search": solver},
        console=_console(),
    )
    first, second = (_journal_lines(tmp_path / d)[0]["key"] for d in ("a", "b"))
    assert first["inputs"] != second["inputs"]  # type: ignore[index]


def test_a_smaller_second_eval_is_refused_then_merges_visibly_with_resume(tmp_path: Path) -> None:
    out = tmp_path / "out"
    solver = Counting()
    evaluate(
        _config(out, tasks=["sofa_traversing", "milk_reaching"], methods=["search"]),
        solvers={"search": solver},
        console=_console(),
    )
    smaller = _config(out, tasks=["milk_reaching"], methods=["search"])
    with pytest.raises(
        EvalError,
        match=r"other settings \(tasks: sofa_traversing,milk_reaching -> milk_reaching\); "
        r"pass --resume",
    ):
        evaluate(smaller, solvers={"search": solver}, console=_console())

    console = _console()
    results = evaluate(smaller.model_copy(update={"resume": True}), solvers={"search": solver}, console=console)
    assert solver.calls == ["sofa_traversing", "milk_reaching"]  # nothing run again
    assert (
        f"reusing 1 of 1 runs from {out}; 1 other run(s) in its journal (other inputs or settings) are not in "
        "this report"
    ) in _printed(console)
    assert [r.key.task for r in results.records] == ["milk_reaching"]
    saved = json.loads((out / "results.json").read_text())
    assert [r["key"]["task"] for r in saved["records"]] == ["milk_reaching"]
    assert "sofa_traversing" not in (out / "report.md").read_text()


def test_cli_refuses_a_folder_with_other_settings_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(eval_solvers, "planner_solver", lambda tools, settings: standin_solution)
    monkeypatch.setenv("COLUMNS", "400")  # the folder's name stays on one line, however long the temp path
    out = str(tmp_path / "out")
    assert main(["--tasks", "sofa_traversing", "--methods", "search", "--worlds", "1", "--out", out]) == 0
    capsys.readouterr()
    assert main(["--tasks", "sofa_traversing", "--methods", "search", "--worlds", "2", "--out", out]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (
        f"error: {out} holds an evaluation with other settings (worlds: 1 -> 2); pass --resume to reuse "
        "its matching runs and add these, or choose another --out"
    )
    assert main(["--tasks", "sofa_traversing", "--methods", "search", "--worlds", "2", "--out", out, "--resume"]) == 0
    assert f"reusing 0 of 1 runs from {out}" in capsys.readouterr().out


def test_a_folder_written_before_run_identity_is_refused_unless_resumed(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "settings.json").write_text(Settings(worlds=1).model_dump_json())  # the older settings-only file
    old = {"key": {"task": "sofa_traversing", "method": "search", "run": 0}, "embodiment": "quadruped",
           "needs_tool": True, "world_seed": 0, "success_rate": 0.0, "failure_class": "invalid"}  # fmt: skip
    (out / JOURNAL).write_text(json.dumps(old) + "\n")
    config = _config(out, tasks=["sofa_traversing"], methods=["search"])
    with pytest.raises(EvalError, match="holds results of an unknown request; pass --resume"):
        evaluate(config, solvers={"search": Counting()}, console=_console())
    solver = Counting()
    results = evaluate(config.model_copy(update={"resume": True}), solvers={"search": solver}, console=_console())
    assert (
        solver.calls == ["sofa_traversing"] and results.records[0].success_rate == 1.0
    )  # the old record is not reused
