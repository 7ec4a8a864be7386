"""The real LM path over HTTP against a local OpenAI-compatible stand-in on 127.0.0.1."""

from __future__ import annotations

import json
from pathlib import Path

import dspy
import pytest
from fixtures.scripted_lm import GRASP_DIRECTLY, STAGE_MARKERS, arm_script

from robotool import tasks
from robotool.cli import main
from robotool.lm import LMConfigError, make_lm
from robotool.program import RoboTool
from robotool.standin import Rule, Script, StandinServer

TASK = "milk_reaching_near"


def _rules(script: dict[str, list[str]], **overrides: list[Rule]) -> list[Rule]:
    """One rule per stage answering with its scripted reply, after any override rules for that stage."""
    rules: list[Rule] = []
    for stage, marker in STAGE_MARKERS.items():
        for rule in overrides.get(stage, []):
            rules.append(rule.model_copy(update={"match": marker}))
        rules.append(Rule(match=marker, reply=script[stage][0]))
    return rules


def _solve(server: StandinServer, timeout: float | None = None, **options):
    lm = make_lm("openai/standin", api_base=server.base_url, cache=False, num_retries=1, timeout=timeout)
    with dspy.context(lm=lm, adapter=dspy.ChatAdapter(use_json_adapter_fallback=False)):
        return RoboTool(worlds_per_candidate=1, **options)(task=tasks.load(TASK)).solution


def test_solves_over_http() -> None:
    with StandinServer(Script(rules=_rules(arm_script([GRASP_DIRECTLY])))) as server:
        solution = _solve(server)
        assert solution.success
        assert len(server.requests) == 4
        assert server.requests[0]["model"] == "standin"
    assert solution.usage["coder"].completion_tokens > 0


def test_rate_limit_is_retried() -> None:
    rules = _rules(arm_script([GRASP_DIRECTLY]), planner=[Rule(status=429, times=1)])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server)
        assert solution.success
        assert len(server.requests) == 5


def test_server_error_fails_the_candidate_readably() -> None:
    rules = _rules(arm_script([GRASP_DIRECTLY]), coder=[Rule(status=500)])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server)
    assert not solution.success
    assert solution.candidates[0].failure.startswith("coder:")
    assert "500" in solution.candidates[0].failure


def test_timeout_fails_the_candidate_readably() -> None:
    rules = _rules(arm_script([GRASP_DIRECTLY]), calculator=[Rule(delay=2.0, reply="late")])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server, timeout=0.5)
    assert not solution.success
    assert solution.candidates[0].failure.startswith("calculator:")
    assert "timed out" in solution.candidates[0].failure


def test_malformed_reply_fails_the_candidate_readably() -> None:
    rules = _rules(arm_script([GRASP_DIRECTLY]), analyzer=[Rule(reply="{ this is not the format")])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server, candidates=2)
    assert not solution.success
    assert all(c.failure.startswith("analyzer:") and "could not be parsed" in c.failure
               for c in solution.candidates)


def test_cli_solve_against_the_standin(tmp_path: Path, capsys) -> None:
    with StandinServer(Script(rules=_rules(arm_script([GRASP_DIRECTLY])))) as server:
        status = main(["solve", TASK, "--lm", "openai/standin", "--api-base", server.base_url, "--no-cache",
                       "--worlds", "1", "--out", str(tmp_path / "p.py"), "--json", str(tmp_path / "r.json")])
    assert status == 0, capsys.readouterr().out
    assert (tmp_path / "p.py").read_text() == GRASP_DIRECTLY
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["success_rate"] == 1.0 and report["method"] == "robotool"


def test_cli_without_lm_says_how_to_configure_and_uses_the_search_planner(monkeypatch, capsys) -> None:
    monkeypatch.delenv("ROBOTOOL_LM", raising=False)
    assert main(["solve", TASK, "--worlds", "1"]) == 0
    out = capsys.readouterr().out
    assert "--lm" in out and "search planner" in out


def test_bad_lm_settings_are_config_errors(monkeypatch) -> None:
    with pytest.raises(LMConfigError, match="provider prefix"):
        make_lm("gpt-4o")
    monkeypatch.delenv("NO_SUCH_KEY_VAR", raising=False)
    with pytest.raises(LMConfigError, match="NO_SUCH_KEY_VAR"):
        make_lm("openai/gpt-4o", api_key_env="NO_SUCH_KEY_VAR")
    monkeypatch.setenv("ROBOTOOL_LM", "openai/from-env")
    assert make_lm().model == "openai/from-env"


def test_readme_standin_example_solves_milk_reaching(capsys) -> None:
    """The README's offline walk-through: the example script served over HTTP solves milk_reaching."""
    example = Path(__file__).parents[1] / "examples" / "standin" / "milk_reaching.json"
    with StandinServer(Script.model_validate_json(example.read_text())) as server:
        status = main(["solve", "milk_reaching", "--lm", "openai/standin", "--api-base", server.base_url,
                       "--no-cache", "--worlds", "2"])
    out = capsys.readouterr().out
    assert status == 0, out
    assert "hammer" in out and "100%" in out
