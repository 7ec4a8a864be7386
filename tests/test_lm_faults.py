"""Transport faults over the real HTTP protocol: replies that are not chat completions, cut-off replies,
dropped connections, and the accounting of every request (issue 30). Replies come from the stand-in."""

from __future__ import annotations

import json
from pathlib import Path

import dspy
import pytest
from fixtures.scripted_lm import GRASP_DIRECTLY, STAGE_MARKERS, arm_script, chat_reply, stage_rules

from robotool import tasks
from robotool.cli import main
from robotool.errors import LMUnavailableError
from robotool.program.lm import make_lm
from robotool.program.lm_program import RoboTool
from robotool.program.standin import Rule, Script, StandinServer

TASK = "milk_reaching_near"
GATEWAY_PAGE = "<html><head><title>502 Bad Gateway</title></head><body><h1>502 Bad Gateway</h1></body></html>"


def _solve(server: StandinServer, num_retries: int = 1, timeout: float | None = None, **options):
    lm = make_lm("openai/standin", api_base=server.base_url, cache=False, num_retries=num_retries, timeout=timeout)
    with dspy.context(lm=lm, adapter=dspy.ChatAdapter(use_json_adapter_fallback=False)):
        return RoboTool(worlds_per_candidate=1, **options)(task=tasks.load(TASK)).solution


_CHOICE = {"index": 0, "finish_reason": "stop", "message": {"role": "assistant", "content": "x"}}


def _raw(body: object) -> Rule:
    """A 200 whose JSON body is ``body`` (with the fields of a chat completion when it is an object)."""
    fields = {"id": "x", "object": "chat.completion", "created": 0, "model": "standin"}
    text = json.dumps({**fields, **body} if isinstance(body, dict) else body)
    return Rule(body=text, content_type="application/json")


@pytest.mark.parametrize(
    ("fault", "expected"),
    [
        (Rule(body=GATEWAY_PAGE), "not JSON"),
        (Rule(body="\x00\x01garbage{", content_type="application/json"), "not JSON"),
        (Rule(reply="ignored", choices=0), "held no choices"),
        # found by an adversarial run: bodies the client could not read, and a proxy's page, were the method's failure
        (_raw({"choices": "oops"}), "choices must be an array"),
        (_raw({"choices": {"0": {"message": {"role": "assistant", "content": "x"}}}}), "choices must be an array"),
        (_raw([1, 2]), "a Chat Completions response body is a JSON object, got list"),
        (_raw("hello"), "a Chat Completions response body is a JSON object, got str"),
        (_raw({"choices": [_CHOICE], "usage": "lots"}), "'str' object has no attribute 'get'"),
        (_raw({"choices": [_CHOICE], "usage": {"prompt_tokens": -5, "completion_tokens": -1}}), "must be >= 0"),
        (Rule(status=413, body="<html>request too big</html>"), "<html>request too big</html>"),
    ],
    ids=[
        "html-gateway-page",
        "garbage",
        "no-choices",
        "choices-a-string",
        "choices-an-object",
        "body-a-list",
        "body-a-string",
        "usage-a-string",
        "usage-negative",
        "413-html-page",
    ],
)
def test_a_reply_that_is_not_a_chat_completion_is_retried_then_ends_the_solve(fault: Rule, expected: str) -> None:
    rules = stage_rules(arm_script([GRASP_DIRECTLY]), analyzer=[fault])
    with StandinServer(Script(rules=rules)) as server, pytest.raises(LMUnavailableError) as raised:
        _solve(server, num_retries=1)
    assert raised.value.kind == "not_a_reply"
    assert len(server.requests) == 2  # retried like a 5xx, and the candidates never ran
    message = str(raised.value)
    assert "not a chat completion on all 2 tries" in message and expected in message and "\n" not in message


def test_a_gateway_page_once_is_retried_and_every_request_is_counted() -> None:
    rules = stage_rules(arm_script([GRASP_DIRECTLY]), analyzer=[Rule(body=GATEWAY_PAGE, times=1)])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server, num_retries=1)
        requests = len(server.requests)
    assert solution.success and solution.stages.key_concepts  # the Analyzer's answer, not the page
    assert requests == 5 and len(solution.lm_calls) == 5
    analyzer = [c for c in solution.lm_calls if c.stage == "analyzer"]
    assert len(analyzer) == 2 and "not JSON" in (analyzer[0].error or "") and analyzer[1].error is None


def test_server_errors_are_counted_as_requests() -> None:
    rules = stage_rules(arm_script([GRASP_DIRECTLY]), planner=[Rule(status=500, times=1)])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server, num_retries=1)
        assert len(server.requests) == 5
    assert solution.success and len(solution.lm_calls) == 5
    assert sum(c.error is not None for c in solution.lm_calls) == 1


def test_a_dropped_connection_is_named_as_such_not_a_timeout() -> None:
    rules = stage_rules(arm_script([GRASP_DIRECTLY]), coder=[Rule(drop=True)])
    with StandinServer(Script(rules=rules)) as server, pytest.raises(LMUnavailableError) as raised:
        _solve(server, num_retries=1, timeout=30)
    assert "dropped the connection without answering on all 2 tries" in str(raised.value)
    assert "did not answer" not in str(raised.value) and "--timeout" not in str(raised.value)


def test_a_reply_cut_off_at_the_token_limit_is_sent_back_as_such_and_the_user_is_told() -> None:
    script = arm_script([GRASP_DIRECTLY])
    cut = script["coder"][0][: len(script["coder"][0]) // 2]  # the program stops mid-line
    rules = stage_rules(script, coder=[Rule(reply=cut, finish_reason="length", times=1)])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server)
        second = server.requests[-1]["messages"][-1]["content"]
    assert solution.success
    tokens = len(cut.split())  # the stand-in counts words as tokens
    assert f"your reply was cut off at {tokens} tokens" in second and "syntax error" not in second
    notes = " | ".join(solution.candidates[0].notes)
    assert f"the reply before was rejected: your reply was cut off at {tokens} tokens" in notes


def _completion(message: dict, finish_reason: str | None, **choice: object) -> str:
    """A raw chat-completion body with one choice, as some providers send it (a test fixture)."""
    body = {"id": "x", "object": "chat.completion", "created": 0, "model": "standin"}
    body["choices"] = [
        {"index": 0, "finish_reason": finish_reason, "message": {"role": "assistant", **message}, **choice}
    ]
    return json.dumps(body)


# Found by an adversarial run: a provider's error in a 200 was read as an empty reply, and a cut or errored reply ran.
PROVIDER_FAULTS = {
    "an error object (vLLM)": (
        json.dumps({"object": "error", "message": "The model is overloaded", "type": "ServiceUnavailableError"}),
        "not a chat completion (it says: The model is overloaded)",
    ),
    "an error object that carries choices": (  # found by an adversarial run: its choice's text was the answer
        json.dumps(
            {
                "object": "error",
                "message": "Upstream failed",
                "choices": [
                    {"index": 0, "finish_reason": "stop", "message": {"role": "assistant", "content": "open_gripper()"}}
                ],
            }
        ),
        "is an error object: it is not a chat completion (it says: Upstream failed)",
    ),
    "a detail object": (json.dumps({"detail": "Internal Server Error"}), "(it says: Internal Server Error)"),
    "a null choice": (json.dumps({"object": "chat.completion", "choices": [None]}), "its choice holds no message"),
    "a stream's chunk": (
        json.dumps({"object": "chat.completion.chunk", "choices": [{"index": 0, "delta": {"content": "x"}}]}),
        "it is one chunk of a stream",
    ),
    "two choices where one was asked for": (
        json.dumps(
            {
                "object": "chat.completion",
                "choices": [
                    {"index": k, "finish_reason": "stop", "message": {"role": "assistant", "content": "x"}}
                    for k in range(2)
                ],
            }
        ),
        "carries 2 choices",
    ),
    "content that is no text": (_completion({"content": {"code": "x"}}, "stop"), "its message's content is a dict"),
    "a choice that ended in the provider's error (OpenRouter)": (
        _completion({"content": "[[ ## code ## ]]\nopen_gripper()\n"}, "error", error={"message": "Provider down"}),
        "ended in the provider's error (finish_reason 'error': Provider down)",
    ),
}


@pytest.mark.parametrize(("body", "expected"), PROVIDER_FAULTS.values(), ids=PROVIDER_FAULTS.keys())
def test_a_providers_error_in_a_200_is_a_transport_fault_never_an_answer(body: str, expected: str) -> None:
    rules = stage_rules(arm_script([GRASP_DIRECTLY]), coder=[Rule(body=body, content_type="application/json")])
    with StandinServer(Script(rules=rules)) as server, pytest.raises(LMUnavailableError) as raised:
        _solve(server, num_retries=1)
    assert raised.value.kind == "not_a_reply" and expected in str(raised.value), str(raised.value)


UNFINISHED = {  # the reply's text holds a whole program, but the reply did not end as a finished answer
    "cut at max_tokens": ("max_tokens", {}, "cut off"),
    "stopped by a content filter": ("content_filter", {}, "stopped by the provider's content filter"),
    "a tool called instead": ("tool_calls", {"tool_calls": []}, "called a tool (finish_reason 'tool_calls')"),
    "an unknown reason": ("paused", {}, "ended with finish_reason 'paused', not as a finished answer"),
}


@pytest.mark.parametrize(("reason", "extra", "expected"), UNFINISHED.values(), ids=UNFINISHED.keys())
def test_a_reply_that_did_not_finish_is_asked_again_with_why(reason: str, extra: dict, expected: str) -> None:
    script = arm_script([GRASP_DIRECTLY])
    body = _completion({"content": script["coder"][0], **extra}, reason)
    rules = stage_rules(script, coder=[Rule(body=body, content_type="application/json", times=1)])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server)
        second = server.requests[-1]["messages"][-1]["content"]
    assert solution.success and expected in second, second


def test_a_reply_with_no_text_but_a_tool_call_is_asked_again_saying_so() -> None:
    tool_call = {"id": "c", "type": "function", "function": {"name": "code", "arguments": "{}"}}
    body = _completion({"content": None, "tool_calls": [tool_call]}, "stop")
    script = arm_script([GRASP_DIRECTLY])
    rules = stage_rules(script, coder=[Rule(body=body, content_type="application/json", times=1)])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server)
        second = server.requests[-1]["messages"][-1]["content"]
    assert solution.success and "the reply called a tool instead of answering" in second


def test_a_reply_with_no_text_is_empty_never_the_repr_of_what_it_held() -> None:
    program = json.dumps({"code": GRASP_DIRECTLY})
    shapes = [
        (
            _completion(
                {
                    "content": None,
                    "tool_calls": [{"id": "c", "type": "function", "function": {"name": "code", "arguments": program}}],
                },
                "stop",
            ),
            "the reply called a tool instead of answering",
        ),
        (
            _completion({"content": "", "reasoning_content": f"```python\n{GRASP_DIRECTLY}```"}, "stop"),
            "the reply was empty",
        ),
    ]
    for body, expected in shapes:
        rules = stage_rules(arm_script([GRASP_DIRECTLY]), coder=[Rule(body=body, content_type="application/json")])
        with StandinServer(Script(rules=rules)) as server:
            solution = _solve(server, format_retries=0)
        assert not solution.success and expected in str(solution.candidates[0].failure)


def test_cli_gateway_page_is_one_line_and_exit_2(capsys) -> None:
    with StandinServer(Script(rules=[Rule(body=GATEWAY_PAGE)])) as server:
        code = main(["solve", TASK, "--lm", "openai/standin", "--api-base", server.base_url, "--no-cache"])
        requests = len(server.requests)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "not a chat completion" in err[0] and "Traceback" not in err[0]
    assert requests == 4  # the default --retries: 3 retries after the first request


def test_eval_never_records_a_run_that_met_a_gateway_page(tmp_path: Path, capsys) -> None:
    from robotool.cli.eval_command import main as eval_main

    rules = stage_rules(arm_script([GRASP_DIRECTLY]), analyzer=[Rule(body=GATEWAY_PAGE)])
    with StandinServer(Script(rules=rules)) as server:
        code = eval_main(
            ["--tasks", TASK, "--methods", "robotool", "--worlds", "1", "--lm", "openai/standin", "--api-base",
             server.base_url, "--no-cache", "--out", str(tmp_path / "out")]
        )  # fmt: skip
    assert code == 3
    assert "not a chat completion" in capsys.readouterr().err
    journal = tmp_path / "out" / "journal.jsonl"
    assert not journal.exists() or journal.read_text().strip() == ""
    results = tmp_path / "out" / "results.json"
    assert not results.exists() or json.loads(results.read_text())["records"] == []


def test_unparsable_python_2_in_the_code_field_is_asked_again_with_its_syntax_error() -> None:
    python2 = chat_reply(code='open_gripper()\nprint "reaching"\nfor i in xrange(1):\n    close_gripper()\n')
    rules = stage_rules(arm_script([GRASP_DIRECTLY]), coder=[Rule(reply=python2, times=1)])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server)
        second = server.requests[-1]["messages"][-1]["content"]
    assert solution.success and solution.code == GRASP_DIRECTLY  # never the lines that parse
    assert "line 2: syntax error: Missing parentheses in call to 'print'" in second


def test_every_problem_of_a_reply_is_named_when_asking_again() -> None:
    bad = chat_reply(
        calculation="x",
        parameters=[
            {"step": 2, "object": "spoon", "target": [0.3, 0.0, 0.1]},
            {"step": 3, "object": "milk", "coords": [0.3, 0.0, 0.1]},
        ],
    )
    rules = stage_rules(arm_script([GRASP_DIRECTLY]), calculator=[Rule(reply=bad, times=1)])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server)
        asked_again = [r for r in server.requests if STAGE_MARKERS["calculator"] in r["messages"][0]["content"]][-1]
    problem = asked_again["messages"][-1]["content"]
    assert solution.success
    assert "unknown object(s) ['spoon']" in problem and "step 3 has no numbers" in problem and "'coords'" in problem


def test_problems_in_several_fields_are_all_named_when_asking_again() -> None:
    bad = chat_reply(
        object_roles="the milk is the target",
        abstract_plan="Teleport.",
        steps=[{"skill": "teleport", "objects": ["milk"], "intent": "cheat"}],
    )
    rules = stage_rules(arm_script([GRASP_DIRECTLY]), planner=[Rule(reply=bad, times=1)])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server)
        asked_again = [r for r in server.requests if STAGE_MARKERS["planner"] in r["messages"][0]["content"]][-1]
    problem = asked_again["messages"][-1]["content"]
    assert solution.success
    assert "field object_roles" in problem and "unknown skill 'teleport'" in problem


def test_a_concept_kind_that_names_nothing_is_asked_again() -> None:
    script = arm_script([GRASP_DIRECTLY])
    friction = script["analyzer"][0].replace('"workspace_excess"', '"friction"')
    rules = stage_rules(script, analyzer=[Rule(reply=friction, times=1)])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server)
        assert len(server.requests) == 5
    assert solution.stages.key_concepts[0].kind == "workspace_excess"
    assert any("kind 'friction' is not one of" in note for note in solution.notes)


def test_a_reasoning_marker_in_a_string_of_the_program_is_the_programs_text_over_http() -> None:
    """Over the stand-in: real reasoning closed by its marker, then a program whose string literal holds the marker.
    The program runs as written (not cut at the literal, not asked again)."""
    program = GRASP_DIRECTLY.replace("open_gripper()\n", 'open_gripper()\nlabel = "no </think> here"\n')
    reply = "<think>Draft: move straight down.</think>\n" + chat_reply(code=program)
    rules = stage_rules(arm_script([GRASP_DIRECTLY]), coder=[Rule(reply=reply, times=1)])
    with StandinServer(Script(rules=rules)) as server:
        solution = _solve(server)
    assert solution.success and solution.code == program, solution.code
