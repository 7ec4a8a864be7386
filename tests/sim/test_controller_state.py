"""The skill controllers' state contract: all per-world state lives in the dataclasses ``world_states()`` names, and
``restore(snapshot())`` puts all of it back (the runner's undo of a batched tick that raised relies on both)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from robotool.sim.backend import BatchedSim, Perturbation
from robotool.sim.backend_choice import make_sim
from robotool.sim.build import embodiment_for
from robotool.sim.embodiment import SkillController, copy_state

NWORLD = 2
MOVES = {  # a task, and a motion skill that moves every world's robot a while
    "quadruped": ("sofa_traversing", "walk_to_position", ((0.2, 0.0, 0.0),)),
    "arm": ("milk_reaching_near", "move_to_position", ((0.3, 0.1, 0.2),)),
}


def _controller(sim_scene: Any, robot: str) -> tuple[SkillController, BatchedSim]:
    scene = sim_scene(MOVES[robot][0])
    sim = make_sim(scene, NWORLD, backend="mujoco", perturbation=Perturbation.none(scene, NWORLD))
    return embodiment_for(scene.task).controller(sim), sim


def _ticks(controller: SkillController, sim: BatchedSim, n: int) -> None:
    for _ in range(n):
        sim.step(sim.scene.control_substeps, np.ones(NWORLD, dtype=bool))
        controller.tick(sim.state())


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and a.shape == b.shape and bool(np.all((a == b) | ((a != a) & (b != b))))
    if isinstance(a, list | tuple):
        return type(a) is type(b) and len(a) == len(b) and all(map(_same, a, b))
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    return a is b or a == b


def _same_state(a: Any, b: Any) -> list[str]:
    """The fields where dataclasses ``a`` and ``b`` differ."""
    return [f.name for f in dataclasses.fields(a) if not _same(getattr(a, f.name), getattr(b, f.name))]


@pytest.mark.parametrize("robot", sorted(MOVES))
def test_restore_puts_back_every_world_state_a_tick_changed(sim_scene: Any, robot: str) -> None:
    controller, sim = _controller(sim_scene, robot)
    _, skill, args = MOVES[robot]
    sim.step(5, np.ones(NWORLD, dtype=bool))
    controller.start(sim.state(), np.arange(NWORLD), skill, args)
    _ticks(controller, sim, 3)
    snapshot = controller.snapshot()
    before = [copy_state(s) for s in controller.world_states()]
    live = controller.world_states()
    changed: list[str] = []
    for _ in range(80):  # until the move in progress changes the state (the arm's when it ends)
        _ticks(controller, sim, 1)
        changed = [
            n for now, then in zip(controller.world_states(), before, strict=True) for n in _same_state(now, then)
        ]
        if changed:
            break
    assert changed, "the ticks changed nothing: the test would prove nothing"
    controller.restore(snapshot)
    assert all(a is b for a, b in zip(controller.world_states(), live, strict=True)), "restored in place"
    for now, then in zip(controller.world_states(), before, strict=True):
        assert _same_state(now, then) == [], f"{type(now).__name__} not restored"
    _ticks(controller, sim, 1)  # the snapshot is a copy: ticking after the restore leaves it as it was
    controller.restore(snapshot)
    for now, then in zip(controller.world_states(), before, strict=True):
        assert _same_state(now, then) == [], f"{type(now).__name__}: the snapshot shares state with the controller"


def _components(obj: Any, seen: set[int]) -> list[Any]:
    """``obj`` and the robot components it holds, recursively (objects of robotool.robots classes)."""
    if id(obj) in seen:
        return []
    seen.add(id(obj))
    found = [obj]
    for value in vars(obj).values():
        module = type(value).__module__
        if module.startswith("robotool.robots.") and hasattr(value, "__dict__") and not dataclasses.is_dataclass(value):
            found += _components(value, seen)
    return found


ACTIVE = {  # a skill that fills what a component may keep for the skill in progress (a push's rules, a grasp)
    "quadruped": ("push_to_position", ("surfboard", (0.6, 0.0, 0.379))),
    "arm": MOVES["arm"][1:],
}


def _outside_state(controller: SkillController) -> list[str]:
    """Where a component keeps an array, list, dict or set outside the dataclasses ``world_states`` names (a frozen
    dataclass of fixed facts aside), or holds a mutable dataclass that is not one of them."""
    states = controller.world_states()
    found = []
    for component in _components(controller, set()):
        for name, value in vars(component).items():
            where = f"{type(component).__name__}.{name}"
            if isinstance(value, np.ndarray | list | dict | set):
                found.append(f"{where} is state outside a dataclass")
            if dataclasses.is_dataclass(value) and type(value).__module__.startswith("robotool.robots."):
                frozen = type(value).__dataclass_params__.frozen  # type: ignore[attr-defined]
                if not frozen and not any(value is s for s in states):
                    found.append(f"{where} is a dataclass world_states() leaves out")
    return found


@pytest.mark.parametrize("robot", sorted(MOVES))
def test_every_component_keeps_its_per_world_state_in_its_state_dataclass(sim_scene: Any, robot: str) -> None:
    """State kept anywhere but in the dataclasses ``world_states`` names would survive a restore: none right after
    the controller is built, nor once a skill has run a while (an attribute filled lazily, None until the first push,
    shows only then)."""
    controller, sim = _controller(sim_scene, robot)
    states = controller.world_states()
    assert len({id(s) for s in states}) == len(states) and all(dataclasses.is_dataclass(s) for s in states)
    assert _outside_state(controller) == []
    sim.step(5, np.ones(NWORLD, dtype=bool))
    skill, args = ACTIVE[robot]
    ends = controller.start(sim.state(), np.arange(NWORLD), skill, args)
    assert ends == [], "the skill did not start: the test would prove nothing"
    _ticks(controller, sim, 30)
    assert _outside_state(controller) == []
    for state in states:
        for f in dataclasses.fields(state):
            value = getattr(state, f.name)
            assert isinstance(value, np.ndarray | list), f"{type(state).__name__}.{f.name}: not per-world"
            assert len(value) == NWORLD, f"{type(state).__name__}.{f.name}: world index first"


def test_copy_state_copies_nested_containers() -> None:
    @dataclasses.dataclass
    class State:
        events: list[list[str]]
        arrays: np.ndarray

    state = State(events=[["grasp_failed"], []], arrays=np.zeros(2))
    copy = copy_state(state)
    state.events[0].append("again")  # a per-world list grown in place
    state.arrays[1] = 5.0
    assert copy.events == [["grasp_failed"], []] and copy.arrays.tolist() == [0.0, 0.0]
    copy_state(copy, into=state)
    assert state.events == [["grasp_failed"], []] and state.arrays.tolist() == [0.0, 0.0]
