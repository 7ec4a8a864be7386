"""Shared test setup: no network, no LM cache, shared models."""

import functools
import os

os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")

import dspy
import pytest

import robotool  # noqa: F401 - before any test imports mujoco: picks EGL for rendering when there is no display

dspy.configure_cache(enable_disk_cache=False, enable_memory_cache=False)


@pytest.fixture(autouse=True)
def _no_wait_between_lm_retries(monkeypatch: pytest.MonkeyPatch) -> None:
    """In-process LM requests retry at once here instead of after 1, 2, 4 ... s (the stand-in servers answer at
    once); tests/test_lm_retry_waits.py checks the waits themselves."""
    from robotool.program import lm_calls

    monkeypatch.setattr(lm_calls, "_retry_delay", lambda fault, attempt: 0.0)


@functools.cache
def _scene(task_name: str):  # -> robotool.sim.Scene, imported lazily
    from robotool import sim, tasks

    return sim.build(tasks.load(task_name))


@pytest.fixture(scope="session")
def sim_scene():
    """Build a built-in task's simulation scene once per test run: ``sim_scene("milk_reaching")``."""
    return _scene


from collections.abc import Sequence  # noqa: E402
from typing import TYPE_CHECKING, Any  # noqa: E402

if TYPE_CHECKING:
    from robotool.rollout import Rollout
    from robotool.sim import Scene
    from robotool.task.task_model import Task


def _run_texts(task: "Task | Scene", codes: Sequence[str], **kwargs: Any) -> "list[Rollout]":
    from robotool import sandbox, sim

    embodiment = (task.task if isinstance(task, sim.Scene) else task).embodiment
    return sim.run_sessions(task, sandbox.start_sessions(codes, embodiment), **kwargs)


@pytest.fixture(scope="session")
def run_texts():
    """Run program texts through the sandbox in the lockstep runner, one world each:
    ``run_texts(scene_or_task, codes, seed=3, backend="warp")`` (keywords go to ``sim.run_sessions``)."""
    return _run_texts


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--record-budgets",
        action="store_true",
        help="write the test files' measured times (doubled) to tests/time_budgets.json instead of checking them",
    )


def pytest_configure(config: pytest.Config) -> None:
    from time_budget import TimeBudget

    config.pluginmanager.register(TimeBudget(config), "time_budget")
    workers = os.environ.get("PYTEST_XDIST_WORKER_COUNT")
    if workers:  # a pytest-xdist worker: the other workers simulate at the same time
        from robotool.sim.backend_mujoco import share_cores

        share_cores(int(workers))


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Keep ``xdist_group`` working: with ``--dist loadgroup`` pytest-xdist sends the tests whose node ids end in
    ``@group`` to one worker, and marks them by assigning ``item._nodeid``, which pytest 9.2 no longer reads (it
    keeps a structured ``_id``), so every group was silently spread over the workers. In a worker, suffix the ids
    here the way xdist means to (once: an id that already ends so is left alone)."""
    if not getattr(config.option, "loadgroup", False):
        return
    from _pytest.nodeid import coerce_node_id

    for item in items:
        marks = item.iter_markers("xdist_group")
        names = {str(m.args[0] if m.args else m.kwargs.get("name", "default")) for m in marks}
        suffix = "@" + "_".join(sorted(names))
        if names and not item.nodeid.endswith(suffix):
            item._id = coerce_node_id(item.nodeid + suffix)  # type: ignore[attr-defined]
