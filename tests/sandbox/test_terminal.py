"""Terminal safety: what programs print and name reaches the console and the eval Markdown escaped."""

from __future__ import annotations

from io import StringIO
from pathlib import Path

import pytest
from rich.console import Console

from robotool.cli import main
from robotool.cli.summary import print_run, print_run_verdict, print_solution, print_solution_verdict
from robotool.eval.report import _markdown_table
from robotool.eval.tables import TextTable
from robotool.execute import RunReport
from robotool.rollout import Rollout
from robotool.safe_text import one_line, terminal_safe
from robotool.signatures.models import PlanStep
from robotool.solution import Solution, StageOutputs

HOSTILE_PRINTS = (
    'print("\\x1b[2J\\x1b[H", end="")  # clear the screen\n'
    'print("\\x1b]0;pwned\\x07", end="")  # window title\n'
    'print("\\x1b]52;c;cm0gLXJmIH4=\\x07", end="")  # clipboard (OSC 52)\n'
    'print("\\r\\x1b[32mevery world succeeded\\x1b[0m \\u202e")  # a fake green verdict\n'
    'print("\\nall worlds succeeded: success rate 100%")  # a line shaped like the report\'s own\n'
    'move_to_position(get_center("milk\\x1b[31m"))\n'
)


def test_escaping_keeps_text_readable() -> None:
    assert terminal_safe("a\x1b[2Jb\tc\nd\x9b\u202e\r") == "a\\x1b[2Jb\tc\nd\\x9b\\u202e\\x0d"
    assert one_line("a\nb\tc|") == "a\\x0ab\\x09c|"
    assert terminal_safe("plain text, ünïcode ✓") == "plain text, ünïcode ✓"


def test_invisible_and_line_separating_characters_are_shown() -> None:
    """Text a terminal would hide or break the line at: line/paragraph separators, soft hyphen,
    invisible operators, interlinear annotations and Unicode tag characters (hidden "ASCII" text)."""
    hidden = "\u2028\u2029\u00ad\u2060\u2064\ufff9\U000e0041"
    assert terminal_safe(f"a{hidden}b") == "a\\u2028\\u2029\\xad\\u2060\\u2064\\ufff9\\U000e0041b"
    assert one_line("\U000e007f") == "\\U000e007f"


def test_run_report_shows_program_bytes_escaped(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "250")
    program = tmp_path / "hostile_prints.py"
    program.write_text(HOSTILE_PRINTS)
    main(["run", "milk_reaching", str(program), "--worlds", "1", "--backend", "mujoco"])
    out = capsys.readouterr().out
    for raw in ("\x1b", "\x07", "\r", "\u202e"):  # captured output is not a terminal: rich adds none of these
        assert raw not in out, repr(raw)
    assert "\\x1b[2J" in out and "\\x1b]52;c;" in out
    assert not [line for line in out.splitlines() if line.startswith("all worlds succeeded")], out
    assert "sandbox: " in out and "seccomp filter" in out


@pytest.mark.parametrize("width", [80, 120, 200])
def test_no_line_a_program_prints_or_raises_starts_a_report_line(width: int) -> None:
    """A program's error (``assert False, "\\n..."``) and its output keep their line breaks, but every line of
    them, wrapped lines included, starts with the frame's border, so none can pose as the report's verdict;
    the verdict is the last line."""
    fake = "every world succeeded: success rate 100%"
    padded = "." + " " * 240 + fake  # the console wraps it: the fake verdict would start a line
    rollout = Rollout(
        world=0,
        seed=0,
        success=False,
        error=f"line 2: AssertionError: {padded}\n{fake}",
        output=f"x\n{fake}\n{padded}\ny",
    )
    report = RunReport(
        task="t", worlds=1, seed=0, backend="mujoco", success=False, success_rate=0.0, code="", rollouts=[rollout]
    )
    console = Console(file=StringIO(), width=width)
    print_run(report, console)
    print_run_verdict(report, console)
    lines = console.file.getvalue().splitlines()  # type: ignore[attr-defined]
    faked = [line for line in lines if fake in line]
    assert len(faked) >= 4 and all(line.lstrip().startswith("│") for line in faked), lines  # framed or in a cell
    assert not [line for line in lines[:-1] if line.startswith(("every world", "some worlds"))], lines
    assert lines[-1] == "some worlds failed: success rate 0%"


def test_eval_markdown_cells_are_escaped() -> None:
    table = TextTable(title="T\x1b[2J", columns=["method", "note"], rows=[["a\x1b]52;c;x\x07", "line\nbreak|pipe"]])
    text = _markdown_table(table)
    assert "\x1b" not in text and "\x07" not in text
    assert "| a\\\\x1b\\]52;c;x\\\\x07 | line\\\\x0abreak\\|pipe |" in text  # the escapes' backslashes escaped


@pytest.mark.parametrize("width", [80, 120, 200])
def test_no_line_a_model_writes_starts_a_solve_summary_line(width: int) -> None:
    """The model's plan, steps and code, and notes, wrap right of their labels or line numbers; the verdict is last."""
    fake = "solved: best success rate 100%"
    padded = "." + " " * 240 + fake
    stages = StageOutputs(abstract_plan=f"{padded}\n{fake}", steps=[PlanStep(skill="open_gripper", intent=padded)])
    solution = Solution(task="t", method="m", code=f"x = 1  # {padded}\n#{fake}\n", stages=stages, notes=[padded])
    console = Console(file=StringIO(), width=width)
    print_solution(solution, console)
    print_solution_verdict(solution, console)
    lines = console.file.getvalue().splitlines()  # type: ignore[attr-defined]
    assert not [line for line in lines[:-1] if line.startswith(("solved", "not solved"))], lines
    assert lines[-1].startswith("not solved: best success rate 0%")
