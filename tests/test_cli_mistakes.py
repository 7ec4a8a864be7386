"""Every user mistake on the command line is one line on stderr and exit status 2, checked before any
work starts; and the command line's manners: --version, bare help, defaults in --help, wide pipes."""

from __future__ import annotations

import importlib.util
import io
import os
import subprocess
import sys
from pathlib import Path

import pytest
from fixtures.cli_calls import forbid_work, must_not_run
from fixtures.cli_calls import status as _status
from fixtures.reference import program_path
from rich.console import Console

from robotool.cli.options import CAPTURED_WIDTH, warn_if_warp_on_cpu
from robotool.sandbox import ProgramRejected
from robotool.sandbox.strict import check_user_program
from robotool.sim.backend import default_backend


@pytest.fixture
def no_work(monkeypatch: pytest.MonkeyPatch) -> None:
    forbid_work(monkeypatch)


def _mistakes(tmp_path: Path) -> list[tuple[list[str], str]]:
    program = str(program_path("milk_reaching_direct"))
    a_file = tmp_path / "a_file.txt"
    a_file.write_text("x")
    missing = tmp_path / "no_such_folder"
    return [
        (["tasks", "--family", "sofa_traversing", "--seed", "-1"], "--seed: expected a seed (a whole number >= 0)"),
        (["tasks", "--family", "sofa_traversing", "--out", str(missing / "t.yaml")], f"folder {missing} does not"),
        (["run", "milk_reaching_near", program, "--worlds", "abc"], "--worlds: expected a positive integer, got 'abc'"),
        (["run", "milk_reaching_near", program, "--worlds", "0"], "--worlds: expected a positive integer, got 0"),
        (["run", "milk_reaching_near", program, "--seed", "x"], "--seed: expected a seed"),
        (["run", "milk_reaching_near", program, "--json", str(missing / "r.json")], "cannot write"),
        (["run", "milk_reaching_near", program, "--json", str(tmp_path)], "is a folder; give a file name"),
        (["solve", "milk_reaching_near", "--json", str(missing / "r.json")], f"folder {missing} does not exist"),
        (["solve", "milk_reaching_near", "--out", str(missing / "best.py")], f"folder {missing} does not exist"),
        (["solve", "milk_reaching_near", "--html", str(missing / "p.html")], f"folder {missing} does not exist"),
        (["solve", "milk_reaching_near", "--video", str(tmp_path / "x.mp4")], "--video names the folder the videos"),
        (["run", "milk_reaching_near", program, "--html", str(tmp_path)], "is a folder; give a file name"),
        (["solve", "milk_reaching_near", "--temperature", "nan"], "--temperature: expected a finite number >= 0"),
        (["solve", "milk_reaching_near", "--candidates", "-2"], "--candidates: expected a positive integer"),
        (["eval", "--out", str(a_file)], "is a file, not a folder"),
        (["eval", "--seed", "-1"], "--seed: expected a seed"),
        (["eval", "--worlds", "many"], "--worlds: expected a positive integer, got 'many'"),
        (["eval", "--seeds", "5-2"], "must be A-B with 0 <= A <= B"),
        (["eval", "--videos", "-1"], "--videos: expected a whole number >= 0, got -1"),
        (["run", "milk_reaching_near", str(tmp_path / "nope.py")], "program file not found"),
        (["describe", "no_such_task"], "no built-in task or file by that name"),
        (["describe", ""], "error: '': give a built-in task name or a task file"),  # it read the folder "."
        (["run", "milk_reaching_near", program, "--json", ""], "--json: expected a file name, got an empty one"),
        (["eval", "--out", " "], "--out: expected a folder name, got an empty one"),  # it wrote into "."
        (
            ["optimize", "--optimizer", "planner-demos", "--out", str(tmp_path / "p.txt")],
            "a compiled program is saved as a .json file",  # which solve --program then refused to load
        ),
    ]


def test_every_mistake_is_one_line_and_exit_2_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], no_work: None
) -> None:
    for argv, expected in _mistakes(tmp_path):
        status = _status(argv)
        captured = capsys.readouterr()
        err = captured.err.strip()
        assert status == 2, (argv, captured)
        assert err.startswith("error: ") and "\n" not in err and expected in err, (argv, err)
        assert not captured.out, argv


def test_version_and_bare_help(capsys: pytest.CaptureFixture[str]) -> None:
    assert _status(["--version"]) == 0
    assert capsys.readouterr().out.startswith("robotool ")
    assert _status([]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: robotool") and "solve" in out and "eval" in out


def test_help_shows_the_same_worlds_default(capsys: pytest.CaptureFixture[str]) -> None:
    _status(["solve", "--help"])
    solve_help = " ".join(capsys.readouterr().out.split())
    _status(["eval", "--help"])
    eval_help = " ".join(capsys.readouterr().out.split())
    _status(["run", "--help"])
    run_help = " ".join(capsys.readouterr().out.split())
    assert "perturbed worlds per candidate (R) (default: 3)" in solve_help
    assert "perturbed worlds per candidate (R) (default: 3)" in eval_help
    assert "(default: 1, one quick check; solve and eval use 3 to rank candidates)" in run_help  # the stated reason
    assert "seed of the world perturbations (default: 0)" in solve_help


def test_tables_keep_their_width_when_piped(tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k != "COLUMNS"}
    result = subprocess.run(
        [sys.executable, "-m", "robotool", "run", "button_pressing", str(program_path("button_pressing_direct")),
         "--backend", "mujoco"],
        capture_output=True, text=True, env=env, check=False,
    )  # fmt: skip
    assert result.returncode == 1, result.stderr
    widths = {len(line) for line in result.stdout.splitlines()}
    assert max(widths) > 80 and max(widths) <= CAPTURED_WIDTH
    assert "target [0.520, -0.100, 0.040] is 0.070 m outside" in result.stdout


@pytest.mark.skipif(default_backend() == "warp", reason="this machine has a CUDA GPU")
def test_warp_without_a_gpu_warns_that_it_runs_on_the_cpu() -> None:
    errors = Console(file=io.StringIO(), width=200)
    warn_if_warp_on_cpu("warp", errors)
    warn_if_warp_on_cpu("mujoco", errors)
    assert errors.file.getvalue().strip() == (  # type: ignore[attr-defined]
        "warning: no CUDA GPU found: --backend warp runs on the CPU, much slower than --backend mujoco"
    )


@pytest.mark.slow  # a new process imports and starts Warp
@pytest.mark.skipif(default_backend() == "warp", reason="this machine has a CUDA GPU")
def test_warp_on_the_cpu_adds_no_note_of_its_own() -> None:
    """The warning above is the only one: Warp's native note that it found no CUDA driver is left out."""
    if importlib.util.find_spec("mujoco_warp") is None:  # the child imports it: not here too (4 s of CPU)
        pytest.skip("mujoco_warp is not installed")
    code = "from robotool.sim.warp_runtime import init_warp; init_warp(); import warp; print(warp.is_cpu_available())"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=False)
    assert result.returncode == 0 and result.stdout.strip() == "True", result.stderr
    assert result.stderr == ""


def test_a_truncated_program_exits_2_naming_its_line_and_nothing_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import robotool.execute

    monkeypatch.setattr(robotool.execute, "run_codes", must_not_run)  # nothing may reach the simulator
    lines = program_path("milk_reaching_direct").read_text().rstrip("\n").split("\n")
    cut = lines[-1].index("(") + 1
    truncated = "\n".join([*lines[:-1], lines[-1][:cut]]) + "\n"  # the last call's bracket is never closed
    path = tmp_path / "truncated.py"
    path.write_text(truncated)
    assert _status(["run", "milk_reaching_near", str(path)]) == 2
    captured = capsys.readouterr()
    assert not captured.out
    assert captured.err.strip() == (
        f"error: {path}: line {len(lines)}: syntax error at column {cut}: '(' was never closed"
    )
    with pytest.raises(ProgramRejected) as info:
        check_user_program(truncated, "arm")
    assert info.value.line == len(lines)
    with pytest.raises(ProgramRejected, match="line 1: syntax error"):  # a Markdown fence is not Python
        check_user_program("```python\nopen_gripper()\n```\n", "arm")
