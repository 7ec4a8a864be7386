"""``robotool run TASK PROGRAM.py``: the reference program files, refusals, bad programs, the JSON report.

Arm programs run in 3 worlds, quadruped programs (slower to simulate) in 2, all on the C backend so
that the outcomes are deterministic.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fixtures.reference import REFERENCE, TOOL_FREE, program, program_path

import robotool
from robotool import tasks
from robotool.cli import main
from robotool.cli.internal_error import EXIT_INTERNAL_ERROR
from robotool.robots.arm.arm_controller import ArmController

REFUSALS = {  # quadruped task -> (skill refused, measured key, value, tolerance) for its tool-free program
    "sofa_traversing": ("walk_to_position", "gap", 0.30, 0.02),  # beyond the end of the board reaching over it
    "sofa_climbing": ("climb_to_position", "step", 0.34, 0.02),
    "cube_lifting": ("push_to_position", "mass", 10.0, 1.5),  # the cube's mass in the world, perturbed by 15 %
}


@pytest.fixture(autouse=True)
def wide_console(monkeypatch: pytest.MonkeyPatch) -> None:
    """A wide console, so that table cells (reasons, measured values) are not folded across lines."""
    monkeypatch.setenv("COLUMNS", "250")


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """``robotool run ARGS`` in-process: (exit status, stdout, stderr)."""
    status = main(["run", *args])
    captured = capsys.readouterr()
    assert "Traceback" not in captured.out + captured.err
    return status, captured.out, captured.err


def worlds(task: str) -> str:
    return "3" if tasks.load(task).embodiment == "arm" else "2"


@pytest.mark.parametrize(("task", "name"), sorted(REFERENCE.items()))
def test_reference_program_file_succeeds(capsys: pytest.CaptureFixture[str], task: str, name: str) -> None:
    status, out, _ = run_cli(capsys, task, str(program_path(name)), "--worlds", worlds(task), "--backend", "mujoco")
    assert status == 0, out
    assert "every world succeeded: success rate 100%" in out


@pytest.mark.parametrize(("task", "name"), sorted(TOOL_FREE.items()))
def test_tool_free_program_fails_with_the_reason(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, task: str, name: str
) -> None:
    report = tmp_path / "report.json"
    args = (task, str(program_path(name)), "--worlds", worlds(task), "--backend", "mujoco", "--json", str(report))
    status, out, _ = run_cli(capsys, *args)
    data = json.loads(report.read_text())
    assert status == 1 and data["success"] is False and data["success_rate"] == 0.0
    assert "some worlds failed: success rate 0%" in out
    for rollout in data["rollouts"]:
        assert not rollout["success"] and not all(rollout["conditions"].values())
        if task in REFUSALS:
            skill, key, value, tolerance = REFUSALS[task]
            (refused,) = [c for c in rollout["calls"] if c["outcome"] == "refused"]
            assert refused["skill"] == skill and refused["measured"][key] == pytest.approx(value, abs=tolerance)
            assert "exceeds the" in refused["reason"]
            flat = " ".join(out.replace("│", " ").split())  # table cells fold long reasons over lines
            assert f"{skill}: refused: {refused['reason']}" in flat  # the summary's "why it failed"
            assert f"{key} {refused['measured'][key]:.3g}" in out  # the trace's measured value
        else:
            clamped = [c for c in rollout["calls"] if "outside_workspace" in c["measured"]]
            assert clamped and clamped[0]["measured"]["clamped_x"] == pytest.approx(0.45)
            assert clamped[0]["reason"] in out and "clamped to [0.450" in out


@pytest.mark.parametrize(
    ("code", "status", "reason"),
    [
        ("import os\n", 2, "error: {path}: line 1: import of 'os' is not allowed"),
        ('grasp("milk")\n', 2, "error: {path}: line 1: unknown function 'grasp'; the arm's skills are: get_center"),
        (
            "open_gripper()\nmove_to_position([0.5, 0, 0.1]\n",
            2,
            "error: {path}: line 2: syntax error at column 17: '(' was never closed",
        ),
        ("while True:\n    pass\n", 1, "CPU time limit exceeded (2 s)"),
    ],
)
def test_bad_program_ends_with_one_line_reason(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, code: str, status: int, reason: str
) -> None:
    path = tmp_path / "prog.py"
    path.write_text(code)
    got, out, err = run_cli(capsys, "milk_reaching_near", str(path), "--backend", "mujoco")
    assert got == status
    if status == 2:
        assert len(err.strip().splitlines()) == 1 and err.startswith(reason.format(path=path)) and not out
    else:
        assert any(line.startswith(f"  │ {reason}") for line in out.splitlines())  # framed, under "error"


def test_runaway_program_through_the_real_entry_point(tmp_path: Path) -> None:
    path = tmp_path / "loop.py"
    path.write_text("open_gripper()\nwhile True:\n    pass\n")
    result = subprocess.run(
        [sys.executable, "-m", "robotool", "run", "milk_reaching_near", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stdout + result.stderr
    assert "CPU time limit exceeded (2 s)" in result.stdout and "success rate 0%" in result.stdout


def test_json_report_matches_the_library(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    report = tmp_path / "report.json"
    path = str(program_path("button_pressing"))
    status, out, _ = run_cli(
        capsys, "button_pressing", path, "--worlds", "2", "--seed", "4", "--backend", "mujoco", "--json", str(report)
    )
    data: dict[str, Any] = json.loads(report.read_text())
    assert status == 0 and f"wrote the report to {report}" in out
    assert data["success"] is True and data["success_rate"] == 1.0
    assert (data["task"], data["worlds"], data["seed"], data["backend"]) == ("button_pressing", 2, 4, "mujoco")
    for rollout in data["rollouts"]:
        assert rollout["conditions"] and all(rollout["conditions"].values())
        assert {c["outcome"] for c in rollout["calls"]} == {"done"}
        assert rollout["calls"][-1]["skill"] == "move_to_position"
    library = robotool.run("button_pressing", program("button_pressing"), worlds=2, seed=4, backend="mujoco")
    assert [r.model_dump(mode="json") for r in library.rollouts] == data["rollouts"]


def test_a_controller_bug_exits_70_with_its_traceback_in_the_json_report(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A skill controller that raises (a bug in robotool) is not the program's failure: the run exits 70, not 1, and
    the traceback its logged line points to is the rollout's ``internal_error`` in the report."""

    def breaks(self: ArmController, state: Any, worlds: np.ndarray, skill: str, args: Any) -> Any:
        raise FloatingPointError("overflow encountered in the servo reference")  # TEST FIXTURE: an injected fault

    monkeypatch.setattr(ArmController, "start", breaks)
    report = tmp_path / "report.json"
    path = str(program_path(REFERENCE["milk_reaching_near"]))
    status, out, _ = run_cli(capsys, "milk_reaching_near", path, "--backend", "mujoco", "--json", str(report))
    (rollout,) = json.loads(report.read_text())["rollouts"]
    assert status == EXIT_INTERNAL_ERROR and "some worlds failed: success rate 0%" in out
    assert (
        "FloatingPointError" in rollout["internal_error"]["reason"]
        and "breaks" in rollout["internal_error"]["traceback"]
    )


def test_bad_task_file_exits_2(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    broken = tmp_path / "broken.yaml"
    broken.write_text("format: 1\nname: x\nobjects:\n  - {name: a, shape: sphere}\n")
    status, out, err = run_cli(capsys, str(broken), str(program_path("milk_reaching_direct")))
    assert status == 2 and not out
    assert err.startswith(f"error: {broken}: 7 problems\n") and "objects[0](a).shape" in err


def test_missing_program_file_exits_2(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    missing = tmp_path / "nope.py"
    status, out, err = run_cli(capsys, "milk_reaching_near", str(missing))
    assert status == 2 and not out
    assert err.strip() == f"error: program file not found: {missing}"


def test_a_program_file_is_read_in_the_encoding_its_coding_line_declares(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """Found by an adversarial run: a PEP 263 coding line was ignored (the file read as UTF-8), unlike Python; an
    encoding Python does not know is one line."""
    declared = tmp_path / "latin.py"
    text = "# -*- coding: latin-1 -*-\n# pour le caf\u00e9\n" + program("milk_reaching_direct")
    declared.write_bytes(text.encode("latin-1"))
    status, out, err = run_cli(capsys, "milk_reaching_near", str(declared))
    assert status == 0 and "Traceback" not in out + err, err
    unknown = tmp_path / "unknown.py"
    unknown.write_bytes(b"# coding: no-such-encoding\n" + program("milk_reaching_direct").encode())
    status, out, err = run_cli(capsys, "milk_reaching_near", str(unknown))
    assert status == 2
    assert err.strip() == f"error: cannot read the program {unknown}: unknown encoding: no-such-encoding"


@pytest.mark.parametrize(
    ("codec", "hidden"),
    [
        ("utf-7", b"# keep holding +AAo-open_gripper()\n"),  # +AAo- is a newline in UTF-7
        ("unicode_escape", b"# keep holding \\u000aopen_gripper()\n"),
        ("shift_jis", b's = "\x81\\"; open_gripper() #"\n'),  # \x81\\ is one character: the quote closes the string
        ("iso2022_jp", b"# \x1b$B!!\x1b(B\n"),  # an escape sequence shifts out of ASCII and back
    ],
)
def test_a_coding_line_that_reads_ascii_otherwise_than_ascii_is_refused(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, codec: str, hidden: bytes
) -> None:
    """Found by an adversarial run: a file declaring UTF-7 or unicode_escape ran an ``open_gripper()`` that an editor
    or a terminal shows inside a comment. A coding line may name only an encoding that reads each ASCII byte of the
    file as itself."""
    path = tmp_path / "hidden.py"
    path.write_bytes(f"# coding: {codec}\n".encode() + b"x = 1\n" + hidden)
    status, out, err = run_cli(capsys, "milk_reaching_near", str(path))
    assert status == 2 and not out
    assert err.startswith(f"error: cannot read the program {path}: its coding line declares"), err
    assert "does not read each ASCII character" in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize("codec", ["rot13", "hex", "base64", "zlib_codec", "punycode"])
def test_a_coding_line_naming_a_codec_python_refuses_for_source_is_one_line(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, codec: str
) -> None:
    """Found by an adversarial run: a coding line naming a codec that is not a text encoding (rot13, hex, base64,
    zlib_codec) or one that cannot decode source (punycode) ended in an internal error (exit 70). Python itself says
    "SyntaxError: encoding problem: <codec>" for these files."""
    path = tmp_path / "codec.py"
    path.write_bytes(f"# -*- coding: {codec} -*-\n".encode() + program("milk_reaching_direct").encode())
    status, out, err = run_cli(capsys, "milk_reaching_near", str(path))
    assert status == 2 and not out
    assert err.startswith(f"error: cannot read the program {path}:") and len(err.strip().splitlines()) == 1, err


def test_a_long_output_is_shown_cut_with_how_much_is_left_out() -> None:
    """Found by an adversarial run: a program's output was cut at 500 characters with no mark, ending mid-word as if
    that were all it printed."""
    from rich.console import Console

    from robotool.cli.summary import print_trace
    from robotool.rollout import Rollout

    console = Console(record=True, width=1000)
    printed = "x" * 499 + "WARNING: the rest is here"
    print_trace(Rollout(world=0, seed=0, success=True, output=printed), console)
    shown = console.export_text()
    assert "x" * 100 in shown and "… (24 more characters, in the JSON report)" in shown
