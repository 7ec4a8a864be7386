"""One stage's LM call, as real models answer: parsed leniently, repaired with feedback, and accounted for.

:func:`call_stage` runs a ``dspy.Predict`` stage. When its reply does not parse or validate, it first
reads the same reply in the other answer format (JSON where field markers were asked for, and the
reverse) and then as plain text where the stage knows how (the Coder takes the program out of a chat
answer). If that does not help, or the outputs fail the stage's own check (the Coder's program must
pass the sandbox's validation), it asks again (at most ``format_retries`` times), showing the model
its rejected reply and every problem found in it (a reply cut off at the token limit is told so). Replies
are read without the model's ``<think>`` reasoning. Transport faults (server errors, rate limits, timeouts,
dropped connections, a 200 that is not a chat completion) are retried here, one request each, so that every
request is recorded as an :class:`~robotool.solution.LMCall` with its tokens, wall time and whether DSPy's
cache answered it, and optionally written to a JSONL log. Failures that no reply can cure (see
:func:`robotool.program.lm.unavailable`), and transport faults on every try, raise
:class:`~robotool.errors.LMUnavailableError`. :func:`reporting_waits` lets a console show signs of life
while a reply is awaited.
"""

from __future__ import annotations

import contextvars
import copy
import functools
import json
import re
import threading
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NoReturn, TypeVar

import dspy
from dspy.utils.callback import BaseCallback
from dspy.utils.exceptions import AdapterParseError, DSPyError, LMError, is_retryable_lm_error
from pydantic import ValidationError

from robotool.errors import LMUnavailableError, RobotoolWarning
from robotool.program.lm import DEFAULT_FORMAT_RETRIES, MAX_RETRY_WAIT_S, LMConfigError, retry_after, unavailable
from robotool.program.reply_checks import (
    costly_to_read,
    not_a_completion,
    repeated_fields,
    unencodable,
    unfinished,
    unreadable_body,
)
from robotool.safe_text import encodable, prompt_block
from robotool.sandbox.reasoning import without_reasoning
from robotool.signatures import validation_notes
from robotool.signatures.models import NoteSink
from robotool.solution import LMCall
from robotool.vocabulary import CallingStage

T = TypeVar("T")

MAX_SHOWN_REPLY = 8000
"""Characters of a rejected reply shown back to the model when asking again."""


class StageFailed(Exception):
    """A stage got no usable reply; ``reason`` is one line, ``calls`` are the requests it made."""

    def __init__(self, reason: str, calls: list[LMCall]):
        super().__init__(reason)
        self.reason = reason
        self.calls = calls


class Cancelled(Exception):
    """Another part of the same solve hit an error that ends it; this stage did not start."""


def run_concurrently(calls: Sequence[Callable[[], T]]) -> list[T]:
    """Run each call in a thread of its own with the caller's context (it carries ``dspy.context`` overrides), and
    return the results in order, leaving out calls that were :class:`Cancelled`; the first other exception is
    raised once every call has ended."""
    with ThreadPoolExecutor(max_workers=max(len(calls), 1)) as pool:
        futures = [pool.submit(contextvars.copy_context().run, call) for call in calls]
        outcomes: list[T | Exception] = []
        for future in futures:
            try:
                outcomes.append(future.result())
            except Exception as e:
                outcomes.append(e)
    errors = [o for o in outcomes if isinstance(o, Exception) and not isinstance(o, Cancelled)]
    if errors:
        raise errors[0]
    return [o for o in outcomes if not isinstance(o, Exception)]


_LOG_LOCKS: dict[Path, threading.Lock] = {}
_LOG_LOCKS_GUARD = threading.Lock()


class PromptLog:
    """A JSONL file with one line per LM request: the messages sent, the reply, its cost and fate.

    Lines are appended (several solves can share a file) and may come from several threads; logs of
    the same file share one lock, so lines never interleave.
    """

    def __init__(self, path: Path):
        """Raises :class:`~robotool.program.lm.LMConfigError` when the file cannot be written."""
        self.path = path
        with _LOG_LOCKS_GUARD:
            self._lock = _LOG_LOCKS.setdefault(path.resolve(), threading.Lock())
        self.broken = False  # a line could not be written: the log ends there, the run goes on
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.open("a", encoding="utf-8").close()
        except OSError as e:
            raise LMConfigError(f"cannot write the prompt log {path}: {e.strerror or e}") from None

    def write(self, record: dict[str, Any]) -> None:
        """Append one line; when one cannot be written (a full disk), warn once and write no more."""
        if self.broken:
            return
        try:
            with self._lock, self.path.open("a", encoding="utf-8") as f:
                f.write(json.dumps(record, default=str) + "\n")
        except OSError as e:
            self.broken = True
            message = f"cannot write the prompt log {self.path}: {e.strerror or e}; it ends here, the run goes on"
            warnings.warn(RobotoolWarning(message), stacklevel=2)


@dataclass
class CallSettings:
    """How every stage call of one solve is made."""

    adapter: dspy.Adapter
    format_retries: int = DEFAULT_FORMAT_RETRIES
    log: PromptLog | None = None
    cancelled: threading.Event = field(default_factory=threading.Event)


@dataclass
class StageResult:
    """A stage's parsed outputs, every request it took, and notes on what was repaired or ignored."""

    outputs: dspy.Prediction
    calls: list[LMCall]
    notes: list[str]


Salvage = Callable[[str], dspy.Prediction]
"""Reads a stage's outputs from a reply that did not follow the answer format (raises ValueError when it cannot)."""

Check = Callable[[dspy.Prediction], str | None]
"""Checks parsed outputs beyond their types: None when they are usable, else what is wrong (shown to the model)."""


@dataclass
class _Request:
    messages: Any
    options: dict[str, Any]
    started: float
    tokens_before: tuple[int, int]
    entries_before: int
    reply: str | None = None
    seconds: float = 0.0
    tokens: tuple[int, int] = (0, 0)
    cached: bool = False
    error: str | None = None
    tool_called: bool = False  # the reply called a tool (whatever text it held)


class _Recorder(BaseCallback):
    """Records each LM request made inside one attempt (all on one thread), with the attempt's usage tracker."""

    def __init__(self, tracker: Any):
        self.tracker = tracker
        self.requests: list[_Request] = []
        self._open: dict[str, _Request] = {}

    def _totals(self) -> tuple[int, int]:
        entries = [e for per_model in self.tracker.usage_data.values() for e in per_model]
        return (
            sum(int(e.get("prompt_tokens") or 0) for e in entries),
            sum(int(e.get("completion_tokens") or 0) for e in entries),
        )

    def _entries(self) -> int:
        return sum(len(per_model) for per_model in self.tracker.usage_data.values())

    def on_lm_start(self, call_id: str, instance: Any, inputs: dict[str, Any]) -> None:
        options = {k: v for k, v in (inputs.get("kwargs") or {}).items() if not k.startswith("api_")}
        messages = inputs.get("messages") or [{"role": "user", "content": inputs.get("prompt")}]
        self._open[call_id] = _Request(messages, options, time.perf_counter(), self._totals(), self._entries())

    def on_lm_end(self, call_id: str, outputs: Any | None, exception: Exception | None = None) -> None:
        request = self._open.pop(call_id, None)
        if request is None:
            return
        request.seconds = time.perf_counter() - request.started
        after = self._totals()
        request.tokens = (after[0] - request.tokens_before[0], after[1] - request.tokens_before[1])
        request.cached = exception is None and self._entries() == request.entries_before  # DSPy adds no usage for hits
        request.reply = _reply_text(outputs)
        first = outputs[0] if outputs else None
        request.tool_called = isinstance(first, dict) and bool(first.get("tool_calls"))
        request.error = _one_line(exception) if exception is not None else None
        self.requests.append(request)


def _reply_text(outputs: Any) -> str | None:
    if not outputs:
        return None
    first = outputs[0]
    return first.get("text") if isinstance(first, dict) else str(first)


def _one_line(what: object, limit: int = 300) -> str:
    text = " ".join(str(what).split())
    return text[:limit] + ("..." if len(text) > limit else "")


@contextmanager
def _attempt_context(settings: CallSettings) -> Iterator[_Recorder]:
    with dspy.track_usage() as tracker:
        recorder = _Recorder(tracker)
        callbacks = [*dspy.settings.get("callbacks", []), recorder]
        with dspy.context(callbacks=callbacks, adapter=_reasoning_free(settings.adapter)):
            yield recorder


def _reasoning_free(adapter: dspy.Adapter) -> dspy.Adapter:
    """A copy of ``adapter`` that parses replies without the model's reasoning (``<think>...</think>``), so that
    a draft inside the reasoning is never read as an answer, and refuses a reply too costly to read
    (:func:`~robotool.program.reply_checks.costly_to_read`) before its readers run."""
    reading = copy.copy(adapter)
    reading.__class__ = _reasoning_free_class(adapter.__class__)
    return reading


@functools.cache
def _reasoning_free_class(kind: type[dspy.Adapter]) -> type[dspy.Adapter]:
    def parse(self: dspy.Adapter, signature: type[dspy.Signature], completion: str) -> dict[str, Any]:
        text = without_reasoning(completion)
        costly = costly_to_read(text)
        if costly is not None:
            raise AdapterParseError(kind.__name__, signature, completion, message=costly)
        names = list(signature.output_fields)
        only = names[0] if len(names) == 1 else None
        try:
            fields = kind.parse(self, signature, text)
        except RecursionError:
            _refuse(kind, signature, completion, only, "it holds a value nested too deeply to read; give it flat")
        except OverflowError:
            _refuse(kind, signature, completion, only, "it holds a number too large to read; give a plausible number")
        for name, value in fields.items():
            if (wrong := unencodable(value)) is not None:
                _refuse(kind, signature, completion, name, wrong)
        return fields

    return type(kind.__name__, (kind,), {"parse": parse, "__module__": kind.__module__})


def _refuse(
    kind: type[dspy.Adapter], signature: type[dspy.Signature], completion: str, name: str | None, problem: str
) -> NoReturn:
    """Raise the adapter's error for a field value that no reader or sink can take, ``problem`` its cause as a wrong
    value's is (see :func:`_value_error`); ``name`` is the field's, when known."""
    message = f"Failed to parse field {name}: {problem}" if name else problem
    raise AdapterParseError(kind.__name__, signature, completion, message=message) from ValueError(problem)


WaitReport = Callable[[str, int | None, float], None]
"""Told, while a request waits for its reply, the stage, the candidate (None: shared) and the seconds so far."""

_WAIT_REPORT: contextvars.ContextVar[tuple[WaitReport, float] | None] = contextvars.ContextVar(
    "robotool_wait_report", default=None
)


@contextmanager
def reporting_waits(report: WaitReport, every: float = 1.0) -> Iterator[None]:
    """Inside this block, every ``every`` seconds that a stage's request waits for its reply, ``report`` is told
    the stage, the candidate and the seconds elapsed (from another thread), so a console can show signs of life."""
    token = _WAIT_REPORT.set((report, every))
    try:
        yield
    finally:
        _WAIT_REPORT.reset(token)


@contextmanager
def _waiting(stage: CallingStage, candidate: int | None) -> Iterator[None]:
    """Report the wait for one request (see :func:`reporting_waits`)."""
    hook = _WAIT_REPORT.get()
    if hook is None:
        yield
        return
    report, every = hook
    done = threading.Event()
    started = time.perf_counter()

    def tick() -> None:
        while not done.wait(every):
            report(stage, candidate, time.perf_counter() - started)

    ticker = threading.Thread(target=tick, name=f"robotool-wait-{stage}", daemon=True)
    ticker.start()
    try:
        yield
    finally:
        done.set()
        ticker.join()


def call_stage(
    predictor: dspy.Predict,
    stage: CallingStage,
    inputs: dict[str, Any],
    *,
    settings: CallSettings,
    candidate: int | None = None,
    config: dict[str, Any] | None = None,
    salvage: Salvage | None = None,
    check: Check | None = None,
) -> StageResult:
    """Call one stage until a reply parses and validates (see the module docstring).

    Raises :class:`StageFailed` when no reply is usable, :class:`~robotool.errors.LMUnavailableError`
    when the model cannot be reached or used at all, and :class:`Cancelled` when ``settings.cancelled``
    is set before an attempt.
    """
    calls: list[LMCall] = []
    rejected: tuple[str, str] | None = None
    problem = ""
    for attempt in range(1, settings.format_retries + 2):
        if settings.cancelled.is_set():
            raise Cancelled(stage)
        signature, kwargs = predictor.signature, dict(inputs)
        if rejected is not None:
            signature = _with_feedback(signature)
            kwargs |= {"rejected_reply": rejected[0], "reply_problem": rejected[1]}
        with _attempt_context(settings) as recorder, validation_notes() as notes:
            try:
                with _waiting(stage, candidate):
                    outputs, failure = _ask(
                        predictor, signature, kwargs, config or {}, settings, recorder, salvage, notes
                    )
            except LMUnavailableError:
                _record(recorder.requests, stage, candidate, attempt, None, settings.log)
                raise
            if outputs is not None and check is not None and (failure := check(outputs)) is not None:
                outputs = None
        calls += _record(recorder.requests, stage, candidate, attempt, failure, settings.log)
        if outputs is not None:
            repaired = [f"attempt {attempt} used; the reply before was rejected: {problem}"] if rejected else []
            return StageResult(outputs, calls, [*repaired, *notes.notes])
        assert failure is not None
        problem = failure
        last = recorder.requests[-1] if recorder.requests else None
        if last is None or last.error is not None:  # the request itself failed: asking again would fail the same way
            break
        reply = encodable(last.reply or "")  # a reply with no text at all (a tool call alone) is asked again too
        shown = reply if len(reply) <= MAX_SHOWN_REPLY else reply[:MAX_SHOWN_REPLY] + "\n[... cut]"
        rejected = (prompt_block(shown), prompt_block(problem))  # its field markers broken: it opens no section
    tried = f"{len({c.attempt for c in calls})} attempt(s)"
    raise StageFailed(f"{problem} ({tried})" if calls else problem, calls)


def _ask(
    predictor: dspy.Predict,
    signature: type[dspy.Signature],
    kwargs: dict[str, Any],
    config: dict[str, Any],
    settings: CallSettings,
    recorder: _Recorder,
    salvage: Salvage | None,
    notes: NoteSink,
) -> tuple[dspy.Prediction | None, str | None]:
    """One reply to the stage's request: (outputs, None) or (None, what was wrong with the reply).

    Transport faults are retried here, each retry its own request, up to the LM's ``num_retries`` (DSPy's own
    retries are turned off, so that every request is counted): a server error, a rate limit, a timeout, a dropped
    connection, and a 200 whose body is not a chat completion (a gateway's HTML page, garbage, no choices).
    When they are used up, or the failure is one no request can cure, raises
    :class:`~robotool.errors.LMUnavailableError`. A reply cut off at the token limit is what was wrong with it.
    """
    lm = predictor.lm or dspy.settings.lm
    if lm is None:  # DSPy says what is missing
        return predictor(signature=signature, config=config, **kwargs), None
    fault: LMError | None = None
    for transport_try in range(int(getattr(lm, "num_retries", 0) or 0) + 1):
        if fault is not None:
            time.sleep(_retry_delay(fault, transport_try - 1))
        single = lm.copy(num_retries=0) if isinstance(lm, dspy.BaseLM) else lm
        fault = None
        try:
            outputs = predictor(signature=signature, config=config, lm=single, **kwargs)
            fault = not_a_completion(single)
            if fault is None:
                problem = unfinished(single) or repeated_fields(_last_reply(recorder), signature)
                return (None, problem) if problem else (outputs, None)
        except AdapterParseError as e:
            fault = not_a_completion(single)
            if fault is None:
                problem = unfinished(single) or repeated_fields(_last_reply(recorder), signature)
                if problem:
                    return None, problem
                reply = _last_reply(recorder) if recorder.requests else e.lm_response
                if not (reply or "").strip() and recorder.requests and recorder.requests[-1].tool_called:
                    return None, "the reply called a tool instead of answering; answer in the text, in the format asked"
                outputs, failure, salvage_note = _salvaged(e, reply, signature, settings.adapter, salvage)
                if salvage_note is not None:
                    notes.notes.append(salvage_note)
                return outputs, failure
        except LMError as e:
            mapped = unavailable(e, lm)
            if mapped is not None and (mapped.kind not in _TRANSIENT or not is_retryable_lm_error(e)):
                settings.cancelled.set()
                raise mapped from None
            if mapped is None and not unreadable_body(e):
                return None, f"the LM request failed: {_one_line((e.message or str(e)).splitlines()[0])}"
            fault = e
        if recorder.requests and fault is not None:
            recorder.requests[-1].error = _one_line(fault.message or str(fault))
    assert fault is not None
    settings.cancelled.set()
    raise (unavailable(fault, lm) or _not_a_reply(fault, lm)) from None


_TRANSIENT = frozenset({"retries_exhausted", "unreachable"})
"""Kinds of :func:`~robotool.program.lm.unavailable` errors that a later request may not meet."""


def _last_reply(recorder: _Recorder) -> str | None:
    """The text of the last reply recorded (None when it held none, such as a tool call alone)."""
    return recorder.requests[-1].reply if recorder.requests else None


def _not_a_reply(fault: LMError, lm: dspy.LM) -> LMUnavailableError:
    api_base = lm.kwargs.get("api_base")
    where = f"the server at {api_base}" if api_base else f"the provider of {lm.model}"
    tries = f"all {lm.num_retries + 1} tries" if lm.num_retries else "the only try"
    detail = re.sub(r"^\[[^\]]*\]\s*", "", _one_line(fault.message or str(fault), 160))
    return LMUnavailableError(
        "not_a_reply",
        f"{where} answered with something that is not a chat completion on {tries} ({detail}): check --api-base "
        "and any proxy or gateway in front of the server",
    )


def _retry_delay(fault: LMError, attempt: int) -> float:
    """Seconds before retrying after ``fault``: the server's Retry-After, else 1, 2, 4 ...; at most
    :data:`~robotool.program.lm.MAX_RETRY_WAIT_S`."""
    hint = retry_after(fault)
    return float(min(hint if hint is not None else 2**attempt, MAX_RETRY_WAIT_S))


def _with_feedback(signature: type[dspy.Signature]) -> type[dspy.Signature]:
    """The stage's signature with the rejected reply and its problem as extra inputs."""
    return signature.append(
        "rejected_reply",
        dspy.InputField(desc="your previous reply to this request, which could not be used"),
        type_=str,
    ).append(
        "reply_problem",
        dspy.InputField(
            desc="exactly what was wrong with that reply; answer again in the required format, fixing this"
        ),
        type_=str,
    )


def _salvaged(
    error: AdapterParseError,
    reply: str | None,
    signature: type[dspy.Signature],
    adapter: dspy.Adapter,
    salvage: Salvage | None,
) -> tuple[dspy.Prediction | None, str | None, str | None]:
    """From a ``reply`` the adapter rejected: (outputs, None, a note on how they were read), or
    (None, what was wrong with it, None). ``reply`` is the reply's text as recorded (the adapter's error may hold
    only part of it, or the repr of a reply with no text at all, which is never read as an answer)."""
    text = without_reasoning(reply or "")
    if not text.strip():
        only_reasoning = bool((reply or "").strip())
        return None, "the reply held only reasoning, no answer" if only_reasoning else "the reply was empty", None
    costly = costly_to_read(text)
    if costly is not None:  # nor is it read in another format
        return None, costly, None
    problem = parse_problem(error, signature, adapter)
    json_asked = isinstance(adapter, dspy.JSONAdapter)
    other = _reasoning_free(dspy.ChatAdapter() if json_asked else dspy.JSONAdapter())
    try:
        outputs = dspy.Prediction(**other.parse(signature, text))
        return outputs, None, f"the reply used {'field markers' if json_asked else 'JSON'}; read it as such"
    except AdapterParseError as e:
        if _value_error(e) is not None:  # it was in that format, but a value was wrong
            problem = parse_problem(e, signature, other)
    except ValueError:
        pass
    if salvage is not None:
        try:
            return salvage(text), None, "the reply did not follow the answer format; it was read as plain text"
        except ValueError:
            pass
    if _value_error(error) is not None:
        problem = "; ".join(_every_value_problem(text, signature, adapter)) or problem
    return None, problem, None


def _every_value_problem(text: str, signature: type[dspy.Signature], adapter: dspy.Adapter) -> list[str]:
    """What is wrong with each output field's value in ``text`` (``adapter``'s format), every field read on its
    own, so that a reply asked for again is told all its problems, not only the first field's."""
    reading = _reasoning_free(adapter)
    problems = []
    for name in signature.output_fields:
        single = signature
        for other in [n for n in signature.output_fields if n != name]:
            single = single.delete(other)
        try:
            reading.parse(single, text)
        except AdapterParseError as e:
            if _value_error(e) is not None or "Failed to parse field" in str(e):
                problems.append(parse_problem(e, single, adapter))
    return problems


def parse_problem(error: AdapterParseError, signature: type[dspy.Signature], adapter: dspy.Adapter) -> str:
    """Exactly what was wrong with a reply, in one line a model can act on."""
    cause = _value_error(error)
    field_name = re.search(r"Failed to parse field (\w+)", str(error))
    name = field_name.group(1) if field_name else None
    if isinstance(cause, ValidationError):
        details = "; ".join(_validation_detail(e) for e in cause.errors(include_url=False))
        return f"field {name or '?'}: {details}"
    if name is not None and cause is not None:
        return f"field {name}: {_one_line(cause)}"
    expected = list(signature.output_fields)
    found = [k for k in (error.parsed_result or {}) if k in expected]
    missing = [k for k in expected if k not in found]
    layout = (
        "as the keys of one JSON object"
        if isinstance(adapter, dspy.JSONAdapter)
        else "each under its own [[ ## field ## ]] header"
    )
    if missing:
        return f"the reply lacks the field(s) {', '.join(missing)}; give {', '.join(expected)} {layout}"
    return f"the reply does not follow the answer format; give {', '.join(expected)} {layout}"


def _value_error(error: AdapterParseError) -> ValueError | None:
    """The error of the field value that failed to parse, if that is why the adapter gave up."""
    cause = error.__cause__ or error.__context__
    return cause if isinstance(cause, ValueError) and not isinstance(cause, DSPyError) else None


def _validation_detail(error: Any) -> str:
    where = "".join(f"[{part}]" if isinstance(part, int) else f".{part}" for part in error.get("loc", ()))
    message = str(error.get("msg", "")).removeprefix("Value error, ")
    value = error.get("input")
    if isinstance(value, dict | list) or str(value) in message:
        return f"{where.lstrip('.') or 'value'}: {message}"
    shown = repr(value)
    shown = shown if len(shown) <= 80 else shown[:77] + "..."
    return f"{where.lstrip('.') or 'value'}: {message} (got {shown})"


def _record(
    requests: list[_Request],
    stage: CallingStage,
    candidate: int | None,
    attempt: int,
    failure: str | None,
    log: PromptLog | None,
) -> list[LMCall]:
    """One :class:`LMCall` per request; the attempt's failure is the last request's error."""
    calls = []
    for i, request in enumerate(requests):
        error = request.error or (failure if i == len(requests) - 1 else None)
        call = LMCall(
            stage=stage,
            candidate=candidate,
            attempt=attempt,
            prompt_tokens=request.tokens[0],
            completion_tokens=request.tokens[1],
            seconds=request.seconds,
            cached=request.cached,
            error=error,
        )
        calls.append(call)
        if log is not None:
            log.write(
                {**call.model_dump(), "options": request.options, "messages": request.messages, "reply": request.reply}
            )
    return calls
