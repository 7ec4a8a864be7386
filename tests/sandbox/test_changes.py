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
    "a wrap": "Note: put `close_gripper()` under an `if p[2] > 0:` check.",
    "an assignment": "One fix: change the target to `p = [0.3, 0.1, 0.2]` before the move.",
    "steps to add, listed": "Then add these steps at the end:\n- move_to_position([0.3, 0.0, 0.3])\n- open_gripper()",
    "what a line should be, in bold": "Actually, the last line should be **move_to_position([0.1, 0.2, 0.3])**.",
    "a removal listed under a colon": "Remove:\n- close_gripper()",
    "a target to use instead": "Use this target instead (the graspable point is off):\n```\np = [0.3, 0.0, 0.1]\n```",
    "a retry in a span": "Actually, retry the move: `for _ in range(3): move_to_position(p)`.",
}


@pytest.mark.parametrize("words", CHANGES.values(), ids=CHANGES.keys())
def test_a_change_in_words_after_the_program_is_asked_again(words: str) -> None:
    with pytest.raises(ProgramRejected, match="asks for a change in words"):
        extract(f"{FENCED}{words}\n")


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


def test_a_comment_that_asks_to_remove_its_line_is_asked_again() -> None:
    """Found by an adversarial run: the line ran."""
    program = GRASP.replace("close_gripper()", "close_gripper()  # remove this line: the task is only to reach")
    with pytest.raises(ProgramRejected, match="a comment in the program asks for a change"):
        extract(f"```python\n{program}```\n")
    kept = GRASP.replace("close_gripper()", "close_gripper()  # drop the carton only once it is over the tray")
    assert extract(f"```python\n{kept}```\n").code == kept
