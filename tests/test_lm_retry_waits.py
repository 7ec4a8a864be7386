"""How long a failed LM request waits before its retry (the other tests retry at once: see tests/conftest.py)."""

from __future__ import annotations

import pytest
from dspy.utils.exceptions import LMProviderError, LMRateLimitError, LMServerError

from robotool.program.lm import MAX_RETRY_WAIT_S, make_lm, unavailable
from robotool.program.lm_calls import _retry_delay  # bound before the conftest fixture replaces it for other tests


@pytest.mark.parametrize(("attempt", "seconds"), [(0, 1.0), (1, 2.0), (2, 4.0), (6, 60.0), (12, 60.0)])
def test_a_fault_without_a_hint_waits_1_2_4_seconds_up_to_a_minute(attempt: int, seconds: float) -> None:
    assert _retry_delay(LMProviderError("gateway page"), attempt) == seconds


@pytest.mark.parametrize("hint", [0.0, 2.5, 59.0])
def test_a_rate_limit_waits_as_long_as_its_retry_after_says(hint: float) -> None:
    assert _retry_delay(LMRateLimitError("slow down", retry_after=hint), 3) == hint


@pytest.mark.parametrize("hint", [90.0, 100_000.0, 1e300])
def test_a_retry_after_longer_than_the_most_a_retry_waits_is_cut_to_it(hint: float) -> None:
    """Found by an adversarial run: ``Retry-After: 100000`` on a 429 or 503 stalled a solve for 28 hours."""
    assert MAX_RETRY_WAIT_S == 60.0
    assert _retry_delay(LMRateLimitError("slow down", retry_after=hint), 1) == MAX_RETRY_WAIT_S


@pytest.mark.parametrize("error", [LMRateLimitError, LMServerError])
def test_the_message_when_the_tries_run_out_says_a_long_retry_after_was_cut(error: type[LMProviderError]) -> None:
    lm = make_lm("openai/some-model", api_base="http://127.0.0.1:9/v1", cache=False, num_retries=2)
    cut = unavailable(error("slow down", retry_after=100_000), lm)
    assert cut is not None and "(it asked to wait 100000 s; the tries waited at most 60 s)" in str(cut)
    plain = unavailable(error("slow down", retry_after=30), lm)
    assert plain is not None and "asked to wait" not in str(plain)


@pytest.mark.parametrize("hint", [float("nan"), float("inf"), -1.0])
def test_a_retry_after_that_is_no_duration_is_ignored(hint: float) -> None:
    assert _retry_delay(LMRateLimitError("slow down", retry_after=hint), 1) == 2.0
