"""Repair rounds with a scripted LM (a labelled test fixture): failures shown what the simulator measured."""

from __future__ import annotations

import hashlib
import io
import json
from pathlib import Path

import dspy
import pytest
from fixtures.reference import program
from fixtures.scripted_lm import REPAIR_MARKER, STAND_STILL, chat_reply, scripted_lm, stage_rules
from rich.console import Console

from robotool import tasks
from robotool.cli import main
from robotool.cli.summary import print_repairs
from robotool.eval import EvalConfig, Settings, evaluate
from robotool.eval.records import inputs_digest
from robotool.program.lm_program import RoboTool
from robotool.program.standin import Rule, Script, StandinServer
from robotool.rollout import Event, Rollout, SkillCall
from robotool.signatures.repair import ShownTrace
from robotool.signatures.traces import failure_trace

TASK = "sofa_traversing"
PUSH_AND_WALK = program("sofa_traversing")
"""The reference program: push the surfboard across the gap, walk over it (fixture)."""
PUSH_SHORT = PUSH_AND_WALK.replace("FAR_OVERLAP = 0.15 ", "FAR_OVERLAP = -0.15 ")
"""The same program pushing the board's end to 0.15 m short of sofa_2 (fixture)."""
assert PUSH_SHORT != PUSH_AND_WALK

STEPS = [
    {"skill": "push_to_position", "objects": ["surfboard"], "intent": "bridge the gap between the sofas"},
    {"skill": "walk_to_position", "objects": ["sofa_2"], "intent": "cross on the board"},
]


def _parameters(overlap: float) -> list[dict[str, object]]:
    return [
        {"step": 1, "object": "surfboard", "relative_to": "sofa_2", "offset": [-0.95 + overlap, 0.0, 0.21]},
        {"step": 2, "relative_to": "sofa_2", "offset": [0.2, 0.0, 0.0]},
    ]


def _script(code: str, repairs: list[str]) -> dict[str, list[str]]:
    """Replies for sofa_traversing: a plan that bridges the gap with the board, then the given programs."""
    return {
        "analyzer": [
            chat_reply(
                analysis="The gap between the sofas is wider than the robot can step over.",
                key_concepts=[
                    {
                        "name": "gap between sofa_1 and sofa_2",
                        "kind": "gap_width",
                        "value": 0.4,
                        "unit": "m",
                        "limit": 0.1,
                        "limit_name": "max_gap",
                        "satisfied": False,
                    }
                ],
            )
        ],
        "planner": [
            chat_reply(
                object_roles=[{"name": "surfboard", "properties": "rigid, 0.9 m long", "role": "bridge"}],
                abstract_plan="Push the surfboard over the gap, then walk across it.",
                steps=STEPS,
            )
        ],
        "calculator": [chat_reply(calculation="Board end 0.15 m short of sofa_2.", parameters=_parameters(-0.15))],
        "coder": [chat_reply(code=f"```python\n{code}```")],
        "repair": repairs,
    }


def _repair_reply(code: str, parameters: list[dict[str, object]] | None = None) -> str:
    return chat_reply(
        diagnosis="The board stopped short: the measured gap is still above the limit.",
        revised_steps=[],
        revised_parameters=parameters if parameters is not None else _parameters(0.15),
        code=f"```python\n{code}```",
    )


def _solve(script: dict[str, list[str]], **options: object):
    lm, engine = scripted_lm(script)
    program_ = RoboTool(**{"worlds_per_candidate": 2, **options})  # type: ignore[arg-type]
    with dspy.context(lm=lm, adapter=dspy.ChatAdapter(use_json_adapter_fallback=False)):
        solution = program_(task=tasks.load(TASK)).solution
    return solution, engine


def test_short_push_succeeds_after_one_repair_shown_the_measured_gap() -> None:
    solution, engine = _solve(_script(PUSH_SHORT, [_repair_reply(PUSH_AND_WALK)]), repair_rounds=2)
    first = solution.candidates[0]
    assert first.code == PUSH_SHORT and first.success_rate == 0.0
    refusal = next(c for c in first.rollouts[0].calls if c.outcome == "refused")
    gap = refusal.measured["gap"]
    assert refusal.skill == "walk_to_position" and gap > 0.1
    assert solution.success and solution.success_rate == 1.0
    assert len(solution.repairs) == 1 and engine.calls["repair"] == 1  # stopped at the first success
    attempt = solution.repairs[0].attempts[0]
    assert (attempt.source, attempt.candidate, attempt.scope) == (0, 1, "parameters")
    assert attempt.shown.calls[-1].measured == refusal.measured and attempt.shown.failed_worlds == 2
    assert set(attempt.changed) == {"parameters", "code"} and attempt.success_rate == 1.0
    assert solution.best == 1 and solution.code == PUSH_AND_WALK
    assert solution.candidates[1].repaired_from == 0
    assert solution.stages.parameters[0].offset[0] == pytest.approx(-0.8)  # the repaired numbers
    prompt = next(text for stage, _, text in engine.prompts if stage == "repair")
    shown = next(line for line in prompt.splitlines() if line.strip().startswith("9. walk_to_position("))
    assert f"-> refused: {refusal.reason}; measured gap = {gap:g}" in shown
    missed = [name for name, ok in first.rollouts[0].conditions.items() if not ok]
    assert f"Goal sub-conditions missed: {', '.join(missed)}." in prompt
    assert [c.stage for c in solution.lm_calls].count("repair") == 1 and "repair" in solution.usage
    saved = json.loads(solution.model_dump_json())
    assert saved["repairs"][0]["attempts"][0]["shown"]["calls"][-1]["measured"] == refusal.measured


def test_a_repair_that_does_worse_is_not_returned_over_the_better_failure() -> None:
    solution, _ = _solve(_script(PUSH_SHORT, [_repair_reply(STAND_STILL)]), repair_rounds=1)
    assert not solution.success and len(solution.repairs) == 1
    repaired = solution.candidates[1]
    assert repaired.repaired_from == 0 and repaired.code == STAND_STILL
    assert solution.best == 0 and solution.code == PUSH_SHORT


def test_repair_rounds_respect_the_round_and_token_budgets() -> None:
    script = _script(PUSH_SHORT, [_repair_reply(STAND_STILL)])
    solution, engine = _solve(script, candidates=2, repair_rounds=2, worlds_per_candidate=1)
    assert [len(r.attempts) for r in solution.repairs] == [2, 2]  # the two best failures each round
    assert engine.calls["repair"] == 4 and len(solution.candidates) == 6
    second = {a.source for a in solution.repairs[1].attempts}
    assert second.isdisjoint({a.source for a in solution.repairs[0].attempts})  # nothing repaired twice
    temperatures = [t for stage, t, _ in engine.prompts if stage == "repair"]
    assert sorted(temperatures) == [0.7, 0.7, 1.0, 1.0]  # each line of repairs samples like its first candidate
    solution, engine = _solve(script, repair_rounds=3, repair_tokens=1, worlds_per_candidate=1)
    assert len(solution.repairs) == 1 and engine.calls["repair"] == 1
    solution, engine = _solve(script, worlds_per_candidate=1)
    assert solution.repairs == [] and engine.calls["repair"] == 0


def test_trace_is_built_from_typed_records_and_scopes_the_repair() -> None:
    def world(calls: list[SkillCall], conditions: dict[str, bool], error: str | None = None) -> Rollout:
        return Rollout(world=0, seed=0, success=False, conditions=conditions, calls=calls, error=error)

    walk = SkillCall(skill="walk_to_position", args=[[1.0, 0.0, 0.0]], outcome="done")
    refused = walk.model_copy(update={"outcome": "refused", "reason": "some words", "measured": {"gap": 0.21}})
    after = SkillCall(skill="get_position", args=["sofa_2"], outcome="done")
    numerical = failure_trace([world([walk, refused, after], {"on": False})])
    assert numerical is not None and numerical.scope == "parameters"
    assert [c.number for c in numerical.calls] == [1, 2] and numerical.calls_made == 3
    assert numerical.conditions_missed == ["on"] and numerical.calls[-1].measured == {"gap": 0.21}
    fixed = refused.model_copy(update={"measured": {}, "reason": "it is fixed in place"})
    plan = failure_trace([world([fixed], {"on": False})])
    assert plan is not None and plan.scope == "plan"
    clamped = walk.model_copy(update={"measured": {"outside_workspace": 0.044, "remaining": 0.0}})
    missed = failure_trace([world([walk, clamped], {"held": False})])
    assert missed is not None and missed.scope == "parameters" and len(missed.calls) == 2
    aimless = failure_trace([world([walk], {"held": False})])
    assert aimless is not None and aimless.scope == "plan"
    crashed = failure_trace([world([walk], {"on": True}, error="NameError: x")])
    assert crashed is not None and crashed.scope == "plan" and crashed.error == "NameError: x"
    grasp = SkillCall(skill="close_gripper", args=[], outcome="done")
    too_wide = {"width": 0.08, "opening": 0.06}
    empty = Event(kind="grasp_failed", call=1, object="can", cause="too_wide", measured=too_wide)
    late = Event(kind="clamped", call=2, limit="workspace", measured={"outside_workspace": 0.05})
    with_events = world([walk, grasp, clamped], {"held": False}).model_copy(update={"events": [empty, late]})
    traced = failure_trace([with_events])
    assert traced is not None and traced.events == [empty, late]
    shown = ShownTrace(trace=traced).format()
    assert "  - call 2 close_gripper: held nothing: can is 0.080 m across the fingers, wider than their" in shown
    solved = Rollout(world=0, seed=0, success=True, conditions={"on": True})
    assert failure_trace([solved]) is None


def test_negative_budgets_are_refused() -> None:
    with pytest.raises(ValueError, match="repair_rounds"):
        RoboTool(repair_rounds=-1)
    with pytest.raises(ValueError, match="repair_tokens"):
        RoboTool(repair_rounds=1, repair_tokens=0)


def test_solve_over_http_shows_the_trace_readably_prints_the_round_and_writes_it(tmp_path: Path, capsys) -> None:
    script = _script(PUSH_SHORT, [_repair_reply(PUSH_AND_WALK)])
    report = tmp_path / "r.json"
    rules = [Rule(match=REPAIR_MARKER, reply=script["repair"][0]), *stage_rules(script)]  # before the Coder's rule
    with StandinServer(Script(rules=rules)) as server:
        args = ["solve", TASK, "--lm", "openai/standin", "--api-base", server.base_url, "--no-cache"]
        status = main([*args, "--worlds", "1", "--repair", "2", "--json", str(report)])
        repair = [r for r in server.requests if REPAIR_MARKER in r["messages"][-1]["content"]]
    out = capsys.readouterr().out
    assert status == 0, out
    saved = json.loads(report.read_text())
    assert len(repair) == 1 and len(saved["repairs"]) == 1 and saved["best"] == 1
    gap = saved["repairs"][0]["attempts"][0]["shown"]["calls"][-1]["measured"]["gap"]
    text = repair[0]["messages"][-1]["content"]
    assert "The program ran in 1 perturbed world(s); the goal was missed in 1." in text
    assert f"-> refused: gap of {gap:.2f} m exceeds the limit of 0.10 m" in text and f"measured gap = {gap:g}" in text
    assert "Scope of the repair: parameters" in text and "{" not in text.split("[[ ## trace ## ]]")[1].split("[[")[0]
    assert "Repair round 1" in out and "0 -> 1" in out and f"(gap {gap:.3g})" in out  # the evidence shown


def test_eval_compares_repair_with_plain_sampling_at_equal_lm_calls(tmp_path: Path) -> None:
    lm, engine = scripted_lm(_script(PUSH_SHORT, [_repair_reply(PUSH_AND_WALK)]))
    config = EvalConfig(
        out=tmp_path / "out", tasks=[TASK], methods=["robotool"], settings=Settings(worlds=1, repair=1), pictures=False
    )
    results = evaluate(config, lm=lm, console=Console(file=io.StringIO()))
    budget = results.records[0].equal_budget
    assert budget is not None and results.records[0].success_rate == 1.0
    assert (budget.sampled, budget.sampled_calls, budget.sampled_success) == (1, 4, 0.0)  # Analyzer + 3 stages
    assert (budget.repair_calls, budget.repair_success) == (5, 1.0)
    assert budget.plain == 2 and budget.plain_calls == 7 and budget.plain_success == 0.0  # K' spends >= the calls
    assert engine.calls["repair"] == 1 and engine.calls["coder"] == 3
    report = (tmp_path / "out" / "report.md").read_text()
    assert "Repair against plain sampling at equal LM calls" in report and "1.00 @ 5.0" in report
    assert (tmp_path / "out" / "repair.png").is_file()
    assert EvalConfig(settings=Settings(lm="m", repair=2)).out_dir.name == "m-k1-r2-w3-s0"


def test_repair_rounds_are_part_of_a_run_identity_only_when_set() -> None:
    task = tasks.load(TASK)
    plain, repaired = Settings(), Settings(repair=1)
    before = {  # what the digest covered before repair rounds existed
        "task": task.model_dump(mode="json"),
        "method": "robotool",
        "run": 0,
        "settings": {k: v for k, v in plain.model_dump(mode="json").items() if k != "repair"},
        "context": {},
    }
    old = hashlib.sha256(json.dumps(before, sort_keys=True).encode()).hexdigest()[:16]
    assert inputs_digest(task, "robotool", 0, plain, {}) == old
    assert inputs_digest(task, "robotool", 0, repaired, {}) != old


@pytest.mark.parametrize("command", [["solve", TASK], ["eval", "--tasks", TASK]])
def test_a_negative_repair_count_is_a_usage_error(command: list[str], capsys) -> None:
    with pytest.raises(SystemExit) as stopped:
        main([*command, "--repair", "-1"])
    assert stopped.value.code == 2 and "--repair: expected a whole number >= 0" in capsys.readouterr().err


def test_the_repair_table_escapes_control_characters_from_the_model_and_the_program() -> None:
    solution, _ = _solve(_script(PUSH_SHORT, [_repair_reply(STAND_STILL)]), repair_rounds=1, worlds_per_candidate=1)
    solution.repairs[0].attempts[0].diagnosis = "moved \x1b[2Jthe board"
    console = Console(file=io.StringIO(), width=200)
    print_repairs(solution, console)
    out = console.file.getvalue()  # type: ignore[attr-defined]
    assert "\x1b" not in out and "moved" in out
