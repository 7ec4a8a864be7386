"""Turn a language model's answer into program text: fences, prose, line endings, tabs, imports."""

from __future__ import annotations

import ast
import contextlib
import re
import textwrap
from collections import Counter
from dataclasses import dataclass

from robotool.sandbox.code_shape import calls, has_action, looks_like_code, quiet_parse
from robotool.sandbox.fences import FENCE, fence_indent, fence_pairs, outside_blocks
from robotool.sandbox.html_blocks import html_code_blocks
from robotool.sandbox.unfenced import unfenced_program
from robotool.sandbox.validate import MAX_PROGRAM_CHARS, ProgramRejected, check_parse_cost, parse_program

_PYTHON_TAG = re.compile(r"(?:python|py)(?:\d+(?:\.\d+)*)?|ipython\d*|", re.IGNORECASE)
"""The tags of a Python (or untagged) code block: python, Python3, py3, python3.11, ipython ..."""
_IMPORTS = {"np": "import numpy as np", "math": "import math"}


@dataclass(frozen=True)
class Extraction:
    """A program taken from an LM answer, how many non-blank lines of the answer were left out, and which
    of several code blocks was chosen (None when there was one or none)."""

    code: str
    dropped_lines: int
    chosen: str | None = None

    @property
    def note(self) -> str | None:
        """A sentence for the user when text was left out (reasoning, prose, other blocks)."""
        parts = [self.chosen] if self.chosen else []
        if self.dropped_lines:
            parts.append(f"{self.dropped_lines} non-blank line(s) of the reply outside the program were left out")
        return "; ".join(parts) or None


def extract_program(text: str) -> str:
    """The Python program in an LM answer, ready for :func:`validate` (see :func:`extract`)."""
    return extract(text).code


def extract(text: str) -> Extraction:
    """The Python program in an LM answer, with a count of the answer's lines left out of it.

    Extraction chooses a block, never cuts one. Reasoning (``<think>...</think>`` and the other forms
    :func:`without_reasoning` knows) is never code. Of several Python (or untagged) Markdown code blocks
    (an unclosed last block runs to the end), the programs are those that parse and do more than name or
    display values (an output listing is none); a program whose lines all lie in another is a quote of it (a
    snippet explained after the whole program, compared with its indentation; not a later block that keeps the
    other's first lines, a correction). Of several programs, the last one a line just before it marks as final
    ("Final program:", "Here is the corrected code:"; not an echo such as "Your current program:" or "the code before
    my fix:") is taken, quote or not; else one program left is taken; otherwise which one is meant is not clear (a
    draft and a correction, a program and a usage example, two options, two different programs marked final, code
    outside the Python blocks too) and :class:`ProgramRejected` says so, to be asked again. A Python block that does
    not parse, and an untagged one that looks like code, is meant as a program: its syntax error is raised, never
    passed over for another block. Blocks are never joined, and :attr:`Extraction.chosen` says which was taken.
    Without a block, the program is the reply with prose before and after it left out; when a line that looks like
    code would be left out too, the program does not parse as a whole and its syntax error is raised.
    Normalizes Windows and old Mac line endings, a BOM, non-breaking spaces and tab indentation Python accepts (a tab is
    four spaces; tabs mixed with spaces the way Python refuses are its syntax error), and adds ``import numpy as np``
    / ``import math`` at the top when the program uses ``np.`` / ``math.`` without importing them. Raises
    :class:`ProgramRejected` when no program is found, it does not parse or is nested too deeply to be read.
    """
    try:
        return _extract(text)
    except RecursionError:  # a line nested deeper than the parser follows (a thousand unary minus signs) is no prose
        raise ProgramRejected(None, "nesting", "program is nested too deeply") from None


def _extract(text: str) -> Extraction:
    if len(text) > MAX_PROGRAM_CHARS:
        raise ProgramRejected(None, "text", f"answer is longer than {MAX_PROGRAM_CHARS} characters")
    check_parse_cost(text, "answer")
    text = text.replace("\r\n", "\n").replace("\r", "\n").replace("\ufeff", "").replace("\u00a0", " ")
    text = html_code_blocks(without_reasoning(text))
    text, lone_fence = _without_a_lone_fence(text)
    blocks = _fenced_blocks(text)
    chosen = None
    if blocks:
        if _has_diff(outside_blocks(text).split("\n")):
            raise ProgramRejected(None, "blocks", _DIFF_PROBLEM)
        index, why = _choose_block(blocks)
        elsewhere = _code_outside_python_blocks(text)
        if elsewhere:
            raise ProgramRejected(
                None,
                "blocks",
                f"the reply holds code block {index + 1} and also code {elsewhere}; it is not clear which is meant; "
                "give exactly one program, in one code block",
            )
        code = blocks[index].code.strip("\n")
        if len(blocks) > 1:
            chosen = f"the reply held {len(blocks)} code blocks; block {index + 1} ({why}) was used, not joined"
        fence_lines = blocks[index].fence_lines
    else:
        if _has_diff(text.split("\n")):
            raise ProgramRejected(None, "blocks", _DIFF_PROBLEM)
        code, fence_lines = unfenced_program(text).strip("\n"), lone_fence
    if not code.strip():
        raise ProgramRejected(None, "text", "no Python program found in the answer")
    tree = parse_program(code)  # as written: tabs mixed with spaces the way Python rejects (a TabError) are refused
    code = "\n".join(_expand_indent_tabs(line) for line in code.split("\n"))
    if not has_action(tree):
        raise ProgramRejected(None, "text", "no Python program found in the answer (only prose, names or values)")
    missing = [stmt for alias, stmt in _IMPORTS.items() if _uses(tree, alias) and not _imports(tree, alias)]
    dropped = _non_blank(text) - _non_blank(code) - fence_lines
    return Extraction(code="\n".join([*missing, code]) + "\n", dropped_lines=max(dropped, 0), chosen=chosen)


_THOUGHT = r"think|thinking|reasoning|thought|seed:think"
_REASONING = re.compile(
    rf"<({_THOUGHT})>.*?(?:</\1>|\Z)|\[THINK\].*?(?:\[/THINK\]|\Z)|◁({_THOUGHT})▷.*?(?:◁/\2▷|\Z)",
    re.DOTALL | re.IGNORECASE,
)
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
    text = _REASONING.sub("", text)
    return _REASONING_END.sub("", text, count=1).translate(_OUT_OF_CODE)


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
    """Comments, and string literals on lines that read as code (``label = "</think>"``), masked."""
    masked = _COMMENT.sub(lambda found: found.group(0).translate(_IN_CODE), text)
    return _CODE_WITH_MARKER.sub(lambda found: _strings_masked(found.group(0)), masked)


_CODE_WITH_MARKER = re.compile(r"^[^\n]*[<\[\u25c1][^\n]*$", re.MULTILINE)
_STRING = re.compile(r"""(?:[rRbBuUfF]{0,2})("|')(?:\\.|(?!\1)[^\\\n])*\1""")


def _strings_masked(line: str) -> str:
    if not looks_like_code(line.translate(_OUT_OF_CODE)):
        return line
    return _STRING.sub(lambda found: found.group(0).translate(_IN_CODE), line)


def _non_blank(text: str) -> int:
    """How many lines of ``text`` hold something other than white space."""
    return sum(1 for line in text.split("\n") if line.strip())


@dataclass(frozen=True)
class _Block:
    code: str
    fence_lines: int
    label: str
    """The last non-blank line of text before the block's opening fence."""
    tagged: bool
    """Whether its fence names Python (else it has no tag)."""


def _without_a_lone_fence(text: str) -> tuple[str, int]:
    """``text`` without its fence line, and 1, when it has only one fence and it names no language: a stray closing
    fence after an unfenced program (its opening was left out) or an opening one never closed, around no block;
    else ``text`` as it is, and 0."""
    fences = list(FENCE.finditer(text))
    if len(fences) != 1 or fences[0].group(2):
        return text, 0
    return text[: fences[0].start()] + text[fences[0].end() + 1 :], 1


_MARKDOWN_TAGS = frozenset({"markdown", "md"})


def _fenced_blocks(text: str, depth: int = 0) -> list[_Block]:
    """The Python or untagged fenced blocks, in order, those inside a Markdown block (````markdown) included; as in
    CommonMark, a block whose opening fence is indented (in a list item) has as many leading spaces of each line
    removed, at most."""
    blocks: list[_Block] = []
    previous_end = 0
    for opening, closing in fence_pairs(text):
        end = closing.start() if closing else len(text)
        _check_fence(opening)
        tag, inner = opening.group(2), text[opening.end() + 1 : end]
        if tag.lower() in _MARKDOWN_TAGS and depth < 2:
            blocks += _fenced_blocks(inner, depth + 1)
        elif _PYTHON_TAG.fullmatch(tag):
            before = [line for line in text[previous_end : opening.start()].split("\n") if line.strip()]
            label = before[-1].strip() if before else ""
            code = _dedented(inner, fence_indent(opening)).strip("\n")
            blocks.append(_Block(code, 1 + (closing is not None), label, tagged=bool(tag)))
        previous_end = closing.end() if closing else len(text)
    return blocks


def _dedented(code: str, columns: int) -> str:
    return "\n".join(line[min(columns, len(line) - len(line.lstrip(" "))) :] for line in code.split("\n"))


def _code_outside_python_blocks(text: str) -> str | None:
    """Where ``text`` holds code outside its Python (and untagged) blocks, in words, or None: a line outside every
    block that reads as code and parses alone with a call (an unfenced program, a Markdown block indented four spaces,
    fences that a zero-width space made text), or a block tagged with another language (``text``) whose body parses as
    a program with a call."""
    for line in outside_blocks(text).split("\n"):
        if looks_like_code(line) and calls(line.strip()):
            return f"outside the code blocks ({line.strip()[:40]!r})"
    for opening, closing in fence_pairs(text):
        tag = opening.group(2)
        body = text[opening.end() + 1 : closing.start() if closing else len(text)]
        if not (_PYTHON_TAG.fullmatch(tag) or tag.lower() in _MARKDOWN_TAGS) and calls(textwrap.dedent(body)):
            return f"in a block tagged {tag!r}"
    return None


_DIFF_PROBLEM = (
    "no Python program found: the reply gives a change as a diff; give the whole program, changes made, in one code "
    "block"
)


def _has_diff(lines: list[str]) -> bool:
    """Whether ``lines`` give a change as a diff (tagged or not): a run of lines that remove (``-``) and add (``+``)
    code, headers (``---``, ``+++``, ``@@``) aside."""
    run: list[str] = []
    for line in [*lines, ""]:
        if line.startswith(("---", "+++", "@@")):
            continue
        if line[:1] in ("-", "+"):
            run.append(line)
            continue
        if {kept[0] for kept in run} == {"-", "+"} and any(looks_like_code(kept[1:]) for kept in run):
            return True
        run = []
    return False


_DIFF_TAGS = frozenset({"diff", "patch", "udiff"})
_CALL = re.compile(r"[A-Za-z_][\w.]*\s*\(")


def _code_on_fence_line(rest: str) -> bool:
    """Whether what follows an opening fence's tag is a statement (``p = open_gripper()``), not attributes
    (``title="x.py"``)."""
    try:
        tree = quiet_parse(rest)
    except (SyntaxError, ValueError, MemoryError):
        return False
    calls = any(isinstance(node, ast.Call) for node in ast.walk(tree))
    return has_action(tree) and (calls or re.search(r"\s=\s|:\s", rest) is not None)


def _check_fence(opening: re.Match[str]) -> None:
    """Refuse a block that gives a change rather than a program (a diff), or whose opening fence line holds code
    after its tag (that code would be read as the block's info string and left out)."""
    tag, rest = opening.group(2), opening.group(3).strip()
    if tag.lower() in _DIFF_TAGS:
        raise ProgramRejected(None, "blocks", _DIFF_PROBLEM)
    if not _PYTHON_TAG.fullmatch(tag):
        rest = (tag + opening.group(3)).strip()  # ```open_gripper() is code, not a language tag
    if _CALL.match(rest) or _code_on_fence_line(rest):
        raise ProgramRejected(
            None,
            "blocks",
            f"a code block's opening fence line holds code after its tag ({rest[:40]!r}); start the code on the next "
            "line",
        )


_FINAL = re.compile(
    r"\b(?:final|corrected|fixed|revised|complete|full|whole|updated|improved)\s+(?:python\s+)?"
    r"(?:program|code|version|script|solution|answer)\b",
    re.IGNORECASE,
)
_NOT_FINAL = re.compile(
    r"\b(?:not|never|no|wrong|incorrect|buggy|broken|original|old|older|previous|earlier|initial|first|draft|current|"
    r"currently|existing|gave|given|sent|fails?|failed|failing|before|provided|reference|comparison|shared|wrote|"
    r"crashed|options?|alternatives?|alternatively|test|testing|example|usage)\b|n't\b",
    re.IGNORECASE,
)


def _marked_final(label: str) -> bool:
    """Whether a label says the block after it is the final program ("Final program:", "Here is the corrected
    code:"), not only names a word ("To complete the task", "What was fixed:") or takes it back in the marker's
    sentence or after it ("This draft is not the final version:", "The original full program:", "The final version?
    No, it is wrong:")."""
    found = _FINAL.search(label)
    if found is None:
        return False
    sentence = max(label.rfind(end, 0, found.start()) for end in ".!?") + 1  # where the marker's sentence begins
    return _NOT_FINAL.search(label[sentence:]) is None


def _choose_block(blocks: list[_Block]) -> tuple[int, str]:
    """The index of the block to run and why (see :func:`extract`); raises :class:`ProgramRejected` when a block
    meant as a program does not parse, or several different programs leave it unclear which one is meant."""
    programs: list[int] = []
    for k, block in enumerate(blocks):
        try:
            tree = quiet_parse(block.code)
        except (SyntaxError, ValueError, MemoryError):
            if _has_diff(block.code.split("\n")):
                raise ProgramRejected(None, "blocks", _DIFF_PROBLEM) from None
            if block.tagged or any(looks_like_code(line) for line in block.code.split("\n")):
                return k, "it does not parse"  # parse_program raises its syntax error
            continue  # an untagged listing of text
        if has_action(tree):
            programs.append(k)
        elif _has_diff(block.code.split("\n")):
            raise ProgramRejected(None, "blocks", _DIFF_PROBLEM)
    if not programs:
        return len(blocks) - 1, "the last"
    marked = [k for k in programs if _marked_final(blocks[k].label)]
    if len({tuple(_statement_lines(blocks[k].code)) for k in marked}) > 1:  # two options, or an echo marked too
        raise ProgramRejected(
            None,
            "blocks",
            f"the reply marks {len(marked)} different programs as final (code blocks "
            f"{', '.join(str(k + 1) for k in marked)}) and does not say which one is meant; give exactly one program, "
            "in one code block",
        )
    if marked and len(programs) > 1:  # a correction marked final is meant, however it compares with a draft
        return marked[-1], f"marked {blocks[marked[-1]].label[:60]!r}"
    whole = _whole_programs(blocks, programs)
    if len(whole) == 1:
        return whole[0], "the only program; the other blocks quote it or are no programs"
    several = (
        f"more than {MOST_PROGRAMS} different programs"
        if len(whole) > MOST_PROGRAMS
        else f"{len(whole)} different programs (code blocks {', '.join(str(k + 1) for k in whole)})"
    )
    raise ProgramRejected(
        None,
        "blocks",
        f"the reply holds {several} and does not say which one is meant; give exactly one program, in one code block",
    )


MOST_PROGRAMS = 8
"""Different programs in one reply past which they are not told apart (each more costs a pass over the blocks)."""


def _whole_programs(blocks: list[_Block], programs: list[int]) -> list[int]:
    """The ``programs`` (block indices, in order) that quote no other: a block quotes another when every line of it is
    one of the other's (as often) and it has at most half as many (a snippet explained; a correction that only leaves
    lines out, or the program again with lines added, is another program), or the same lines in the same order (of
    two equal blocks, the earlier quotes the later). A later block that repeats the other's first lines (more than one)
    is its beginning kept, a correction that leaves the rest out, not a quote. Past :data:`MOST_PROGRAMS`, those found
    so far. Each comparison costs the snippet's lines, not the program's."""
    lines = {k: _statement_lines(blocks[k].code) for k in programs}
    counts = {k: Counter(lines[k]) for k in programs}
    columns: dict[int, dict[str, set[int]]] = {}
    for k in programs:
        columns[k] = {}
        for line in lines[k]:
            columns[k].setdefault(line.lstrip(), set()).add(_columns(line))

    def quotes(k: int, j: int) -> bool:
        if lines[k] == lines[j]:
            return True
        if 2 * len(lines[k]) > len(lines[j]) or (k > j and len(lines[k]) > 1 and lines[j][: len(lines[k])] == lines[k]):
            return False
        return _quotes(lines[k], columns[j].get(lines[k][0].lstrip(), set()), counts[j])

    whole: list[int] = []
    for k in sorted(programs, key=lambda k: (-len(lines[k]), -k)):  # a block can only quote one before it here
        if not any(quotes(k, j) for j in whole):
            whole.append(k)
            if len(whole) > MOST_PROGRAMS:
                break
    return sorted(whole)


def _quotes(snippet: list[str], columns: set[int], counts: Counter[str]) -> bool:
    """Whether every line of ``snippet`` is one of the program's (``counts``, as often), the snippet's indentation kept
    or all of it moved right by the same columns (a loop's body quoted on its own); ``columns``: where the program
    indents the snippet's first line."""
    shifts = {column - _columns(snippet[0]) for column in columns}
    for shift in shifts:
        if shift >= 0:
            moved = Counter(" " * shift + line for line in snippet)
            if all(count <= counts[line] for line, count in moved.items()):
                return True
    return False


def _columns(line: str) -> int:
    return len(line) - len(line.lstrip(" "))


def _statement_lines(code: str) -> list[str]:
    """A block's lines as code, one by one: its indentation as written (a tab is four columns), then the line as
    ``ast.unparse`` writes it when it parses alone (comments, spacing and quotes do not matter), else as written (the
    head of a compound statement); none for a blank or comment line."""
    lines = []
    for line in code.split("\n"):
        text = line.strip()
        with contextlib.suppress(SyntaxError, ValueError, MemoryError):
            text = ast.unparse(quiet_parse(text))
        if text:
            lines.append(line[: len(line) - len(line.lstrip())].expandtabs(4) + text)
    return lines


def _expand_indent_tabs(line: str) -> str:
    stripped = line.lstrip(" \t")
    return line[: len(line) - len(stripped)].replace("\t", "    ") + stripped


def _uses(tree: ast.Module, alias: str) -> bool:
    return any(isinstance(n, ast.Name) and n.id == alias for n in ast.walk(tree))


def _imports(tree: ast.Module, alias: str) -> bool:
    imports = (n for n in ast.walk(tree) if isinstance(n, ast.Import))
    return any((a.asname or a.name) == alias for n in imports for a in n.names)
