"""A change to the program asked for in words after it is asked again; an explanation after it is not (the words of
real chat models' epilogues). Found by an adversarial run: the change in words went unseen and the program ran."""

from __future__ import annotations

import pytest

from robotool.sandbox import ProgramRejected, extract

GRASP = 'p = get_graspable_point("milk")\nopen_gripper()\nmove_to_position(p)\nclose_gripper()\n'
FENCED = f"```python\n{GRASP}```\n"

CHANGES = {
    "replace in a span": "Actually, replace the last line with `move_to_position([0.1, 0.2, 0.3])`.",
    "replace, then an output": "Actually, replace the last line with `open_gripper()`.\nOutput:\n```\nDone\n```",
    "a removal naming a call the program makes": "Actually, drop the `close_gripper()` line: only reach the milk.",
    "a removal without a span": "Actually, remove the close_gripper() call at the end.",
    "a reorder": "Wait: swap `open_gripper()` and `move_to_position(p)`, the gripper must open after the move.",
    "a wrap after a take-back": "Actually, put `close_gripper()` under an `if p[2] > 0:` check.",
    "in bold, after a heading": "## Correction\n\nThe last line is wrong. It should be `open_gripper()`.",
    "one call into another": "`close_gripper()` → `open_gripper()` (sorry, typo)",
    "an assignment": "One fix: change the target to `p = [0.3, 0.1, 0.2]` before the move.",
    "steps to add, listed": "Then add these steps at the end:\n- move_to_position([0.3, 0.0, 0.3])\n- open_gripper()",
    "what a line should be, in bold": "Actually, the last line should be **move_to_position([0.1, 0.2, 0.3])**.",
    "a removal listed under a colon": "Remove:\n- close_gripper()",
    "a target to use instead": "Use this target instead (the graspable point is off):\n```\np = [0.3, 0.0, 0.1]\n```",
    "a retry in a span": "Actually, retry the move: `for _ in range(3): move_to_position(p)`.",
    # found by an adversarial run: take-backs in the languages whose final markers are read
    "in Spanish": "En realidad, reemplaza la última línea por `open_gripper()`.",
    "in French": "En fait, remplacez la dernière ligne par `open_gripper()`.",
    "in German": "Korrektur: ersetze die letzte Zeile durch `open_gripper()`.",
    "in Chinese": "更正：把最后一行改成 `open_gripper()`。",
    # found by a later adversarial run: Japanese, Korean and Russian, taken back or asked in the imperative
    "in Japanese, an apology": "申し訳ありません、最後の行は `open_gripper()` にする必要があります。",
    "in Japanese, asked": "最後の行を `open_gripper()` に置き換えてください。",
    "in Korean, an apology": "죄송합니다, 마지막 줄은 `open_gripper()`이어야 합니다.",
    "in Korean, asked": "마지막 줄을 `open_gripper()`로 바꾸세요.",
    "in Russian, an apology": "Извините, последняя строка должна быть `open_gripper()`.",
    "in Russian, asked": "Замените последнюю строку на `open_gripper()`.",
    # found by a later adversarial run: notes that name what a place should hold, or ask for a call the program lacks
    "what the last line must be": "**Important:** the last line must be `open_gripper()`, not `close_gripper()`.",
    "instead of one call, another": "Instead of `close_gripper()`, call `open_gripper()` at the end.",
    "rather than one, another": "Rather than `move_to_position(p)`, use `move_to_position([0.3, 0.0, 0.3])` here.",
    "a call to insert": "Insert `open_gripper()` before `move_to_position(p)`.",
    "a call not to forget": "Don't forget to call `move_to_position([0.3, 0.0, 0.3])` after the grasp to lift it.",
    "a call to add at the end": "Also call `move_to_position([0.3, 0.0, 0.3])` at the end to lift it clear.",
    "withdrawn": "Wait, this is wrong: the carton is out of reach. Let me reconsider.",
    "the above won't work": "Hmm, the above won't work: the gripper is already closed.",
    "a step called unnecessary": "**Update:** the final move is unnecessary; the carton is reached already.",
    "a step undone after a take-back": "Actually, don't close the gripper: the task only asks to reach the milk.",
    "a number changed after a take-back": "Wait, but the approach height should be 0.15, not 0.1.",
}


@pytest.mark.parametrize("words", CHANGES.values(), ids=CHANGES.keys())
def test_a_change_in_words_after_the_program_is_asked_again(words: str) -> None:
    with pytest.raises(ProgramRejected, match="asks for a change in words"):
        extract(f"{FENCED}{words}\n")


TERMINAL = {
    "bold": "\x1b[1mActually, replace the last line with `open_gripper()`.\x1b[0m",
    "a coloured label": "\x1b[31mNote:\x1b[0m replace the last line with `open_gripper()`.",
    "after a window title": "\x1b]0;reply\x07Wait: swap `open_gripper()` and `move_to_position(p)`.",
}


@pytest.mark.parametrize("words", TERMINAL.values(), ids=TERMINAL.keys())
def test_a_change_in_words_wrapped_in_terminal_sequences_is_asked_again(words: str) -> None:
    """Found by an adversarial run: a reply relayed from a terminal opened its change with a colour code, which hid the
    word that opens the sentence, and the program as written ran."""
    with pytest.raises(ProgramRejected, match="asks for a change in words"):
        extract(f"{FENCED}{words}\n")


def test_an_explanation_wrapped_in_terminal_sequences_is_no_change() -> None:
    words = "\x1b[32mThis program opens the gripper, moves to the milk and closes it.\x1b[0m"
    assert extract(f"{FENCED}{words}\n").code.strip() == GRASP.strip()


def test_a_change_in_words_after_an_unfenced_program_is_asked_again() -> None:
    with pytest.raises(ProgramRejected, match="asks for a change in words"):
        extract(f"{GRASP}\nActually the last line should be move_to_position([0.3, 0.0, 0.3]) instead.\n")


EXPLANATIONS = [
    "This program first gets the graspable point, then opens the gripper, moves to the milk and closes it.",
    "You can change the offset if the milk is taller.",
    "Note that `move_to_position` takes a 3D point in metres.",
    'I used `get_graspable_point("milk")` rather than `get_center("milk")`, so the fingers close on the carton.',
    "If the grasp fails, try raising the approach height.",
    "Steps:\n1. Open the gripper.\n2. Move to the milk.\n3. Add 5 cm to z for the approach.\n4. Close the gripper.",
    "Actually, this works for any position of the milk within reach.",
    "Sorry for the confusion earlier: this version opens the gripper before the move.",
    "I forgot to add the open step in my first attempt; this version adds it.",
    "Let me know if you want me to add a retreat step.",
    "Changing the offset to 0.1 would approach from higher.",
    "En realidad, este programa funciona para cualquier posición de la leche.",
    "其实这个程序适用于任何位置。",
    "抱歉，上面的代码缺少 `open_gripper()`，已修正。",  # an apology answering a re-ask, the code already fixed
    "Изменения: добавил `open_gripper()` перед движением.",  # a change made (past tense), not asked for
    "Don't forget: `open_gripper()` must come before the move, which the program does.",
    "I used `get_graspable_point` instead of `get_center` so the fingers close on the carton.",
    "It is important to call `open_gripper()` first, so the fingers clear the carton.",
    "Without the open step this would fail, so the program opens first.",
    "If the carton is out of reach, this won't work.",
    # found by an adversarial run: each was asked again by the first version of the rule
    "### Explanation:\n5. **Lower and grasp**: The second call lowers the gripper, then `close_gripper()` closes it.",
    "How it works:\n6. Put the milk down by lowering it and calling `open_gripper()`.",
    'Replace `"milk"` with the name of your object if it differs.',
    "Sorry, I forgot to add the `open_gripper()` call before the move last time; it's fixed now.",
    "**Change:** `open_gripper()` now comes before the move.",
    "You can adapt it to other objects, e.g. replace `milk` with `juice` where you need to.",
    "**Changes made:**\n- Replace `get_center` with `get_graspable_point` for a better grasp.",
    # found by an adversarial run: change logs under other headings were read as asking for the changes they list
    "### Summary of changes\n- Add `open_gripper()` at the start so the fingers clear the carton.",
    "**Fixes applied:**\n- Use `get_graspable_point` instead of `get_center` for the target.",
    "**What I fixed:**\n1. Add `open_gripper()` before the move.",
    "Here's what's different:\n- Replace `get_center` with `get_graspable_point`.",
    "3. **Swap**: `move_to_position(p)` does this part.",
]


@pytest.mark.parametrize("words", EXPLANATIONS)
def test_an_explanation_after_the_program_leaves_it(words: str) -> None:
    assert extract(f"Here is the program:\n{FENCED}{words}\n").code == GRASP


QUOTED_OR_SHOWN = {
    "a line in a block quote": "Actually, the last line should be:\n> move_to_position([0.1, 0.2, 0.3])\n",
    "a corrected program in a quoted block": (
        "> **Correction:** the gripper must open first:\n> ```python\n> open_gripper()\n"
        '> p = get_graspable_point("milk")\n> move_to_position(p)\n> close_gripper()\n> ```\n'
    ),
    "a correction shown as a session": (
        "Corrected:\n```pycon\n>>> open_gripper()\n>>> move_to_position(get_graspable_point('milk'))\n```\n"
    ),
}


@pytest.mark.parametrize("after", QUOTED_OR_SHOWN.values(), ids=QUOTED_OR_SHOWN.keys())
def test_code_in_a_block_quote_or_a_session_after_the_program_is_seen(after: str) -> None:
    """Found by an adversarial run: the quote and the session were read as prose, and the program above ran."""
    with pytest.raises(ProgramRejected, match=r"different programs|code outside the code blocks|block tagged 'pycon'"):
        extract(f"{FENCED}{after}")


def test_a_quote_of_the_task_beside_the_program_leaves_it() -> None:
    answer = f"> Grasp the milk carton.\n\nHere is the program:\n{FENCED}> It opens the gripper before the move.\n"
    assert extract(answer).code == GRASP


@pytest.mark.parametrize(
    "comment",
    [
        "remove this line: the task is only to reach",
        # found by a later adversarial run: each ran the line it stands beside
        "<-- change this to open_gripper()",
        "oops, this should open the gripper",
        "not needed, remove",
        "FIXME: this closes too early",
        "TODO: replace with open_gripper()",
        "wrong call: use open_gripper()",
        "<- delete",
    ],
)
def test_a_comment_that_asks_to_change_its_line_is_asked_again(comment: str) -> None:
    """Found by an adversarial run: the line ran."""
    program = GRASP.replace("close_gripper()", f"close_gripper()  # {comment}")
    with pytest.raises(ProgramRejected, match="a comment in the program asks for a change"):
        extract(f"```python\n{program}```\n")


@pytest.mark.parametrize(
    "comment",
    ["drop the carton only once it is over the tray", "close after the move, else the fingers hit the carton"],
)
def test_a_comment_that_explains_its_line_leaves_it(comment: str) -> None:
    kept = GRASP.replace("close_gripper()", f"close_gripper()  # {comment}")
    assert extract(f"```python\n{kept}```\n").code == kept


# Found by a second adversarial run: honest replies that the first versions of the rules above asked again, and words
# after the program that were not the words read.
DEF_AND_CALL = 'def grasp_milk():\n    p = get_graspable_point("milk")\n    open_gripper()\n    move_to_position(p)\n'
DEF_AND_CALL += "    close_gripper()\n\n\ngrasp_milk()\n"
BRANCHES = (
    'p = get_graspable_point("milk")\nopen_gripper()\nif p[2] > 0.5:\n    # Option 1: on the high shelf\n'
    "    move_to_position([p[0] - 0.1, p[1], p[2]])\nelse:\n    # Option 2: on the table, from above\n"
    "    move_to_position(p)\nclose_gripper()\n"
)
KEPT = {
    "a call of the program's function, 'simply'": (
        f"```python\n{DEF_AND_CALL}```\nTo run it, simply call:\n```python\ngrasp_milk()\n```\n",
        DEF_AND_CALL,
    ),
    "the user's draft quoted before the fix": (
        'Your program:\n> ```python\n> p = get_graspable_point("milk")\n> move_to_position(p)\n> close_gripper()\n'
        f"> ```\n\nIt never opens the gripper. Add the open step:\n{FENCED}",
        GRASP,
    ),
    "the user's line quoted before the fix": (
        f'The line\n> move_to_position("milk")\n\npasses a name. Fixed:\n{FENCED}',
        GRASP,
    ),
    "a comment on waiting": (
        f"```python\n{GRASP}# Wait for the grip to settle\nmove_to_position([0.3, 0.0, 0.3])\n```\n",
        f"{GRASP}# Wait for the grip to settle\nmove_to_position([0.3, 0.0, 0.3])\n",
    ),
    "a comment on the approach height": (
        f"```python\n# Approach 10 cm above the milk\n{GRASP}```\n",
        f"# Approach 10 cm above the milk\n{GRASP}",
    ),
    "options as the branches of one program": (f"```python\n{BRANCHES}```\n", BRANCHES),
}


@pytest.mark.parametrize(("answer", "program"), KEPT.values(), ids=KEPT.keys())
def test_snippets_quotes_and_comments_that_change_nothing_leave_the_program(answer: str, program: str) -> None:
    assert extract(answer).code == program


@pytest.mark.parametrize(
    "answer",
    [
        "open_gripper()\n\nWait, also add `close_gripper()` after `open_gripper()`.\n",
        f"````markdown\nHere's the program:\n{FENCED}````\n\nActually, replace the last line with `open_gripper()`.\n",
        f"{FENCED}```\n\nActually, replace the last line with `open_gripper()`.\n",
    ],
    ids=["after an unfenced program the words quote", "after a Markdown wrapper", "after a doubled closing fence"],
)
def test_the_words_read_are_those_after_the_program(answer: str) -> None:
    with pytest.raises(ProgramRejected, match="asks for a change in words"):
        extract(answer)


@pytest.mark.parametrize(
    "after",
    ["Usage:\n```python\ngrasp('milk')\n```\n", "Then call `grasp('milk')` to pick up the milk.\n"],
    ids=["a usage block", "a call in words"],
)
def test_a_program_that_only_defines_its_function_is_asked_again(after: str) -> None:
    """Found by an adversarial run: the definition alone ran, and the robot did nothing."""
    definition = "def grasp(name):\n    p = get_graspable_point(name)\n    open_gripper()\n    move_to_position(p)\n"
    # (the call asked for in words is also a call the program does not hold: a change asked in words)
    with pytest.raises(ProgramRejected, match=r"only defines grasp and never calls them|asks for a change in words"):
        extract(f"Final program:\n```python\n{definition}```\n{after}")
