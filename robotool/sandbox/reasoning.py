"""A model's reasoning in its reply (``<think>...</think>`` and its other spellings), told apart from its answer."""

from __future__ import annotations

import re

from robotool.sandbox.code_shape import looks_like_code
from robotool.sandbox.fences import fence_pairs

_THOUGHT = r"think|thinking|reasoning|thought|seed:think"
_REASONING_OPEN = re.compile(rf"<({_THOUGHT})>|\[(THINK)\]|◁({_THOUGHT})▷", re.IGNORECASE)
_REASONING_END = re.compile(
    rf"^.*?(?:</(?:{_THOUGHT})>|\[/THINK\]|◁/(?:{_THOUGHT})▷)[ \t]*(?=\n|\Z)", re.DOTALL | re.IGNORECASE
)
"""Reasoning whose opening tag the server left out: all before the first closing tag that ends its line (a tag named
in a sentence, ``the reply has no </think> tag, so``, ends nothing)."""
_THOUGHT_TOKENS = re.compile(
    r"<\|begin_of_thought\|>.*?(?:<\|end_of_thought\|>|\Z)|<\|(?:begin|end)_of_solution\|>", re.DOTALL
)
_STRIPPED_ANALYSIS = re.compile(r"\A\s*analysis(?:(?=[A-Z])|(?=(?s:.*)assistantfinal))")  # not `analysis = ...`
_ANSWER_AFTER = [  # (how a reply opens its reasoning, what opens its answer): the answer is what follows the last
    (re.compile(r"\A\s*Here is my thought process:", re.IGNORECASE), re.compile(r"^\s*Here is my response:", re.M)),
    (re.compile(r"\A\s*Here are my reasoning steps:", re.IGNORECASE), re.compile(r"\[BEGIN FINAL RESPONSE\]")),
    (_STRIPPED_ANALYSIS, re.compile(r"assistantfinal")),  # channels whose special tokens were stripped
]
_FINAL_RESPONSE_END = "[END FINAL RESPONSE]"
_END_OF_TURN = re.compile(
    r"(?:<\|im_end\|>|<\|eot_id\|>|<\|eom_id\|>|<\|endoftext\|>|<\|end_of_text\|>|<end_of_turn>|</s>)"
    r"(?=\s*(?:\Z|<\|im_start\|>|<\|start_header_id\|>|<start_of_turn>|<s>|\[INST\]|<\|(?:user|assistant|system)\|>"
    r"|(?:user|assistant|system|Human|User|Assistant)\s*(?::|\n)))"
)
"""An end of turn where a model emits one: at the end of the reply, or where the turn it goes on to invent opens (a
marker named in prose, ``This <s>works</s> does not``, cuts nothing)."""
_PYTHON_TAG_TOKEN = "<|python_tag|>"
"""What Llama writes before a tool call's code when the server does not skip special tokens."""
_CHANNEL = "<|channel|>"
_FINAL_CHANNEL = re.compile(
    r"<\|channel\|>\s*final\s*(?:<\|constrain\|>\S*\s*)?<\|message\|>(.*?)(?=<\|(?:end|return|start|call)\|>|\Z)",
    re.DOTALL,
)


def without_reasoning(text: str) -> str:
    """``text`` without the model's reasoning: ``<think>...</think>`` spans and their other spellings
    (``<thinking>``, ``<reasoning>``, ``<seed:think>``, ``[THINK]...[/THINK]``, ``◁think▷...◁/think▷``,
    ``<|begin_of_thought|>...``; an unclosed one runs to the end), everything before a closing tag that ends its line
    and whose opening tag the server left out; in a reply in channels (``<|channel|>analysis<|message|>...``),
    everything but its last final channel's message (none when it has none: the answer has not begun); in a reply
    that opens with its reasoning in words ("Here is my thought process:", "Here are my reasoning steps:", a stripped
    ``analysis`` channel), all but what follows the last opening of its answer ("Here is my response:",
    ``[BEGIN FINAL RESPONSE]``, ``assistantfinal``); everything after the model's end of turn (``<|im_end|>``,
    ``<|eot_id|>`` at the reply's end or before a turn it went on to invent, which is no answer); and Llama's
    ``<|python_tag|>`` (a line break)."""
    text = _code_masked(text)
    if _CHANNEL in text:
        finals = _FINAL_CHANNEL.findall(text)
        text = finals[-1] if finals else ""
    text = _END_OF_TURN.split(text, maxsplit=1)[0]  # what follows the model's end of turn is no answer of its own
    text = text.replace(_PYTHON_TAG_TOKEN, "\n")
    for opening, answer in _ANSWER_AFTER:
        if opening.search(text):
            starts = list(answer.finditer(text))
            text = text[starts[-1].end() :].split(_FINAL_RESPONSE_END)[0] if starts else ""
    text = _THOUGHT_TOKENS.sub("", text)
    text = _without_thoughts(text)
    return _REASONING_END.sub("", text, count=1).translate(_OUT_OF_CODE)


def _without_thoughts(text: str) -> str:
    """``text`` without its reasoning spans (``<think>...</think>`` and the other spellings), each closed, or unclosed
    and opening the reply or a line (it runs to the end); an unclosed tag in a sentence (``planned in a <think>
    block``) is prose. One pass: a closing tag looked for in vain is not looked for again."""
    parts: list[str] = []
    end, never_closed = 0, set[str]()
    while (opening := _REASONING_OPEN.search(text, end)) is not None:
        tag = opening.group(0)
        closing_tag = (tag[0] + "/" + tag[1:]).lower()
        closing = None
        if closing_tag not in never_closed:
            closing = re.compile(re.escape(closing_tag), re.IGNORECASE).search(text, opening.end())
        if closing is None:
            never_closed.add(closing_tag)
            before = opening.start()
            while before > 0 and text[before - 1] in " \t":
                before -= 1
            if before == 0 or text[before - 1] == "\n":
                return "".join([*parts, text[end : opening.start()]])
            parts.append(text[end : opening.end()])
            end = opening.end()
            continue
        parts.append(text[end : opening.start()])
        end = closing.end()
    return "".join([*parts, text[end:]])


_IN_CODE = str.maketrans({"<": "\ue000", "[": "\ue001", "\u25c1": "\ue002"})
_OUT_OF_CODE = str.maketrans({"\ue000": "<", "\ue001": "[", "\ue002": "\u25c1"})
_COMMENT = re.compile(r"(?:^[ \t]*|(?<=\S)[ \t]{2,}|(?<=[)\]'\"]))#[^\n]*", re.MULTILINE)


def _code_masked(text: str) -> str:
    """``text`` with the characters that open markers of reasoning or of an end of turn replaced by private stand-ins
    inside code (the lines of fenced blocks, comments such as ``# no </think> here``), where they are code, not the
    model's reasoning; :func:`without_reasoning` puts them back."""
    parts, end = [], 0
    for opening, closing in fence_pairs(text):
        inner_end = closing.start() if closing else len(text)
        parts += [_comments_masked(text[end : opening.end()]), text[opening.end() : inner_end].translate(_IN_CODE)]
        end = inner_end
    parts.append(_comments_masked(text[end:]))
    return "".join(parts)


def _comments_masked(text: str) -> str:
    """Comments, triple-quoted strings opened where code opens one (``banner = '''``, over several lines), and string
    literals on lines that read as code (``label = "</think>"``), masked."""
    masked = _TRIPLE_QUOTED.sub(lambda found: found.group(0).translate(_IN_CODE), text)
    masked = _COMMENT.sub(lambda found: found.group(0).translate(_IN_CODE), masked)
    return _CODE_WITH_MARKER.sub(lambda found: _strings_masked(found.group(0)), masked)


_TRIPLE_QUOTED = re.compile(r"(?:^[ \t]*|[=(,\[:][ \t]*)[rRbBuUfF]{0,2}(\"\"\"|''')[\s\S]*?\1", re.MULTILINE)
"""A triple-quoted string that opens a line or follows ``=``, ``(``, ``,``, ``[`` or ``:`` (not one named in prose)."""
_CODE_WITH_MARKER = re.compile(r"^[^\n]*[<\[\u25c1][^\n]*$", re.MULTILINE)


def _strings_masked(line: str) -> str:
    """A line that reads as code with its string literals masked, in one pass (an unclosed string masks nothing)."""
    if not looks_like_code(line.translate(_OUT_OF_CODE)):
        return line
    parts, start, k = [], 0, 0
    while k < len(line):
        if line[k] not in "'\"":
            k += 1
            continue
        end = _string_end(line, k)
        if end is None:
            break
        parts += [line[start:k], line[k:end].translate(_IN_CODE)]
        start = k = end
    return "".join([*parts, line[start:]])


def _string_end(line: str, opening: int) -> int | None:
    """Where the string literal opened by the quote at ``opening`` ends (after its closing quote), or None."""
    k = opening + 1
    while k < len(line):
        if line[k] == "\\":
            k += 2
        elif line[k] == line[opening]:
            return k + 1
        else:
            k += 1
    return None
