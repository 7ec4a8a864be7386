"""What the words before a code block in an LM reply say of it: that it is the final program ("Final program:",
"Here is the corrected code:", "最终代码："; :func:`marks_final`), that it is set aside ("For comparison, the naive
version:", "The code you provided:"; :func:`aside`), or that it takes back the block before ("Wait, the rest is
wrong. Simply:"; :func:`retracts`). :mod:`.extract` chooses a block by them."""

from __future__ import annotations

import re

from robotool.sandbox.changes import takes_back

_FINAL = re.compile(
    r"\b(?:final|corrected|fixed|revised|complete|full|whole|updated|improved|combined)\s+(?:python\s+)?"
    r"(?:program|code|version|script|solution|answer)\b|"
    r"\bputting it all together\b|\beverything (?:combined|together)\b|"
    r"\b(?:código|programa|versión|versão|code|programme|codice|programma|versione)\s+"
    r"(?:final|finale|corregid[oa]|corrigid[oa]|corrigée?|corrett[oa])\b|"
    r"\b(?:endgültige|finale|korrigierte)[sr]?\s+(?:programm|code|version)\b|最终(?:代码|程序|版本)|修正后的(?:代码|程序)|"
    r"最終(?:的な)?(?:コード|プログラム)|修正(?:後|した)の?(?:コード|プログラム)|(?:최종|수정된) ?(?:코드|프로그램)|"
    r"\b(?:окончательн|итогов|исправленн)\w*\s+(?:код|программ)\w*",
    re.IGNORECASE,
)
"""A final marker, in English and in the languages models answer in most (found by adversarial runs: '最终代码：',
'Código final:', 'Programme final :', 'Endgültiges Programm:', '修正後のコード：', '수정된 코드:',
'Исправленный код:' were read as no marker, and so were "Combined program:" and "Putting it all together:" after step
snippets that name things otherwise)."""
_FAULTY = r"wrong|incorrect|buggy|broken|fails?|failed|failing|crashed"  # may say so of the block before the label
_SET_ASIDE = (
    r"not|never|no|original|old|older|previous|earlier|initial|first|draft|current|currently|existing|gave|given|sent|"
    r"before|provided|reference|comparison|shared|wrote|options?|alternatives?|alternatively|test|testing|example|usage"
)
_BARE_FINAL = re.compile(r"[#*_\s]*final[*_\s]*:?[*_\s]*", re.IGNORECASE)  # one word: 'FINAL:', '### Final'
_NOT_FINAL = re.compile(rf"\b(?:{_SET_ASIDE}|{_FAULTY})\b|n't\b", re.IGNORECASE)
_ASIDE = re.compile(
    r"\b(?:for (?:comparison|reference)|alternatively|alternatives?|another option|options? \d|"
    r"(?:the|your|my) (?:original|old|older|previous|earlier|initial|current|first) "
    r"(?:program|code|version|script|attempt|draft)|"
    r"(?:you|I) (?:provided|gave|sent|wrote|shared)|usage|example|test(?:ing)?\b)",
    re.IGNORECASE,
)
"""Words that set a block aside as not the program, after a program marked final (a correction says nothing of the
kind; what this misses is asked again, the safe side: found by an adversarial run, "not", "no", "first", "before" in
a correction's label set the correction aside and ran the draft)."""


_CALLS_IT_WRONG = re.compile(
    rf"\b(?:that|this|the above|the rest|the (?:first|previous|earlier) (?:version|program|draft|attempt))\b"
    rf"[^.!?]{{0,80}}?\b(?:is|are|was|were)\b[^.!?]{{0,80}}?\b(?:{_FAULTY}|not needed|unnecessary)\b|"
    r"\bonly \w+(?: \w+)? (?:is|are) (?:needed|necessary|required)\b",
    re.IGNORECASE,
)
"""A sentence that calls the block before wrong or not needed ("the turn and the climb are wrong"), or says only a
part is needed: a later block that repeats part of the program after it is a correction, not a quote."""
_SHORTER = re.compile(
    r"[#*_\s]*(?:or,?\s*)?(?:simply|just|instead|rather|shorter|simpler|"
    r"(?:the )?(?:shorter|simpler) (?:version|program|code))[*_\s]*[:：]?",
    re.IGNORECASE,
)
"""A last sentence that is only "Simply:", "Just:", "Shorter version:": what follows replaces the block before."""
_CORRECTION_ALONE = re.compile(
    r"[#*_\s]*(?:(?:so,?\s*)?(?:here(?:'s| is)|this is|below is)\s+)?(?:the |a |my )?(?:"
    r"corrected|fixed|updated?|revised|better|correct(?:ed)? (?:version|program|code)|(?:the )?fix|edit|after|"
    r"(?:it )?should (?:just |only )?(?:be|read)(?: just| only)?|(?:use|try) this(?: instead)?|use|"
    r"(?:right|cleaner|simpler|better|working) (?:program|code|version)(?: is)?)[*_\s]*[:：]?[*_\s]*",
    re.IGNORECASE,
)
"""A last sentence that is only a correction's label ("Corrected:", "Fixed:", "Here's the fix:", "Use this:", "It should
be:"): what follows replaces the block before (found by an adversarial run: a shorter fix under such a label was read
as a quote, and the draft ran)."""
_ASKS_FOR_A_CHANGE = re.compile(
    r"\b(?:should|must)\s+(?:just |only )?(?:be|read|end with|start with|begin with|look like)\b|"
    r"\b(?:isn't|is not|aren't|are not|not)\s+(?:needed|necessary|required)\b|"
    r"\bonly the (?:last|first) (?:\w+ )?(?:lines?|calls?|steps?) (?:is|are) (?:needed|necessary|required)\b|"
    r"\bmove (?:this|these|that) (?:line|lines|call|calls)\b|\b(?:don't|do not) need\b",
    re.IGNORECASE,
)
"""A label that asks for a change to the block before, with what follows as the change ("The last line should be:",
"The push isn't necessary; start from here:", "Move this line to the end:"): found by an adversarial run, where the
fragment after it read as a quote and the unchanged program ran."""
_MARKER_ALONE = re.compile(
    rf"[#*_\s]*(?:(?:so,?\s*)?(?:here(?:'s| is)|this is|below is)\s+)?(?:the |my |a )?(?:{_FINAL.pattern})"
    r"[*_\s]*[:：]?",
    re.IGNORECASE,
)


def marks_final(label: str, heading: str) -> bool:
    """Whether a block's label, or the heading above it (``## Final program``, then a sentence), marks it final."""
    return _marked_final(label) or (heading != label and _marked_final(heading))


def _marked_final(label: str) -> bool:
    """Whether a label says the block after it is the final program ("Final program:", "Here is the corrected
    code:"), not only names a word ("To complete the task", "What was fixed:") or takes it back in the marker's
    sentence or after it ("This draft is not the final version:", "The original full program:", "The final version?
    No, it is wrong:"); a label of the one word (``Final:``, ``**FINAL:**``, ``### Final``) marks it too."""
    if _BARE_FINAL.fullmatch(label):
        return True
    found = _FINAL.search(label)
    if found is None:
        return False
    sentence = max(label.rfind(end, 0, found.start()) for end in ".!?") + 1  # where the marker's sentence begins
    return _NOT_FINAL.search(label[sentence:]) is None


def retracts(label: str) -> bool:
    """Whether a label takes back the block before it: one of its sentences opens by taking something back ("Wait,",
    "Actually,", "Oops": :func:`.changes.takes_back`) or calls the block wrong (:data:`_CALLS_IT_WRONG`), or its last
    sentence is only a word that shortens ("Simply:", "Just:"), a final marker ("Final program:", "最终代码：") or a
    correction's label ("Corrected:", "Here's the fix:": :data:`_CORRECTION_ALONE`). Such
    words inside an explanation ("To run it, simply call:", "The part that actually does the approach:") take
    nothing back (found by an adversarial run: snippets explained were asked again)."""
    sentences = [s.strip() for s in re.split(r"(?<=[.!?])\s+", label) if s.strip()]
    last = sentences[-1] if sentences else ""
    return (
        any(takes_back(sentence) for sentence in sentences)
        or _CALLS_IT_WRONG.search(label) is not None
        or _SHORTER.fullmatch(last) is not None
        or _MARKER_ALONE.fullmatch(last) is not None
        or _CORRECTION_ALONE.fullmatch(last) is not None
        or _ASKS_FOR_A_CHANGE.search(label) is not None
    )


_NOT_AN_ANSWER = re.compile(
    r"\b(?:(?:first |rough )?draft|pseudo-?code|(?:rough )?sketch|untested|not (?:the |a )?final|what not to do|"
    r"superseded|naive (?:version|attempt|approach|program)|partial (?:fix|program|solution|version)|"
    r"(?:code|program) (?:you|the user) (?:provided|gave|sent|shared|wrote)|from (?:your|the) prompt)\b|"
    r"^[#*_\s]*(?:your|the user's) (?:final |original |current )?(?:code|program)[*_\s]*[:：]?[*_\s]*$",
    re.IGNORECASE,
)
"""Words before a reply's only program that say it is not the answer: a draft, pseudo-code, a sketch, a partial fix,
what not to do, the user's own code echoed (found by an adversarial run, where each ran as the program)."""


def not_an_answer(label: str, heading: str) -> bool:
    """Whether a block's label, or the heading above it, says it is no answer (:data:`_NOT_AN_ANSWER`), and it is not
    marked final."""
    return not marks_final(label, heading) and any(_NOT_AN_ANSWER.search(text) for text in (label, heading))


_FAULTY_LABEL = re.compile(rf"\b(?:{_FAULTY}|never|misses|missing)\b", re.IGNORECASE)
"""Words that call the block before a label faulty: what follows them is its correction, not an aside."""


def aside(label: str) -> bool:
    """Whether a label's last sentence says the block after it is not the program (``For comparison, the naive
    version:``, ``The code you provided:``); a correction after a program marked final says nothing of the kind, and
    a sentence that calls something wrong may take back the block before it (``Wait, that is wrong.``: found by an
    adversarial run, where the retracted block ran); nor is a label that takes back the block before it or calls it
    faulty (:func:`retracts`, :data:`_FAULTY_LABEL`: "Wait, the previous code never opens the gripper; use this:",
    "My first attempt above is wrong; use this instead:", found by a second adversarial run), nor one that prefers it
    (:data:`_PREFERS`)."""
    sentence = max(label.rstrip(" .!?:").rfind(end) for end in ".!?") + 1
    return (
        _ASIDE.search(label[sentence:]) is not None
        and not retracts(label)
        and not _FAULTY_LABEL.search(label)
        and not _PREFERS.search(label)
    )


_PREFERS = re.compile(
    r"\b(?:recommend(?:ed)?|better|prefer(?:red|able)?|corrected|fixed|forgot|actually works?|that works|working)\b",
    re.IGNORECASE,
)
"""Words that prefer the block after a label to the one before ("Alternatively, and this is what I'd recommend:",
"For comparison, the corrected version:", "The original code forgot to open the gripper; use this version:"): no
aside (found by an adversarial run, where the program marked final before it ran)."""
