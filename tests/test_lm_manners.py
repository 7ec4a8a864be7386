"""Manners on the wire (issue 30): a stated timeout, signs of life while a reply is awaited, and the provider's
key variable with --api-base; over the real HTTP protocol against the stand-in."""

from __future__ import annotations

import dspy
import pytest
from fixtures.scripted_lm import GRASP_DIRECTLY, arm_script, stage_rules

from robotool import tasks
from robotool.cli import main, solve_command
from robotool.program.lm import DEFAULT_TIMEOUT, PLACEHOLDER_KEY, make_lm
from robotool.program.lm_calls import reporting_waits
from robotool.program.lm_program import RoboTool
from robotool.program.standin import Rule, Script, StandinServer

TASK = "milk_reaching_near"


@pytest.mark.parametrize(
    "module", ["robotool.cli.dispatch", "robotool.cli.eval_command", "robotool.cli.optimize_command"]
)
def test_timeout_has_a_stated_default(module: str, capsys) -> None:
    import importlib

    entry = importlib.import_module(module).main
    with pytest.raises(SystemExit):
        entry(["solve", "--help"] if module == "robotool.cli.dispatch" else ["--help"])
    assert f"(default: {DEFAULT_TIMEOUT:g})" in " ".join(capsys.readouterr().out.split())
    assert make_lm("openai/x", api_base="http://127.0.0.1:9/v1").kwargs["timeout"] == DEFAULT_TIMEOUT


def test_the_wait_for_a_reply_is_reported_with_its_stage_and_seconds() -> None:
    rules = stage_rules(
        arm_script([GRASP_DIRECTLY]), calculator=[Rule(delay=1.6, reply=arm_script([])["calculator"][0])]
    )
    seen: list[tuple[str, int | None, float]] = []
    with StandinServer(Script(rules=rules)) as server, reporting_waits(lambda *told: seen.append(told), every=0.5):
        lm = make_lm("openai/standin", api_base=server.base_url, cache=False, num_retries=0)
        with dspy.context(lm=lm):
            solution = RoboTool(worlds_per_candidate=1)(task=tasks.load(TASK)).solution
    assert solution.success
    calculator = [seconds for stage, candidate, seconds in seen if stage == "calculator" and candidate == 0]
    assert len(calculator) >= 2 and calculator == sorted(calculator) and calculator[-1] >= 1.0
    assert all(stage == "calculator" for stage, _, _ in seen)  # the quick replies were not reported


def test_cli_tells_a_console_that_is_not_a_terminal_that_a_reply_is_awaited(monkeypatch, capsys) -> None:
    monkeypatch.setattr(solve_command, "WAIT_LINE_EVERY", 1)
    rules = stage_rules(
        arm_script([GRASP_DIRECTLY]), coder=[Rule(delay=2.5, reply=arm_script([GRASP_DIRECTLY])["coder"][0])]
    )
    with StandinServer(Script(rules=rules)) as server:
        code = main(
            ["solve", TASK, "--lm", "openai/standin", "--api-base", server.base_url, "--no-cache", "--worlds", "1"]
        )
    out = capsys.readouterr().out
    assert code == 0, out
    assert "waiting 1 s for the coder's reply for candidate 0" in out and "waiting 2 s for the coder's" in out


def test_api_base_uses_the_providers_key_variable_when_it_is_set(monkeypatch) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "sk-from-the-environment")
    with StandinServer(Script(rules=stage_rules(arm_script([GRASP_DIRECTLY])))) as server:
        assert (
            main(
                ["solve", TASK, "--lm", "openai/standin", "--api-base", server.base_url, "--no-cache", "--worlds", "1"]
            )
            == 0
        )
        assert set(server.authorizations) == {"Bearer sk-from-the-environment"}
    monkeypatch.delenv("OPENAI_API_KEY")
    assert make_lm("openai/x", api_base="http://127.0.0.1:9/v1").kwargs["api_key"] == PLACEHOLDER_KEY


def test_a_rejected_placeholder_key_says_which_variable_to_set(monkeypatch, capsys) -> None:
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)
    with StandinServer(Script(rules=[Rule(status=401)])) as server:
        code = main(["solve", TASK, "--lm", "openai/standin", "--api-base", server.base_url, "--no-cache"])
    err = capsys.readouterr().err
    assert code == 2 and "set OPENAI_API_KEY, or name the variable that holds it with --api-key-env" in err


def test_a_rejected_key_from_the_providers_variable_is_named(monkeypatch, capsys) -> None:
    monkeypatch.setenv("OPENAI_API_KEY", "sk-wrong")
    with StandinServer(Script(rules=[Rule(status=401)])) as server:
        code = main(["solve", TASK, "--lm", "openai/standin", "--api-base", server.base_url, "--no-cache"])
    err = capsys.readouterr().err
    assert code == 2 and "check the API key in OPENAI_API_KEY" in err


def test_a_run_reads_the_bundled_model_metadata_instead_of_fetching_it(monkeypatch, caplog) -> None:
    """Offline, DSPy's first LM call tried to fetch the remote model map and warned ("Model metadata refresh failed")
    on every run; an LM made here reads the bundled snapshot, and a user who set the variable keeps it."""
    from dspy.clients import model_metadata

    def no_fetch(*args: object, **kwargs: object) -> None:
        raise AssertionError("the remote model map was fetched")

    monkeypatch.setattr(model_metadata.urllib.request, "urlopen", no_fetch)
    monkeypatch.delenv("LITELLM_LOCAL_MODEL_COST_MAP", raising=False)
    monkeypatch.setattr(model_metadata, "_data", None)
    rules = stage_rules(arm_script([GRASP_DIRECTLY]))
    with StandinServer(Script(rules=rules)) as server:
        lm = make_lm("openai/standin", api_base=server.base_url, cache=False, num_retries=0)
        with dspy.context(lm=lm):
            assert RoboTool()(task=tasks.load(TASK)).code
    assert model_metadata.source_info()["is_env_forced"] and "metadata" not in caplog.text
    monkeypatch.setenv("LITELLM_LOCAL_MODEL_COST_MAP", "False")
    make_lm("openai/standin", api_base=server.base_url)
    assert model_metadata.os.environ["LITELLM_LOCAL_MODEL_COST_MAP"] == "False"
