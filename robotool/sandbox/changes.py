"""A change to the program asked for in words after it, in an LM reply: "Actually, replace the last line with ...",
"Wait. The last call is wrong: it should be `open_gripper()`", "Then add these steps at the end:". Such a reply means a
program it does not show, so it is asked again (found by an adversarial run: the program as written ran, the change
said in words unseen).

Most words after a program explain it, and a second adversarial run showed how easily a word list refuses them: step
lists name the robot's own actions ("**Lower and grasp**: the second call lowers ..."), tips speak to the user
("Replace `"milk"` with your object's name if it differs"), and answers to a request to ask again apologise ("Sorry, I
forgot the open step; it is fixed now"). So a sentence asks for a change only in these shapes, read with Markdown
emphasis, list and quote marks taken off:

- it opens with an edit of code ("Replace", "Then add", "Note: remove", "Make ... instead"; the robot's own verbs,
  such as lower, raise, drop or put, are no edit) whose object, within its first words, is a place in the program (the
  last line, line 3, the first call, at the end, code in backticks) or that ends with a colon, before what it adds,
  and it sets no condition ("if your object differs", "to suit your gripper": a tip), describes no program shown
  ("Change: the gripper now opens first") and lists no changes made ("Changes made: - Replace ..."); or it turns one
  call into another (`close_gripper()` -> `open_gripper()`);
- it names the code a place should hold ("the last line must be `x`, not `y`", "Instead of `y`, call `x`"), asks
  in the imperative to call code the program does not hold ("Don't forget to call `x`"), asks for an edit in
  Japanese, Korean or Russian naming code, or withdraws the program ("Wait, this is wrong ... Let me reconsider.");
- or a sentence that opens by taking something back ("Actually,", "Wait.", "Oops", "Correction:", "My mistake",
  "Fix:") names code or a place in the program, or one of the next two sentences names it and says what it should be
  ("should be", "is wrong", "not needed", an edit), and none of them describes the program shown ("this version",
  "is fixed now", "as above", told in the past) or sets a condition.
"""

from __future__ import annotations

import re

from robotool.sandbox.placeholder import comments
from robotool.sandbox.validate import ProgramRejected

_TERMINAL = re.compile(r"\x1b(?:\[[0-?]*[ -/]*[@-~]|\][^\x07\x1b]*(?:\x07|\x1b\\)?|[@-Z\\-_])|[\x00-\x08\x0e-\x1f\x7f]")
"""A terminal's control sequences (colours, bold, titles) and other control characters: a reply relayed from a
terminal may wrap its words in them, which would hide the word that opens a sentence (found by an adversarial run:
"\\x1b[1mActually, replace the last line ..." ran the program as written)."""
_MARKS = re.compile(r"\*\*|__|~~|^(?:[^\w`]|_)*(?:\d+[.)]\s+|\[!\w+\]\s*)?")
"""Markdown emphasis anywhere, and at a sentence's start what is no word nor code (list, quote, heading and table
marks, an emoji, an opening bracket) and a step's number."""
_ABBREVIATIONS = re.compile(r"\b(?:e\.g|i\.e|etc|vs|cf|approx|incl)\.", re.IGNORECASE)
_SENTENCE_END = re.compile(r"(?<=[.!?])\s+|\n")
_PREFIX = (
    r"(?:(?:note|also|then|and|so|now|finally|ps|p\.s|todo|nb|important|update|edit|fix|correction|actually|oh|one fix|"
    r"one more thing|instead|you (?:should|need to|must|have to))\b[\s:,.\-—–]*)*(?:please\s+)?"
)
_EDIT = (
    r"replace|(?:change|modify|update|edit)(?!\s*:)|swap|remove|delete|add|append|prepend|skip|scrap|comment out|"
    r"get rid of|leave out|make(?! sure)|use\b.{0,60}\binstead|insert|switch|reorder|(?:put|move)(?=\s+\*{0,2}`)"
)
_PLACE = (
    r"`[^`]+`|\b(?:the )?(?:last|first|second|third|fourth|final|next|previous|\d+(?:st|nd|rd|th)) "
    r"(?:line|call|step|move|command|one)s?\b|\blines? \d+\b|\bat the (?:very )?(?:end|start|beginning|top|bottom)\b|"
    r"\b(?:before|after) (?:the )?`?\w+\("
)
_OPENS_WITH_AN_EDIT = re.compile(rf"{_PREFIX}(?:{_EDIT})\b(?P<rest>.*)", re.IGNORECASE | re.DOTALL)
_NAMES_A_PLACE = re.compile(_PLACE, re.IGNORECASE)
_CONDITION = re.compile(
    r"\b(?:if|when|whenever|unless|in case|to suit|as needed|your|you'd|you want|for (?:other|taller|shorter|heavier)|"
    r"to grasp|to handle|to make)\b",
    re.IGNORECASE,
)
_TAKES_BACK = re.compile(
    r"(?:(?:hmm|oh),?\s*)?(?:actually\b|wait\s*[,.!:;—–-]|oops\b(?!-)|sorry(?! (?:for|about|if|to)\b)|correction\b|"
    r"one correction\b|(?:small |one |quick )?fix:|my mistake|on second thought|no,? wait|no\s*[,.—–-]|scratch that|"
    r"typo\b|"
    # the same in the languages whose final markers the labels read (es, pt, fr, de, zh, ja, ko, ru)
    r"en realidad\b|corrección\b|na verdade\b|correção\b|en fait\b|eigentlich\b|korrektur\b|更正|修正：|其实|"
    r"申し訳|すみません|ごめんなさい|訂正|正しくは|죄송|잠깐|정정|извините|подождите|поправка\b|на самом деле\b)",
    re.IGNORECASE,
)
_EDIT_ASKED_ELSEWHERE = re.compile(
    r"置き換えて|に置き換え|変更して|削除して|追加して|にしてください|"
    r"바꾸세요|바꿔 ?주세요|변경하세요|삭제하세요|추가하세요|넣으세요|"
    r"\b(?:замените|измените|поменяйте|удалите|уберите|добавьте|вставьте)\b",
    re.IGNORECASE,
)
"""An edit asked for in the imperative in Japanese, Korean or Russian ("最後の行を `x` に置き換えてください",
"마지막 줄을 `x`로 바꾸세요", "Замените последнюю строку на `x`"): with code named, a change to the program (found by an
adversarial run, where the English verbs alone were read)."""
_NAMES_CODE = re.compile(r"`[^`]*`|\w\(|\b(?:line|call|step)s?\b", re.IGNORECASE)
_SAYS_WHAT_IT_SHOULD_BE = re.compile(
    rf"\b(?:should (?:be|read|come|stay|go)|must (?:be|come)|has to (?:be|come)|needs? to (?:be|come)|is wrong|"
    rf"are wrong|not needed|don't|do not|no need|instead|rather than|I meant|missing|use|{_EDIT})\b|\bnot `|→|->",
    re.IGNORECASE,
)
_DESCRIBES_THE_PROGRAM = re.compile(
    r"\b(?:this version|(?:the )?(?:version|program|code) above|as above|now|fixed|applied|already|as it is|as shown|"
    r"I forgot|I had|I've|I have|was|were|which (?:this|it) does|(?:is|are) (?:called|done|there|in place))\b",
    re.IGNORECASE,
)
_BLANKED_CODE = re.compile(r"`[^`]*`")
_CHANGE_LOG = re.compile(
    r"(?:here(?:'s| is) )?(?:key |main )?(?:changes(?: made| applied)?|(?:a )?summary of (?:the )?changes|"
    r"(?:fix(?:es)?|modifications|improvements|edits) (?:made|applied)|what (?:was |I )?(?:changed|fixed)|"
    r"what(?:'s| is) different)\s*(?::|$)",
    re.IGNORECASE,
)
"""A list of the changes made, in the imperative ("Changes made: - Replace ...", "Summary of changes:", "Fixes
applied:", "What I fixed:"), describes the program shown. A bare "Fix:" or "Modifications:" may as well ask for them
(after the program as it was), and is read as a request."""
_CALL_SPAN = r"\*{0,2}`[^`]*\w\([^`]*`"
_NAMES_ITS_REPLACEMENT = re.compile(
    rf"\b(?:should|must|needs? to|has to) (?:be|read|end with|come (?:first|last))\s*:?\s*{_CALL_SPAN}|"
    rf"\binstead of\s+\*{{0,2}}`[^`]+`[^.!?]*?\b(?:call|use)\s+\*{{0,2}}`|"
    rf"\brather than\s+\*{{0,2}}`[^`]+`[^.!?]*?\b(?:call|use)\s+\*{{0,2}}`|"
    rf"\b(?:call|use)\s+\*{{0,2}}`[^`]+`[^.!?]{{0,60}}\binstead of\b|"
    rf"\buse\s+\*{{0,2}}`[^`]+`[^.!?]{{0,30}},? not\s+\*{{0,2}}`",
    re.IGNORECASE,
)
"""A sentence that names the code a place of the program should hold ("the last line must be `open_gripper()`, not
...", "Instead of `close_gripper()`, call `open_gripper()`", "Use `x` here, not `y`"), whatever opens it (found by an
adversarial run: such notes after the only program, opened by no edit verb nor take-back, ran the program as it was)."""
_WITHDRAWS = re.compile(
    r"\b(?:this|that|it|the above|the (?:program|code|version) above)\b[^.!?:]{0,40}?\b(?:is wrong|is incorrect|"
    r"won't work|will not work|doesn't work|does not work|fails|is unnecessary|is not needed)\b|"
    r"\blet me (?:reconsider|redo|rethink|try (?:again|another)|fix (?:this|that|it)|correct (?:this|that|it))\b|"
    r"\bthe (?:\w+ )?(?:push|walk|climb|move|turn|grasp|step|call|line)e?s? (?:is|are) "
    r"(?:unnecessary|not needed|wrong)\b",
    re.IGNORECASE,
)
"""Words after the program that withdraw it ("Wait, this is wrong ... Let me reconsider.", "Hmm, the above won't
work: the box is fixed."): found by an adversarial run, where the program ran as if meant."""
_UNDONE = re.compile(
    r"\b(?:don't|do not|no need to)\s+(?:\w+\s+)?(?:push|walk|climb|move|turn|grasp|open|close|lift|lower)\b|"
    r"\bshould (?:be|read)\s+(?:-?\d|\[|[A-Za-z_]\w*\[)",
    re.IGNORECASE,
)
"""After a take-back, a step undone or a number changed without naming the code ("Actually, don't push the box",
"Wait, but the climb height should be 0.45", "the push target should be [1.2, 0.0, 0.0]", "x should be box[0] - 0.6"):
found by adversarial runs, where the program ran as written."""
_TOKEN = re.compile(r"[\w.]+")
"""A program's names and numbers, as written (``0.3``, ``box``; ``p2[0]`` is ``p2`` and ``0``)."""
_NOT_A_NUMBER = re.compile(r"\b(?:not|instead of|rather than)\s+(-?\d+(?:\.\d+)?)\b(?!\s*%)", re.IGNORECASE)
"""After a take-back, a number of the program said not to be meant ("Wait, the box is 0.25 m tall, not 0.3."): found by
an adversarial run of replies shaped like real models', where the program ran with 0.3."""
_FIRST_PERSON = re.compile(r"\b(?:I|we)\b")
"""What the model did ("I used `x` instead of hard-coding ..."), not what it asks for."""
_ARROW = re.compile(r"`[^`]*\w\([^`]*`\s*(?:→|->|=>)\s*`[^`]*`")
"""One call turned into another (`close_gripper()` → `open_gripper()`)."""


def change_in_words(prose: str, program: str | None = None) -> str | None:
    """The first sentence of ``prose`` (a reply's words after its program) that asks for a change to the program (see
    the module), or None; given the ``program``, also one that asks to call code the program does not hold
    (:func:`_asks_for_a_missing_call`)."""
    plain = _ABBREVIATIONS.sub("", _TERMINAL.sub("", prose))
    sentences = [_MARKS.sub("", s).strip() for s in _SENTENCE_END.split(plain)]
    sentences = [s for s in sentences if s]
    held = frozenset(_TOKEN.findall(program)) if program is not None else frozenset()  # its numbers, once
    code = _plain(program) if program is not None else None  # (once: not once per sentence)
    for k, sentence in enumerate(sentences):
        if _ARROW.search(sentence) or (not _logged(sentences[max(k - 5, 0) : k]) and _asks(sentence, code)):
            return sentence
        if _WITHDRAWS.search(sentence) and not _CONDITION.search(_BLANKED_CODE.sub("x", sentence)):
            return sentence
        if _TAKES_BACK.match(sentence):
            for later in sentences[k : k + 3]:
                words = _BLANKED_CODE.sub("x", later)
                if _DESCRIBES_THE_PROGRAM.search(words) or _CONDITION.search(words):
                    continue
                named = (
                    _NAMES_CODE.search(later)
                    or _NAMES_A_PLACE.search(later)
                    or _UNDONE.search(words)
                    or _takes_back_a_number(words, held)
                )
                if named and (later is sentence or _SAYS_WHAT_IT_SHOULD_BE.search(words)):
                    return later
    return None


def _takes_back_a_number(words: str, held: frozenset[str]) -> bool:
    """Whether words say a number the program holds (its tokens ``held``) is not meant (:data:`_NOT_A_NUMBER`): one
    set lookup per number said, so a long reply against a long program costs their lengths added, not multiplied
    (a hostile reply of 20,000 "not 9.9" against a 100 kB program took 75 s when each was searched for)."""
    return any(found[1].lstrip("-") in held for found in _NOT_A_NUMBER.finditer(words))


def _logged(earlier: list[str]) -> bool:
    """Whether one of the sentences before opens a list of the changes made (:data:`_CHANGE_LOG`)."""
    return any(_CHANGE_LOG.match(sentence) for sentence in earlier)


def _asks(sentence: str, code: str | None) -> bool:
    """Whether a sentence asks for a change in one of the shapes read without a take-back before it: an edit opening
    it, an edit asked in Japanese, Korean or Russian naming code, the code a place should hold, or (given the
    program's ``code``, :func:`_plain`) a call the program does not hold."""
    return (
        _asks_an_edit(sentence)
        or (_EDIT_ASKED_ELSEWHERE.search(sentence) is not None and _BLANKED_CODE.search(sentence) is not None)
        or (_NAMES_ITS_REPLACEMENT.search(sentence) is not None and not _tells(_BLANKED_CODE.sub("x", sentence)))
        or (code is not None and _asks_for_a_missing_call(sentence, code))
    )


def takes_back(sentence: str) -> bool:
    """Whether a sentence opens by taking something back ("Actually,", "Wait.", "Oops", "Correction:", "My mistake"),
    Markdown marks and terminal sequences aside."""
    return _TAKES_BACK.match(_MARKS.sub("", _TERMINAL.sub("", sentence)).strip()) is not None


def _asks_an_edit(sentence: str) -> bool:
    """Whether a sentence opens with an edit of a place in the program, and sets no condition (see the module)."""
    found = _OPENS_WITH_AN_EDIT.match(sentence)
    words = _BLANKED_CODE.sub("x", sentence)
    if found is None or _CONDITION.search(words) or _DESCRIBES_THE_PROGRAM.search(words):
        return False
    rest = found.group("rest")
    if rest.lstrip().startswith(":") and rest.lstrip()[1:].strip():
        return False  # a step's label ("3. **Swap**: the two moves trade places"), not an order
    return rest.rstrip().endswith(":") or _NAMES_A_PLACE.search(" ".join(rest.split()[:8])) is not None


_ASKS_TO_CALL = re.compile(r"\b(?:call|calling|add|insert|run)\s+\*{0,2}`(?P<code>[^`]*\w\([^`]*)`", re.IGNORECASE)


def _asks_for_a_missing_call(sentence: str, code: str) -> bool:
    """Whether a sentence asks to call code (``call `open_gripper()` first``, "don't forget to call ...") that the
    program (its ``code``, :func:`_plain`) does not hold as written, and tells nothing done or shown (found by an
    adversarial run: "Don't forget to call `open_gripper()` before the move", after a program without it, ran that
    program)."""
    if _tells(_BLANKED_CODE.sub("x", sentence)):
        return False
    return any(_plain(found["code"]) not in code for found in _ASKS_TO_CALL.finditer(sentence))


def _plain(code: str) -> str:
    """Code without its white space, its quotes all double: the same call however it is spaced or quoted."""
    return re.sub(r"\s+", "", code).replace("'", '"')


def _tells(words: str) -> bool:
    """Whether a sentence (its code blanked) tells what was done or what is shown, or sets a condition: no request."""
    return any(pattern.search(words) for pattern in (_FIRST_PERSON, _DESCRIBES_THE_PROGRAM, _CONDITION))


def refuse_change_in_words(prose: str, program: str | None = None) -> None:
    """Raise :class:`ProgramRejected` when ``prose`` (the reply's words after its ``program``) asks for a change to the
    program (:func:`change_in_words`)."""
    sentence = change_in_words(prose, program)
    if sentence is not None:
        raise ProgramRejected(
            None,
            "text",
            f"after its program the reply asks for a change in words ({sentence[:80]!r}); give the whole program, "
            "changes made, in one code block",
        )


_REMOVE_ME = re.compile(
    r"\b(?:remove|delete|drop)\s+(?:this|that)(?:\s+(?:line|call|step))?\s*(?:$|[:;,.(—–-])|"
    r"\b(?:this|the) line (?:is )?not needed\b|\bshould be `?\w+\(|"
    # found by a later adversarial run: each ran the line it stands beside
    r"(?:^|<-+|-+>|→|:|,)\s*(?:remove|delete|drop)(?:\s+(?:it|this|me))?\s*[.!]?\s*$|"
    r"\b(?:change|replace|swap)\s+(?:this|it|that)(?:\s+(?:line|call))?\s+(?:to|with|for|by)\b|"
    r"\b(?:TODO|FIXME)\b\W*(?:replace|change|remove|delete|add|fix|use|swap)\b|\bFIXME\b|\boops\b|"
    r"\bwrong\b[^#]{0,40}\buse\b",
    re.IGNORECASE,
)


def refuse_change_in_comments(code: str) -> None:
    """Raise :class:`ProgramRejected` when a comment in the program asks to remove the code it stands beside or says
    what it should be instead (``close_gripper()  # remove this line: the task is only to reach``,
    ``close_gripper()  # should be open_gripper() here``: found by adversarial runs, where the line ran)."""
    for line, text in comments(code).items():
        if _REMOVE_ME.search(text):
            raise ProgramRejected(
                line,
                "text",
                f"a comment in the program asks for a change ({text[:60]!r}); give the whole program, changes made",
            )
