"""A change to the program asked for in words after it, in an LM reply: "Actually, replace the last line with ...",
"Wait: swap the two calls", "Then add these steps at the end:". Such a reply means a program it does not show, so it
is asked again (found by an adversarial run: the program as written ran, the change said in words unseen). An
explanation ("It uses get_graspable_point rather than get_center", "You can change the offset") is no such request:
a sentence asks for a change when it opens with an edit verb ("Replace", "Then add", "Note: put"), or takes the
program back ("actually", "wait", "oops", "correction") and names an edit ("drop", "swap") or what a line should be;
and it names code (a call, a line, a step, the program; or it ends with a colon, before what it adds). An edit told
in the past ("this version adds the open step") describes the program shown, and a step told in the imperative
("2. Add 5 cm for the approach") what the program does."""

from __future__ import annotations

import re

from robotool.sandbox.placeholder import comments
from robotool.sandbox.validate import ProgramRejected

_EDITS = r"replace|change|swap|drop|remove|delete|insert|add|put|wrap|raise|lower|retry"
_OPENS_WITH_AN_EDIT = re.compile(
    r"[\W\d_]*(?:(?:note|also|then|and|so|now|finally|one fix|fix|correction|edit|update)\b[\s:,-]*)*(?:please\s+)?"
    r"(?:replace|change|swap|drop|remove|delete|insert|add|put|wrap|raise|lower|set|use\b.*\binstead)\b",
    re.IGNORECASE,
)
_TAKES_BACK = re.compile(r"\b(?:actually|wait|oops|sorry|correction|my mistake|one fix)\b", re.IGNORECASE)
_NAMES_AN_EDIT = re.compile(rf"\b(?:{_EDITS})\b|\b(?:should|must|needs? to) be\b", re.IGNORECASE)
_NAMES_CODE = re.compile(
    r"`|\w\(|\b(?:lines?|calls?|steps?|code|program|script|block|version|target|at the end|instead)\b|:\s*$",
    re.IGNORECASE,
)
_SENTENCE_END = re.compile(r"(?<=[.!?])\s+|\n")


def change_in_words(prose: str) -> str | None:
    """The first sentence of ``prose`` (a reply's words after its program) that asks for a change to the program (see
    the module), or None."""
    for sentence in _SENTENCE_END.split(prose):
        sentence = sentence.strip()
        edit = _OPENS_WITH_AN_EDIT.match(sentence) or (_TAKES_BACK.search(sentence) and _NAMES_AN_EDIT.search(sentence))
        if edit and _NAMES_CODE.search(sentence):
            return sentence
    return None


def refuse_change_in_words(prose: str) -> None:
    """Raise :class:`ProgramRejected` when ``prose`` (the reply's words after its program) asks for a change to the
    program (:func:`change_in_words`)."""
    sentence = change_in_words(prose)
    if sentence is not None:
        raise ProgramRejected(
            None,
            "text",
            f"after its program the reply asks for a change in words ({sentence[:80]!r}); give the whole program, "
            "changes made, in one code block",
        )


_REMOVE_ME = re.compile(
    r"\b(?:remove|delete)\s+(?:this|that)\b|\bdrop\s+(?:this|that)\s+(?:line|call|step)\b|"
    r"\b(?:this|the) line (?:is )?not needed\b",
    re.IGNORECASE,
)


def refuse_change_in_comments(code: str) -> None:
    """Raise :class:`ProgramRejected` when a comment in the program asks to remove the code it stands beside
    (``close_gripper()  # remove this line: the task is only to reach``: found by an adversarial run, where the line
    ran)."""
    for line, text in comments(code).items():
        if _REMOVE_ME.search(text):
            raise ProgramRejected(
                line,
                "text",
                f"a comment in the program asks for a change ({text[:60]!r}); give the whole program, changes made",
            )
