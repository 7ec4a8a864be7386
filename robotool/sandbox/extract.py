"""Turn a language model's answer into program text: fences, prose, line endings, tabs, imports."""

from __future__ import annotations

import ast
import codeop
import contextlib
import itertools
import re
import warnings
from collections import Counter
from dataclasses import dataclass

from robotool.sandbox.html_blocks import html_code_blocks
from robotool.sandbox.validate import MAX_PROGRAM_CHARS, ProgramRejected, check_parse_cost, parse_program

_FENCE = re.compile(r"^[ \t]*(```+|~~~+)[ \t]*([\w.+-]*)([^\n]*)$", re.MULTILINE)  # fence, tag, the rest
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
    snippet explained after the whole program, compared with its indentation). Of several programs, the last one a line
    just before it marks as final ("Final program:", "Here is the corrected code:"; not an echo such as "Your current
    program:") is taken, quote or not; else one program left is taken; otherwise which
    one is meant is not clear (a draft and a correction, a program and a usage example, two options) and
    :class:`ProgramRejected` says so, to be asked again. A Python block that does not parse, and an untagged one
    that looks like code, is meant as a program: its syntax error is raised, never passed over for another
    block. Blocks are never joined, and :attr:`Extraction.chosen` says which was taken. Without a block,
    the program is the reply with prose before and after it left out; when a line that looks like code
    would be left out too, the program does not parse as a whole and its syntax error is raised.
    Normalizes Windows and old Mac line endings, a BOM, non-breaking spaces and tab indentation Python accepts (a tab is
    four spaces; tabs mixed with spaces the way Python refuses are its syntax error), and adds ``import numpy as np``
    / ``import math`` at the top when the program uses ``np.`` / ``math.`` without importing them. Raises
    :class:`ProgramRejected` when no program is found or it does not parse.
    """
    if len(text) > MAX_PROGRAM_CHARS:
        raise ProgramRejected(None, "text", f"answer is longer than {MAX_PROGRAM_CHARS} characters")
    check_parse_cost(text, "answer")
    text = text.replace("\r\n", "\n").replace("\r", "\n").replace("\ufeff", "").replace("\u00a0", " ")
    text = html_code_blocks(without_reasoning(text))
    text, lone_fence = _without_a_lone_fence(text)
    blocks = _fenced_blocks(text)
    chosen = None
    if blocks:
        if _has_diff(_outside_blocks(text).split("\n")):
            raise ProgramRejected(None, "blocks", _DIFF_PROBLEM)
        index, why = _choose_block(blocks)
        code = blocks[index].code.strip("\n")
        if len(blocks) > 1:
            chosen = f"the reply held {len(blocks)} code blocks; block {index + 1} ({why}) was used, not joined"
        fence_lines = blocks[index].fence_lines
    else:
        code, fence_lines = _unfenced_program(text).strip("\n"), lone_fence
    if not code.strip():
        raise ProgramRejected(None, "text", "no Python program found in the answer")
    tree = parse_program(code)  # as written: tabs mixed with spaces the way Python rejects (a TabError) are refused
    code = "\n".join(_expand_indent_tabs(line) for line in code.split("\n"))
    if not _has_action(tree):
        raise ProgramRejected(None, "text", "no Python program found in the answer (only prose, names or values)")
    missing = [stmt for alias, stmt in _IMPORTS.items() if _uses(tree, alias) and not _imports(tree, alias)]
    dropped = _non_blank(text) - _non_blank(code) - fence_lines
    return Extraction(code="\n".join([*missing, code]) + "\n", dropped_lines=max(dropped, 0), chosen=chosen)


_THOUGHT = r"think|thinking|reasoning|thought|seed:think"
_REASONING = re.compile(
    rf"<({_THOUGHT})>.*?(?:</\1>|\Z)|\[THINK\].*?(?:\[/THINK\]|\Z)|◁({_THOUGHT})▷.*?(?:◁/\2▷|\Z)",
    re.DOTALL | re.IGNORECASE,
)
_REASONING_END = re.compile(rf"^.*?(?:</(?:{_THOUGHT})>|\[/THINK\]|◁/(?:{_THOUGHT})▷)", re.DOTALL | re.IGNORECASE)
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
_END_OF_TURN = re.compile(r"<\|im_end\|>|<\|eot_id\|>|<\|endoftext\|>|<\|end_of_text\|>|<end_of_turn>|</s>")
_CHANNEL = "<|channel|>"
_FINAL_CHANNEL = re.compile(
    r"<\|channel\|>\s*final\s*(?:<\|constrain\|>\S*\s*)?<\|message\|>(.*?)(?=<\|(?:end|return|start|call)\|>|\Z)",
    re.DOTALL,
)


def without_reasoning(text: str) -> str:
    """``text`` without the model's reasoning: ``<think>...</think>`` spans and their other spellings
    (``<thinking>``, ``<reasoning>``, ``<seed:think>``, ``[THINK]...[/THINK]``, ``◁think▷...◁/think▷``,
    ``<|begin_of_thought|>...``; an unclosed one runs to the end), everything before a closing tag whose opening tag
    the server left out; in a reply in channels (``<|channel|>analysis<|message|>...``), everything but its last final
    channel's message (none when it has none: the answer has not begun); in a reply that opens with its reasoning in
    words ("Here is my thought process:", "Here are my reasoning steps:", a stripped ``analysis`` channel), all
    but what follows the last opening of its answer ("Here is my response:", ``[BEGIN FINAL RESPONSE]``,
    ``assistantfinal``); and everything after the model's end of turn (``<|im_end|>``, ``<|eot_id|>``: a turn it
    went on to invent is no answer)."""
    text = _code_masked(text)
    if _CHANNEL in text:
        finals = _FINAL_CHANNEL.findall(text)
        text = finals[-1] if finals else ""
    text = _END_OF_TURN.split(text, maxsplit=1)[0]  # what follows the model's end of turn is no answer of its own
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
    for opening, closing in _fence_pairs(text):
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
    if not _looks_like_code(line.translate(_OUT_OF_CODE)):
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
    fences = list(_FENCE.finditer(text))
    if len(fences) != 1 or fences[0].group(2):
        return text, 0
    return text[: fences[0].start()] + text[fences[0].end() + 1 :], 1


def _fence_pairs(text: str) -> list[tuple[re.Match[str], re.Match[str] | None]]:
    """Each code block's opening fence and its closing one (None: the block runs to the end), as CommonMark pairs them:
    a fence closes a block when it is of the same character, at least as long, has no info string and is indented at
    most three columns more than the opening (a fence in an indented docstring is code)."""
    fences = list(_FENCE.finditer(text))
    pairs: list[tuple[re.Match[str], re.Match[str] | None]] = []
    i = 0
    while i < len(fences):
        opening, j = fences[i], i + 1
        while j < len(fences) and not _closes(opening, fences[j]):
            j += 1
        pairs.append((opening, fences[j] if j < len(fences) else None))
        i = j + 1
    return pairs


def _closes(opening: re.Match[str], fence: re.Match[str]) -> bool:
    mark, close = opening.group(1), fence.group(1)
    indented = _indent(fence) <= _indent(opening) + 3
    return close[0] == mark[0] and len(close) >= len(mark) and not fence.group(2) and indented


def _indent(fence: re.Match[str]) -> int:
    line = fence.group(0)
    return len(line[: len(line) - len(line.lstrip(" \t"))].expandtabs(4))


_MARKDOWN_TAGS = frozenset({"markdown", "md"})


def _fenced_blocks(text: str, depth: int = 0) -> list[_Block]:
    """The Python or untagged fenced blocks, in order, those inside a Markdown block (````markdown) included."""
    blocks: list[_Block] = []
    previous_end = 0
    for opening, closing in _fence_pairs(text):
        end = closing.start() if closing else len(text)
        _check_fence(opening)
        tag, inner = opening.group(2), text[opening.end() + 1 : end]
        if tag.lower() in _MARKDOWN_TAGS and depth < 2:
            blocks += _fenced_blocks(inner, depth + 1)
        elif _PYTHON_TAG.fullmatch(tag):
            before = [line for line in text[previous_end : opening.start()].split("\n") if line.strip()]
            label = before[-1].strip() if before else ""
            blocks.append(_Block(inner.strip("\n"), 1 + (closing is not None), label, tagged=bool(tag)))
        previous_end = closing.end() if closing else len(text)
    return blocks


def _outside_blocks(text: str) -> str:
    parts, end = [], 0
    for opening, closing in _fence_pairs(text):
        parts.append(text[end : opening.start()])
        end = closing.end() if closing else len(text)
    return "\n".join([*parts, text[end:]])


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
        if {kept[0] for kept in run} == {"-", "+"} and any(_looks_like_code(kept[1:]) for kept in run):
            return True
        run = []
    return False


_DIFF_TAGS = frozenset({"diff", "patch", "udiff"})
_CALL = re.compile(r"[A-Za-z_][\w.]*\s*\(")


def _code_on_fence_line(rest: str) -> bool:
    """Whether what follows an opening fence's tag is a statement (``p = open_gripper()``), not attributes
    (``title="x.py"``)."""
    try:
        tree = _quiet_parse(rest)
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return False
    calls = any(isinstance(node, ast.Call) for node in ast.walk(tree))
    return _has_action(tree) and (calls or re.search(r"\s=\s|:\s", rest) is not None)


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
    r"currently|existing|gave|given|sent|fails?|failed|failing)\b|n't\b",
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
            tree = _quiet_parse(block.code)
        except (SyntaxError, ValueError, RecursionError, MemoryError):
            if _has_diff(block.code.split("\n")):
                raise ProgramRejected(None, "blocks", _DIFF_PROBLEM) from None
            if block.tagged or any(_looks_like_code(line) for line in block.code.split("\n")):
                return k, "it does not parse"  # parse_program raises its syntax error
            continue  # an untagged listing of text
        if _has_action(tree):
            programs.append(k)
        elif _has_diff(block.code.split("\n")):
            raise ProgramRejected(None, "blocks", _DIFF_PROBLEM)
    if not programs:
        return len(blocks) - 1, "the last"
    marked = [k for k in programs if _marked_final(blocks[k].label)]
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
    two equal blocks, the earlier quotes the later). Past :data:`MOST_PROGRAMS`, those found so far."""
    lines = {k: _statement_lines(blocks[k].code) for k in programs}
    counts = {k: Counter(lines[k]) for k in programs}
    whole: list[int] = []
    for k in sorted(programs, key=lambda k: (-len(lines[k]), -k)):  # a block can only quote one before it here
        quoted = (
            lines[k] == lines[j] or (2 * len(lines[k]) <= len(lines[j]) and _quotes(lines[k], lines[j], counts[j]))
            for j in whole
        )
        if not any(quoted):
            whole.append(k)
            if len(whole) > MOST_PROGRAMS:
                break
    return sorted(whole)


def _quotes(snippet: list[str], program: list[str], counts: Counter[str]) -> bool:
    """Whether every line of ``snippet`` is one of ``program``'s (as often), the snippet's indentation kept or all of it
    moved right by the same columns (a loop's body quoted on its own)."""
    shifts = {_columns(line) - _columns(snippet[0]) for line in program if line.lstrip() == snippet[0].lstrip()}
    return any(Counter(" " * shift + line for line in snippet) <= counts for shift in shifts if shift >= 0)


def _columns(line: str) -> int:
    return len(line) - len(line.lstrip(" "))


def _statement_lines(code: str) -> list[str]:
    """A block's lines as code, one by one: its indentation as written (a tab is four columns), then the line as
    ``ast.unparse`` writes it when it parses alone (comments, spacing and quotes do not matter), else as written (the
    head of a compound statement); none for a blank or comment line."""
    lines = []
    for line in code.split("\n"):
        text = line.strip()
        with contextlib.suppress(SyntaxError, ValueError, RecursionError, MemoryError):
            text = ast.unparse(_quiet_parse(text))
        if text:
            lines.append(line[: len(line) - len(line.lstrip())].expandtabs(4) + text)
    return lines


_CODE_LINE = re.compile(
    r"""^\s*(?:
        [A-Za-z_][\w.]*(?:\s*,\s*[A-Za-z_]\w*)*\s*(?:\(|\[|[-+*/%]?=(?!=))   # a call, subscript or assignment
      | (?:for|while|if|elif|else|def|class|try|except|finally|with)\b.*:\s*(?:\#.*)?$  # a compound statement
      | (?:import|from)\s+[\w.]+(?:\s+import\b.*)?\s*$                       # an import
      | (?:print|exec)\s+["'\w(]                                             # a Python 2 statement
      | (?:return|pass|break|continue|raise|assert|del|global|nonlocal)\b
      | @[A-Za-z_]                                                             # a decorator
      | \(                                                                     # a parenthesised expression
    )""",
    re.VERBOSE,
)


_CLAUSE = re.compile(r"(?:else|elif|except|finally)\b")


def _looks_like_code(line: str) -> bool:
    """Whether a line reads as Python, not prose: a :data:`_CODE_LINE` shape, or a line that parses, alone, as a
    compound statement's head or as a clause after one (``if x: f()``, ``else: g()``, ``[f(w) for w in ws]``,
    ``not f()``, ``lift: float = 0.2``) and does more than name a value."""
    text = line.strip()
    if _CODE_LINE.match(line):
        return True
    if not text or len(text) > 2000 or text.startswith("#"):
        return False
    sources = [text, *([f"{text}\n    pass", f"{text}\n    case _: pass"] if text.endswith(":") else [])]
    if _CLAUSE.match(text):
        sources = [f"{before}: pass\n{source}" for before in ("if 1", "try") for source in sources]
    for source in sources:
        try:
            return _has_action(_quiet_parse(source))
        except (SyntaxError, ValueError, RecursionError, MemoryError):
            continue
    return False


def _unfenced_program(text: str) -> str:
    """The program of a reply without code blocks: the longest run of lines that parses and acts, when every
    line left out is prose; raises :class:`ProgramRejected` with the syntax error of the whole code when a line
    that looks like code would be left out (the program would be cut)."""
    lines = text.split("\n")
    start, end = _longest_parsing_run(text)
    if _has_diff(lines):
        raise ProgramRejected(None, "blocks", _DIFF_PROBLEM)
    code_like = [k for k, line in enumerate(lines) if (k < start or k >= end) and _looks_like_code(line)]
    if not code_like:
        return "\n".join(lines[start:end])
    first, last = (
        min([*code_like, *([start] if end > start else [])]),
        max([*code_like, *([end - 1] if end > start else [])]),
    )
    whole = "\n".join(lines[first : last + 1])
    parse_program(whole)  # raises the syntax error that stops the code from parsing as a whole
    return whole


def _longest_parsing_run(text: str) -> tuple[int, int]:
    """The longest run of whole lines that parses and acts, preferring the earliest, as (first line, end line);
    an empty span if none is found.

    Each line may start a run; one that cannot start a program on its own (prose such as "Here is
    the code:") is ruled out by compiling that line alone. From a start, a syntax error at line k
    of a candidate means no run from there can extend past line k-1, so each start costs a few
    parses. A parse that succeeds without any action, made of one-line statements only, rules out
    every later start inside it. The whole search is bounded by :data:`SEARCH_EFFORT` parsed
    characters per character of text; past that, the best run found so far is kept.
    """
    lines = text.split("\n")
    offsets = list(itertools.accumulate((len(line) + 1 for line in lines), initial=0))
    budget = SEARCH_EFFORT * len(text) + _PARSE_OVERHEAD_CHARS * 64
    best = (0, 0)
    start = 0
    while start < len(lines) and budget > 0:
        next_start = start + 1
        end = len(lines)
        if not lines[start].strip() or not _can_start_program(lines[start]):
            start = next_start
            continue
        while end - start > best[1] - best[0] and budget > 0:
            candidate = text[offsets[start] : offsets[end] - 1]
            budget -= len(candidate) // 16 + _PARSE_OVERHEAD_CHARS  # slicing and encoding the candidate
            try:
                tree = _quiet_parse(candidate)
            except SyntaxError as e:
                error_line = start + (e.lineno or 1)
                budget -= offsets[min(error_line, end)] - offsets[start]
                end = min(end - 1, error_line - 1)
                continue
            except (ValueError, RecursionError, MemoryError):
                break
            budget -= len(candidate)
            if _has_action(tree):
                best = (start, end)
            elif all(statement.end_lineno == statement.lineno for statement in tree.body):
                next_start = end
            break
        start = next_start
    return best


SEARCH_EFFORT = 4
"""Characters the unfenced-program search may parse per character of the answer."""

_PARSE_OVERHEAD_CHARS = 256


def _can_start_program(line: str) -> bool:
    """False when the line alone is invalid Python however it continues (complete or incomplete is fine)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            codeop.compile_command(line, symbol="exec")
    except (SyntaxError, ValueError, OverflowError, MemoryError, RecursionError):
        return False
    return True


def _quiet_parse(code: str) -> ast.Module:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # SyntaxWarnings about text that is not the program
        return ast.parse(code)


def _has_action(tree: ast.Module) -> bool:
    """True when some statement does more than name a value (prose like ``Done`` parses as a name)."""
    return not all(_names_a_value(s) for s in tree.body)


def _names_a_value(statement: ast.stmt) -> bool:
    """An expression statement that only names or displays a value, or negates one (``- close_gripper()``: a diff's
    or a bullet list's line, which parses as Python but is no step of a program)."""
    if not isinstance(statement, ast.Expr):
        return False
    value = statement.value
    return _displays_a_value(value) or (isinstance(value, ast.UnaryOp) and isinstance(value.op, ast.UAdd | ast.USub))


def _displays_a_value(node: ast.expr) -> bool:
    """A name, a constant, or a literal display of them (``[0.35, 0.0, -0.1]``, ``{"code": "..."}``): what an
    output listing or a value given in place of a program parses as."""
    if isinstance(node, ast.Name | ast.Constant):
        return True
    if isinstance(node, ast.UnaryOp):
        return _displays_a_value(node.operand)
    if isinstance(node, ast.List | ast.Tuple | ast.Set):
        return all(_displays_a_value(e) for e in node.elts)
    if isinstance(node, ast.Dict):
        return all(_displays_a_value(e) for e in [*node.values, *(k for k in node.keys if k is not None)])
    return False


def _expand_indent_tabs(line: str) -> str:
    stripped = line.lstrip(" \t")
    return line[: len(line) - len(stripped)].replace("\t", "    ") + stripped


def _uses(tree: ast.Module, alias: str) -> bool:
    return any(isinstance(n, ast.Name) and n.id == alias for n in ast.walk(tree))


def _imports(tree: ast.Module, alias: str) -> bool:
    imports = (n for n in ast.walk(tree) if isinstance(n, ast.Import))
    return any((a.asname or a.name) == alias for n in imports for a in n.names)
