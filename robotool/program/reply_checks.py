"""What an HTTP 200 reply says about itself before its text is read as an answer.

A body that is not a chat completion (no choices: a provider's error object such as ``{"object": "error", ...}`` or
``{"detail": ...}``), or a choice that ended in the provider's own error (``finish_reason: "error"``, a choice-level
``error``), is a transport fault: its text, whole or cut, is never an answer. A choice that ended for any reason but
a finished answer (cut off at the token limit, stopped by a content filter, a tool called instead of an answer, a
reason this module does not know) is what was wrong with the reply, to be asked again. A reply in field markers that
gives one field twice (a draft, then "Corrected:" and the field again), or goes on with more code after its answer
(after ``[[ ## completed ## ]]``, or after its JSON object), or holds code its reader would drop (under a header or
a JSON key that is no field, or before the answer), does not say which value is meant. Reasons
are read from the provider's own body where the client kept it (LiteLLM maps ``"error"`` to ``"stop"``). A reply too
long, or too full of brackets for its length, is not read at all (:func:`costly_to_read`). A reply whose body the
client could not read as a chat completion is a transport fault too (:func:`unreadable_body`). An output value holding
text that no encoding can write is refused by :func:`unencodable`.
"""

from __future__ import annotations

import json
import re
import traceback
from typing import Any

import dspy
from dspy.utils.exceptions import LMError, LMProviderError, LMUnexpectedError
from pydantic import BaseModel

from robotool.safe_text import capped
from robotool.sandbox.changes import change_in_words
from robotool.sandbox.code_shape import calling_line
from robotool.sandbox.reasoning import without_reasoning

MAX_REPLY_CHARS = 100_000
"""The longest reply text (its reasoning left out) that is read as an answer."""
READING_BUDGET = 20_000_000
"""Most characters times brackets (``{`` and ``[``) in a reply that is read: the answer formats' readers (a JSON
object's search, the repair of a typed field's JSON) take time that grows with both, about 1.4 s at this budget on a
2-core machine; 24 KB holding 12,000 open braces took 16 s of CPU, 48 KB four times that (an adversarial run)."""

FINISHED = frozenset({"stop", "eos", "eos_token", "end_turn", "stop_sequence", "end"})
"""Finish reasons of an answer the model finished (a missing reason is taken as finished: many servers omit it)."""
CUT_OFF = frozenset({"length", "max_tokens", "max_output_tokens", "model_length"})
FILTERED = frozenset({"content_filter", "safety", "recitation", "blocklist", "prohibited_content"})
TOOL_CALLED = frozenset({"tool_calls", "tool_call", "function_call", "tool_use"})
PROVIDER_FAILED = frozenset({"error", "abort", "aborted", "cancelled", "canceled"})


class NotACompletion(LMError):
    """A 200 reply that is not a chat completion (no choices), or whose choice ended in the provider's error."""


def unreadable_body(error: LMError) -> bool:
    """Whether ``error`` is a reply whose body is not one chat completion: a 200 that is no JSON (an HTML page,
    garbage), that holds several choices where one was asked for, or whose shape the client could not read (choices
    that are no list, a body that is no object, usage that is no counts); or an HTTP error answered with a gateway's
    HTML page (a 413 from a proxy), not the provider's error."""
    said = str(error)
    if isinstance(error, LMProviderError) and ("is not JSON" in said or _HTML_PAGE.search(said)):
        return True
    if isinstance(error, LMUnexpectedError) and error.__cause__ is not None:
        frames = traceback.walk_tb(error.__cause__.__traceback__)
        if any(frame.f_code.co_name == "parse_response" for frame, _ in frames):  # the client reading the body
            return True
    return re.search(r"carries \d+ choices", said) is not None


_HTML_PAGE = re.compile(r"<(?:!doctype html|html)\b", re.IGNORECASE)


def _last_response(lm: dspy.LM) -> Any:
    return lm.history[-1].get("response") if lm.history else None


def _body(response: Any) -> dict[str, Any] | None:
    body = getattr(response, "provider_data", None)
    return body if isinstance(body, dict) else None


def _first_choice(body: dict[str, Any] | None) -> dict[str, Any] | None:
    choices = body.get("choices") if body is not None else None
    first = choices[0] if isinstance(choices, list) and choices else None
    return first if isinstance(first, dict) else None


def _said(value: object) -> str:
    """A provider's message as one bounded line."""
    return capped(" ".join(str(value).split()), 160)


def not_a_completion(lm: dspy.LM) -> NotACompletion | None:
    """The fault of the last reply ``lm`` got when it was no chat completion, or ended in the provider's error."""
    body = _body(_last_response(lm))
    if body is None:
        return None
    if body.get("object") == "error":  # an error object, whatever else it carries (choices included), is no answer
        said = next((body[k] for k in ("message", "detail", "error") if body.get(k)), None)
        detail = f" (it says: {_said(said)})" if said is not None else ""
        return NotACompletion(f"the reply (HTTP 200) is an error object: it is not a chat completion{detail}")
    if "choices" in body and not body["choices"]:
        return NotACompletion("the reply (HTTP 200) held no choices: it is not a chat completion")
    if not isinstance(body.get("choices"), list):
        said = next((body[k] for k in ("message", "detail", "error") if body.get(k)), None)
        detail = f" (it says: {_said(said)})" if said is not None else ""
        return NotACompletion(f"the reply (HTTP 200) holds no choices: it is not a chat completion{detail}")
    shape = _not_one_message(body)
    if shape is not None:
        return NotACompletion(f"the reply (HTTP 200) is not a chat completion: {shape}")
    choice = _first_choice(body) or {}
    reason = str(choice.get("finish_reason") or "").lower()
    if reason in PROVIDER_FAILED or choice.get("error"):
        error = choice.get("error")
        said = error.get("message", error) if isinstance(error, dict) else error
        detail = f": {_said(said)}" if said else ""
        return NotACompletion(
            f"the reply (HTTP 200) ended in the provider's error (finish_reason {reason or 'none'!r}{detail}); "
            "its text is not an answer"
        )
    return None


def _not_one_message(body: dict[str, Any]) -> str | None:
    """What is wrong with a body's choices, when it is not one message (a stream's chunk, a null or empty choice, two
    choices where one was asked for, content that is no text)."""
    choices = body["choices"]
    if body.get("object") == "chat.completion.chunk" or any(isinstance(c, dict) and "delta" in c for c in choices):
        return "it is one chunk of a stream"
    if len(choices) > 1:
        return f"it holds {len(choices)} choices where one was asked for"
    choice = choices[0]
    message = choice.get("message") if isinstance(choice, dict) else None
    if not isinstance(message, dict):
        return "its choice holds no message"
    content = message.get("content")
    if content is not None and not isinstance(content, str | list):
        return f"its message's content is a {type(content).__name__}, not text"
    return None


def finish_reason(lm: dspy.LM) -> str | None:
    """Why the last reply ``lm`` got ended, as the provider said it (lower case), or None when it did not say."""
    response = _last_response(lm)
    choice = _first_choice(_body(response))
    reason = choice.get("finish_reason") if choice is not None else getattr(response, "finish_reason", None)
    return str(reason).lower() if reason else None


def unfinished(lm: dspy.LM) -> str | None:
    """What was wrong with the last reply ``lm`` got when it ended as no finished answer, else None."""
    reason = finish_reason(lm)
    if reason is None or reason in FINISHED:
        return None
    if reason in CUT_OFF:
        usage = getattr(_last_response(lm), "usage", None)
        tokens = getattr(usage, "output_tokens", None) or lm.kwargs.get("max_tokens")
        at = f" at {tokens} tokens" if tokens else ""
        return (
            f"your reply was cut off{at} (the token limit); give the whole answer, more briefly (or raise --max-tokens)"
        )
    if reason in FILTERED:
        return f"your reply was stopped by the provider's content filter (finish_reason {reason!r})"
    if reason in TOOL_CALLED:
        return f"your reply called a tool (finish_reason {reason!r}) instead of answering; answer in the text"
    return f"your reply ended with finish_reason {reason!r}, not as a finished answer; give the whole answer"


def repeated_fields(reply: str | None, signature: type[dspy.Signature]) -> str | None:
    """What was wrong with ``reply`` when it gives an output field more than once (the adapter would read the first,
    or the last): its ``[[ ## name ## ]]`` header on more than one line (bold, with words after it or code on its
    line too), its ``"name":`` key in more than one JSON object, or more code after ``[[ ## completed ## ]]`` or the
    JSON answer (a correction after the end), or words there that ask for a change to a program the stage writes
    (:func:`.changes.change_in_words`); else None. Reasoning is left out first."""
    text = without_reasoning(reply or "")
    twice = []
    for name in signature.output_fields:
        headers = len(re.findall(rf"^.*\[\[ ## {re.escape(name)} ## \]\]", text, re.MULTILINE))
        keys = len(re.findall(rf'"{re.escape(name)}"\s*:', text))
        if max(headers, keys) > 1:
            twice.append(f"{name} ({max(headers, keys)} times)")
    if twice:
        return f"the reply gives the field(s) {', '.join(twice)}; it is not clear which is meant: give each field once"
    _, completed, after = text.partition("[[ ## completed ## ]]")
    if completed and _more_code(after):
        return "the reply goes on after [[ ## completed ## ]] with more code; give the answer once, then end it"
    coded = "code" in signature.output_fields  # a stage that writes a program
    change = change_in_words(after) if completed and coded else None
    if change is not None:
        return f"after [[ ## completed ## ]] the reply asks for a change in words ({capped(change, 80)!r}); {_WHOLE}"
    stray = _code_beside_fields(text, set(signature.output_fields))
    if stray is not None:
        return f"the reply holds code {stray}; give the program in its field only"
    rest = _after_json_answer(text, set(signature.output_fields))
    if rest is not None and _more_code(rest):
        return "the reply goes on after its JSON object with more code; give the answer once, then end it"
    change = change_in_words(rest) if rest is not None and coded else None
    if change is not None:
        return f"after its JSON object the reply asks for a change in words ({capped(change, 80)!r}); {_WHOLE}"
    return None


_WHOLE = "give the whole program, changes made, in its field"


_HEADER = re.compile(r"^.*?\[\[ ## (.+?) ## \]\]", re.MULTILINE)
_OPENING_FENCE = re.compile(r"(?:```|~~~)[\w-]*[ \t]*\n?[ \t]*\Z")


def _code_beside_fields(text: str, names: set[str]) -> str | None:
    """Where a reply holds code that its format's reader would drop, in words, or None: under a field header that is
    none of the output fields ``names`` (``[[ ## corrected_code ## ]]``, ``[[ ## CODE ## ]]``), before the first
    field header or before the JSON answer (a program, then the answer), or under a key of the JSON answer that is no
    field (``"final_code"``)."""
    headers = list(_HEADER.finditer(text))
    for k, header in enumerate(headers):
        end = headers[k + 1].start() if k + 1 < len(headers) else len(text)
        if header.group(1) not in {*names, "completed"} and _more_code(text[header.end() : end]):
            return f"under the field header {capped(header.group(1), 40)!r}, which is no field of the answer"
    answer = _json_answer(text, names)
    in_fields = any(header.group(1) in names for header in headers)
    before = text[: headers[0].start()] if in_fields else text[: answer[1]] if answer else ""
    if _more_code(_OPENING_FENCE.sub("", before.rstrip(" \t"))):
        return "before its answer"
    for key, value in answer[0].items() if answer else ():
        if key not in names and isinstance(value, str) and _more_code(value):
            return f"under the JSON key {capped(key, 40)!r}, which is no field of the answer"
    return None


def _more_code(text: str) -> bool:
    """Whether ``text`` (what follows an answer, or stands beside it) holds more code: a fenced block or a field, or
    a line that reads as code and calls something (a correction written without fences, or indented as a Markdown
    code block)."""
    return bool(_MORE_CODE.search(text)) or any(calling_line(line) for line in text.split("\n")[:MAX_LINES_AFTER])


MAX_LINES_AFTER = 200
"""The lines after an answer read for more code (a correction comes soon after the answer it corrects)."""


_MORE_CODE = re.compile(r"^[ \t]*(?:```|~~~|\[\[ ## )", re.MULTILINE)
"""A line that starts a fenced block or a field: more code, or another answer."""
_CLOSING_FENCE = re.compile(r"\A[ \t]*\n?[ \t]*(?:```|~~~)[ \t]*(?:\n|\Z)")


def _after_json_answer(text: str, names: set[str]) -> str | None:
    """The text after the first JSON object that starts a line and gives one of the output fields ``names`` (and
    after the fence that closes it, when it stood in one), or None when there is no such object."""
    answer = _json_answer(text, names)
    if answer is None:
        return None
    rest = text[answer[2] :]
    closing = _CLOSING_FENCE.match(rest)
    return rest[closing.end() :] if closing else rest


def _json_answer(text: str, names: set[str]) -> tuple[dict[str, Any], int, int] | None:
    """The first JSON object that starts a line and gives one of the output fields ``names``, where it starts and
    where it ends; None when there is no such object."""
    decoder = json.JSONDecoder()
    for start in re.finditer(r"^[ \t]*\{", text, re.MULTILINE):
        try:
            answer, end = decoder.raw_decode(text, start.end() - 1)
        except (ValueError, RecursionError):  # not JSON, or too deep to read: no answer here
            continue
        if isinstance(answer, dict) and names & set(answer):
            return answer, start.start(), end
    return None


def costly_to_read(text: str) -> str | None:
    """What is wrong with a reply's text (its reasoning left out) that would take too long to read as an answer: over
    :data:`MAX_REPLY_CHARS`, or more brackets than :data:`READING_BUDGET` allows for its length; None if it may be
    read."""
    if len(text) > MAX_REPLY_CHARS:
        return (
            f"the reply is {len(text)} characters long, over the {MAX_REPLY_CHARS} an answer may take; answer briefly"
        )
    brackets = text.count("{") + text.count("[")
    if brackets * len(text) > READING_BUDGET:
        return (
            f"the reply holds {brackets} brackets in {len(text)} characters, more than can be read (at most "
            f"{READING_BUDGET // len(text)} in a reply this long); answer briefly"
        )
    return None


_SURROGATE = re.compile(r"[\ud800-\udfff]")


def unencodable(value: object) -> str | None:
    """What is wrong with a parsed output value (text, or lists, mappings and models of it) that holds a lone
    surrogate (a ``\\ud800`` escape in the reply's JSON): no prompt, report or journal can carry such text. None
    when it holds none."""
    if isinstance(value, BaseModel):
        value = value.model_dump()
    if isinstance(value, str):
        found = _SURROGATE.search(value)
        if found is None:
            return None
        return (
            f"it holds text that is not valid Unicode (a lone surrogate U+{ord(found.group()):04X}, such as a "
            "\\ud800 escape); write the text without it"
        )
    if isinstance(value, dict):
        value = [*value, *value.values()]
    if isinstance(value, list | tuple | set | frozenset):
        return next((problem for item in value if (problem := unencodable(item)) is not None), None)
    return None
