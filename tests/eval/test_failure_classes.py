"""The error classifier on hand-built rollouts of each class, and the key-concept matching rule."""

from __future__ import annotations

from typing import Any

import pytest

from robotool import tasks
from robotool.eval.failure_classes import TaskFacts, classify, run_class, tools_used
from robotool.eval.grading import grade, matches
from robotool.eval.reference import BUILTIN_TOOLS
from robotool.rollout import Event, Rollout, SkillCall
from robotool.task.concepts import KeyConcept, key_concepts, needs_tool


def call(skill: str, *args: Any, outcome: str = "done", reason: str | None = None, **measured: float) -> SkillCall:
    return SkillCall(skill=skill, args=list(args), outcome=outcome, reason=reason, measured=measured)


def rollout(
    *calls: SkillCall, success: bool = False, error: str | None = None, events: tuple[Event, ...] = ()
) -> Rollout:
    return Rollout(
        world=0,
        seed=0,
        success=success,
        calls=list(calls),
        error=error,
        events=list(events),
        conditions={"goal": success},
    )


def facts(name: str, known_tools: bool = True) -> TaskFacts:
    task = tasks.load(name)
    return TaskFacts.of(task, needs_tool=needs_tool(task), needed=BUILTIN_TOOLS[name] if known_tools else None)


P = [1.0, 0.0, 0.34]
CASES: dict[str, tuple[str, Rollout, str | None]] = {
    "reached the goal": (
        "sofa_traversing",
        rollout(call("push_to_position", "surfboard", P), call("walk_to_position", P), success=True),
        None,
    ),
    "program raised": ("sofa_traversing", rollout(call("get_position", "surfboard"), error="NameError: x"), "invalid"),
    "call ended in error": ("milk_reaching", rollout(call("get_center", "spoon", outcome="error")), "invalid"),
    "no tool where one is needed": (
        "sofa_traversing",
        rollout(
            call("get_position", "sofa_2"),
            call("walk_to_position", P, outcome="refused", reason="gap of 0.40 m exceeds the limit of 0.10 m"),
        ),
        "tool_use",
    ),
    "the wrong tool (cloth cannot bridge)": (
        "sofa_traversing",
        rollout(call("push_to_position", "strip_of_cloth", P), call("walk_to_position", P)),
        "tool_use",
    ),
    "a tool where none is needed": (
        "sofa_traversing_small_gap",
        rollout(call("push_to_position", "surfboard", P), call("walk_to_position", P, outcome="stalled")),
        "tool_use",
    ),
    "refused step (constraint ignored)": (
        "sofa_climbing",
        rollout(
            call("get_position", "box_1"),
            call("get_position", "box_2"),
            call("climb_to_position", P, outcome="refused", reason="step up of 0.22 m exceeds the limit of 0.12 m"),
        ),
        "logical",
    ),
    "missing step (chair never moved)": (
        "cube_lifting",
        rollout(call("get_position", "surfboard"), call("climb_to_position", P)),
        "logical",
    ),
    "no motion at all": ("milk_reaching", rollout(call("get_graspable_point", "hammer")), "logical"),
    "target clamped to the workspace": (
        "milk_reaching",
        rollout(
            call("get_graspable_point", "hammer"),
            call("move_to_position", P),
            events=(Event(kind="clamped", call=1, limit="workspace", measured={"outside_workspace": 0.2}),),
        ),
        "numerical",
    ),
    "grasp held nothing": (
        "milk_reaching_near",
        rollout(
            call("get_graspable_point", "milk"),
            call("move_to_position", P),
            call("close_gripper"),
            events=(Event(kind="grasp_failed", call=2, object="milk", cause="on_top"),),
        ),
        "numerical",
    ),
    "push stalled": (
        "sofa_traversing",
        rollout(call("push_to_position", "surfboard", P, outcome="stalled"), call("walk_to_position", P)),
        "numerical",
    ),
    "goal missed by distance": (
        "sofa_traversing",
        rollout(call("push_to_position", "surfboard", P), call("walk_to_position", P)),
        "numerical",
    ),
}


@pytest.mark.parametrize("case", list(CASES))
def test_classifier_labels_hand_built_rollouts(case: str) -> None:
    name, world, expected = CASES[case]
    assert classify(world, facts(name)) == expected


def test_without_reference_tools_any_tool_counts() -> None:
    wrong_tool = CASES["the wrong tool (cloth cannot bridge)"][1]
    assert classify(wrong_tool, facts("sofa_traversing", known_tools=False)) == "numerical"


def test_tools_used_counts_named_and_held_objects_but_not_the_target_or_fixed_ones() -> None:
    world = rollout(
        call("get_graspable_point", "milk"),
        call("move_to_position", P),
        call("close_gripper"),
        events=(Event(kind="grasped", call=2, object="hammer"),),
    )
    assert tools_used(world, facts("milk_reaching")) == {"hammer"}
    climb = rollout(call("get_position", "sofa"), call("get_position", "box_2"), call("climb_to_position", P))
    assert tools_used(climb, facts("sofa_climbing")) == {"box_2"}


def test_classes_read_typed_fields_never_the_reason_text() -> None:
    words_only = rollout(
        call("get_graspable_point", "milk"),
        call("move_to_position", P),
        call("close_gripper", reason="holding hammer; clamped; held nothing"),
    )
    assert tools_used(words_only, facts("milk_reaching")) == set()
    assert classify(words_only, facts("milk_reaching_near")) == "numerical"  # every step done, goal missed
    stalled = rollout(
        call("get_graspable_point", "milk"),
        call("move_to_position", P, outcome="stalled"),
        call("close_gripper"),
        events=(Event(kind="grasped", call=2, object="milk"),),
    )
    assert classify(stalled, facts("milk_reaching_near")) == "numerical"


def test_reference_tools_may_be_fixed_and_are_no_error_where_the_reference_uses_them() -> None:
    stairs = rollout(call("get_position", "box_1"), call("climb_to_position", P))
    assert tools_used(stairs, facts("vase_lowering")) == {"box_1"}  # fixed boxes used as stairs
    lever = TaskFacts.of(tasks.load("sofa_traversing_small_gap"), needs_tool=False, needed=frozenset({"surfboard"}))
    assert classify(rollout(call("push_to_position", "surfboard", P), call("walk_to_position", P)), lever) == (
        "numerical"
    )


def test_run_class_is_the_most_common_failure() -> None:
    assert run_class([None, None]) is None
    assert run_class(["numerical", "logical", "numerical", None]) == "numerical"
    assert run_class(["numerical", "tool_use"]) == "tool_use"  # ties go to the earlier class


def _concept(kind: str, value: float, satisfied: bool, unit: str = "m") -> KeyConcept:
    return KeyConcept(name="x", kind=kind, value=value, unit=unit, limit=0.1, limit_name="l", satisfied=satisfied)


@pytest.mark.parametrize(
    ("predicted", "ok"),
    [
        (_concept("gap_width", 0.40, False), True),
        (_concept("gap_width", 0.43, False), True),  # within 10%
        (_concept("gap_width", 0.45, False), False),
        (_concept("gap_width", 0.40, True), False),  # wrong verdict
        (_concept("climb_height", 0.40, False), False),  # wrong kind
    ],
)
def test_concept_matching_rule(predicted: KeyConcept, ok: bool) -> None:
    assert matches(_concept("gap_width", 0.40, False), predicted) is ok


def test_absolute_tolerance_for_small_values_and_masses() -> None:
    assert matches(_concept("workspace_excess", 0.0, True), _concept("workspace_excess", 0.015, True))
    assert matches(_concept("mass", 10.0, False, "kg"), _concept("mass", 10.9, False, "kg"))
    assert not matches(_concept("mass", 1.0, False, "kg"), _concept("mass", 1.6, False, "kg"))


def test_grade_against_geometry() -> None:
    truth = key_concepts(tasks.load("sofa_traversing"))
    assert grade(truth, truth).correct is True
    assert grade(truth, []).correct is False
    assert grade(truth, None).correct is None  # no Analyzer: not graded
    wrong = [c.model_copy(update={"value": c.value * 2}) for c in truth]
    assert grade(truth, wrong).recovered == [False] * len(truth)
