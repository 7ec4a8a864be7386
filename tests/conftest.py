"""Shared test setup: no network, no LM cache, shared models."""

import os

os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")

import dspy  # noqa: E402 - after the environment is set

dspy.configure_cache(enable_disk_cache=False, enable_memory_cache=False)


import functools  # noqa: E402

import pytest  # noqa: E402


@functools.cache
def _scene(task_name: str):  # -> robotool.sim.Scene, imported lazily
    from robotool import sim, tasks

    return sim.build(tasks.load(task_name))


@pytest.fixture(scope="session")
def sim_scene():
    """Build a built-in task's simulation scene once per test run: ``sim_scene("milk_reaching")``."""
    return _scene
