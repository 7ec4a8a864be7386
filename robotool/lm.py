"""Language-model configuration: any model string DSPy accepts, from flags or the environment.

``ROBOTOOL_LM`` names the model when ``--lm`` is not given (``ROBOTOOL_API_BASE`` likewise the
server). DSPy's response cache is on by default, so repeated runs cost nothing; tests turn it off.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import dspy

MODEL_ENV = "ROBOTOOL_LM"
API_BASE_ENV = "ROBOTOOL_API_BASE"

HOW_TO_CONFIGURE = (
    "No language model is configured. Pass --lm MODEL (any model string DSPy accepts, e.g. "
    "openai/gpt-4o-mini or anthropic/claude-sonnet-4-5) or set ROBOTOOL_LM. For a local "
    "OpenAI-compatible server add --api-base http://127.0.0.1:8000/v1; name the environment "
    "variable that holds the API key with --api-key-env (default: the provider's usual one)."
)


class LMConfigError(ValueError):
    """The language-model settings cannot be used; the message says how to fix them."""


def configured_model(model: str | None = None) -> str | None:
    """The model string from the argument or ``ROBOTOOL_LM`` (None when neither is set)."""
    return model or os.environ.get(MODEL_ENV) or None


def make_lm(
    model: str | None = None,
    *,
    api_base: str | None = None,
    api_key_env: str | None = None,
    temperature: float | None = None,
    max_tokens: int | None = None,
    cache: bool = True,
    num_retries: int = 3,
    timeout: float | None = None,
) -> dspy.LM | None:
    """A ``dspy.LM`` from explicit settings and the environment, or None when no model is set."""
    model = configured_model(model)
    if model is None:
        return None
    if "/" not in model:
        raise LMConfigError(f"model {model!r} needs a provider prefix, e.g. openai/{model}")
    kwargs: dict[str, object] = {}
    api_base = api_base or os.environ.get(API_BASE_ENV)
    if api_base:
        kwargs["api_base"] = api_base
    if api_key_env:
        key = os.environ.get(api_key_env)
        if not key:
            raise LMConfigError(f"--api-key-env names {api_key_env}, but that variable is not set")
        kwargs["api_key"] = key
    elif api_base:
        kwargs["api_key"] = "unused"  # local OpenAI-compatible servers accept any key
    if timeout is not None:
        kwargs["timeout"] = timeout
    if temperature is not None and temperature < 0:
        raise LMConfigError(f"temperature must be at least 0, got {temperature}")
    if max_tokens is not None and max_tokens < 1:
        raise LMConfigError(f"max tokens must be positive, got {max_tokens}")
    import dspy

    try:
        return dspy.LM(model, temperature=temperature, max_tokens=max_tokens, cache=cache,
                       num_retries=num_retries, **kwargs)
    except (ValueError, TypeError) as e:
        raise LMConfigError(f"cannot use model {model!r}: {e}") from None
