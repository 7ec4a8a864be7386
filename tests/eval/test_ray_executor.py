"""The evaluator on the Ray executor: same results folder as the local executor, no run lost to a dead worker."""

from __future__ import annotations

import io
import json
import logging
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from fixtures.standin_solution import standin_solution
from rich.console import Console

from robotool.cli.eval_command import main
from robotool.errors import LMUnavailableError
from robotool.eval import EvalConfig, EvalError, RunsNotAttempted, Settings, evaluate
from robotool.eval.journal import JOURNAL
from robotool.eval.solvers import planner_missing
from robotool.program.lm import make_lm
from robotool.program.standin import Script, StandinServer
from robotool.solution import Solution
from robotool.task.task_model import Task

TESTS = Path(__file__).parents[1]
REPO = TESTS.parent
pytestmark = pytest.mark.xdist_group("ray")  # one worker starts one local Ray (local_ray) for every test here


@pytest.fixture(scope="module")
def local_ray() -> Iterator[None]:
    """A Ray on this machine with 2 CPUs; its workers import this folder's modules (the test solvers)."""
    ray = pytest.importorskip("ray")
    path = os.pathsep.join(p for p in (str(TESTS), str(REPO), os.environ.get("PYTHONPATH", "")) if p)
    ray.init(num_cpus=2, include_dashboard=False, object_store_memory=80 * 2**20, logging_level=logging.ERROR,
             log_to_driver=False, runtime_env={"env_vars": {"PYTHONPATH": path}})
    try:
        yield
    finally:
        ray.shutdown()


def _quiet() -> Console:
    return Console(file=io.StringIO(), width=200)


VOLATILE = {"wall_s", "timings"}


def _comparable(results_json: Path) -> dict[str, object]:
    """results.json without what differs between two identical evaluations: wall times and the folder."""

    def strip(value: object) -> object:
        if isinstance(value, dict):
            return {k: strip(v) for k, v in value.items() if k not in VOLATILE}
        if isinstance(value, list):
            return [strip(v) for v in value]
        return value

    data = json.loads(results_json.read_text())
    data["config"].pop("out")
    return strip(data)  # type: ignore[return-value]


@pytest.mark.skipif(planner_missing() is not None, reason="the search planner is not in this checkout")
@pytest.mark.slow
def test_ray_sweep_writes_the_same_results_as_the_local_executor(tmp_path: Path, local_ray: None) -> None:
    tasks = ["milk_reaching_near", "sofa_traversing_small_gap"]  # an arm and a quadruped task, each quick to plan
    sweep = ["--tasks", *tasks, "--methods", "search", "no_tool", "--worlds", "1"]
    assert main([*sweep, "--out", str(tmp_path / "local")]) == 0
    assert main([*sweep, "--executor", "ray", "--out", str(tmp_path / "ray")]) == 0
    local, on_ray = _comparable(tmp_path / "local" / "results.json"), _comparable(tmp_path / "ray" / "results.json")
    assert len(on_ray["records"]) == 4  # type: ignore[arg-type]
    assert on_ray == local
    for name in ("journal.jsonl", "settings.json"):
        assert (tmp_path / "local" / name).read_text().count("\n") == (tmp_path / "ray" / name).read_text().count("\n")
    assert (tmp_path / "local" / "settings.json").read_text() == (tmp_path / "ray" / "settings.json").read_text()


@dataclass(frozen=True)
class DiesOnRay:
    """TEST FIXTURE solver: logs every call to ``log``, kills its own (Ray worker) process the first
    ``deaths[task]`` times it is called for a task, otherwise returns the stand-in solution after ``pause_s``."""

    log: Path
    deaths: Mapping[str, int] = field(default_factory=dict)
    pause_s: float = 0.3

    def __call__(self, task: Task, *, seed: int, run: int) -> Solution:
        with self.log.open("a") as f:
            f.write(f"{task.name}\n")
        calls = self.log.read_text().splitlines().count(task.name)
        if calls <= self.deaths.get(task.name, 0):
            os.kill(os.getpid(), signal.SIGKILL)
        time.sleep(self.pause_s)
        return standin_solution(task, seed=seed, run=run)


@pytest.mark.slow
def test_killed_ray_workers_lose_no_run(tmp_path: Path, local_ray: None) -> None:
    logs = {m: tmp_path / f"{m}.log" for m in ("search", "no_tool")}
    solvers = {
        "search": DiesOnRay(logs["search"], deaths={"milk_reaching": 1}),  # dies once: the retry finishes it
        "no_tool": DiesOnRay(logs["no_tool"], deaths={"sofa_traversing": 9}),  # dies on every attempt
    }
    from robotool.eval.ray_executor import RayExecutor

    config = EvalConfig(out=tmp_path / "out", tasks=["sofa_traversing", "milk_reaching", "milk_reaching_near"],
                        methods=["search", "no_tool"], settings=Settings(worlds=1))
    with RayExecutor() as executor:
        results = evaluate(config, solvers=solvers, console=_quiet(), executor=executor)

    by_run = {(r.key.task, r.key.method): r for r in results.records}
    assert len(by_run) == 6 and len({r.key.id for r in results.records}) == 6
    lost = by_run[("sofa_traversing", "no_tool")]
    assert lost.failure_class is None and lost.success_rate == 0.0  # an internal error: left out of the tables
    assert lost.internal_error is not None and lost.internal_error.reason.startswith("WorkerLost: ")
    assert "WorkerLost" in (lost.error or "") and "lost on all 2 attempts" in (lost.error or "")
    assert all(r.success_rate == 1.0 and r.error is None for r in by_run.values() if r is not lost)
    assert sorted(logs["search"].read_text().split()) == ["milk_reaching", "milk_reaching", "milk_reaching_near",
                                                          "sofa_traversing"]  # only the killed run ran twice
    assert sorted(logs["no_tool"].read_text().split()) == ["milk_reaching", "milk_reaching_near", "sofa_traversing",
                                                           "sofa_traversing"]  # one retry, then recorded
    journal = [json.loads(line)["key"] for line in (tmp_path / "out" / JOURNAL).read_text().splitlines()]
    assert sorted((k["task"], k["method"]) for k in journal) == sorted(by_run)

    with RayExecutor() as executor:  # resuming reuses every recorded run, the lost one included
        again = evaluate(config, solvers=solvers, console=_quiet(), executor=executor)
    assert [r.key.id for r in again.records] == [r.key.id for r in results.records]
    assert len(logs["search"].read_text().split()) == 4 and len(logs["no_tool"].read_text().split()) == 4


@pytest.mark.slow
def test_lm_runs_on_ray_match_the_local_executor_over_http(tmp_path: Path, local_ray: None) -> None:
    """The LM travels with the Ray task and its workers call the stand-in server over HTTP."""
    from robotool.eval.ray_executor import RayExecutor

    example = REPO / "examples" / "standin" / "milk_reaching.json"
    with StandinServer(Script.model_validate_json(example.read_text())) as server:
        lm = make_lm("openai/standin", api_base=server.base_url, cache=False, num_retries=1)
        config = EvalConfig(tasks=["milk_reaching"], methods=["robotool"], settings=Settings(worlds=1),
                            api_base=server.base_url)
        local = evaluate(config.model_copy(update={"out": tmp_path / "local"}), lm=lm, console=_quiet())
        asked = len(server.requests)
        with RayExecutor() as executor:
            evaluate(config.model_copy(update={"out": tmp_path / "ray"}), lm=lm, console=_quiet(), executor=executor)
        assert len(server.requests) == 2 * asked > 0  # the Ray worker asked the server as the local run did
    assert local.records[0].success_rate == 1.0 and local.records[0].tokens > 0
    assert _comparable(tmp_path / "ray" / "results.json") == _comparable(tmp_path / "local" / "results.json")


def test_a_worker_with_another_robotool_version_stops_the_sweep(tmp_path: Path, local_ray: None,
                                                               monkeypatch) -> None:
    from robotool.eval import ray_executor

    monkeypatch.setattr(ray_executor, "version", lambda: "0.0.0+driver")  # this machine, as seen by the executor
    config = EvalConfig(out=tmp_path / "out", tasks=["sofa_traversing"], methods=["search"],
                        settings=Settings(worlds=1))
    mismatch = r"a Ray task failed: a Ray worker runs robotool .*, this machine 0\.0\.0\+driver"
    with ray_executor.RayExecutor() as executor, pytest.raises(EvalError, match=mismatch):
        evaluate(config, solvers={"search": standin_solution}, console=_quiet(), executor=executor)
    assert not (tmp_path / "out" / JOURNAL).exists() or not (tmp_path / "out" / JOURNAL).read_text()


def unavailable(task: Task, *, seed: int, run: int) -> Solution:
    """TEST FIXTURE solver: the language model cannot be reached."""
    raise LMUnavailableError("unreachable", "the LM server at http://127.0.0.1:9 does not answer")


def test_runs_without_an_lm_on_ray_are_not_recorded(tmp_path: Path, local_ray: None) -> None:
    from robotool.eval.ray_executor import RayExecutor

    config = EvalConfig(out=tmp_path / "out", tasks=["sofa_traversing"], methods=["search", "no_tool"],
                        settings=Settings(worlds=1))
    with RayExecutor() as executor, pytest.raises(RunsNotAttempted, match="1 of 2 run") as caught:
        evaluate(config, solvers={"search": standin_solution, "no_tool": unavailable}, console=_quiet(),
                 executor=executor)
    assert caught.value.cause.kind == "unreachable"
    lines = (tmp_path / "out" / JOURNAL).read_text().splitlines()
    assert [json.loads(line)["key"]["method"] for line in lines] == ["search"]


def test_on_a_cluster_with_gpus_runs_use_warp_with_a_gpu_share(monkeypatch, local_ray: None) -> None:
    from robotool.eval.ray_executor import JOBS_PER_GPU, RayExecutor, task_options

    with RayExecutor() as executor:
        assert executor.backend(None) == "mujoco"  # this machine's Ray has no GPU
        monkeypatch.setattr(executor, "_resources", lambda: {"CPU": 64.0, "GPU": 8.0})
        assert executor.backend(None) == "warp" and executor.backend("mujoco") == "mujoco"
    gpus = {"CPU": 64.0, "GPU": 8.0}
    assert task_options("warp", gpus) == {"num_cpus": 1, "num_gpus": 1 / JOBS_PER_GPU, "max_retries": 0}
    assert task_options("mujoco", gpus)["num_gpus"] == 0 and task_options("warp", {"CPU": 2.0})["num_gpus"] == 0


def test_ray_executor_without_ray_says_how_to_install(tmp_path: Path, capsys, monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # as if Ray were not installed
    assert main(["--executor", "ray", "--tasks", "sofa_traversing", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "error: the Ray executor needs Ray, which is not installed: pip install 'robotool[ray]'"


@pytest.mark.parametrize(("argv", "message"), [
    (["--address", "auto"], "--address needs --executor ray"),
    (["--executor", "ray", "--address", "127.0.0.1:1"], "cannot reach the Ray cluster at 127.0.0.1:1"),
    (["--executor", "ray", "--address", "head-node"], "a Ray cluster address is auto, HOST:PORT or ray://HOST:PORT"),
    (["--executor", "dask"], "invalid choice: 'dask'"),
    (["--executor", "ray", "--log-prompts", "prompts.jsonl"], "--log-prompts writes a file on this machine"),
])
def test_bad_executor_arguments_give_one_line_and_status_2(argv: list[str], message: str, tmp_path: Path,
                                                           capsys) -> None:
    if "127.0.0.1:1" in argv or "head-node" in argv:
        pytest.importorskip("ray")
    try:
        status = main([*argv, "--tasks", "sofa_traversing", "--out", str(tmp_path)])
    except SystemExit as e:
        status = e.code
    err = capsys.readouterr().err.strip()
    assert status == 2 and message in err and "\n" not in err


KILLABLE_ON_RAY = """
import logging, sys, time
sys.path.insert(0, {tests!r})
from pathlib import Path
import ray
from rich.console import Console
from robotool.eval import EvalConfig, Settings, evaluate
from robotool.eval.ray_executor import RayExecutor
from fixtures.standin_solution import standin_solution

def slow(task, *, seed, run):
    time.sleep(0.5)
    return standin_solution(task, seed=seed, run=run)

ray.init(num_cpus=2, include_dashboard=False, object_store_memory=80 * 2**20, logging_level=logging.ERROR,
         log_to_driver=False, runtime_env={{"env_vars": {{"PYTHONPATH": {path!r}}}}})
config = EvalConfig(out=Path({out!r}), tasks=["sofa_traversing", "milk_reaching"], methods=["search", "no_tool"],
                    runs=3, settings=Settings(worlds=1))
evaluate(config, solvers={{"search": slow, "no_tool": slow}}, console=Console(quiet=True), executor=RayExecutor())
"""


@pytest.mark.slow
def test_sigkill_of_a_ray_sweep_then_rerun_records_every_run_once(tmp_path: Path) -> None:
    pytest.importorskip("ray")
    out = tmp_path / "out"
    path = os.pathsep.join(p for p in (str(TESTS), str(REPO), os.environ.get("PYTHONPATH", "")) if p)
    script = KILLABLE_ON_RAY.format(tests=str(TESTS), out=str(out), path=path)
    journal = out / JOURNAL
    process = subprocess.Popen([sys.executable, "-c", script])
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not (journal.exists() and len(journal.read_text().splitlines()) >= 3):
        time.sleep(0.05)
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    before = [json.loads(line)["key"] for line in journal.read_text().splitlines() if line.endswith("}")]
    assert 3 <= len(before) < 12

    calls: list[str] = []

    def counts(task: Task, *, seed: int, run: int) -> Solution:
        calls.append(task.name)
        return standin_solution(task, seed=seed, run=run)

    config = EvalConfig(out=out, tasks=["sofa_traversing", "milk_reaching"], methods=["search", "no_tool"], runs=3,
                        settings=Settings(worlds=1))
    results = evaluate(config, solvers={"search": counts, "no_tool": counts}, console=_quiet())  # local executor
    assert len(calls) == 12 - len(before)  # what the Ray sweep finished is reused, not redone
    ids = [r.key.id for r in results.records]
    assert len(ids) == 12 and len(set(ids)) == 12
    assert len(journal.read_text().splitlines()) == 12
