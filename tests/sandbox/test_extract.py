"""Getting the program out of what a language model actually answers."""

from __future__ import annotations

import contextlib
import gc
import re
import time

import pytest

from robotool.sandbox import ProgramRejected, extract, extract_program, validate
from robotool.sandbox.reasoning import without_reasoning

# CPU seconds for 100 kB: linear work takes about one on a slow 2-core machine, a quadratic blow-up minutes
CPU_LIMIT_S = 5.0

PROGRAM = 'import numpy as np\np = np.array(get_center("milk"))\nif p[2] > 0:\n    move_to_position(p)\n'


def test_plain_program_is_kept() -> None:
    assert extract_program(PROGRAM) == PROGRAM


@pytest.mark.parametrize("tag", ["python", "py", "Python3", ""])
def test_fenced_block_inside_prose(tag: str) -> None:
    answer = f"Sure! Here is the program:\n\n```{tag}\n{PROGRAM}```\n\nIt grasps the milk. Let me know!"
    assert extract_program(answer) == PROGRAM


def test_of_several_different_programs_none_marked_none_is_guessed_the_reply_is_asked_again() -> None:
    answer = (
        'Draft:\n```python\nopen_gripper()\n```\nThe scene as JSON:\n```json\n{"milk": 1}\n```\n'
        "Better:\n~~~py\nclose_gripper()\n~~~\n"
    )
    with pytest.raises(ProgramRejected, match=r"2 different programs \(code blocks 1, 2\).*give exactly one program"):
        extract(answer)


def test_the_block_marked_final_is_taken_even_before_a_later_one() -> None:
    answer = (
        "Final program:\n```python\nopen_gripper()\nclose_gripper()\n```\n"
        "For comparison, the naive version:\n```python\nmove_to_position([0.3, 0.0, 0.1])\n```\n"
    )
    extraction = extract(answer)
    assert extraction.code == "open_gripper()\nclose_gripper()\n"
    assert "block 1 (marked 'Final program:')" in extraction.note


@pytest.mark.parametrize(
    "label",
    [
        "Alternatively, and this is what I'd actually recommend, open first:",
        "For comparison, the corrected version that opens the gripper:",
        "The original code forgot to open the gripper; use this version:",
    ],
)
def test_a_later_program_preferred_to_the_one_marked_final_is_no_aside(label: str) -> None:
    """Found by an adversarial run: the aside word set the preferred program aside, and the one marked final ran."""
    answer = f"Final program:\n```python\n{NOGRIP}```\n{label}\n```python\n{GRASP}```\n"
    with pytest.raises(ProgramRejected, match="2 different programs"):
        extract(answer)


def test_an_output_listing_after_the_program_is_not_taken_for_it() -> None:
    extraction = extract(f"```python\n{PROGRAM}```\nOutput:\n```\nDone\n```\n")
    assert extraction.code == PROGRAM and "block 1 (the only program" in extraction.note


# Found by an adversarial run: each of these ran a block the model did not mean, or guessed between programs.
QUOTING_REPLIES = {
    "snippets explained after the whole program": (
        f"Here is the program:\n```python\n{PROGRAM}```\nExplanation:\n1. It reads the centre:\n"
        '```python\np = np.array(get_center("milk"))\n```\n2. Then it moves:\n```python\nmove_to_position(p)\n```\n'
    ),
    "a snippet first, under a label naming a marker word": (
        "To complete the task, the robot first reads the milk:\n```python\np = np.array(get_center('milk'))\n```\n"
        f"Here is the whole program:\n```python\n{PROGRAM}```\n"
    ),
    "a fixed line with its own comment, then the full program": (
        f"What was fixed:\n```python\nmove_to_position(p)  # was missing\n```\nFull program:\n```python\n{PROGRAM}```"
    ),
    "output listings that parse as values": (
        f"```python\n{PROGRAM}```\nIt prints:\n```\n[0.35, 0.0, 0.12]\n```\nthen\n```\n-0.38\n```\n"
        "and\n```\n(1, {'a': -2})\n```\n"
    ),
    "an output listing of text": f"```python\n{PROGRAM}```\nWhen run, it prints:\n```\nMoving to the milk\ndone\n```\n",
    "the final block tagged py3": f"Draft:\n```python\nmove_to_position(p)\n```\nFinal:\n```py3\n{PROGRAM}```\n",
    "a stray closing fence after an unfenced program": f"{PROGRAM}```\n\nThis program grasps the milk.\n",
}


@pytest.mark.parametrize("answer", QUOTING_REPLIES.values(), ids=QUOTING_REPLIES.keys())
def test_blocks_that_quote_the_program_or_show_its_output_leave_the_program(answer: str) -> None:
    assert extract(answer).code == PROGRAM


OTHER = "p = get_graspable_point('milk')\nopen_gripper()\nmove_to_position([p[0] - 0.1, p[1], p[2]])\nclose_gripper()\n"
AMBIGUOUS_REPLIES = {
    "a usage example after the program": (
        f"```python\n{PROGRAM}```\nYou can reuse it, e.g.:\n```python\ngrasp('box')\n```"
    ),
    "two options and a recommendation in prose": (
        f"Option A (direct):\n```python\n{PROGRAM}```\nOption B:\n```python\n{OTHER}```\nI recommend option A."
    ),
    "a draft under a negated marker, then another program": (
        f"This first draft is not the final program:\n```python\n{OTHER}```\nOn reflection:\n```python\n{PROGRAM}```"
    ),
    "a draft tagged python, the correction tagged python3.11": (
        f"```python\n{OTHER}```\nWait, that approaches from the side.\n```python3.11\n{PROGRAM}```"
    ),
}


@pytest.mark.parametrize("answer", AMBIGUOUS_REPLIES.values(), ids=AMBIGUOUS_REPLIES.keys())
def test_several_different_programs_are_asked_again_never_guessed(answer: str) -> None:
    with pytest.raises(ProgramRejected, match="2 different programs"):
        extract(answer)


def test_a_reply_of_thousands_of_different_programs_is_refused_in_linear_time() -> None:
    answer = "".join(f"```python\nopen_gripper({k})\n```\n" for k in range(3000))
    gc.collect()  # (the collection of earlier tests' garbage is not the extractor's time)
    started = time.thread_time()  # this thread's CPU time: not a pool thread's left from an earlier test in the worker
    with pytest.raises(ProgramRejected, match="more than 8 different programs"):
        extract(answer)
    assert time.thread_time() - started < CPU_LIMIT_S / 10


# Found by a second adversarial run.
LONGER = f"{PROGRAM}move_to_position([0.3, 0.0, 0.2])\nmove_to_position(p)\n"
SECOND_ROUND_AMBIGUOUS = {
    "the program again with lines added, as an option": (
        f"```python\n{PROGRAM}```\nOptionally, to put it back afterwards:\n```python\n{LONGER}```"
    ),
    "the original full program quoted before the change": (
        f"The original full program:\n```python\n{LONGER}```\nChanged so it stops above:\n```python\n{PROGRAM}```"
    ),
    "a final label taken back": (
        f"This is the final version? No, wait, it is wrong:\n```python\n{LONGER}```\nUse:\n```python\n{PROGRAM}```"
    ),
}


@pytest.mark.parametrize("answer", SECOND_ROUND_AMBIGUOUS.values(), ids=SECOND_ROUND_AMBIGUOUS.keys())
def test_a_variant_or_a_retracted_program_is_asked_again(answer: str) -> None:
    with pytest.raises(ProgramRejected, match="2 different programs"):
        extract(answer)


DRAFT_WITH_WAYPOINTS = (
    'p = get_center("milk")\nopen_gripper()\nmove_to_position([0.3, 0.0, 0.3])\nmove_to_position([p[0], p[1], 0.3])\n'
    "move_to_position(p)\nclose_gripper()\n"
)


@pytest.mark.parametrize(
    "label",
    ["Corrected:", "**Fixed:**", "Here's the fix:", "Use this:", "Try this instead:", "It should be just:", "UPDATE:"],
)
def test_a_shorter_fix_under_a_correction_label_is_no_quote_of_the_draft(label: str) -> None:
    """Found by an adversarial run: the fix kept a run of the draft's lines, so it read as a quote, and the draft (with
    the waypoints the model dropped) ran."""
    answer = f"```python\n{DRAFT_WITH_WAYPOINTS}```\n{label}\n```python\nmove_to_position(p)\nclose_gripper()\n```"
    with pytest.raises(ProgramRejected, match="repeats part of block 1 after"):
        extract(answer)


@pytest.mark.parametrize(
    "label",
    [
        "First draft:",
        "Here is some pseudo-code for the approach:",
        "A rough sketch (untested, not the final program):",
        "Partial fix (the lift still needs to be added):",
        "This is what NOT to do:",
        "Your code:",
        "The code you provided:",
        "## Draft",
    ],
)
def test_the_only_program_labelled_as_no_answer_is_asked_again(label: str) -> None:
    """Found by an adversarial run: the label before a reply's only block was never read, and a draft, pseudo-code, a
    partial fix or the user's own code echoed ran as the program."""
    with pytest.raises(ProgramRejected, match="which says it is not the final program"):
        extract(f"{label}\n```python\n{GRASP}```\nThis fails because the push comes too late.\n")
    assert extract(f"Here is an example program:\n```python\n{GRASP}```\n").code == GRASP  # an answer, shown


@pytest.mark.parametrize(
    ("draft", "final"),
    [("Draft:\n\n---\n", "Final program:\n\n---\n"), ("Draft\n-----\n", "Final\n=====\n")],
    ids=["a rule under the label", "setext headings"],
)
def test_a_rule_or_a_heading_underline_is_no_label(draft: str, final: str) -> None:
    """Found by an adversarial run: the line of dashes was read as the block's label, and the marker above it not."""
    answer = f"{draft}```python\n{LONGER}```\n{final}```python\n{PROGRAM}```\n"
    assert extract(answer).code == PROGRAM


@pytest.mark.parametrize(
    "label",
    [
        "The last line should be:",
        "Only the last two lines are needed:",
        "The push step isn't necessary, you can start from here:",
        "The task only asks to grasp it, so the program should end with:",
        "Move this line to the end:",
    ],
)
def test_a_fragment_under_words_that_ask_for_a_change_is_no_quote(label: str) -> None:
    """Found by an adversarial run: the fragment read as a snippet explained, and the unchanged program ran."""
    answer = f"```python\n{DRAFT_WITH_WAYPOINTS}```\n{label}\n```python\nmove_to_position(p)\nclose_gripper()\n```"
    with pytest.raises(ProgramRejected, match="repeats part of block 1 after"):
        extract(answer)
    explained = f"```python\n{DRAFT_WITH_WAYPOINTS}```\nThe key step is the grasp:\n```python\nclose_gripper()\n```"
    assert extract(explained).code == DRAFT_WITH_WAYPOINTS


WALK_AROUND = "walk_to_position([1.0, 1.0, 0.0])\nwalk_to_position([2.0, 0.0, 0.0])\n"


@pytest.mark.parametrize(
    ("first", "second"),
    [
        ("Option 1 (direct):", "Option 2 (around the obstacle):"),
        ("### Approach 1: straight", "### Approach 2: around the box first"),
        ("The simple one:", "Or, around the box first:"),
    ],
)
def test_a_short_option_whose_lines_run_in_another_is_no_quote_of_it(first: str, second: str) -> None:
    """Found by an adversarial run: a one-line option whose line ran in the other read as a quote of it, and the other
    option ran."""
    answer = f"{first}\n```python\nwalk_to_position([2.0, 0.0, 0.0])\n```\n{second}\n```python\n{WALK_AROUND}```\n"
    with pytest.raises(ProgramRejected, match="2 different programs"):
        extract(answer)


def test_a_correction_that_leaves_lines_out_is_no_quote_of_the_draft() -> None:
    label = "Wait, the last two lines are wrong. Here is the corrected code:"
    answer = f"```python\n{LONGER}```\n{label}\n```python\n{PROGRAM}```"
    assert extract(answer).code == PROGRAM


@pytest.mark.parametrize(
    ("answer", "problem"),
    [
        ("```\n- close_gripper()\n+ open_gripper()\n```", "no Python program found"),
        ("The robot should:\n- open_gripper()\n- move_to_position(p)\n- close_gripper()\n", "no Python program found"),
        (
            f"```python\n{PROGRAM}```\nApply this fix:\n```diff\n-    move_to_position(p)\n+    close_gripper()\n```",
            "diff",
        ),
        (f"```python open_gripper()\n{PROGRAM}```", "opening fence line holds code"),
        (f"{PROGRAM}\nFinally, stop if the carton was not lifted:\nassert p[2] > 0\n", "syntax error"),
        # found by an adversarial run: a diff's lines in a Python block parse (unary minus on a call), and the push
        # the model removed was made
        (
            'Remove the push:\n```python\nwalk_to_position([1.0, 0.0, 0.0])\n-push_to_position("box_1", [0.5, 0.2, '
            "0.1])\nclimb_to_position([1.5, 0.0, 0.4])\n```",
            "line 2: a call with a sign before it reads as a line of a diff",
        ),
        ("```python\nopen_gripper()\nif True:\n    + close_gripper()\n```", "line 3: a call with a sign before it"),
    ],
    ids=[
        "an untagged diff",
        "a bullet list",
        "a fix as a diff",
        "code on the fence line",
        "an assert after prose",
        "a removed line in a Python block",
        "an added line indented",
    ],
)
def test_what_is_no_whole_program_is_asked_again_with_why(answer: str, problem: str) -> None:
    with pytest.raises(ProgramRejected, match=problem):
        extract(answer)


HEAD = 'p = get_graspable_point("milk")\nopen_gripper()\nmove_to_position([p[0], p[1], p[2] + 0.12])\n'


@pytest.mark.parametrize(
    ("answer", "placeholder"),
    [
        (
            f"Your program:\n```python\n{PROGRAM}```\nCorrected code:\n"
            f"```python\n{HEAD}# ... rest of the code unchanged ...\n```",
            "# ... rest of the code unchanged ...",
        ),
        (f"```python\n{PROGRAM}```\nFixed code:\n```python\n{HEAD}...\n```", "..."),
        (f"```python\n{HEAD}# ... (same as before)\n```", "# ... (same as before)"),
        (f"```python\n{HEAD}# (rest unchanged)\n```", "# (rest unchanged)"),
        (f"```python\n{HEAD}# rest of the code here\n```", "# rest of the code here"),
        (f"```python\n{HEAD}# TODO: move to the milk and grasp it\npass\n```", "# TODO: move to the milk"),
        (f"```python\n{HEAD}q = ...  # the lift, as before\nmove_to_position(q)\n```", "q = ...  # the lift"),
    ],
    ids=[
        "rest unchanged after a correction label",
        "a bare ellipsis",
        "same as before",
        "rest unchanged",
        "rest of the code",
        "TODO pass",
        "an ellipsis as a value",
    ],
)
def test_a_block_that_says_it_leaves_code_out_is_asked_again_naming_the_line(answer: str, placeholder: str) -> None:
    """Found by an adversarial run: a corrected block ending in '# ... rest of the code unchanged ...' ran alone."""
    with pytest.raises(
        ProgramRejected, match=r"line [45]: .*placeholder for code left out \(" + re.escape(repr(placeholder)[:-1])
    ):
        extract(answer)


@pytest.mark.parametrize(
    "comment",
    [
        "# the rest of the walk is done",
        "# keep the gripper unchanged ...",
        "# lift ... slowly",
        "# TODO: tune the height",
        "# keep the rest of the code simple",
    ],
)
def test_a_comment_about_the_task_is_no_placeholder(comment: str) -> None:
    program = f"{HEAD}{comment}\nclose_gripper()\n"
    assert extract(f"Corrected code:\n```python\n{program}```").code == program


DRAFT = "```python\nopen_gripper()\nclose_gripper()\n```"
SECOND_ROUND_REASONING = {
    "in words (Granite)": f"Here is my thought process:\nA first idea:\n{DRAFT}\nNo.\n\nHere is my response:\n",
    "begin_of_thought tokens": f"<|begin_of_thought|>\n{DRAFT}\n<|end_of_thought|>\n<|begin_of_solution|>\n",
    "channels with their tokens stripped": f"analysisWe need to move first. Draft:\n{DRAFT}\nFix it.assistantfinal",
    "final response markers (Apriel)": f"Here are my reasoning steps:\n{DRAFT}\nNo.\n[BEGIN FINAL RESPONSE]\n",
}


@pytest.mark.parametrize("reasoning", SECOND_ROUND_REASONING.values(), ids=SECOND_ROUND_REASONING.keys())
def test_a_draft_in_reasoning_written_out_is_never_code(reasoning: str) -> None:
    ending = "[END FINAL RESPONSE]\n" if "BEGIN FINAL" in reasoning else ""
    assert extract(reasoning + PROGRAM + ending).code == PROGRAM


@pytest.mark.parametrize(
    "end",
    [
        "<|im_end|>\n<|im_start|>user\nNow carry it.<|im_end|>\n<|im_start|>assistant\n",
        "<|eot_id|><|start_header_id|>user<|end_header_id|>\n\nNow carry it.<|eot_id|>",
    ],
)
def test_a_turn_the_model_invented_after_its_own_is_no_answer(end: str) -> None:
    answer = f"```python\n{PROGRAM}```{end}Here is the updated code:\n```python\n{LONGER}```"
    assert extract(answer).code == PROGRAM


def test_a_later_python_block_that_does_not_parse_is_its_syntax_error_not_the_earlier_draft() -> None:
    answer = f"First try:\n```python\n{OTHER}```\nFinal program:\n```python\nopen_gripper(\nmove_to_position(p)\n```"
    with pytest.raises(ProgramRejected, match="syntax error"):
        extract(answer)


@pytest.mark.parametrize(
    "answer",
    ['{"code": "open_gripper()"}', '["p = get_center(\'milk\')", "move_to_position(p)"]', "(-0.38, [1, 2])"],
    ids=["a JSON object", "a list of lines", "a tuple of values"],
)
def test_a_value_given_in_place_of_a_program_is_no_program(answer: str) -> None:
    with pytest.raises(ProgramRejected, match="no Python program found"):
        extract(f"```python\n{answer}\n```")


REASONING_FORMS = {
    "[THINK] (Magistral)": "[THINK]\nDraft:\n```python\nclose_gripper()\n```\nNo, open first.[/THINK]\n",
    "<seed:think>": "<seed:think>\n```python\nclose_gripper()\n```\n</seed:think>\n",
    "◁think▷ (Kimi)": "◁think▷\n```python\nclose_gripper()\n```\n◁/think▷\n",
    "channels (gpt-oss)": (
        "<|channel|>analysis<|message|>Let me draft:\n```python\nclose_gripper()\n```\nNeed to open first.<|end|>"
        "<|start|>assistant<|channel|>final<|message|>"
    ),
}


@pytest.mark.parametrize("reasoning", REASONING_FORMS.values(), ids=REASONING_FORMS.keys())
def test_a_draft_in_any_spelling_of_reasoning_is_never_code(reasoning: str) -> None:
    extraction = extract(reasoning + PROGRAM)
    assert extraction.code == PROGRAM and extraction.chosen is None


def test_a_reply_in_channels_without_a_final_channel_has_no_answer_yet() -> None:
    with pytest.raises(ProgramRejected, match="no Python program found"):
        extract(f"<|channel|>analysis<|message|>Draft:\n```python\n{PROGRAM}```<|end|>")


def test_a_draft_inside_reasoning_is_never_code() -> None:
    answer = (
        "<think>\nFirst idea:\n```python\nclose_gripper()\n```\nNo, that grasps nothing.\n</think>\n\n"
        f"Final program:\n```python\n{PROGRAM}```"
    )
    extraction = extract(answer)
    assert extraction.code == PROGRAM and extraction.chosen is None
    with pytest.raises(ProgramRejected, match="no Python program found"):
        extract("<think>\n```python\nclose_gripper()\n```\n")  # reasoning cut off: no answer yet
    assert extract_program(f"The open tag was stripped by the server.\n</think>\n{PROGRAM}") == PROGRAM


def test_unfenced_python_2_is_rejected_with_its_syntax_error_never_cut_to_the_lines_that_parse() -> None:
    answer = (
        'push_to_position("box", [1, 0, 0])\nwalk_to_position([1, 0, 0])\nprint "climbing"\n'
        "for i in xrange(2):\n    climb_to_position([1, 0, 0.2])\n"
    )
    with pytest.raises(ProgramRejected, match="line 3: syntax error: Missing parentheses"):
        extract(answer)
    with pytest.raises(ProgramRejected, match="line 1: syntax error"):
        extract('print "hello"\nopen_gripper()\n')


def test_unclosed_fence_runs_to_the_end() -> None:
    assert extract_program(f"Program:\n```python\n{PROGRAM}") == PROGRAM


def test_prose_around_unfenced_code_is_dropped() -> None:
    answer = f"Here is how the robot grasps the milk:\n{PROGRAM}\nThis works because the milk is in reach."
    assert extract_program(answer) == PROGRAM


def test_windows_line_endings_bom_tabs_and_nbsp() -> None:
    answer = "\ufeff```python\r\nfor i in range(2):\r\n\tif i:\r\n\t\tmove_to_position([0.3, 0, 0.1])\r\n```"
    program = extract_program(answer.replace("range(2)", "range(\u00a02)"))
    assert program == "for i in range( 2):\n    if i:\n        move_to_position([0.3, 0, 0.1])\n"
    validate(program, "arm")


def test_missing_imports_are_added() -> None:
    program = extract_program("d = np.linalg.norm(get_center('milk'))\nr = math.sqrt(d)\n")
    assert program.startswith("import numpy as np\nimport math\nd = ")
    validate(program, "arm")
    assert extract_program("import math\nx = math.pi\n") == "import math\nx = math.pi\n"


@pytest.mark.parametrize(
    "answer",
    [
        "",
        "I cannot help with that.",
        "Done",
        "```python\n\n```",
        "The robot should first open the gripper, then move to the milk and close the gripper.",
    ],
)
def test_no_program_is_rejected_clearly(answer: str) -> None:
    with pytest.raises(ProgramRejected, match="no Python program found"):
        extract_program(answer)


def test_fenced_code_with_syntax_error_names_the_line() -> None:
    with pytest.raises(ProgramRejected, match="line 2: syntax error"):
        extract_program("```python\nopen_gripper()\nmove_to_position([0.3, 0.0\n```")


def test_long_prose_is_searched_in_reasonable_time() -> None:
    prose = "\n".join(f"Sentence number {i} explains the plan." for i in range(300))
    assert extract_program(f"{prose}\n{PROGRAM}{prose}") == PROGRAM


@pytest.mark.parametrize(
    "answer",
    [
        "Done\n" * 20_000,  # names only: every suffix parses and none acts
        "This is prose text here.\n" * 4_000,
        '"""\n' + "word\n" * 19_000 + '"""\n',
        "Let me think.\nx = 1\n" * 5_000,
        "f(\n" * 33_000,
        "x = 1\na b\n" * 9_000,
        "Step: the gripper\n" * 5_500,
        "```\n~~~\n" * 12_000,  # fences that never close each other
        "```json\n" * 12_000,
        'x = f"' + "{1}" * 30_000 + '"',  # Python 3.11 parses one f-string's fields in quadratic time
        "x = ['" + "\\'" * 47_000 + "\n",  # string masking from every quote (second adversarial run)
        ("x = " + "lambda: " * 2_850 + "1\nHmm.\n") * 4,  # compiling nested lambdas (second adversarial run)
        # a program, then words that take back thousands of numbers: each was searched for in the whole program
        "```python\n" + "move_to_position([0.1, 0.2, 0.3])\n" * 1_600 + "```\nWait, " + "not 9.9, " * 4_800,
    ],
    ids=[
        "names",
        "prose",
        "one-string",
        "alternating",
        "open-brackets",
        "code-then-junk",
        "annotations",
        "fences",
        "tagged-fences",
        "f-string-fields",
        "escaped-quotes",
        "nested-lambdas",
        "numbers-taken-back",
    ],
)
def test_extraction_of_100_kb_stays_linear(answer: str) -> None:
    import time

    assert 90_000 <= len(answer) <= 100_000
    started = time.process_time()
    with contextlib.suppress(ProgramRejected):
        extract_program(answer)
    assert time.process_time() - started < CPU_LIMIT_S


def test_code_after_long_prose_is_still_found() -> None:
    prose = "The plan has several careful steps, explained here.\n" * 1_500
    assert extract_program(prose + PROGRAM) == PROGRAM


def test_extraction_counts_the_lines_it_left_out() -> None:
    assert extract(PROGRAM).dropped_lines == 0 and extract(PROGRAM).note is None
    fenced = extract(f"Sure! Here is the program:\n```python\n{PROGRAM}```\nIt grasps the milk.\n")
    assert fenced.code == PROGRAM and fenced.dropped_lines == 2
    prose = extract(f"Here it is:\n{PROGRAM}That is all.\n")
    assert prose.code == PROGRAM and prose.dropped_lines == 2
    assert "2 non-blank line(s)" in prose.note
    with pytest.raises(ProgramRejected, match="line 5: syntax error"):  # a cut-off last line is not dropped
        extract(f"{PROGRAM}move_to_position([0.3, 0,\n")


@pytest.mark.parametrize("cut", ["move_to_pos", "close_gripp", "close_gripper", "if", "while"])
def test_a_reply_cut_off_after_its_unfenced_program_is_asked_again_never_run_short(cut: str) -> None:
    """Found by an adversarial run of replies shaped like real models': a reply cut at its length limit in the middle
    of its last line lost that line as a word of prose (as "Done" is), and the program ran without its last call."""
    with pytest.raises(ProgramRejected, match="line 6: the reply ends in the middle of its program"):
        extract(f"Here is the code:\n\n{GRASP_THEN}{cut}")
    assert extract(f"Here is the code:\n\n{GRASP_THEN}\nDone").code == GRASP_THEN


GRASP_THEN = 'p = get_center("milk")\nopen_gripper()\nmove_to_position(p)\n'
CLIMB = (
    'box = get_position("box")\nwalk_to_position([box[0] - 0.5, box[1], 0.0])\n'
    'push_to_position("box", [1.5, 0.0, 0.0])\nclimb_to_position([1.5, 0.0, 0.3])\n'
)


@pytest.mark.parametrize(
    "words",
    [
        "Wait, the box is 0.25 m tall, not 0.3.",
        "Correction: climb to z = 0.25, the box height, not 0.3.",
        "Oh wait — the push target should be [1.2, 0.0, 0.0] so the box touches the platform.",
        "One fix: the walk target x should be box[0] - 0.6 to leave room for the legs.",
    ],
)
def test_a_number_taken_back_in_words_after_the_program_is_asked_again(words: str) -> None:
    """Found by an adversarial run of replies shaped like real models': each ran the program with the number the words
    after it take back. A number the program does not hold, or words that take nothing back, leave it."""
    with pytest.raises(ProgramRejected, match="asks for a change in words"):
        extract(f"```python\n{CLIMB}```\n{words}\n")
    for kept in ("Wait, the box is 0.3 m tall, not 0.25.", "**Note:** the climb height matches the box (0.3 m here)."):
        assert extract(f"```python\n{CLIMB}```\n{kept}\n").code == CLIMB


@pytest.mark.parametrize("label", ["Putting it all together:", "Combined program:", "Here's everything combined:"])
def test_the_program_after_step_snippets_under_a_combining_label_is_final(label: str) -> None:
    """Found by the same run: step snippets that name things otherwise than the whole program after them made three
    different programs, and the reply was asked again."""
    steps = (
        '### Step 1\n```python\npoint = get_graspable_point("milk")\n```\n'
        "### Step 2\n```python\nopen_gripper()\nmove_to_position(point)\nclose_gripper()\n```\n"
    )
    assert extract(f"{steps}{label}\n\n```python\n{GRASP_THEN}close_gripper()\n```\n").code == (
        f"{GRASP_THEN}close_gripper()\n"
    )


# Found by a third adversarial run: each ran a program the model did not mean (a draft, a quote, a cut program).
GRASP = 'p = get_graspable_point("milk")\nopen_gripper()\nmove_to_position(p)\nclose_gripper()\n'
PUT_DOWN = f"{GRASP}move_to_position([0.3, 0.0, 0.3])\nopen_gripper()\nmove_to_position([0.3, 0.2, 0.3])\n" + (
    "close_gripper()\n"
)


@pytest.mark.parametrize("word", ["move_to_position", "open_gripper", "close_gripper()"])
def test_inline_code_at_the_start_of_a_line_is_prose_not_a_fence(word: str) -> None:
    answer = (
        f"Here is a first attempt:\n```python\n{PUT_DOWN}```\n```{word}``` to the side drops the milk again. "
        f"Final program:\n```python\n{GRASP}```\n"
    )
    extraction = extract(answer)
    assert extraction.code == GRASP and "block 2 (marked" in extraction.note


@pytest.mark.parametrize(
    "answer",
    [
        "```python\n" + "-" * 1000 + "1\nopen_gripper()\n```\n",
        "-" * 5000 + "1\nopen_gripper()\n",
        "Program:\n" + "~" * 3000 + "x\nopen_gripper()\nDone.\n",
    ],
    ids=["fenced", "unfenced", "after-prose"],
)
def test_a_reply_nested_deeper_than_the_parser_follows_is_refused_never_raised_nor_cut(answer: str) -> None:
    with pytest.raises(ProgramRejected, match="nested too deeply"):
        extract(answer)


def test_many_quotes_of_a_long_program_are_told_apart_in_linear_time() -> None:
    answer = "```python\n" + "".join(f"a{k}=1\n" for k in range(6800)) + "```\n" + "```\na1=1\n```\n" * 3500
    assert len(answer) < 100_000
    gc.collect()
    started = time.thread_time()
    assert extract(answer).code.startswith("a0=1\na1=1\n")
    # the quadratic check took 5.1 s here; the linear one 0.6-0.8 s on an idle 2-core machine and 1.0 s in a loaded CI
    assert time.thread_time() - started < CPU_LIMIT_S / 2


@pytest.mark.parametrize(
    "prose",
    [
        "This <s>works</s> does not work: it puts the milk down again.",
        "The tokenizer adds <|endoftext|> here.",
        "A model ends its turn with <|im_end|> or </s> tokens.",
    ],
)
def test_an_end_of_turn_marker_named_in_prose_cuts_nothing(prose: str) -> None:
    answer = f"Draft:\n```python\n{PUT_DOWN}```\n{prose} Final program:\n```python\n{GRASP}```\n"
    assert extract(answer).code == GRASP


def test_a_closing_think_tag_named_in_a_sentence_ends_no_reasoning() -> None:
    answer = (
        f"Final program:\n```python\n{GRASP}```\nThe reply has no </think> tag, so nothing is stripped. "
        f"For comparison, the other grasp:\n```python\n{PUT_DOWN}```\n"
    )
    assert extract(answer).code == GRASP
    assert extract(f"I should open the gripper first.</think>\n\n{GRASP}").code == GRASP  # the tag ends its line


def test_a_closing_think_tag_inside_a_multi_line_string_of_unfenced_code_is_code() -> None:
    """Found by an adversarial run: the tag inside a field's unfenced code cut the program's start off."""
    program = f'open_gripper()\nbanner = """\n</think>\n"""\n{GRASP}'
    reply = f"[[ ## code ## ]]\n{program}\n[[ ## completed ## ]]"
    assert without_reasoning(reply) == reply and extract(program).code == program
    # a triple quote named in the reasoning is no string of code: the reasoning still ends at the tag
    assert extract(f'I would give it a """ docstring.\n</think>\n{GRASP}').code == GRASP


@pytest.mark.parametrize(
    "program",
    [
        f"# Log lines are shown as <pre><code>\n{GRASP}# blocks, closed by </code></pre>\nopen_gripper()\n",
        'open_gripper()\nreport = "<pre><code>"\nmove_to_position(get_graspable_point("milk"))\n'
        'report += "</code></pre>"\nclose_gripper()\nprint(report)\n',
    ],
    ids=["comments", "strings"],
)
def test_html_code_tags_inside_a_fenced_program_are_its_code(program: str) -> None:
    assert extract(f"Final program:\n```python\n{program}```\n").code == program
    assert extract(program).code == program  # unfenced: a tag in a comment or a string opens no HTML block


@pytest.mark.parametrize(
    ("final", "where"),
    [
        (GRASP, "outside the code blocks"),
        ("".join(f"    {line}\n" for line in GRASP.splitlines()), "outside the code blocks"),
        (f"\u200b```python\n{GRASP}\u200b```\n", "outside the code blocks"),
        (f"```text\n{GRASP}```\n", "in a block tagged 'text'"),
    ],
    ids=["unfenced", "indented-four-spaces", "zero-width-space-fences", "tagged-text"],
)
def test_code_outside_the_python_block_makes_the_choice_unclear(final: str, where: str) -> None:
    answer = f"Draft:\n```python\n{PUT_DOWN}```\nThe last four lines put the milk down again. Final program:\n\n{final}"
    with pytest.raises(ProgramRejected, match=f"code block 1 and also code {where}"):
        extract(answer)


@pytest.mark.parametrize(
    "label",
    ["For comparison, the complete code before my fix:", "For reference, the full program you provided:"],
)
def test_an_echo_of_the_old_program_is_no_final_program(label: str) -> None:
    answer = f"Here is the corrected program:\n```python\n{GRASP}```\n{label}\n```python\n{PUT_DOWN}```\n"
    assert extract(answer).code == GRASP


def test_a_test_after_the_final_program_is_not_taken_for_it() -> None:
    test = "print(get_graspable_point('milk'))\nmove_to_position([0.3, 0.0, 0.3])\n"
    answer = f"Final program:\n```python\n{GRASP}```\nAnd the complete code for testing it:\n```python\n{test}```\n"
    assert extract(answer).code == GRASP


def test_two_different_programs_both_marked_final_are_asked_again() -> None:
    answer = f"Final program:\n```python\n{GRASP}```\nOr, from above, the final code:\n```python\n{OTHER}```"
    with pytest.raises(ProgramRejected, match=r"marks 2 different programs as final \(code blocks 1, 2\)"):
        extract(answer)
    options = f"The full code for option A:\n```python\n{GRASP}```\nFull code for option B:\n```python\n{OTHER}```"
    with pytest.raises(ProgramRejected, match="2 different programs"):
        extract(options)


def test_a_later_block_that_keeps_the_drafts_beginning_is_a_correction_not_a_quote() -> None:
    answer = (
        f"```python\n{PUT_DOWN}```\nWait, the extra moves at the end are wrong: they put the milk down again. "
        f"Just this:\n```python\n{GRASP}```\n"
    )
    with pytest.raises(ProgramRejected, match=r"2 different programs \(code blocks 1, 2\)"):
        extract(answer)


def test_a_marker_glued_to_an_unfenced_programs_first_line_never_cuts_it() -> None:
    assert extract(f"<|python_tag|>{GRASP}").code == GRASP  # Llama's tool-call marker, special tokens kept
    with pytest.raises(ProgramRejected, match="line 1: code follows prose on one line"):
        extract(f"Sure! {GRASP}")
    assert extract(f"Run this on the arm (UR5)\n{GRASP}").code == GRASP  # a word and a bracket are no call


def test_a_block_indented_in_a_list_item_loses_the_list_indentation() -> None:
    indented = "".join(f"   {line}\n" for line in GRASP.splitlines())
    assert extract(f"1. The program:\n   ```python\n{indented}   ```\n2. Run it.\n").code == GRASP


def test_a_word_after_an_unfenced_program_is_prose_not_a_line_of_it() -> None:
    extraction = extract(f"{GRASP}Done\n")
    assert extraction.code == GRASP and extraction.dropped_lines == 1
    assert extract("x = \\\n1\nopen_gripper()\n").code == "x = \\\n1\nopen_gripper()\n"  # a continued line is kept


# Found by the second adversarial run (adv5): each ran a program the model did not mean, refused a clear reply, or took
# seconds.
NOGRIP = 'p = get_graspable_point("milk")\nmove_to_position(p)\nclose_gripper()\n'
WAYPOINTS = "\n".join(f"move_to_position([0.3, {y}, 0.3])" for y in (0.0, 0.1, 0.2)) + "\nprint(p)"


def test_reasoning_is_stripped_from_a_long_line_of_escaped_quotes_in_linear_time() -> None:
    line = "x = ['" + "\\'" * 48_000 + "<think>\n"
    started = time.process_time()
    assert without_reasoning(line) == line
    assert time.process_time() - started < CPU_LIMIT_S / 5


ADV5_AMBIGUOUS = {
    "a correction after a block marked final": (
        f"Here is the complete code:\n```python\n{NOGRIP}```\nWait, the gripper has to be opened before moving. "
        f"Here is the correct code:\n```python\n{GRASP}```\n"
    ),
    "an echo marked full, then a fix": (
        f"The full code from the last attempt:\n```python\n{OTHER}```\nIt misses the milk. Use its graspable point "
        f"instead:\n```python\n{GRASP}```\n"
    ),
    "a program marked final split over two blocks": (
        'Final program:\n```python\np = get_graspable_point("milk")\nopen_gripper()\n```\n'
        "```python\nmove_to_position(p)\nclose_gripper()\n```\n"
    ),
    "a def marked complete, its call in the next block": (
        "Here's the complete code:\n```python\ndef pick(name):\n    p = get_graspable_point(name)\n    open_gripper()\n"
        '    move_to_position(p)\n    close_gripper()\n```\nThen call it:\n```python\npick("milk")\n```\n'
    ),
    "a line added at the end of the full program": (
        f"```python\n{NOGRIP}```\nTo lift it, add this at the end of the full program:\n"
        "```python\nmove_to_position([0.3, 0.0, 0.3])\n```\n"
    ),
    "a shorter correction that drops the draft's middle lines": (
        f"```python\n{GRASP.replace('open_gripper()', 'open_gripper()' + chr(10) + WAYPOINTS)}```\nThe waypoints "
        f"are not needed. Simply:\n```python\n{GRASP}```\n"
    ),
    "a shorter correction that drops the draft's first lines": (
        f"```python\n{WAYPOINTS}\n{GRASP}```\nWait, the first four lines are wrong. Just this:\n```python\n{GRASP}```\n"
    ),
    "a simple version, then a longer optional one": (
        f"Here's a simple version:\n```python\n{GRASP}```\nIf you also want to put it down, extend it like this:\n"
        f"```python\n{PUT_DOWN}```\n"
    ),
}


@pytest.mark.parametrize("answer", ADV5_AMBIGUOUS.values(), ids=ADV5_AMBIGUOUS.keys())
def test_a_later_different_program_or_a_fragment_marked_final_is_asked_again(answer: str) -> None:
    with pytest.raises(ProgramRejected, match="2 different programs"):
        extract(answer)


@pytest.mark.parametrize(
    "label", ["The key line of the complete program is the grasp itself:", "The only change in the revised code:"]
)
def test_a_line_of_the_program_under_a_marker_word_is_a_quote_not_the_program(label: str) -> None:
    answer = f"Here is the program:\n```python\n{GRASP}```\n{label}\n```python\nopen_gripper()\n```\n"
    assert extract(answer).code == GRASP


# Found by a fourth adversarial run: a correction that keeps a run of the draft's lines read as a quote of it, and the
# longer draft ran.
OPEN_FIRST = 'open_gripper()\np = get_graspable_point("milk")\nmove_to_position(p)\nclose_gripper()\n'
SHORTENED = {
    "one line, after 'Simply:'": ("Wait, the task is only to open it; the rest is wrong. Simply:", GRASP, 1, 2),
    "one line, marked final": ("Final program:", GRASP, 1, 2),
    "the last line, after 'only ... is needed'": ("Actually it is open, so only the grasp is needed:", GRASP, 3, 4),
    "a run from the middle, after 'Just:'": ("Wait, the task is only to move to the milk. Just:", OPEN_FIRST, 1, 3),
    # found by an adversarial run: the same take-backs in the languages whose final markers are read
    "one line, after 'Korrektur:'": ("Korrektur:", GRASP, 1, 2),
    "one line, after 'Corrección:'": ("Corrección:", GRASP, 1, 2),
    "one line, after '更正后：'": ("更正后：", GRASP, 1, 2),
}


@pytest.mark.parametrize(("label", "draft", "start", "end"), SHORTENED.values(), ids=SHORTENED.keys())
def test_a_correction_that_repeats_a_run_of_the_drafts_lines_is_asked_again(
    label: str, draft: str, start: int, end: int
) -> None:
    part = "".join(draft.splitlines(keepends=True)[start:end])
    answer = f"```python\n{draft}```\n{label}\n```python\n{part}```\n"
    with pytest.raises(ProgramRejected, match="repeats part of block 1"):
        extract(answer)
    assert extract(f"```python\n{draft}```\nThe step that matters:\n```python\n{part}```\n").code == draft


@pytest.mark.parametrize("tag", ["<think>", "<reasoning>", "[THINK]", "`<think>`"])
def test_an_unclosed_think_tag_in_a_sentence_cuts_nothing(tag: str) -> None:
    answer = (
        f"Draft:\n```python\n{NOGRIP}```\nThis misses the open step (I should have planned it in a {tag} block). "
        f"Final program:\n```python\n{GRASP}```\n"
    )
    assert extract(answer).code == GRASP
    if not tag.startswith("`"):  # opening a line, unclosed, it runs to the end
        assert extract(f"{GRASP}\n  {tag}\nDraft:\n```python\n{NOGRIP}```\n").code == GRASP


@pytest.mark.parametrize(
    "listing",
    [
        "Expected output:\n```\nResult: success\n```",
        "Output:\n```\nGripper: closed\n```",
        "Example output:\n```\np = [0.35, 0.0, 0.12]\n```",
        "Task file used:\n```\ntask: milk_reaching_near\nstage: coder\n```",
        "When run, the simulator logs:\n```\nopen_gripper() -> ok\nclose_gripper() -> ok\n```",
        "The reach is checked as\n\n    d = sqrt(x**2 + y**2)\n\nwhich is within reach.",
        "The reach is\nreach = np.linalg.norm(np.array([dx, dy]))\nwhich is enough.",
    ],
    ids=["status", "state", "assignment", "yaml", "trace", "formula", "numpy formula"],
)
def test_an_output_listing_or_a_formula_beside_the_program_is_no_second_program(listing: str) -> None:
    assert extract(f"```python\n{GRASP}```\n{listing}\n").code == GRASP


@pytest.mark.parametrize(
    ("after", "line"),
    [
        ('p = get_graspable_point("milk")\nmoved = move_to_position(p)\nheld = close_gripper()', "p = get_graspable"),
        ("held = close_gripper()", "held = close_gripper()"),
    ],
    ids=["three steps", "one step"],
)
def test_a_line_outside_the_block_that_calls_a_skill_is_no_formula(after: str, line: str) -> None:
    """Found by an adversarial run: each line, an assignment of names the block does not use, was passed over as a
    formula; only the block ran."""
    with pytest.raises(ProgramRejected, match=rf"also code outside the code blocks \('{re.escape(line)}"):
        extract(f"Start with:\n```python\nopen_gripper()\n```\nThen continue:\n\n{after}\n")


def test_an_untagged_correction_that_does_not_parse_is_still_its_syntax_error() -> None:
    answer = f"```python\n{NOGRIP}```\nFixed:\n```\nopen_gripper()\nmove_to_position(p\n```\n"
    with pytest.raises(ProgramRejected, match="syntax error"):
        extract(answer)


@pytest.mark.parametrize("between", ["...", "OR"])
def test_two_unfenced_programs_with_a_value_line_between_are_asked_again(between: str) -> None:
    with pytest.raises(ProgramRejected, match=f"two programs, one before and one after '{between}'"):
        extract(f"{NOGRIP}{between}\n{GRASP}")
    program = f'{GRASP}"""Then lift it."""\nmove_to_position([0.3, 0.0, 0.3])\n'
    assert extract(program).code == program  # a string between statements is a comment


ADV5_CONTROLS = {
    "inline code after the block": f"```python\n{GRASP}```\n1. `open_gripper()` opens it first.\n",
    "a pip block beside it": f"```bash\npip install numpy\n```\n```python\n{GRASP}```\n",
    "a json result block": f'```python\n{GRASP}```\nResult:\n```json\n{{"held": true}}\n```\n',
    "answer tags after reasoning": f"<think>\nDraft:\n```python\n{NOGRIP}```\n</think>\n<answer>\n{GRASP}</answer>\n",
}


@pytest.mark.parametrize("answer", ADV5_CONTROLS.values(), ids=ADV5_CONTROLS.keys())
def test_clear_replies_found_by_the_second_adversarial_run_are_kept(answer: str) -> None:
    assert extract(answer).code == GRASP


RETRACTED = "open_gripper()\nmove_to_position([0.3, 0.2, 0.3])\nclose_gripper()\n"
RETRACTED_FINAL = {
    "a final program, then 'that is wrong' and a correction": (
        f"Final program:\n```python\n{RETRACTED}```\nWait, that is wrong.\n\n```python\n{PROGRAM}```\n"
    ),
    "a corrected code, then 'still wrong; here is the corrected code'": (
        f"Here is the corrected code:\n```python\n{RETRACTED}```\nHmm, still wrong; here is the corrected code:\n"
        f"```python\n{PROGRAM}```\n"
    ),
}


@pytest.mark.parametrize("answer", RETRACTED_FINAL.values(), ids=RETRACTED_FINAL.keys())
def test_a_program_marked_final_then_taken_back_is_never_run(answer: str) -> None:
    """Found by an adversarial run: the retracted block ran (the sentence taking it back stands before the
    correction, where it reads as a label saying the correction is not final). Taking the correction or asking again
    are both right; running the retracted block is not."""
    try:
        code = extract(answer).code
    except ProgramRejected:
        return
    assert code == PROGRAM


@pytest.mark.parametrize("label", ["FINAL:", "**Final:**", "### Final"])
def test_a_bare_final_label_after_a_draft_marks_the_block_final(label: str) -> None:
    """Found by an adversarial run: 'Final version:' and 'FINAL ANSWER:' were read, a bare 'Final:' was not (the
    reply was asked again)."""
    answer = f"Draft:\n```python\n{RETRACTED}```\nThat draft misses the milk.\n\n{label}\n```python\n{PROGRAM}```\n"
    assert extract(answer).code == PROGRAM


@pytest.mark.parametrize(
    "answer",
    [
        f"Final:\n```python\n{RETRACTED}```\nFINAL:\n```python\n{PROGRAM}```\n",  # two programs marked final
        f"### Final\n```python\n{RETRACTED}```\nOn second thought:\n```python\n{PROGRAM}```\n",  # a different one after
    ],
    ids=["two bare labels", "a different program after it"],
)
def test_a_bare_final_label_is_asked_again_when_another_program_competes(answer: str) -> None:
    with pytest.raises(ProgramRejected, match="which one is meant"):
        extract(answer)


@pytest.mark.parametrize(
    "label",
    [
        "Correction: open the gripper before grasping:",
        "That doesn't open the gripper, so use this instead:",
        "No wait, this is the right one:",
        "Hmm, that never opens the gripper. Corrected version, which opens the gripper first:",
    ],
)
def test_a_correction_after_a_program_marked_final_is_asked_again(label: str) -> None:
    """Found by an adversarial run: everyday words in the correction's label ("before", "n't", "no", "first") set the
    correction aside as no program, and the draft marked final ran."""
    with pytest.raises(ProgramRejected, match="2 different programs"):
        extract(f"Final program:\n```python\n{NOGRIP}```\n{label}\n```python\n{GRASP}```\n")


@pytest.mark.parametrize(
    "label",
    ["Alternatively, from above:", "Your original program:", "Example usage:", "The code you provided:"],
)
def test_an_aside_after_a_program_marked_final_is_set_aside(label: str) -> None:
    assert extract(f"Final program:\n```python\n{GRASP}```\n{label}\n```python\n{NOGRIP}```\n").code == GRASP


@pytest.mark.parametrize(
    "comment",
    [
        "# same as above",
        "# etc.",
        "# \u2026 and so on",
        "# [unchanged]",
        "# (keep the remaining lines from your version)",
        "# the other steps as in your program",
        "# rest as you had it",
    ],
)
def test_a_comment_line_that_only_says_the_rest_is_as_it_was_is_a_placeholder(comment: str) -> None:
    """Found by an adversarial run: each two-line fragment ran as the whole program."""
    with pytest.raises(ProgramRejected, match="placeholder for code left out"):
        extract(f"Corrected code:\n```python\n{HEAD}{comment}\n```\n")


@pytest.mark.parametrize(
    "line",
    ["close_gripper()  # same as above", "close_gripper()  # as in your program", "# close the gripper as before"],
)
def test_such_words_beside_code_or_naming_a_step_are_no_placeholder(line: str) -> None:
    program = f"{HEAD}{line}\nclose_gripper()\n"
    assert extract(f"Corrected code:\n```python\n{program}```").code == program


TOP = 'p = get_graspable_point("milk")\nopen_gripper()\nmove_to_position([p[0], p[1], p[2] + 0.1])\nclose_gripper()\n'


@pytest.mark.parametrize(
    "answer",
    [
        f"```python\n# Option 1: grasp from the side\n{GRASP}\n# Option 2: grasp from above\n{TOP}```\n",
        f"```python\n# First attempt (wrong: never opens the gripper)\n{NOGRIP}\n# Corrected version\n{GRASP}```\n",
        f"Option 1, from the side:\n{GRASP}\n# Option 2, from above:\n{TOP}",
        f"{NOGRIP}\n# Wait, that never opens the gripper. Corrected:\n{GRASP}",
        f'{GRASP}"""Alternatively, from above:"""\n{TOP}',
        f"```python\n{GRASP}\n# Another way: grasp from above\n{TOP}```\n",
    ],
    ids=[
        "two options in a block",
        "a draft and its fix in a block",
        "unfenced options",
        "unfenced draft and fix",
        "unfenced options split by a string",
        "another way in a block",
    ],
)
def test_two_programs_joined_by_their_comments_are_asked_again(answer: str) -> None:
    """Found by an adversarial run: both ran, one after the other."""
    with pytest.raises(ProgramRejected, match="joined in one block"):
        extract(answer)


@pytest.mark.parametrize(
    "program",
    [
        f"# Option 2 (from above), the one that fits under the shelf\n{TOP}",
        f"# Final version: open first, then grasp\n{GRASP}",
        f"{GRASP}# Step 2: lift it\nmove_to_position([0.3, 0.0, 0.3])\n",
    ],
    ids=["one option named", "a final version named first", "numbered steps"],
)
def test_one_program_whose_comments_name_an_option_or_a_version_is_kept(program: str) -> None:
    assert extract(f"```python\n{program}```\n").code == program


@pytest.mark.parametrize(
    "label",
    [
        "最终代码：",
        "Código final:",
        "Programme final :",
        "Endgültiges Programm:",
        "修正後のコード：",
        "수정된 코드:",
        "Исправленный код:",
        "## Final program\n\nIt opens:",
    ],
    ids=["zh", "es", "fr", "de", "ja", "ko", "ru", "a heading, then a sentence"],
)
def test_a_fix_marked_final_in_another_language_or_by_a_heading_is_taken(label: str) -> None:
    """Found by an adversarial run: honest replies asked again, as two programs neither marked."""
    answer = f"```python\n{NOGRIP}```\nThat misses the open step.\n\n{label}\n```python\n{GRASP}```\n"
    assert extract(answer).code == GRASP


@pytest.mark.parametrize(
    "label",
    [
        "Wait — the previous code never opens the gripper, use this:",
        "My first attempt above is wrong; use this instead:",
        "Scratch that, the current code is wrong — this is the right one:",
    ],
)
def test_a_correction_after_a_program_marked_final_that_takes_it_back_is_no_aside(label: str) -> None:
    """Found by an adversarial run: 'previous code', 'first attempt', 'current code' set the correction aside as an
    echo, and the draft marked final ran."""
    with pytest.raises(ProgramRejected, match="2 different programs"):
        extract(f"Final program:\n```python\n{NOGRIP}```\n\n{label}\n```python\n{GRASP}```\n")
