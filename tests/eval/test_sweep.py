"""The evaluator end to end: scripted-LM methods, stand-in planner methods, output folder, CLI, resuming."""

from __future__ import annotations

import io
import json
import logging
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import dspy
import numpy as np
import pytest
from fixtures.reference import REFERENCE, program
from fixtures.scripted_lm import GRASP_DIRECTLY, arm_script, scripted_lm
from fixtures.standin_solution import standin_solution
from rich.console import Console

from robotool.cli.eval_command import main
from robotool.eval import EvalConfig, EvalError, Settings, evaluate
from robotool.eval.journal import JOURNAL
from robotool.eval.report import internal_error_lines
from robotool.eval.solvers import METHODS, planner_missing
from robotool.robots.arm.arm_controller import ArmController
from robotool.safe_text import markdown_text
from robotool.solution import Candidate, Proposal, Solution
from robotool.task.task_model import Task
from robotool.verify import select

TESTS = Path(__file__).parents[1]


STANDINS = {"search": standin_solution, "no_tool": standin_solution}


def _config(tmp_path: Path, **fields: object) -> EvalConfig:
    return EvalConfig(out=tmp_path / "out", settings=Settings(worlds=1), **fields)  # type: ignore[arg-type]


def _quiet() -> Console:
    return Console(file=io.StringIO(), width=200)


def test_every_method_produces_rows_with_a_scripted_lm(tmp_path: Path) -> None:
    lm, engine = scripted_lm(arm_script([GRASP_DIRECTLY]))
    config = _config(tmp_path, tasks=["milk_reaching_near"], methods=list(METHODS))
    console = _quiet()
    with dspy.context(adapter=dspy.ChatAdapter(use_json_adapter_fallback=False)):
        results = evaluate(config, lm=lm, solvers=STANDINS, console=console)
    printed = console.file.getvalue()  # type: ignore[attr-defined]
    assert "Success rate on other tasks" in printed and "Discriminative tool use" in printed
    assert [r.key.method for r in results.records] == list(METHODS)
    by_method = {r.key.method: r for r in results.records}
    assert all(r.success_rate == 1.0 and r.failure_class is None for r in results.records), [
        (r.key.method, r.candidate_failures, r.error) for r in results.records]
    assert by_method["robotool"].concepts.correct is True  # scripted analyzer: milk inside the workspace
    assert by_method["coder"].concepts.correct is None  # no Analyzer: not graded
    assert by_method["robotool"].tokens > 0 and by_method["search"].tokens == 0
    assert by_method["robotool"].worlds[0].tools_used == []
    assert engine.calls["coder"] == 5

    folder = tmp_path / "out"
    assert {"results.json", "report.md", "journal.jsonl", "settings.json", "success.png", "errors.png",
            "discrimination.png"} <= {p.name for p in folder.iterdir()}
    report = (folder / "report.md").read_text()
    for method in METHODS.values():
        assert f"| {method.label} | 1.00 |" in report
    assert "paper:" not in report  # the paper has no milk_reaching_near: no reference rows
    saved = json.loads((folder / "results.json").read_text())
    assert len(saved["records"]) == len(METHODS) and saved["config"]["settings"]["lm"] == "scripted/fixture"


def test_default_run_without_lm_skips_lm_methods_and_says_why(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.delenv("ROBOTOOL_LM", raising=False)
    results = evaluate(_config(tmp_path, tasks=["sofa_traversing", "milk_reaching"]), solvers=STANDINS,
                       console=_quiet())
    assert set(results.skipped) == {m for m, info in METHODS.items() if info.uses_lm}
    assert all("no language model" in why for why in results.skipped.values())
    assert {r.key.method for r in results.records} == {"search", "no_tool"}
    report = (tmp_path / "out" / "report.md").read_text()
    assert "skipped robotool, no_analyzer, no_calculator, planner_coder, coder: no language model" in report
    assert "| milk_reaching | sofa_traversing | average |" in report  # the paper's column order
    assert "| paper: RoboTool | 0.90 | 1.00 | 0.95 |" in report  # reference rows under the tasks run
    assert "| paper: Coder | 0.00 | 0.00 | 0.00 |" in report


def test_asking_for_an_lm_method_without_an_lm_is_an_error(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.delenv("ROBOTOOL_LM", raising=False)
    with pytest.raises(EvalError, match="cannot run robotool: no language model"):
        evaluate(_config(tmp_path, tasks=["sofa_traversing"], methods=["robotool"]), console=_quiet())


def test_other_settings_do_not_mix_into_a_results_folder(tmp_path: Path) -> None:
    evaluate(_config(tmp_path, tasks=["sofa_traversing"]), solvers=STANDINS, console=_quiet())
    other = _config(tmp_path, tasks=["sofa_traversing"]).model_copy(update={"settings": Settings(worlds=2)})
    with pytest.raises(EvalError, match="other settings"):
        evaluate(other, solvers=STANDINS, console=_quiet())


@pytest.mark.skipif(planner_missing() is not None, reason="the search planner is not in this checkout")
def test_command_line_runs_the_real_planner(tmp_path: Path, capsys) -> None:
    argv = ["--tasks", "milk_reaching_near", "--methods", "search", "no_tool", "--worlds", "1", "--out", str(tmp_path)]
    assert main(argv) == 0
    assert "Success rate on other tasks" in capsys.readouterr().out
    records = json.loads((tmp_path / "results.json").read_text())["records"]
    assert [(r["key"]["method"], r["success_rate"]) for r in records] == [("search", 1.0), ("no_tool", 1.0)]


@pytest.mark.parametrize("argv", [
    ["--runs", "0"], ["--methods", "magic"], ["--seeds", "5-2"], ["--tasks", "no_such_task"],
    ["--methods", "coder"], ["--seed", "-1"],
])
def test_bad_arguments_give_one_line_and_status_2(argv: list[str], tmp_path: Path, capsys, monkeypatch) -> None:
    monkeypatch.delenv("ROBOTOOL_LM", raising=False)
    try:
        status = main([*argv, "--out", str(tmp_path)])
    except SystemExit as e:
        status = e.code
    err = capsys.readouterr().err.strip()
    assert status == 2
    assert err.startswith("error:") and "\n" not in err and "Traceback" not in err


class Killed(BaseException):
    """Stands in for the process being killed: not an Exception, so the evaluator does not catch it."""


def test_killed_evaluation_resumes_with_every_run_exactly_once(tmp_path: Path) -> None:
    calls: list[tuple[str, int]] = []

    def dies_on_third(task: Task, *, seed: int, run: int) -> Solution:
        if len(calls) == 2:
            raise Killed
        calls.append((task.name, run))
        return standin_solution(task, seed=seed, run=run)

    config = _config(tmp_path, tasks=["sofa_traversing", "milk_reaching"], methods=["search", "no_tool"], runs=2)
    with pytest.raises(Killed):
        evaluate(config, solvers={"search": dies_on_third, "no_tool": dies_on_third}, console=_quiet())
    journal = tmp_path / "out" / JOURNAL
    assert len(journal.read_text().splitlines()) == 2
    with journal.open("a") as f:
        f.write('{"key": {"task": "sofa_trav')  # a line torn by the kill

    def counts(task: Task, *, seed: int, run: int) -> Solution:
        calls.append((task.name, run))
        return standin_solution(task, seed=seed, run=run)

    results = evaluate(config, solvers={"search": counts, "no_tool": counts}, console=_quiet())
    assert len(calls) == 8  # 2 before the kill + 6 after: nothing redone
    ids = [r.key.id for r in results.records]
    assert len(ids) == 8 and len(set(ids)) == 8
    lines = journal.read_text().splitlines()
    assert sorted(json.loads(line)["key"]["run"] for line in lines) == [0, 0, 0, 0, 1, 1, 1, 1]
    assert len({tuple(json.loads(line)["key"].values()) for line in lines}) == 8


def test_exception_in_a_method_is_an_internal_error_of_that_run_only(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A method that raises is a bug in robotool: the run records an internal error with the traceback (logged
    too), has no failure class, and the report lists it apart; the other method's run is scored as usual."""

    def broken(task: Task, *, seed: int, run: int) -> Solution:
        raise RuntimeError("planner bug")

    config = _config(tmp_path, tasks=["sofa_traversing"])
    with caplog.at_level(logging.ERROR, logger="robotool.eval.work"):
        results = evaluate(config, solvers={"search": broken, "no_tool": standin_solution}, console=_quiet())
    (crashed,) = [r for r in results.records if r.key.method == "search"]
    assert crashed.failure_class is None and crashed.internal_error is not None
    assert crashed.internal_error.where == "the search method"
    assert crashed.internal_error.reason == "RuntimeError: planner bug"
    assert "Traceback" in crashed.internal_error.traceback and "in broken" in crashed.internal_error.traceback
    logged = [r.getMessage() for r in caplog.records]  # one line: the traceback is in the record, not the console
    assert any("planner bug" in line and "\n" not in line for line in logged), logged
    report = (config.out_dir / "report.md").read_text(encoding="utf-8")
    assert "internal errors: 1 run(s) ended by a bug in robotool" in report
    assert f"run {crashed.key.id}: internal error in the search method: RuntimeError: planner bug" in report
    methods = [row[0] for row in _table(report, "Success rate (paper Table 1)")]
    assert methods[0] == "No tool (floor)" and "Search planner (no LM)" not in methods


def test_an_evaluation_whose_run_met_a_bug_ends_with_status_70_in_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Found by an adversarial run: a run ended by a bug in robotool printed a raw traceback and the evaluation exited
    0. Now the log says it in one line, the report is written, and the command ends with status 70, naming where the
    tracebacks are kept."""

    def broken(tools: bool, settings: Any) -> Any:
        def solve(task: Task, *, seed: int, run: int) -> Solution:
            raise ValueError("repeated name 'world' in body")

        return solve

    monkeypatch.setattr("robotool.eval.solvers.planner_solver", broken)
    out = tmp_path / "out"
    argv = ["--methods", "no_tool", "--tasks", "milk_reaching", "--worlds", "1", "--processes", "1", "--no-pictures"]
    status = main([*argv, "--out", str(out)])
    said = capsys.readouterr()
    assert status == 70 and "Traceback" not in said.out + said.err, said.err
    assert "1 run(s) ended by a bug in robotool" in said.err and "results.json" in said.err
    assert json.loads((out / "results.json").read_text(encoding="utf-8"))["records"][0]["internal_error"]


def test_a_compiled_program_that_is_not_there_is_said_before_the_language_model_it_needs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Found by an adversarial run: ``--program missing.json`` without a model said a model was needed, not that the
    file is not there."""
    monkeypatch.delenv("ROBOTOOL_LM", raising=False)
    missing = tmp_path / "missing.json"
    assert main(["--program", str(missing), "--out", str(tmp_path / "out")]) == 2
    assert f"compiled program not found: {missing}" in capsys.readouterr().err


def _table(report: str, title: str) -> list[list[str]]:
    """The rows of a Markdown table of ``report.md``, by its title."""
    lines = report.split(f"## {title}\n\n", 1)[1].split("\n\n", 1)[0].splitlines()[2:]
    return [[cell.strip() for cell in line.strip("|").split("|")] for line in lines]


def test_a_controller_bug_is_an_internal_error_the_tables_leave_out_and_the_report_lists(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """A fault injected into the arm's controller (it raises in world 1 of the batch): the run's record holds the
    internal error with its traceback, the success table leaves the run out and says so, the report lists it."""
    original = ArmController.start

    def breaks_in_world_1(self: ArmController, state: Any, worlds: np.ndarray, skill: str, args: Any) -> Any:
        if 1 in np.asarray(worlds):  # TEST FIXTURE: a fault injected into the controller
            raise FloatingPointError("overflow encountered in the servo reference")
        return original(self, state, worlds, skill, args)

    def reference(task: Task, *, seed: int, run: int) -> Solution:
        """TEST FIXTURE standing in for a method: the task's reference program, verified in the run's worlds."""
        candidate = Candidate(index=0, code=program(REFERENCE[task.name]))
        return select(task, Proposal(task=task.name, method="reference", candidates=[candidate]), worlds=2, seed=seed)

    monkeypatch.setattr(ArmController, "start", breaks_in_world_1)
    config = EvalConfig(out=tmp_path / "out", settings=Settings(worlds=2), tasks=["milk_reaching_near"])
    with caplog.at_level(logging.ERROR, logger="robotool.sim.lockstep"):
        results = evaluate(config, solvers={"search": standin_solution, "no_tool": reference}, console=_quiet())
    (broken,) = [r for r in results.records if r.key.method == "no_tool"]
    assert broken.success_rate == 0.5 and [w.internal_error for w in broken.worlds] == [False, True]
    assert broken.internal_error is not None and broken.internal_error.where.endswith("world 1")
    assert "breaks_in_world_1" in broken.internal_error.traceback
    assert any("FloatingPointError" in r.getMessage() and r.exc_info is None for r in caplog.records)
    report = (config.out_dir / "report.md").read_text(encoding="utf-8")
    index = [r.key.method for r in results.records].index("no_tool")
    listed = (
        f"run {broken.key.id}: internal error in the arm controller, in open_gripper, world 1: FloatingPointError: "
        f"overflow encountered in the servo reference (its traceback: records[{index}].internal_error in results.json)"
    )
    assert internal_error_lines(results.records)[1:] == [listed] and markdown_text(listed) in report
    assert [row[0] for row in _table(report, "Success rate on other tasks")] == ["Search planner (no LM)"]
    assert "1 run(s) with an internal error (a bug in robotool, not a failure) left out." in report
    saved = json.loads((config.out_dir / "results.json").read_text(encoding="utf-8"))
    assert "Traceback" in saved["records"][index]["internal_error"]["traceback"]
    page = (config.out_dir / "report.html").read_text(encoding="utf-8")
    assert "internal errors: 1 run(s)" in page and "a bug in robotool, not a failure; the run is left out" in page


KILLABLE = """
import sys, time
sys.path.insert(0, {tests!r})
from pathlib import Path
from rich.console import Console
from robotool.eval import EvalConfig, Settings, evaluate
from fixtures.standin_solution import standin_solution

def slow(task, *, seed, run):
    time.sleep(0.15)
    return standin_solution(task, seed=seed, run=run)

config = EvalConfig(out=Path({out!r}), tasks=["sofa_traversing", "milk_reaching"], methods=["search", "no_tool"],
                    runs=2, settings=Settings(worlds=1))
evaluate(config, solvers={{"search": slow, "no_tool": slow}}, console=Console(quiet=True))
"""


@pytest.mark.slow
def test_sigkill_mid_run_then_rerun_records_every_run_once(tmp_path: Path) -> None:
    out = tmp_path / "out"
    script = KILLABLE.format(tests=str(TESTS), out=str(out))
    journal = out / JOURNAL
    process = subprocess.Popen([sys.executable, "-c", script])
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (journal.exists() and len(journal.read_text().splitlines()) >= 2):
        time.sleep(0.05)
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    done_before = len(journal.read_text().splitlines())
    assert 2 <= done_before < 8
    subprocess.run([sys.executable, "-c", script], check=True, timeout=120)
    records = json.loads((out / "results.json").read_text())["records"]
    ids = [(r["key"]["task"], r["key"]["method"], r["key"]["run"]) for r in records]
    assert len(ids) == 8 and len(set(ids)) == 8
    assert len(journal.read_text().splitlines()) == 8


def test_the_longest_runs_start_first_and_records_keep_plan_order(tmp_path: Path) -> None:
    from robotool.eval.instances import builtin
    from robotool.eval.records import RunKey
    from robotool.eval.sweep import longest_first
    from robotool.eval.work import RunJob

    jobs = [
        RunJob(builtin(task), RunKey(task=task, method=method, run=0), 0)
        for task in ("milk_reaching", "vase_lowering")
        for method in ("no_tool", "search")
    ]
    started = [(job.key.task, job.key.method) for job in longest_first(jobs)]
    assert started == [
        ("vase_lowering", "search"),
        ("milk_reaching", "search"),
        ("vase_lowering", "no_tool"),
        ("milk_reaching", "no_tool"),
    ]
    config = _config(tmp_path, tasks=["milk_reaching_near", "can_grasping"], pictures=False)
    results = evaluate(config, solvers=STANDINS, console=_quiet())
    assert [(r.key.task, r.key.method) for r in results.records] == [
        (task, method) for task in ("milk_reaching_near", "can_grasping") for method in ("search", "no_tool")
    ]
