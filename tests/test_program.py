"""The RoboTool program end to end with a scripted LM (a labelled test fixture), offline."""

from __future__ import annotations

from pathlib import Path

import dspy
import pytest
from fixtures.scripted_lm import (
    CLIMB_DIRECTLY,
    GRASP_DIRECTLY,
    STAND_STILL,
    arm_script,
    chat_reply,
    quadruped_script,
    scripted_lm,
)

from robotool import tasks
from robotool.methods import METHODS
from robotool.program import RoboTool

CASES = {
    "milk_reaching_near": arm_script([GRASP_DIRECTLY]),
    "sofa_climbing_low_sofa": quadruped_script([CLIMB_DIRECTLY]),
}
STAGES_RUN = {
    "robotool": {"analyzer", "planner", "calculator", "coder"},
    "no_analyzer": {"planner", "calculator", "coder"},
    "no_calculator": {"analyzer", "planner", "coder"},
    "planner_coder": {"planner", "coder"},
    "coder": {"coder"},
}


def _solve(task_name: str, script: dict[str, list[str]], method: str = "robotool", **options):
    lm, engine = scripted_lm(script)
    program = RoboTool.method(method, **{"worlds_per_candidate": 2, **options})
    with dspy.context(lm=lm, adapter=dspy.ChatAdapter(use_json_adapter_fallback=False)):
        solution = program(task=tasks.load(task_name)).solution
    return solution, engine


@pytest.mark.parametrize("method", list(METHODS))
@pytest.mark.parametrize("task_name", list(CASES))
def test_every_method_solves_with_scripted_lm(task_name: str, method: str) -> None:
    solution, engine = _solve(task_name, CASES[task_name], method)
    assert solution.method == method
    assert solution.success and solution.success_rate == 1.0, solution.candidates[0].failure
    assert {stage for stage, n in engine.calls.items() if n} == STAGES_RUN[method]
    assert set(solution.usage) == STAGES_RUN[method]
    assert (solution.stages.key_concepts is not None) == ("analyzer" in STAGES_RUN[method])
    assert (solution.stages.steps is not None) == ("planner" in STAGES_RUN[method])
    assert (solution.stages.parameters is not None) == ("calculator" in STAGES_RUN[method])
    assert solution.code and "get_" in solution.code
    assert len(solution.candidates[0].rollouts) == 2


def test_wrong_candidate_loses_to_right_one() -> None:
    solution, engine = _solve("milk_reaching_near", arm_script([STAND_STILL, GRASP_DIRECTLY]), candidates=2)
    assert engine.calls["analyzer"] == 1  # shared by the candidates
    assert engine.calls["coder"] == 2
    best = solution.candidates[solution.best]
    assert best.code == GRASP_DIRECTLY and best.success_rate == 1.0
    loser = next(c for c in solution.candidates if c.index != solution.best)
    assert loser.success_rate == 0.0 and "goal not reached" in loser.failure


def test_unparsable_reply_fails_only_that_candidate() -> None:
    script = arm_script([GRASP_DIRECTLY])
    script["planner"] = ["I would rather not answer in fields.", script["planner"][0]]
    solution, _ = _solve("milk_reaching_near", script, candidates=2)
    failed = [c for c in solution.candidates if c.failure and c.failure.startswith("planner:")]
    assert len(failed) == 1 and "could not be parsed" in failed[0].failure
    assert solution.success


def test_plan_naming_an_unknown_skill_is_rejected_by_the_model() -> None:
    script = arm_script([GRASP_DIRECTLY])
    script["planner"] = [chat_reply(object_roles=[], abstract_plan="teleport",
                                    steps=[{"skill": "teleport", "objects": ["milk"], "intent": "cheat"}])]
    solution, _ = _solve("milk_reaching_near", script)
    assert not solution.success
    assert "unknown skill 'teleport'" in solution.candidates[0].failure


def test_rejected_code_fails_its_candidate() -> None:
    solution, _ = _solve("milk_reaching_near", arm_script(["import os\nos.system('true')\n"]))
    assert not solution.success
    assert solution.candidates[0].failure.startswith("coder:") and "os" in solution.candidates[0].failure


def test_save_and_load_round_trip(tmp_path: Path) -> None:
    program = RoboTool()
    program.code.signature = program.code.signature.with_instructions("Write short programs.")
    program.save(tmp_path / "program.json")
    loaded = RoboTool()
    loaded.load(tmp_path / "program.json")
    assert loaded.code.signature.instructions == "Write short programs."
    coder_only = RoboTool.method("coder")
    coder_only.load(tmp_path / "program.json")  # extra stages in the file are ignored
    assert coder_only.code.signature.instructions == "Write short programs."
    assert [name for name, _ in coder_only.named_predictors()] == ["code"]


def test_calculator_without_planner_is_refused() -> None:
    with pytest.raises(ValueError, match="Planner"):
        RoboTool(planner=False, calculator=True)
