"""Turn a language model's answer into program text: fences, prose, line endings, tabs, imports."""

from __future__ import annotations

import ast
import builtins
import contextlib
import re
import textwrap
from collections import Counter
from dataclasses import dataclass

from robotool.sandbox.allowlist import BUILTINS, MATH_NAMES, NUMPY_FUNCTIONS, NUMPY_LINALG
from robotool.sandbox.changes import refuse_change_in_comments, refuse_change_in_words
from robotool.sandbox.code_shape import calling_line, calls, has_action, looks_like_code, quiet_parse
from robotool.sandbox.fences import FENCE, fence_indent, fence_pairs, outside_blocks
from robotool.sandbox.html_blocks import html_code_blocks
from robotool.sandbox.joined import refuse_joined
from robotool.sandbox.labels import aside, marks_final, not_an_answer, retracts
from robotool.sandbox.placeholder import refuse_placeholder
from robotool.sandbox.reasoning import without_reasoning
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
    display values (an output listing is none, nor an untagged block that calls nothing, or does not parse and has
    no line that calls, beside a Python block); a program whose lines lie in another, in order and one after another,
    is a quote of it (a snippet explained; not a block that does the task alone, nor a later block that keeps the
    other's first lines, a correction). Of several programs, the last one a line just before it marks as final
    ("Final program:", "Here is the corrected code:"; not an echo such as "Your current program:", nor a fragment of
    another program) is taken when no different program follows it but an aside ("For comparison, ..."); else one
    program left is taken; otherwise which one is meant is not clear (a
    draft and a correction, a program and a usage example, two options, two different programs marked final, code
    outside the Python blocks too) and :class:`ProgramRejected` says so, to be asked again. A Python block that does
    not parse, and an untagged one that looks like code, is meant as a program: its syntax error is raised, never
    passed over for another block. Blocks are never joined, and :attr:`Extraction.chosen` says which was taken.
    Without a block, the program is the reply with prose before and after it left out; when a line that looks like
    code would be left out too, the program does not parse as a whole and its syntax error is raised.
    Normalizes Windows and old Mac line endings, a BOM, non-breaking spaces and tab indentation Python accepts (a tab is
    four spaces; tabs mixed with spaces the way Python refuses are its syntax error), and adds ``import numpy as np``
    / ``import math`` at the top when the program uses ``np.`` / ``math.`` without importing them. Raises
    :class:`ProgramRejected` when no program is found, it does not parse or is nested too deeply to be read, or it
    says it leaves part of itself out (``# ... rest of the code unchanged ...``, ``...``; see :mod:`.placeholder`), or
    its comments join two programs (``# Option 1:`` ... ``# Option 2:``; see :mod:`.joined`), or the words after it
    ask for a change to it ("Actually, replace the last line with ..."; see :mod:`.changes`), or a later block repeats
    a run of its lines after words that take it back ("Wait, the rest is wrong. Simply:").
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
    text = _unquoted(html_code_blocks(without_reasoning(text)))
    text, lone_fence = _without_a_lone_fence(text)
    blocks = _fenced_blocks(text)
    chosen = None
    if blocks:
        if _has_diff(outside_blocks(text).split("\n")):
            raise ProgramRejected(None, "blocks", _DIFF_PROBLEM)
        index, why = _choose_block(blocks)
        elsewhere = _code_outside_python_blocks(text, blocks)
        if elsewhere:
            raise ProgramRejected(
                None,
                "blocks",
                f"the reply holds code block {index + 1} and also code {elsewhere}; it is not clear which is meant; "
                "give exactly one program, in one code block",
            )
        if why == _ONLY_PROGRAM and not_an_answer(blocks[index].label, blocks[index].heading):
            raise ProgramRejected(
                None,
                "blocks",
                f"the only program follows {blocks[index].label[-80:]!r}, which says it is not the final program "
                "(a draft, pseudo-code, a partial fix, your own code); give the final program, in one code block",
            )
        code = blocks[index].code.strip("\n")
        refuse_change_in_words(_prose_after(text, blocks[index].end), code)
        if len(blocks) > 1:
            chosen = f"the reply held {len(blocks)} code blocks; block {index + 1} ({why}) was used, not joined"
        fence_lines = blocks[index].fence_lines
    else:
        if _has_diff(text.split("\n")):
            raise ProgramRejected(None, "blocks", _DIFF_PROBLEM)
        code, fence_lines = unfenced_program(text).strip("\n"), lone_fence
        if code.strip():
            refuse_change_in_words(text[text.find(code) + len(code) :], code)  # the program, not a quote of it after
    if not code.strip():
        raise ProgramRejected(None, "text", "no Python program found in the answer")
    tree = parse_program(code)  # as written: tabs mixed with spaces the way Python rejects (a TabError) are refused
    _refuse_signed_calls(tree)
    refuse_placeholder(code, tree)
    refuse_joined(code, tree)
    refuse_change_in_comments(code)
    code = "\n".join(_expand_indent_tabs(line) for line in code.split("\n"))
    if not has_action(tree):
        raise ProgramRejected(None, "text", "no Python program found in the answer (only prose, names or values)")
    defined = _only_defines(tree)
    if defined:
        raise ProgramRejected(
            None,
            "text",
            f"the program only defines {', '.join(defined[:5])} and never calls them (a call shown apart, as usage or "
            "in words, does not run); give the whole program, with its calls, in one code block",
        )
    missing = [stmt for alias, stmt in _IMPORTS.items() if _uses(tree, alias) and not _imports(tree, alias)]
    dropped = _non_blank(text) - _non_blank(code) - fence_lines
    return Extraction(code="\n".join([*missing, code]) + "\n", dropped_lines=max(dropped, 0), chosen=chosen)


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
    heading: str
    """The last Markdown heading (``## Final program``) between the block before it and its opening fence, or ''."""
    end: int
    """Where in the reply its closing fence ends (the reply's end when it has none)."""


def _without_a_lone_fence(text: str) -> tuple[str, int]:
    """``text`` without its fence line, and 1, when it has only one fence and it names no language: a stray closing
    fence after an unfenced program (its opening was left out) or an opening one never closed, around no block;
    else ``text`` as it is, and 0."""
    fences = list(FENCE.finditer(text))
    if len(fences) != 1 or fences[0].group(2):
        return text, 0
    return text[: fences[0].start()] + text[fences[0].end() + 1 :], 1


_MARKDOWN_TAGS = frozenset({"markdown", "md"})
_HEADING = re.compile(r"[ ]{0,3}#{1,6}[ \t]")
_RULE = re.compile(r"[ ]{0,3}(?:(?:-[ \t]*){3,}|(?:\*[ \t]*){3,}|(?:_[ \t]*){3,}|=+)[ \t]*")
"""A thematic break (``---``, ``***``) or a setext heading's underline (``-----``, ``=====``): no label of a block;
the words above it are (found by an adversarial run: '---' was read as the label, and 'Final program:' above it
not)."""


def _fenced_blocks(text: str, depth: int = 0, at: int = 0) -> list[_Block]:
    """The Python or untagged fenced blocks, in order, those inside a Markdown block (````markdown) included; as in
    CommonMark, a block whose opening fence is indented (in a list item) has as many leading spaces of each line
    removed, at most. ``text`` starts at offset ``at`` of the reply."""
    blocks: list[_Block] = []
    previous_end = 0
    for opening, closing in fence_pairs(text):
        end = closing.start() if closing else len(text)
        _check_fence(opening)
        tag, inner = opening.group(2), text[opening.end() + 1 : end]
        if tag.lower() in _MARKDOWN_TAGS and depth < 2:
            blocks += _fenced_blocks(inner, depth + 1, at + opening.end() + 1)
        elif _PYTHON_TAG.fullmatch(tag):
            before = [line for line in text[previous_end : opening.start()].split("\n") if line.strip()]
            words = [line for line in before if not _RULE.fullmatch(line)]  # a rule, or a setext heading's underline
            label = words[-1].strip() if words else ""
            heading = next((line.strip() for line in reversed(before) if _HEADING.match(line)), "")
            code = _dedented(inner, fence_indent(opening)).strip("\n")
            ends = at + (closing.end() if closing else len(text))
            blocks.append(_Block(code, 1 + (closing is not None), label, bool(tag), heading, ends))
        previous_end = closing.end() if closing else len(text)
    return blocks


def _dedented(code: str, columns: int) -> str:
    return "\n".join(line[min(columns, len(line) - len(line.lstrip(" "))) :] for line in code.split("\n"))


_WORD = re.compile(r"[A-Za-z_]\w*")


_MATH_CALLS = BUILTINS | MATH_NAMES | NUMPY_FUNCTIONS | NUMPY_LINALG


def _formula(line: str, named: set[str]) -> bool:
    """Whether a line is one assignment whose names none of the Python blocks uses and which calls only math
    (``d = sqrt(x**2 + y**2)`` in prose): math shown, not a step of the program (``moved = move_to_position(p)``)."""
    tree = quiet_parse(line)
    names = {node.id for node in ast.walk(tree) if isinstance(node, ast.Name)}
    called = {_callee(node.func) for node in ast.walk(tree) if isinstance(node, ast.Call)}
    return len(tree.body) == 1 and isinstance(tree.body[0], ast.Assign) and not names & named and called <= _MATH_CALLS


def _callee(func: ast.expr) -> str | None:
    """The name a call calls (``sqrt`` of ``np.sqrt(x)``), or None for an expression that is none."""
    return func.id if isinstance(func, ast.Name) else func.attr if isinstance(func, ast.Attribute) else None


def _code_outside_python_blocks(text: str, blocks: list[_Block]) -> str | None:
    """Where ``text`` holds code outside its Python (and untagged) blocks, in words, or None: a line outside every
    block that reads as code and parses alone with a call (an unfenced program, a Markdown block indented four spaces,
    fences that a zero-width space made text; not :func:`_formula`), or a block tagged with another language
    (``text``) whose body parses as a program with a call."""
    named = {word for block in blocks for word in _WORD.findall(block.code)}
    for line in outside_blocks(text).split("\n"):
        if calling_line(line) and not _formula(line.strip(), named):
            return f"outside the code blocks ({line.strip()[:40]!r})"
    for opening, closing in fence_pairs(text):
        tag = opening.group(2)
        body = _PROMPT.sub("", text[opening.end() + 1 : closing.start() if closing else len(text)])
        if not (_PYTHON_TAG.fullmatch(tag) or tag.lower() in _MARKDOWN_TAGS) and calls(textwrap.dedent(body)):
            return f"in a block tagged {tag!r}"
    return None


def _prose_after(text: str, end: int) -> str:
    """The reply's words after offset ``end`` (a block's end), outside its fenced blocks paired over the whole reply
    (a slice pairs them anew: a wrapper's closing fence would open a block), and inside a Markdown block the program
    lies in; an unclosed block at the end, after a doubled closing fence, is words too."""
    parts, start = [], end
    for opening, closing in fence_pairs(text):
        if (closing.end() if closing else len(text)) <= end:
            continue
        if opening.start() < end:  # a Markdown block the program lies in: its words after the program
            parts.append(outside_blocks(text[end : closing.start() if closing else len(text)]))
        else:
            parts.append(text[max(start, end) : opening.start()])
        if closing is None and opening.start() >= end:
            parts.append(text[opening.end() :])
        start = closing.end() if closing else len(text)
    return "\n".join([*parts, text[max(start, end) :]])


_PROMPT = re.compile(r"^[ \t]*(?:>>>|\.\.\.)(?: |$)", re.MULTILINE)
"""A Python prompt at a line's start, in a session shown in a block (```pycon: found by an adversarial run, a
correction shown as a session went unseen)."""
_QUOTE_MARKS = re.compile(r"^[ ]{0,3}>(?!>>)[ ]?(?:[ ]{0,3}>(?!>>)[ ]?)*", re.MULTILINE)


def _unquoted(text: str) -> str:
    """``text`` with its Markdown block quotes' marks (``> ``) taken off the lines after its first fenced block and
    outside the fenced blocks, so that what a quote after the program holds is read as the reply's own text (found by
    an adversarial run: a corrected program in a fenced block inside a quote went unseen, and the draft ran); a quote
    before it echoes the user's code or task, and a Python prompt (``>>>``) is no mark."""
    pairs = list(fence_pairs(text)) if ">" in text else []
    if not pairs:
        return text
    parts, end = [], pairs[0][1].end() if pairs[0][1] else len(text)
    parts.append(text[:end])
    for opening, closing in pairs[1:]:
        parts += [
            _QUOTE_MARKS.sub("", text[end : opening.start()]),
            text[opening.start() : closing.end() if closing else len(text)],
        ]
        end = closing.end() if closing else len(text)
    return "".join([*parts, _QUOTE_MARKS.sub("", text[end:])])


_DIFF_PROBLEM = (
    "no Python program found: the reply gives a change as a diff; give the whole program, changes made, in one code "
    "block"
)


_SIGNED_CALL_PROBLEM = (
    "a call with a sign before it reads as a line of a diff (- removed, + added), not as code to run; give the whole "
    "program, changes made, in one code block"
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


def _refuse_signed_calls(tree: ast.Module) -> None:
    """Refuse a statement that is a call with a sign before it (``-push_to_position(...)``, ``+ open_gripper()``):
    no program negates what a call returns and throws it away, but a diff's removed and added lines parse so, and
    a removed line would still run (found by an adversarial run: a push the model removed was made)."""
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Expr)
            and isinstance(node.value, ast.UnaryOp)
            and isinstance(node.value.op, (ast.USub, ast.UAdd))
            and isinstance(node.value.operand, ast.Call)
        ):
            raise ProgramRejected(node.lineno, "blocks", _SIGNED_CALL_PROBLEM)


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


_ONLY_PROGRAM = "the only program; the other blocks quote it or are no programs"


def _choose_block(blocks: list[_Block]) -> tuple[int, str]:
    """The index of the block to run and why (see :func:`extract`); raises :class:`ProgramRejected` when a block
    meant as a program does not parse, or several different programs leave it unclear which one is meant."""
    trees: dict[int, ast.Module | None] = {}
    for k, block in enumerate(blocks):
        try:
            trees[k] = quiet_parse(block.code)
        except (SyntaxError, ValueError, MemoryError):
            trees[k] = None
    tagged = any(block.tagged and trees[k] is not None for k, block in enumerate(blocks))
    programs: list[int] = []
    for k, block in enumerate(blocks):
        tree, code = trees[k], block.code
        if tree is None:
            if _has_diff(code.split("\n")):
                raise ProgramRejected(None, "blocks", _DIFF_PROBLEM)
            if block.tagged or (not tagged and any(looks_like_code(line) for line in code.split("\n"))):
                return k, "it does not parse"  # parse_program raises its syntax error
            if not tagged or any(calls(line.strip()) for line in code.split("\n")):
                return k, "it does not parse"
            continue  # an untagged listing (``open_gripper() -> ok``) beside a Python block that parses
        if has_action(tree) and (block.tagged or not tagged or _has_call(tree)):
            programs.append(k)  # an untagged block that calls nothing beside a Python block is an output listing
        elif _has_diff(code.split("\n")):
            raise ProgramRejected(None, "blocks", _DIFF_PROBLEM)
    if not programs:
        return len(blocks) - 1, "the last"
    quotes = _Quotes(blocks, programs)
    marked = [k for k in programs if marks_final(blocks[k].label, blocks[k].heading) and not quotes.fragment(k)]
    if len({tuple(_statement_lines(blocks[k].code)) for k in marked}) > 1:  # two options, or an echo marked too
        raise ProgramRejected(
            None,
            "blocks",
            f"the reply marks {len(marked)} different programs as final (code blocks "
            f"{', '.join(str(k + 1) for k in marked)}) and does not say which one is meant; give exactly one program, "
            "in one code block",
        )
    if marked and len(programs) > 1:  # a program marked final is meant unless a different one follows it
        later = [k for k in programs if k > marked[-1] and not quotes(k, marked[-1]) and not aside(blocks[k].label)]
        if not later:
            return _unretracted(blocks, programs, quotes, marked[-1]), f"marked {blocks[marked[-1]].label[:60]!r}"
        whole = [marked[-1], *later]
    else:
        whole = quotes.whole()
        if len(whole) == 1:
            return _unretracted(blocks, programs, quotes, whole[0]), _ONLY_PROGRAM
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


def _unretracted(blocks: list[_Block], programs: list[int], quotes: _Quotes, chosen: int) -> int:
    """``chosen``, unless a later block that repeats part of it follows words that take it back or mark the part as
    the program ("Wait, the rest is wrong. Simply:", "Final program:"): a correction that keeps a run of the draft's
    lines reads as a quote of it (found by an adversarial run, where the longer draft ran); it is asked again."""
    for k in programs:
        if k > chosen and quotes(k, chosen) and retracts(blocks[k].label):
            raise ProgramRejected(
                None,
                "blocks",
                f"code block {k + 1} repeats part of block {chosen + 1} after {blocks[k].label[-80:]!r}; it is not "
                "clear whether it replaces it; give exactly one program, in one code block",
            )
    return chosen


def _only_defines(tree: ast.Module) -> list[str]:
    """The functions and classes a program defines when it does nothing else at its top level (imports and a docstring
    aside), else []: run, it would do nothing (found by an adversarial run: "Final program:" over the definition, then
    "Usage:" over its call, ran the definition alone)."""
    names = []
    for k, node in enumerate(tree.body):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.append(node.name)
        elif not (
            isinstance(node, ast.Import | ast.ImportFrom)
            or (k == 0 and isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant))
        ):
            return []
    return names


def _has_call(tree: ast.Module) -> bool:
    return any(isinstance(node, ast.Call) for node in ast.walk(tree))


MOST_PROGRAMS = 8
"""Different programs in one reply past which they are not told apart (each more costs a pass over the blocks)."""


class _Quotes:
    """Which program blocks quote which: ``quotes(k, j)`` when block ``k`` is the same lines as block ``j`` in the same
    order, or a snippet of it explained: at most half as many lines, found in it in the same order, one after another,
    with the same indentation or all of it moved right (a loop's body quoted on its own); never a block that does the
    task on its own (:func:`_stands_alone`: a correction that leaves lines out, or the program an option extends), nor
    a later block that repeats the other's first lines (more than one), a correction that leaves the rest out. Each
    comparison costs the snippet's lines, and the program's text only when every line of the snippet is one of its."""

    def __init__(self, blocks: list[_Block], programs: list[int]) -> None:
        self.programs = programs
        self.lines = {k: _statement_lines(blocks[k].code) for k in programs}
        self.counts = {k: Counter(self.lines[k]) for k in programs}
        self.joined = {k: "\n" + "\n".join(self.lines[k]) + "\n" for k in programs}
        self.alone = {
            k: (len(self.lines[k]) >= 3 or _names_an_option(blocks[k])) and _stands_alone(quiet_parse(blocks[k].code))
            for k in programs
        }
        self.columns: dict[int, dict[str, set[int]]] = {k: {} for k in programs}
        for k in programs:
            for line in self.lines[k]:
                self.columns[k].setdefault(line.lstrip(), set()).add(_columns(line))

    def __call__(self, k: int, j: int) -> bool:
        lines = self.lines
        if k == j or lines[k] == lines[j]:
            return k != j
        if 2 * len(lines[k]) > len(lines[j]) or self.alone[k]:
            return False
        if k > j and len(lines[k]) > 1 and lines[j][: len(lines[k])] == lines[k]:
            return False
        shifts = {column - _columns(lines[k][0]) for column in self.columns[j].get(lines[k][0].lstrip(), set())}
        for shift in (shift for shift in shifts if shift >= 0):
            moved = [" " * shift + line for line in lines[k]]
            in_it = all(n <= self.counts[j][line] for line, n in Counter(moved).items())
            if in_it and "\n".join(["", *moved, ""]) in self.joined[j]:  # in order, one after another
                return True
        return False

    def fragment(self, k: int) -> bool:
        """Whether block ``k`` is part of another program rather than one: it quotes one, or it is at most half as
        long as one and does not do the task on its own (``add this at the end of the full program:``)."""
        return not self.alone[k] and any(2 * len(self.lines[k]) <= len(self.lines[j]) for j in self.programs)

    def whole(self) -> list[int]:
        """The programs (block indices, in order) that quote no other (of two equal blocks, the earlier quotes the
        later); past :data:`MOST_PROGRAMS`, those found so far."""
        whole: list[int] = []
        for k in sorted(self.programs, key=lambda k: (-len(self.lines[k]), -k)):  # a block only quotes a longer one
            if not any(self(k, j) for j in whole):
                whole.append(k)
                if len(whole) > MOST_PROGRAMS:
                    break
        return sorted(whole)


_OPTION = re.compile(
    r"\b(?:option|approach|alternative(?:ly)?|variant|plan [a-z0-9])\b|^\W*or\b|"
    r"\bif (?:you (?:also |only |just )?(?:want|need|prefer)|there(?:'s| is| are))\b|"
    r"\b(?:the )?(?:simple|simpler|short|shorter|direct|safer|minimal) (?:one|version|way|route)\b",
    re.IGNORECASE,
)
"""Words before a block that offer it as one of several ways ("Option 2 (around the obstacle):", "Or, pushing the box
first:", "If you also want it to cross the platform:"): a program so offered is one on its own, however short, not a
quote of a longer one (found by an adversarial run: a 1-2 line option whose lines ran in the other was read as a quote
of it, and the other ran)."""


def _names_an_option(block: _Block) -> bool:
    """Whether the words before ``block`` (its label or heading) offer it as one of several ways (:data:`_OPTION`)."""
    return any(_OPTION.search(text) for text in (block.label, block.heading))


def _stands_alone(tree: ast.Module) -> bool:
    """Whether a program reads only names it assigns, imports or defines (calls and builtins aside): it does the task
    on its own, not a piece of a program that uses the names another part assigns."""
    stored, read = set(_IMPORTS), set[str]()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            (read if isinstance(node.ctx, ast.Load) else stored).add(node.id)
        elif isinstance(node, ast.arg):
            stored.add(node.arg)
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            stored.add(node.name)
        elif isinstance(node, ast.alias):
            stored.add((node.asname or node.name).split(".")[0])
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            stored.add(node.func.id)
    return read <= stored | set(dir(builtins))


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
