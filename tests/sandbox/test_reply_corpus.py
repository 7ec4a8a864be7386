"""Replies shaped like real models' (a labelled fixture corpus), through the real HTTP path to the stand-in."""

from __future__ import annotations

import dspy
import pytest
from fixtures.reply_corpus import CASES, CONCEPT, Case
from fixtures.scripted_lm import GRASP_DIRECTLY, STAGE_MARKERS, arm_script

from robotool import tasks
from robotool.program.lm import make_lm
from robotool.program.lm_program import RoboTool
from robotool.program.standin import Rule, Script, StandinServer

JSON_PROMPTS = {
    "analyzer": "`analysis`",
    "planner": "`abstract_plan`",
    "calculator": "`calculation`",
    "coder": "`code`",
}
"""What identifies each stage's request when the JSON answer format is asked for."""


def _solve(case: Case, adapter: str):
    script = arm_script([GRASP_DIRECTLY])
    matches = STAGE_MARKERS if adapter == "chat" else JSON_PROMPTS
    rules = [
        Rule(match=matches[stage], reply=case.reply if stage == case.stage else script[stage][0])
        for stage in STAGE_MARKERS
    ]
    with StandinServer(Script(rules=rules)) as server:
        lm = make_lm("openai/standin", api_base=server.base_url, cache=False, num_retries=0)
        program = RoboTool(worlds_per_candidate=1, format_retries=0, adapter=adapter)  # type: ignore[arg-type]
        with dspy.context(lm=lm):
            return program(task=tasks.load("milk_reaching_near")).solution


@pytest.mark.parametrize("adapter", ["chat", "json"])
@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_reply_parses_to_the_right_program_or_fails_clearly(case: Case, adapter: str) -> None:
    """Both answer formats read the same untidy replies (the rest of the script answers with field markers)."""
    solution = _solve(case, adapter)
    candidate = solution.candidates[0]
    notes = " | ".join([*solution.notes, *candidate.notes])
    if case.expect is None:
        assert solution.success, candidate.failure
        assert solution.code.strip() == case.program.strip()
        concepts = [(c.kind, c.value, c.unit, c.limit, c.satisfied) for c in solution.stages.key_concepts]
        assert concepts == [(CONCEPT["kind"], 0.0, "m", 0.0, True)]
        assert len(solution.stages.steps) == 3 and solution.stages.parameters[0].offset == [0.0, 0.0, 0.055]
    else:
        assert not solution.success
        shown = str(candidate.failure or "")
        assert case.expect in shown, shown
        assert "Traceback" not in shown and len(shown) < 400
    for note in case.notes if adapter == "chat" else ():
        assert note in notes, notes
