"""How long a failed LM request waits before its retry (the other tests retry at once: see tests/conftest.py)."""

from __future__ import annotations

import pytest
from dspy.utils.exceptions import LMProviderError, LMRateLimitError

from robotool.program.lm_calls import _retry_delay  # bound before the conftest fixture replaces it for other tests


@pytest.mark.parametrize(("attempt", "seconds"), [(0, 1.0), (1, 2.0), (2, 4.0), (6, 60.0), (12, 60.0)])
def test_a_fault_without_a_hint_waits_1_2_4_seconds_up_to_a_minute(attempt: int, seconds: float) -> None:
    assert _retry_delay(LMProviderError("gateway page"), attempt) == seconds


@pytest.mark.parametrize("hint", [0.0, 2.5, 90.0])
def test_a_rate_limit_waits_as_long_as_its_retry_after_says(hint: float) -> None:
    assert _retry_delay(LMRateLimitError("slow down", retry_after=hint), 3) == hint


@pytest.mark.parametrize("hint", [float("nan"), float("inf"), -1.0])
def test_a_retry_after_that_is_no_duration_is_ignored(hint: float) -> None:
    assert _retry_delay(LMRateLimitError("slow down", retry_after=hint), 1) == 2.0
