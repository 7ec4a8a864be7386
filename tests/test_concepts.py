"""Ground-truth key concepts come from geometry and pin the paper's values."""

from __future__ import annotations

import pytest

from robotool import tasks
from robotool.task.concepts import key_concepts, needs_tool
from robotool.task.task_file import parse_task


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


BUILTIN_CONCEPTS = {
    "milk_reaching": [("workspace_excess", 0.118, False)],
    "milk_reaching_near": [("workspace_excess", 0.0, True)],
    "can_grasping": [("workspace_excess", 0.25, False)],
    "button_pressing": [("workspace_excess", 0.05, False)],
    "sofa_traversing": [("gap_width", 0.40, False)],
    "sofa_traversing_small_gap": [("gap_width", 0.08, True)],
    "sofa_climbing": [("climb_height", 0.34, False)],
    "sofa_climbing_low_sofa": [("climb_height", 0.10, True)],
    "cube_lifting": [("lift_height", 0.10, False), ("mass", 10.0, False)],
    "vase_lowering": [("climb_height", 0.34, False), ("fall_height", 0.34, False), ("mass", 0.5, True)],
}
"""Every built-in task's key concepts (kind, value, satisfied): the ground truth the Analyzer is graded on."""


@pytest.mark.parametrize("name", sorted(BUILTIN_CONCEPTS))
def test_builtin_concepts_are_pinned(name: str) -> None:
    got = [(c.kind, c.value, c.satisfied) for c in key_concepts(tasks.load(name))]
    assert [k for k, _, _ in got] == [k for k, _, _ in BUILTIN_CONCEPTS[name]]
    for (_, value, satisfied), (_, want, ok) in zip(got, BUILTIN_CONCEPTS[name], strict=True):
        assert value == pytest.approx(want, abs=1e-3) and satisfied is ok


def _sofas_apart(gap: float) -> dict:
    data = tasks.load("sofa_traversing").model_dump(mode="json")
    sofa_2 = next(o for o in data["objects"] if o["name"] == "sofa_2")
    sofa_2["center"][0] += gap - 0.40
    return data


@pytest.mark.parametrize(("gap", "concept"), [(0.04, None), (0.09, True), (0.25, False), (0.55, False)])
def test_the_gap_is_the_one_the_terrain_model_finds_under_the_feet(gap: float, concept: bool | None) -> None:
    """The simulator's terrain model measures the gap (a slit narrower than a foot carries it: no gap at all)."""
    found = [c for c in key_concepts(parse_task(_sofas_apart(gap))) if c.kind == "gap_width"]
    if concept is None:
        assert found == []
    else:
        (c,) = found
        assert c.value == pytest.approx(gap, abs=0.011) and c.satisfied is concept


def test_a_robot_with_longer_strides_is_judged_by_the_same_limit_rule() -> None:
    data = _sofas_apart(0.25)
    data["robot"]["limits"] = {"max_gap": 0.245}  # within the terrain's measurement tolerance
    assert not needs_tool(parse_task(data))
    data["robot"]["limits"] = {"max_gap": 0.2}
    assert needs_tool(parse_task(data))
