"""The quadruped on mujoco_warp (Warp's CPU device): the reference program of every built-in quadruped task that
needs a tool and its tool-free program, side by side in one batch per task.

Two reference worlds per task (the C backend's tests run more): Warp on CPU is slow, and what is checked here is that
the Warp backend judges the same programs the same way, not how often a program holds under perturbation. The
variants solved without a tool (a narrower gap walked across, a lower sofa climbed) are left to the C backend's
tests: their walk and climb are those of the tool tasks' programs, which run here.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from typing import Any

import pytest
from fixtures.reference import REFERENCE, TOOL_FREE, program
from fixtures.warp_group import ON_WARP

from robotool import tasks
from robotool.rollout import Rollout
from robotool.sim.backend import Perturbation
from robotool.task.concepts import needs_tool

if importlib.util.find_spec("mujoco_warp") is None:  # not imported here: collecting stays quick where deselected
    pytest.skip("mujoco_warp is not installed", allow_module_level=True)
pytestmark = [pytest.mark.slow, ON_WARP]  # Warp compiles its kernels on the CPU first

QUADRUPED_TASKS = [t for t in REFERENCE if tasks.load(t).robot.type == "quadruped" and needs_tool(tasks.load(t))]
WORLDS = 2  # reference worlds per task
SEED = 5

TOOL_FREE_REFUSAL = {  # task -> (the refused skill, its measured key, the value; None: the world's cube mass)
    "sofa_traversing": ("walk_to_position", "gap", 0.30),  # beyond the end of the overhanging board
    "sofa_climbing": ("climb_to_position", "step", 0.34),
    "cube_lifting": ("push_to_position", "mass", None),
}


@pytest.fixture(scope="session")
def warp_batch(sim_scene: Any, run_texts: Any) -> Callable[[str], list[Rollout]]:
    """``warp_batch(task)``: the reference program's worlds, then the tool-free program's (if any), on Warp (once: the
    Warp tests share one xdist worker)."""
    cache: dict[str, list[Rollout]] = {}

    def batch(task: str) -> list[Rollout]:
        if task not in cache:
            programs = [program(REFERENCE[task])] * WORLDS
            programs += [program(TOOL_FREE[task])] if task in TOOL_FREE else []
            cache[task] = run_texts(sim_scene(task), programs, seed=SEED, backend="warp")
        return cache[task]

    return batch


@pytest.mark.parametrize("task", QUADRUPED_TASKS)
def test_reference_program_solves_its_task_on_warp(warp_batch: Callable[[str], list[Rollout]], task: str) -> None:
    rollouts = warp_batch(task)[:WORLDS]
    assert all(r.success for r in rollouts), [
        [(c.skill, c.outcome, c.reason) for c in r.calls if c.outcome != "done"] or r.conditions
        for r in rollouts
        if not r.success
    ]


@pytest.mark.parametrize("task", sorted(TOOL_FREE_REFUSAL))
def test_tool_free_program_is_refused_with_the_measured_value_on_warp(
    sim_scene: Any, warp_batch: Callable[[str], list[Rollout]], task: str
) -> None:
    skill, key, value = TOOL_FREE_REFUSAL[task]
    direct = warp_batch(task)[-1]
    if value is None:  # the cube's mass in that world, perturbed
        scene = sim_scene(task)
        value = Perturbation.sample(scene, WORLDS + 1, SEED).mass_scale[WORLDS, scene.object_index("cube")] * 10.0
    refused = [c for c in direct.calls if c.outcome == "refused"]
    assert not direct.success and [c.skill for c in refused] == [skill]
    assert refused[0].measured[key] == pytest.approx(value, abs=0.02)
