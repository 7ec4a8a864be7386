"""Numbers and files far beyond any real use are user mistakes: one line, exit status 2, before any work starts;
never a hang, a machine's memory filled, a traceback or an "internal error".

Found by an adversarial run: ``--seeds 0-99999999999`` (a MemoryError traceback), ``--runs 1000000000`` (a silent
hang), ``--worlds 13000`` (an internal error from the sandbox's memory split), a task file's 9000-digit ``format`` (an
internal error), ``/dev/zero`` as a program or a task file (read whole before the size check), a task file of 3000
stacked boxes (minutes of geometry checks) and a centre of 1e308 m (numpy's overflow warnings before the error).
"""

from __future__ import annotations

import json
import os
import re
import warnings
from pathlib import Path

import pytest
import yaml
from fixtures.cli_calls import forbid_work, must_not_run
from fixtures.cli_calls import status as _status
from fixtures.reference import program_path

from robotool import tasks
from robotool.task.task_file import TaskFileError, load_task


@pytest.fixture
def no_work(monkeypatch: pytest.MonkeyPatch) -> None:
    forbid_work(monkeypatch)


def _one_line_error(capsys: pytest.CaptureFixture[str], argv: list[str], status: int) -> str:
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert status == 2, (argv, captured)
    assert err.startswith("error: ") and "\n" not in err, (argv, err)
    assert "internal error" not in err and "Traceback" not in err, (argv, err)
    return err


def _too_big(tmp_path: Path) -> list[tuple[list[str], str]]:
    """Every integer option of every command, one past its bound."""
    program = str(program_path("milk_reaching_direct"))
    run = ["run", "milk_reaching_near", program]
    opt = ["optimize", "--optimizer", "planner-demos", "--out", str(tmp_path / "p.json")]
    return [
        ([*run, "--worlds", "13000"], "--worlds: expected a positive integer of at most 1000, got 13000"),
        ([*run, "--seed", "9" * 9000], "--seed: expected a seed"),
        ([*run, "--seed", str(2**63)], "--seed: expected a seed (a whole number >= 0) of at most"),
        (["solve", "milk_reaching_near", "--candidates", "101"], "--candidates: expected a positive integer of at"),
        (["solve", "milk_reaching_near", "--repair", "1000000"], "--repair: expected a whole number >= 0 of at most"),
        (["solve", "milk_reaching_near", "--format-retries", "1000"], "--format-retries: expected"),
        (["solve", "milk_reaching_near", "--max-tokens", "10000000000"], "--max-tokens: expected"),
        (["eval", "--runs", "1000000000"], "--runs: expected a positive integer of at most 1000, got 1000000000"),
        (["eval", "--workers", "100000"], "--workers: expected a positive integer of at most"),
        (["eval", "--processes", "100000"], "--processes: expected a positive integer of at most"),
        (["eval", "--videos", "100000"], "--videos: expected a whole number >= 0 of at most"),
        (["eval", "--worlds", "1001"], "--worlds: expected a positive integer of at most 1000"),
        (["eval", "--seeds", "0-99999999999"], "--seeds: at most 1000 seeds at once"),
        (["eval", "--seeds", "0-300000000"], "--seeds: at most 1000 seeds at once"),
        (["eval", "--seeds", "0-" + "9" * 5000], "seeds must look like 0-9 or 1,4,7"),
        ([*opt, "--train", "1000000"], "--train: expected a positive integer of at most"),
        ([*opt, "--val", "1000000"], "--val: expected a whole number >= 0 of at most"),
        ([*opt, "--threads", "100000"], "--threads: expected"),
        ([*opt, "--max-metric-calls", "10000000"], "--max-metric-calls: expected"),
        ([*opt, "--trials", "10000000"], "--trials: expected"),
        ([*opt, "--candidates", "10000000"], "--candidates: expected"),
        ([*opt, "--steps", "10000000"], "--steps: expected"),
        ([*opt, "--demos", "10000000"], "--demos: expected"),
        (["render", "milk_reaching_near", "--out", str(tmp_path / "s.png"), "--width", "10" * 10], "--width: expected"),
        (["render", "milk_reaching_near", "--out", str(tmp_path / "s.png"), "--height", "99999"], "--height: expected"),
        (["tasks", "--family", "sofa_traversing", "--seed", "1" + "0" * 30], "--seed: expected a seed"),
    ]


def test_every_integer_option_has_a_bound(tmp_path: Path, capsys: pytest.CaptureFixture[str], no_work: None) -> None:
    for argv, expected in _too_big(tmp_path):
        err = _one_line_error(capsys, argv, _status(argv))
        assert expected in err and len(err) < 300, (argv, err)


@pytest.mark.parametrize("command", ["solve", "eval", "optimize"])
def test_an_empty_api_key_variable_name_is_refused_not_taken_for_none(
    command: str, capsys: pytest.CaptureFixture[str], no_work: None
) -> None:
    """Found by an adversarial run: ``--api-key-env ''`` was taken as not given, and the error then asked for
    ``--api-key-env``."""
    argv = [command, *(["milk_reaching_near"] if command == "solve" else []), "--lm", "openai/x", "--api-key-env", ""]
    err = _one_line_error(capsys, argv, _status(argv))
    assert "--api-key-env: expected the name of an environment variable, got ''" in err, err


BAD_LM_SETTINGS = {  # options (or the API base's variable), what the one-line error says
    "api-base-not-a-url": (["--lm", "openai/x", "--api-base", "not a url"], "'not a url' (--api-base or"),
    "api-base-a-file-url": (["--lm", "openai/x", "--api-base", "file:///etc/passwd"], "is not an http:// or https://"),
    "api-base-unclosed-ipv6": (["--lm", "openai/x", "--api-base", "http://[::1"], "is not an http:// or https://"),
    "api-base-variable": (["--lm", "openai/x", "ROBOTOOL_API_BASE=::::"], "'::::' (--api-base or ROBOTOOL_API_BASE)"),
    "unknown-provider": (
        ["--lm", "nosuchprovider/x", "--api-base", "http://127.0.0.1:9/v1"],
        "names no provider DSPy or LiteLLM knows ('nosuchprovider'): check --lm",
    ),
    "huge-timeout": (["--lm", "openai/x", "--timeout", "1e10"], "--timeout: expected a number of seconds of at most"),
}


@pytest.mark.parametrize("command", ["solve", "eval", "optimize"])
@pytest.mark.parametrize(("options", "expected"), BAD_LM_SETTINGS.values(), ids=list(BAD_LM_SETTINGS))
def test_lm_settings_that_cannot_work_are_refused_before_anything_runs(
    command: str,
    options: list[str],
    expected: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Found by an adversarial run: a malformed --api-base, an unknown provider or a timeout of 1e10 s failed each
    LM request, and those runs were recorded as the method's failures (exit 1, or an evaluation's exit 0)."""
    import robotool.eval.sweep
    from robotool.program.lm_program import RoboTool

    if command != "eval":  # an evaluation builds its LM first, then selects its tasks
        forbid_work(monkeypatch)
    monkeypatch.setattr(robotool.eval.sweep, "select", must_not_run)
    monkeypatch.setattr(RoboTool, "forward", must_not_run)
    monkeypatch.delenv("ROBOTOOL_API_BASE", raising=False)
    for option in [o for o in options if o.startswith("ROBOTOOL_")]:
        monkeypatch.setenv(*option.split("=", 1))
    given = [o for o in options if not o.startswith("ROBOTOOL_")]
    where = {
        "solve": ["solve", "milk_reaching_near", "--method", "coder"],
        "eval": ["eval", "--tasks", "milk_reaching_near", "--methods", "coder", "--out", str(tmp_path / "ev")],
        "optimize": ["optimize", "--optimizer", "planner-demos", "--out", str(tmp_path / "p.json")],
    }[command]
    argv = [*where, *given]
    err = _one_line_error(capsys, argv, _status(argv))
    assert expected in err, err
    assert not (tmp_path / "ev").exists()


def test_a_batch_the_sandbox_cannot_split_is_refused_before_anything_runs(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, no_work: None
) -> None:
    """Each of a batch's programs needs 1 MiB of the sandbox's memory; on this 'machine' 64 MiB in all. It was an
    internal error from deep in the sandbox (exit 70), and in eval every run was recorded as one."""
    from robotool.sandbox import limits

    monkeypatch.setattr(limits, "default_batch_memory_mb", lambda: 64)
    program = str(program_path("milk_reaching_direct"))
    cases = [
        (["run", "milk_reaching_near", program, "--worlds", "65"], "--worlds 65: a batch of 65 programs"),
        (["solve", "milk_reaching_near", "--candidates", "5", "--worlds", "13"], "--candidates 5 x --worlds 13"),
        (["eval", "--candidates", "9", "--worlds", "9"], "--candidates 9 x --worlds 9: a batch of 81 programs"),
        (["optimize", "--optimizer", "planner-demos", "--out", "/tmp/x.json", "--worlds", "100"], "--worlds 100"),
    ]
    for argv, expected in cases:
        err = _one_line_error(capsys, argv, _status(argv))
        assert expected in err and "does not fit in 64 MiB" in err, (argv, err)
    assert _status(["run", "milk_reaching_near", program, "--worlds", "64", "--json", "/nonexistent/x.json"]) == 2
    assert "--worlds" not in capsys.readouterr().err  # 64 fit: the next check speaks


def test_an_evaluation_of_too_many_runs_is_refused_before_its_folder_is_made(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import robotool.eval.sweep

    monkeypatch.setattr(robotool.eval.sweep, "MAX_RUNS", 10)
    out = tmp_path / "ev"
    argv = ["eval", "--tasks", "milk_reaching_near", "--methods", "no_tool", "--runs", "11", "--out", str(out)]
    err = _one_line_error(capsys, argv, _status(argv))
    assert "1 task instance(s) x 1 method(s) x 11 run(s) is 11 runs; one evaluation runs at most 10" in err
    assert not out.exists()


def _task_text() -> str:
    return tasks.source("milk_reaching_near")


def test_a_task_file_number_of_thousands_of_digits_is_a_task_file_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = yaml.safe_load(_task_text())
    as_json = tmp_path / "big.json"
    as_json.write_text(json.dumps(data).replace('"format": 1', '"format": ' + "9" * 9000))
    as_yaml = tmp_path / "big.yaml"
    as_yaml.write_text(re.sub(r"(?m)^format: 1$", "format: " + "9" * 9000, _task_text()))
    hex_yaml = tmp_path / "hex.yaml"  # YAML reads 0x... of any length: the error message must still show it
    hex_yaml.write_text(re.sub(r"(?m)^format: 1$", "format: 0x" + "f" * 5000, _task_text()))
    for path, expected in [
        (as_json, "not valid JSON: a number has more than 4300 digits"),
        (as_yaml, "not valid YAML: a number has more than 4300 digits"),
        (
            hex_yaml,
            "format: Unable to parse input string as an integer, exceeded maximum size "
            "(got an integer of about 6020 digits)",
        ),
    ]:
        err = _one_line_error(capsys, ["describe", str(path)], _status(["describe", str(path)]))
        assert err == f"error: {path}: {expected}", err


def test_a_program_or_task_file_that_is_no_regular_file_is_not_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``/dev/zero`` never ends: reading it whole filled the host's memory before the 100 KB check; a named pipe as
    the program waited for a writer for ever (found by an adversarial run). Neither is opened now."""
    program = str(program_path("milk_reaching_direct"))
    pipe = tmp_path / "pipe.py"
    os.mkfifo(pipe)
    for argv, expected in [
        (["run", "milk_reaching_near", "/dev/zero"], "error: cannot read the program /dev/zero: not a regular file (a"),
        (["run", "milk_reaching_near", str(pipe)], f"error: cannot read the program {pipe}: not a regular file"),
        (["run", "/dev/zero", program], "error: /dev/zero: not a regular file (a device)"),
        (["describe", "/dev/zero"], "error: /dev/zero: not a regular file (a device)"),
    ]:
        err = _one_line_error(capsys, argv, _status(argv))
        assert err.startswith(expected), (argv, err)


def _objects(count: int, *, stacked: bool) -> list[dict[str, object]]:
    """``count`` small boxes: one stack, or spread on a grid clear of the robot and the milk."""
    if stacked:
        return [
            {"name": f"o{i}", "shape": "box", "center": [0.45, -0.3, 0.025 + 0.05 * i], "size": [0.04, 0.04, 0.05]}
            for i in range(count)
        ]
    return [
        {"name": f"o{i}", "shape": "box", "center": [0.2 + 0.06 * (i % 20), -0.5 - 0.06 * (i // 20), 0.02]}
        | {"size": [0.04, 0.04, 0.04]}
        for i in range(count)
    ]


def _with_objects(tmp_path: Path, objects: list[dict[str, object]]) -> Path:
    data = yaml.safe_load(_task_text())
    data["objects"] += objects
    path = tmp_path / "many.json"  # JSON: YAML would take seconds to read 3000 objects
    path.write_text(json.dumps(data))
    return path


def test_a_task_file_of_thousands_of_objects_is_refused_at_once(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """3000 stacked boxes took minutes to load (the resting checks); the cap is far above any real task's count."""
    path = _with_objects(tmp_path, _objects(3000, stacked=True))
    err = _one_line_error(capsys, ["describe", str(path)], _status(["describe", str(path)]))
    assert (
        err == f"error: {path}: objects: 3004 objects; a task holds at most 200 (a real task holds a few dozen at most)"
    )


def test_the_resting_checks_look_only_under_each_object(tmp_path: Path) -> None:
    """Each object's support and what it sinks into are looked for only among the objects under its x-y bounds: 200
    objects spread out load in well under a second (every other object was measured: seconds, quadratic)."""
    import time

    path = _with_objects(tmp_path, _objects(196, stacked=False))
    started = time.monotonic()
    task = load_task(path)
    assert len(task.objects) == 200 and time.monotonic() - started < 1.0
    floating = _with_objects(tmp_path, [{"name": "up", "shape": "box", "center": [0.2, 0.5, 0.1], "size": [0.04] * 3}])
    with pytest.raises(TaskFileError, match=r"objects\[4\]\(up\).center: floats 0.080 m above"):
        load_task(floating)


@pytest.mark.parametrize(
    ("field", "value", "expected"),
    [
        ("center", "[1.0e+308, 0.12, 0.1]", "center[0]: Input should be less than or equal to 1000 (got 1e+308)"),
        ("size", "[1.0e+308, 0.06, 0.2]", "size[0]: Input should be less than or equal to 1000 (got 1e+308)"),
        ("mass", "1.0e+308", "mass: Input should be less than or equal to 100000 (got 1e+308)"),
    ],
)
def test_a_coordinate_or_size_out_of_all_proportion_is_one_clean_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], field: str, value: str, expected: str
) -> None:
    """A centre of 1e308 m made the geometry checks overflow: numpy's RuntimeWarnings (host paths, source lines)
    printed before the error."""
    data = yaml.safe_load(_task_text())
    milk = next(o for o in data["objects"] if o["name"] == "milk")
    milk[field] = yaml.safe_load(value)
    path = tmp_path / "huge.yaml"
    path.write_text(yaml.safe_dump(data))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        err = _one_line_error(capsys, ["describe", str(path)], _status(["describe", str(path)]))
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)]
    assert err.endswith(f"(milk).{expected}"), err
