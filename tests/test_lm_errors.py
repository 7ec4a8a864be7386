"""LM failures that no reply can cure become one-line typed errors naming what to change."""

from __future__ import annotations

import pytest
from dspy.utils import exceptions as dx

from robotool.program.lm import make_lm, unavailable

API_BASE = "http://127.0.0.1:9/v1"


@pytest.mark.parametrize(
    ("error", "kind", "expected"),
    [
        (
            dx.LMNotConfiguredError("no API key found. Set ANTHROPIC_API_KEY in the environment"),
            "no_key",
            "set ANTHROPIC_API_KEY",
        ),
        (dx.LMAuthError("bad key", status=401), "authentication", "--api-key-env"),
        (dx.LMBillingError("no credit", status=402), "quota", "billing or quota"),
        (dx.LMRateLimitError("slow down", status=429, provider_code="insufficient_quota"), "quota", "quota"),
        (dx.LMInvalidRequestError("no such model", status=404), "unknown_model", "check --lm"),
        (dx.LMRateLimitError("slow down", status=429), "retries_exhausted", "rate limit"),
        (dx.LMServerError("boom", status=503), "retries_exhausted", "on all 3 tries"),
        (dx.LMTransportError("read timed out"), "retries_exhausted", "did not answer within 5 s"),
    ],
)
def test_unrecoverable_failures_map_to_typed_errors(error: Exception, kind: str, expected: str) -> None:
    lm = make_lm("openai/some-model", api_base=API_BASE, cache=False, num_retries=2, timeout=5)
    mapped = unavailable(error, lm)
    assert mapped is not None and mapped.kind == kind
    assert expected in str(mapped) and "\n" not in str(mapped)


def test_connection_failures_are_unreachable_and_timeouts_are_not() -> None:
    lm = make_lm("openai/some-model", api_base=API_BASE, cache=False)
    try:
        raise dx.LMTransportError("failed to connect") from ConnectionRefusedError(111, "Connection refused")
    except dx.LMTransportError as e:
        refused = e
    mapped = unavailable(refused, lm)
    assert mapped is not None and mapped.kind == "unreachable" and API_BASE in str(mapped)
    try:
        raise dx.LMTransportError("read timed out") from TimeoutError("timed out")
    except dx.LMTransportError as e:
        slow = e
    assert unavailable(slow, lm).kind == "retries_exhausted"  # type: ignore[union-attr]


def test_failures_of_one_request_are_left_to_the_stage() -> None:
    lm = make_lm("openai/some-model", api_base=API_BASE, cache=False)
    assert unavailable(dx.LMInvalidRequestError("max_tokens too large", status=400), lm) is None
    assert unavailable(dx.ContextWindowExceededError(model="openai/some-model"), lm) is None
