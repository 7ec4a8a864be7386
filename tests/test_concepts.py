"""Ground-truth key concepts come from geometry and pin the paper's values."""

from __future__ import annotations

import pytest

from robotool import tasks
from robotool.concepts import key_concepts, needs_tool
from robotool.task_file import parse_task


def _concept(name: str, kind: str):
    found = [c for c in key_concepts(tasks.load(name)) if c.kind == kind]
    assert len(found) == 1, key_concepts(tasks.load(name))
    return found[0]


def test_sofa_traversing_gap() -> None:
    gap = _concept("sofa_traversing", "gap_width")
    assert gap.value == pytest.approx(0.40, abs=1e-3)
    assert gap.limit == pytest.approx(0.10)
    assert not gap.satisfied


def test_sofa_climbing_height() -> None:
    climb = _concept("sofa_climbing", "climb_height")
    assert climb.value == pytest.approx(0.34, abs=1e-3)
    assert climb.limit == pytest.approx(0.12)
    assert not climb.satisfied


def test_milk_outside_workspace() -> None:
    reach = _concept("milk_reaching", "workspace_excess")
    assert reach.value == pytest.approx(0.568 - 0.45, abs=1e-3)
    assert not reach.satisfied


def test_cube_heavier_than_push_limit() -> None:
    mass = _concept("cube_lifting", "mass")
    assert mass.value == pytest.approx(10.0)
    assert mass.limit == pytest.approx(5.0)
    assert not mass.satisfied


@pytest.mark.parametrize(
    ("name", "tool"),
    [
        ("milk_reaching", True), ("can_grasping", True), ("button_pressing", True),
        ("sofa_traversing", True), ("sofa_climbing", True), ("cube_lifting", True), ("vase_lowering", True),
        ("milk_reaching_near", False), ("sofa_traversing_small_gap", False), ("sofa_climbing_low_sofa", False),
    ],
)
def test_needs_tool(name: str, tool: bool) -> None:
    assert needs_tool(tasks.load(name)) is tool


def test_concepts_follow_geometry_not_names() -> None:
    """Renaming a task and mirroring its layout leaves the concepts unchanged."""
    data = tasks.load("sofa_traversing").model_dump(mode="json")
    data["name"] = "anything"
    data["robot"]["position"] = [0.5, 0.0]
    for obj in data["objects"]:
        obj["center"][0] = -obj["center"][0]
    mirrored = parse_task(data)
    gap = next(c for c in key_concepts(mirrored) if c.kind == "gap_width")
    assert gap.value == pytest.approx(0.40, abs=1e-3)


def test_limit_override_changes_verdict() -> None:
    data = tasks.load("sofa_traversing").model_dump(mode="json")
    data["robot"]["limits"] = {"max_gap": 0.5}
    assert not needs_tool(parse_task(data))


def test_lifted_goal_needs_a_tool_whatever_the_mass() -> None:
    """A quadruped cannot raise anything by itself: a light cube still needs the lever."""
    data = tasks.load("cube_lifting").model_dump(mode="json")
    next(o for o in data["objects"] if o["name"] == "cube")["mass"] = 2.0
    task = parse_task(data)
    lift = next(c for c in key_concepts(task) if c.kind == "lift_height")
    assert lift.value == pytest.approx(0.10) and not lift.satisfied
    assert next(c for c in key_concepts(task) if c.kind == "mass").satisfied
    assert needs_tool(task)
