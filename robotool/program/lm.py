"""Language-model configuration, and what its failures mean to a user.

``ROBOTOOL_LM`` names the model when ``--lm`` is not given (``ROBOTOOL_API_BASE`` likewise the
server). DSPy's response cache is on by default, so repeated runs cost nothing; tests turn it off. Model
metadata (context windows, prices) comes from the snapshot DSPy and LiteLLM ship, not fetched anew on every run
(offline, each fetch waited and warned): ``LITELLM_LOCAL_MODEL_COST_MAP=False`` asks for the remote map.
:func:`unavailable` turns an LM call's error that no reply can cure (no key, a rejected key, an
unknown model, an unreachable server, no quota, retries used up) into a one-line
:class:`~robotool.errors.LMUnavailableError` that names the flag or variable to fix.
"""

from __future__ import annotations

import math
import os
import re
from typing import TYPE_CHECKING
from urllib.parse import urlsplit

from robotool.errors import LMUnavailableError, RobotoolError
from robotool.safe_text import capped

if TYPE_CHECKING:
    import dspy

MODEL_ENV = "ROBOTOOL_LM"
API_BASE_ENV = "ROBOTOOL_API_BASE"
PLACEHOLDER_KEY = "unused"  # local OpenAI-compatible servers accept any key
DEFAULT_TIMEOUT = 180.0
"""Seconds to wait for each LM reply when no timeout is given."""
MAX_TIMEOUT = 3600.0
"""The longest wait for one LM reply that may be set (far longer ones overflow the transport's clock)."""
BUNDLED_METADATA = "LITELLM_LOCAL_MODEL_COST_MAP"
"""Set to "True" (unless set already) when an LM is made: model metadata from the bundled snapshot."""
DEFAULT_FORMAT_RETRIES = 2
"""Repairs after a reply that does not parse: each shows the model its reply and what was wrong."""
MAX_RETRY_WAIT_S = 60.0
"""The longest wait before a transport retry, whatever a server's Retry-After asks (a 429 may ask for hours)."""

HOW_TO_CONFIGURE = (
    "No language model is configured. Pass --lm MODEL (any model string DSPy accepts, e.g. "
    "openai/gpt-4o-mini or anthropic/claude-sonnet-4-5) or set ROBOTOOL_LM. For a local "
    "OpenAI-compatible server add --api-base http://127.0.0.1:8000/v1; name the environment "
    "variable that holds the API key with --api-key-env (default: the provider's usual one)."
)


class LMConfigError(RobotoolError, ValueError):
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
    """A ``dspy.LM`` from explicit settings and the environment, or None when no model is set.

    The API key is read from the variable ``api_key_env`` names; without it, DSPy reads the provider's usual
    variable (``OPENAI_API_KEY`` for ``openai/...``), and with an ``api_base`` that variable is used when it is
    set, else a placeholder (local servers accept any key). ``timeout`` defaults to :data:`DEFAULT_TIMEOUT`.
    """
    model = configured_model(model)
    if model is None:
        return None
    if "/" not in model:
        raise LMConfigError(f"model {model!r} needs a provider prefix, e.g. openai/{model}")
    os.environ.setdefault(BUNDLED_METADATA, "True")
    if not _provider_known(model):
        raise LMConfigError(
            f"model {model!r} names no provider DSPy or LiteLLM knows ({model.split('/', 1)[0]!r}): check --lm; an "
            "OpenAI-compatible server is openai/MODEL with --api-base"
        )
    kwargs: dict[str, object] = {}
    api_base = api_base or os.environ.get(API_BASE_ENV)
    if api_base:
        kwargs["api_base"] = _checked_api_base(api_base)
    if api_key_env:
        key = os.environ.get(api_key_env)
        if not key:
            raise LMUnavailableError(
                "no_key", f"--api-key-env names {api_key_env}, but that variable is not set; set it to the API key"
            )
        kwargs["api_key"] = key
    elif api_base:
        kwargs["api_key"] = os.environ.get(provider_key_variable(model)) or PLACEHOLDER_KEY
    timeout = DEFAULT_TIMEOUT if timeout is None else timeout
    if not 0 < timeout <= MAX_TIMEOUT:
        raise LMConfigError(f"the timeout (--timeout) must be above 0 and at most {MAX_TIMEOUT:g} s, got {timeout:g} s")
    kwargs["timeout"] = timeout
    if temperature is not None and temperature < 0:
        raise LMConfigError(f"temperature must be at least 0, got {temperature}")
    if max_tokens is not None and max_tokens < 1:
        raise LMConfigError(f"max tokens must be positive, got {max_tokens}")
    import dspy

    try:
        return dspy.LM(
            model, temperature=temperature, max_tokens=max_tokens, cache=cache, num_retries=num_retries, **kwargs
        )
    except (ValueError, TypeError) as e:
        raise LMConfigError(f"cannot use model {model!r}: {e}") from None


def _provider_known(model: str) -> bool:
    """Whether DSPy can route ``model``: its own engine's providers, else LiteLLM's (imported only then)."""
    from dspy.clients.engines.lm15_engine import LM15Engine
    from dspy.lm15 import RouterConfig, UnknownModelError

    try:
        LM15Engine(RouterConfig(env={}, providers=()), model_type="chat").resolve(model)
    except UnknownModelError:
        from dspy.clients._litellm import get_litellm

        return model.split("/", 1)[0] in get_litellm(feature="checking the provider of --lm").provider_list
    return True


def _checked_api_base(api_base: str) -> str:
    """``api_base`` when it is an http(s) URL with a host, else the :class:`LMConfigError` that says so."""
    try:
        parts = urlsplit(api_base)
        usable = parts.scheme in ("http", "https") and bool(parts.hostname) and parts.port != 0
    except ValueError:  # an unclosed IPv6 bracket, a port that is no number or out of range
        usable = False
    if not usable:
        raise LMConfigError(
            f"the API base {capped(api_base, 80)!r} (--api-base or {API_BASE_ENV}) is not an http:// or https:// URL "
            "with a host: check --api-base, e.g. http://127.0.0.1:8000/v1"
        )
    return api_base


def provider_key_variable(model: str) -> str:
    """The environment variable that holds the API key of ``model``'s provider by convention (``OPENAI_API_KEY``)."""
    return re.sub(r"\W", "_", model.split("/", 1)[0]).upper() + "_API_KEY"


_KEY_VARIABLE = re.compile(r"\b([A-Z][A-Z0-9_]*_API_KEY)\b")


def unavailable(error: BaseException, lm: dspy.LM) -> LMUnavailableError | None:
    """The user-facing error for an LM call's ``error`` that no other reply can cure, else None.

    None means the failure belongs to this one request (a malformed request, a context window
    exceeded) and the caller reports it as that stage's failure.
    """
    from dspy.utils import exceptions as dx

    model = lm.model
    api_base = lm.kwargs.get("api_base")
    where = f"the server at {api_base}" if api_base else f"the provider of {model}"
    tries = f"all {lm.num_retries + 1} tries" if lm.num_retries else "the only try"
    if isinstance(error, dx.LMNotConfiguredError):
        variable = _KEY_VARIABLE.search(str(error))
        fix = f"set {variable.group(1)}" if variable else "set the provider's API key variable"
        return LMUnavailableError(
            "no_key", f"no API key for {model}: {fix}, or name the variable that holds the key with --api-key-env"
        )
    if isinstance(error, dx.LMAuthError):
        if lm.kwargs.get("api_key") == PLACEHOLDER_KEY:
            fix = (
                f"it needs an API key: set {provider_key_variable(model)}, or name the variable that holds it with "
                "--api-key-env"
            )
        elif (key_variable := provider_key_variable(model)) and lm.kwargs.get("api_key") == os.environ.get(
            key_variable
        ):
            fix = f"check the API key in {key_variable}, or name another variable with --api-key-env"
        else:
            fix = "check the API key (in the variable --api-key-env names, or the provider's usual one)"
        return LMUnavailableError("authentication", f"{where} rejected the credentials for {model}: {fix}")
    if isinstance(error, dx.LMBillingError) or getattr(error, "provider_code", None) == "insufficient_quota":
        return LMUnavailableError(
            "quota", f"{where} refused {model} for billing or quota reasons: check the account's plan and credit"
        )
    if isinstance(error, dx.LMUnsupportedModelError) or (
        isinstance(error, dx.LMInvalidRequestError) and getattr(error, "status", None) == 404
    ):
        fix = "check --lm (or ROBOTOOL_LM)" + (" and that --api-base ends in /v1" if api_base else "")
        return LMUnavailableError("unknown_model", f"{where} does not know the model {model!r}: {fix}")
    if isinstance(error, dx.LMTransportError) and _connection_dropped(error):
        return LMUnavailableError(
            "retries_exhausted",
            f"{where} dropped the connection without answering on {tries}: check the server and any proxy in front "
            "of it",
        )
    if isinstance(error, dx.LMTransportError) and _connection_failed(error):
        target = f"the language-model server at {api_base}" if api_base else f"the provider of {model}"
        fix = (
            "check --api-base (or ROBOTOOL_API_BASE) and that the server is running"
            if api_base
            else "check the network connection"
        )
        return LMUnavailableError("unreachable", f"cannot reach {target}: {fix}")
    if isinstance(error, dx.LMTransportError):
        timeout = lm.kwargs.get("timeout")
        limit = f"within {timeout:g} s " if timeout else ""
        return LMUnavailableError(
            "retries_exhausted", f"{where} did not answer {limit}on {tries}: raise --timeout or check the server"
        )
    if isinstance(error, dx.LMRateLimitError):
        return LMUnavailableError(
            "retries_exhausted",
            f"{where} turned requests away as too many (rate limit) on {tries}{_wait_cut(error)}: wait and rerun, or "
            "lower --candidates",
        )
    if isinstance(error, dx.LMServerError):
        return LMUnavailableError(
            "retries_exhausted",
            f"{where} failed to answer on {tries} (server error){_wait_cut(error)}: try again later",
        )
    return None


def retry_after(error: BaseException) -> float | None:
    """The seconds a failed request's server asked to wait before the next (its Retry-After), when it said so."""
    hint = getattr(error, "retry_after", None)
    return float(hint) if isinstance(hint, int | float) and math.isfinite(hint) and hint >= 0 else None


def _wait_cut(error: BaseException) -> str:
    """Says so when the server asked for a longer wait between tries than :data:`MAX_RETRY_WAIT_S`."""
    hint = retry_after(error)
    if hint is None or hint <= MAX_RETRY_WAIT_S:
        return ""
    return f" (it asked to wait {hint:g} s; the tries waited at most {MAX_RETRY_WAIT_S:g} s)"


def _causes(error: BaseException) -> list[BaseException]:
    """``error`` and the errors it was raised from, outermost first."""
    seen: list[BaseException] = []
    current: BaseException | None = error
    while current is not None and all(current is not e for e in seen):
        seen.append(current)
        current = current.__cause__ or current.__context__
    return seen


def _connection_dropped(error: BaseException) -> bool:
    """Whether a transport error is the server closing or resetting an open connection (not a slow answer)."""
    for cause in _causes(error):
        names = {klass.__name__ for klass in type(cause).__mro__}
        if any("Timeout" in name for name in names) or isinstance(cause, TimeoutError):
            return False
        if names & {"ReadError", "RemoteProtocolError", "ConnectionResetError", "BrokenPipeError"}:
            return True
        if re.search(r"closed (the )?connection|connection (was )?(reset|closed|aborted)", str(cause), re.IGNORECASE):
            return True
    return False


def _connection_failed(error: BaseException) -> bool:
    """Whether a transport error, or one it was raised from, is a failure to connect (not a slow answer)."""
    for cause in _causes(error):
        names = {klass.__name__ for klass in type(cause).__mro__}
        if "ConnectError" in names or (isinstance(cause, OSError) and not isinstance(cause, TimeoutError)):
            return True
    return False
