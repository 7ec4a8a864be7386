"""The command line: listing, describing, and bad input ending with status 2 and no traceback."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from io import StringIO
from pathlib import Path

import pytest
from rich.console import Console

from robotool import tasks
from robotool.cli import main
from robotool.cli.summary import print_solution_verdict
from robotool.rollout import Rollout
from robotool.solution import Candidate, Solution


def test_tasks_lists_all_ten(capsys) -> None:
    assert main(["tasks"]) == 0
    out = capsys.readouterr().out
    for name in tasks.names():
        assert name in out
    assert len(tasks.names()) == 10


def test_describe_prints_numbers(capsys) -> None:
    assert main(["describe", "sofa_traversing"]) == 0
    out = capsys.readouterr().out
    assert "sofa_2" in out and "0.34" in out and "climbs up a step of at most 0.12 m" in out


def test_broken_file_exits_2_without_traceback(tmp_path: Path) -> None:
    broken = tmp_path / "broken.yaml"
    broken.write_text("format: 1\nname: x\nobjects:\n  - {name: a, shape: sphere}\n")
    result = subprocess.run(
        [sys.executable, "-m", "robotool", "describe", str(broken)], capture_output=True, text=True, check=False
    )
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert "objects[0](a).shape" in result.stderr


def test_unknown_task_exits_2(capsys) -> None:
    assert main(["describe", "no_such_task"]) == 2
    assert "built-in tasks" in capsys.readouterr().err


def test_tasks_writes_a_generated_instance(tmp_path: Path, capsys) -> None:
    out = tmp_path / "t.yaml"
    assert main(["tasks", "--family", "sofa_traversing", "--seed", "3", "--out", str(out)]) == 0
    assert tasks.load(out).name == "sofa_traversing_3"
    assert main(["tasks", "--family", "no_such_family"]) == 2
    assert "families:" in capsys.readouterr().err


def test_eval_subcommand_hands_over_to_the_evaluator(capsys) -> None:
    with pytest.raises(SystemExit) as exit_info:  # argparse's own exit for a bad option
        main(["eval", "--runs", "0"])
    assert exit_info.value.code == 2
    assert "--runs" in capsys.readouterr().err


def _options(parser: argparse.ArgumentParser, group: str) -> set[str]:
    (found,) = [g for g in parser._action_groups if g.title == group]
    return {option for action in found._group_actions for option in action.option_strings}


def test_every_command_takes_the_same_lm_and_world_options() -> None:
    from robotool.cli import eval_command, optimize_command
    from robotool.cli.dispatch import build_parser

    verbs = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    lm = {"--lm", "--api-base", "--api-key-env", "--temperature", "--adapter", "--timeout", "--no-cache"}
    worlds = {"--worlds", "--backend", "--seed"}
    standalone = {}
    for name, module in (("eval", eval_command), ("optimize", optimize_command)):
        standalone[name] = argparse.ArgumentParser()
        module.add_arguments(standalone[name])
    for parser in (verbs["solve"], verbs["eval"], verbs["optimize"], *standalone.values()):
        assert lm <= _options(parser, "language model"), parser.prog
        assert _options(parser, "worlds") == worlds, parser.prog
    assert _options(verbs["run"], "worlds") == worlds
    assert (
        _options(verbs["solve"], "candidates") == _options(verbs["eval"], "candidates") == {"--candidates", "--repair"}
    )
    for name, parser in standalone.items():  # python -m robotool.<name> and robotool <name> are one parser
        assert {o for a in parser._actions for o in a.option_strings} == {
            o for a in verbs[name]._actions for o in a.option_strings
        }


def test_goal_text_comes_from_the_goal_model() -> None:
    assert tasks.load("cube_lifting").goal.text() == "cube lifted to >= 0.1 m"
    assert tasks.load("milk_reaching").goal.text() == "grasp milk"
    assert tasks.load("sofa_traversing").goal.text() == "robot on sofa_2"
    vase = tasks.load("vase_lowering").goal
    assert vase.text() == "glass_vase lowered to <= 0.2 m"
    assert (
        vase.sentence(unbroken=True)
        == "The bottom of glass_vase is at most 0.2 m above the ground at the end, unbroken."
    )
    assert tasks.load("milk_reaching").goal.sentence() == "The gripper holds milk at the end."


def test_a_verb_imports_only_its_own_module() -> None:
    """``robotool run`` does not wait for the optimiser's imports (DSPy): the other verbs are listed by name and help
    line, from :mod:`robotool.cli.verbs`, without importing their modules."""
    probe = (
        "import sys\n"
        "from robotool.cli.dispatch import build_parser\n"
        "from robotool.cli.verbs import VERBS\n"
        "parser = build_parser(['run'])\n"
        "verbs = next(a for a in parser._actions if a.dest == 'verb')\n"
        "assert list(verbs.choices) == list(VERBS), list(verbs.choices)\n"
        "print(sorted(m for m in sys.modules if m.endswith(('_command', '_commands'))))\n"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "['robotool.cli.run_command']"


def _verdict(successes: list[bool]) -> str:
    """The last line ``solve`` prints for a best program that succeeded in the worlds ``successes`` says."""
    rollouts = [Rollout(world=w, seed=w, success=s) for w, s in enumerate(successes)]
    candidate = Candidate(index=0, code="pass", rollouts=rollouts)
    solution = Solution(
        task="t",
        method="search",
        code="pass",
        best=0,
        success_rate=candidate.success_rate,
        candidates=[candidate],
        timings={"total": 1.0},
    )
    out = StringIO()
    print_solution_verdict(solution, Console(file=out, width=200))
    return out.getvalue().strip()


def test_the_verdict_says_when_the_best_program_failed_in_some_worlds() -> None:
    """A best program that reached the goal in 6 of its 8 perturbed worlds was printed 'solved: best success rate
    75%', like one that held in all of them (a held-out task file): it now says in how many it did."""
    assert _verdict([True] * 8).startswith("solved: best success rate 100%;")
    partly = _verdict([True, True, True, False, True, True, False, True])
    assert partly.startswith("solved in some worlds only: best success rate 75% (6 of 8 perturbed worlds"), partly
    assert _verdict([False] * 3).startswith("not solved: best success rate 0%;")


@pytest.mark.parametrize("columns", ["0", "00", " 0 "])
def test_a_columns_of_zero_is_ignored_not_taken_for_a_width_of_nothing(
    columns: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Found by an adversarial run: with ``COLUMNS=0`` every report vanished (``describe`` printed nothing and exited
    0), as rich took it for a width of no columns."""
    monkeypatch.setenv("COLUMNS", columns)
    assert main(["describe", "milk_reaching"]) == 0
    assert "Grasp the milk carton" in capsys.readouterr().out


def test_a_lone_surrogate_in_a_task_file_is_shown_escaped(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Found by an adversarial run: a task file's ``notes: "\\ud800"`` (a YAML escape) ended ``describe`` in an internal
    error, as no encoding can write a lone surrogate."""
    data = tasks.load("milk_reaching").model_dump(mode="json", exclude_defaults=True)
    data["objects"][0]["notes"] = "\ud800"
    path = tmp_path / "surrogate.json"
    path.write_text(json.dumps(data), encoding="ascii")  # (the escape "\\ud800" in the file)
    assert main(["describe", str(path)]) == 0
    assert "\\ud800" in capsys.readouterr().out
