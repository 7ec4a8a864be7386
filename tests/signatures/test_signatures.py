"""The stage output models: lenient where a reply's meaning is clear, strict where it matters."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from robotool import robots, tasks
from robotool.sandbox import ProgramRejected, validate
from robotool.signatures import AnalyzedConcept, Code, PlanStep, Repair, StepParameters, scene_context, validation_notes
from robotool.signatures.models import parse_quantity

QUADRUPED = tasks.load("sofa_climbing_low_sofa")
ARM = tasks.load("milk_reaching_near")


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        (0.4, (0.4, None)),
        ("0.4", (0.4, None)),
        ("0.4 m", (0.4, "m")),
        ("40cm", (0.4, "m")),
        ("-25 mm", (-0.025, "m")),
        ("2 kg", (2.0, "kg")),
        ("500 g", (0.5, "kg")),
        ("1,200 mm", (1.2, "m")),
        ("1e-1 metres", (0.1, "m")),
    ],
)
def test_numbers_may_carry_units(text: object, expected: tuple[float, str | None]) -> None:
    number, unit = parse_quantity(text)
    assert number == pytest.approx(expected[0]) and unit == expected[1]


@pytest.mark.parametrize("text", ["nan", "-inf", float("inf"), "about 3 m", "3 furlongs", True, None, [1.0]])
def test_non_numbers_and_non_finite_numbers_are_rejected(text: object) -> None:
    with pytest.raises(ValueError):
        parse_quantity(text)


def test_concept_in_centimetres_becomes_metres_and_a_missing_verdict_is_read_from_the_limit() -> None:
    with validation_notes() as sink:
        concept = AnalyzedConcept.model_validate(
            {"name": "height to climb", "kind": "Climb height", "value": "10 cm", "limit": "0.12 m"}
        )
    assert (concept.kind, concept.value, concept.unit, concept.limit) == ("climb_height", 0.1, "m", 0.12)
    assert concept.satisfied is True and concept.limit_name == ""
    assert any("no verdict" in note for note in sink.notes)
    too_high = AnalyzedConcept.model_validate({"name": "h", "value": 0.3, "limit": 0.12, "satisfied": None})
    assert too_high.satisfied is False


def test_concept_with_mixed_units_is_rejected() -> None:
    with pytest.raises(ValidationError, match="different units"):
        AnalyzedConcept.model_validate({"name": "m", "value": "3 kg", "limit": "0.1 m", "satisfied": True})


def test_two_number_targets_are_padded_for_the_quadruped_only() -> None:
    with scene_context(QUADRUPED, robots.get(QUADRUPED.embodiment)):
        step = StepParameters(step=1, object="sofa", target=["1.2 m", 0.5])
        assert step.target == [1.2, 0.5, 0.0]
        assert StepParameters(step=1, relative_to="sofa", offset=[0.1, 0]).offset == [0.1, 0.0, 0.0]
    with scene_context(ARM, robots.get(ARM.embodiment)), pytest.raises(ValidationError, match="three numbers"):
        StepParameters(step=1, object="milk", target=[0.3, 0.0])


def test_informational_names_are_dropped_with_a_note_but_acted_on_objects_must_exist() -> None:
    with scene_context(QUADRUPED, robots.get(QUADRUPED.embodiment)), validation_notes() as sink:
        step = PlanStep(skill="climb_to_position", objects=["gap", "sofa"], intent="climb")
        assert step.objects == ["sofa"] and "'gap'" in sink.notes[0]
        with pytest.raises(ValidationError, match="unknown object"):
            StepParameters(step=1, object="gap", target=[1.0, 0.0, 0.0])
        with pytest.raises(ValidationError, match="unknown skill 'jump'"):
            PlanStep(skill="jump", objects=["sofa"], intent="jump")


@pytest.mark.parametrize("value", [float("nan"), float("inf"), "NaN", "-Infinity"])
def test_key_concepts_with_non_finite_numbers_are_rejected(value: object) -> None:
    with pytest.raises(ValidationError, match="finite"):
        AnalyzedConcept.model_validate({"name": "x", "value": value, "limit": 0.1, "satisfied": True})


def test_a_skill_written_as_a_call_names_the_skill() -> None:
    with scene_context(ARM, robots.get(ARM.embodiment)):
        assert PlanStep(skill=" move_to_position([0.1, 0, 0.2]) ", objects=[]).skill == "move_to_position"
        assert PlanStep(skill="open_gripper()").skill == "open_gripper"
        with pytest.raises(ValidationError, match="unknown skill"):
            PlanStep(skill="os.system('ls')")


def test_plain_numbers_in_the_unit_the_concept_names_become_si() -> None:
    concept = AnalyzedConcept.model_validate(
        {"name": "gap", "kind": "gap_width", "value": 40, "limit": 10, "unit": "cm", "satisfied": False}
    )
    assert (concept.value, concept.limit, concept.unit) == (0.4, 0.1, "m")


@pytest.mark.parametrize("signature", [Code, Repair], ids=["coder", "repair"])
def test_the_program_prompts_and_the_sandbox_agree_on_what_a_program_may_contain(signature) -> None:
    """What the Coder and Repair prompts allow the sandbox accepts, and what they forbid it refuses."""
    instructions = " ".join(signature.instructions.split())
    allowed = {"Helper functions (def) are allowed": "def reach(name):\n    move_to_position(get_center(name))\n"}
    forbidden = {
        "classes": ("class Plan:\n    pass\n", "class definitions"),
        "try/except": ("try:\n    open_gripper()\nexcept Exception:\n    pass\n", "try/except"),
        "with statements": ("with x:\n    pass\n", "with statements"),
        "generators": ("def steps():\n    yield 1\n", "yield"),
    }
    for phrase, program in allowed.items():
        assert phrase in instructions
        validate(program + "reach('milk')\n", "arm")
    for phrase, (program, refusal) in forbidden.items():
        assert phrase in instructions.split("are allowed;")[1]
        with pytest.raises(ProgramRejected, match=refusal):
            validate(program, "arm")


def test_object_names_match_case_space_and_separator_insensitively_when_one_object_fits() -> None:
    traversing = tasks.load("sofa_traversing")  # sofa_1, sofa_2, strip_of_cloth, surfboard
    with scene_context(traversing, robots.get(traversing.embodiment)), validation_notes() as sink:
        step = PlanStep(skill="push_to_position", objects=["Surfboard", "Sofa 1", "sofa-2", "Strip of Cloth", "Sofa"])
        parameters = StepParameters(step=1, object="Surfboard", relative_to="SOFA_2", offset=[0.0, 0.0, 0.0])
    assert step.objects == ["surfboard", "sofa_1", "sofa_2", "strip_of_cloth"]  # "Sofa" fits two objects: not guessed
    assert parameters.object == "surfboard" and parameters.relative_to == "sofa_2"
    assert "object 'Surfboard' read as 'surfboard'" in sink.notes
    assert any("'Sofa', not object(s) of the scene" in note for note in sink.notes)


@pytest.mark.parametrize(
    ("written", "kind"),
    [
        ("gap", "gap_width"),
        ("Gap", "gap_width"),
        ("gap width", "gap_width"),
        ("reach", "workspace_excess"),
        ("weight", "mass"),
        ("step-up", "climb_height"),
        ("drop", "drop_height"),
        ("other", "other"),
    ],
)
def test_concept_kinds_are_read_by_meaning(written: str, kind: str) -> None:
    concept = {"name": "x", "kind": written, "value": 0.1, "limit": 0.2, "satisfied": True}
    assert AnalyzedConcept.model_validate(concept).kind == kind


@pytest.mark.parametrize("written", ["friction", "height", "gap or climb"])
def test_a_concept_kind_that_names_no_kind_or_several_is_asked_for_again(written: str) -> None:
    concept = {"name": "x", "kind": written, "value": 0.1, "limit": 0.2, "satisfied": True}
    with pytest.raises(ValidationError, match=f"kind {written!r} is not one of"):
        AnalyzedConcept.model_validate(concept)


def test_step_parameter_synonyms_are_read_and_a_step_without_numbers_is_rejected() -> None:
    with scene_context(ARM, robots.get(ARM.embodiment)), validation_notes() as sink:
        read = StepParameters.model_validate({"step": 2, "object": "milk", "position": [0.3, 0.0, 0.1]})
        with pytest.raises(ValidationError, match="both 'target' and 'position'"):
            StepParameters.model_validate({"step": 2, "target": [0.3, 0.0, 0.1], "position": [0.3, 0.0, 0.2]})
        with pytest.raises(ValidationError, match="step 2 has no numbers"):
            StepParameters.model_validate({"step": 2, "object": "milk", "target": None, "offset": None})
    assert read.target == [0.3, 0.0, 0.1] and "step parameter 'position' read as 'target'" in sink.notes
