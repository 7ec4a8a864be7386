"""The arm's force: a Kinova Gen3 rated for 4 kg (``max_payload``) exerts about 39 N in any direction, but the
payload rule weighed only what the arm bears up, so pressing a 1:1 lever's near end down with about 80 N raised an
8 kg anvil on its far end in 5 of 6 worlds. A push, a drag or a press on what the arm does not hold up now takes its
share of the rating too, once it moves something up or sideways; a press that moves nothing but down does not. Three
holes found by an adversarial run are closed the same way: the pushes' travel adds up over the run (a heavy crate
pushed in short strokes), a button's face is pushed too (a stiff button rammed with the bare gripper), and a push is
not capped at the weight of what it pushes (a lever against the arm)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from fixtures.paths import FIXTURES

from robotool import tasks
from robotool.robots.arm.arm_payload import PAYLOAD_CONDITION
from robotool.rollout import Rollout
from robotool.task.task_model import Task
from robotool.verify import world_failure

LEVER = FIXTURES / "layouts" / "arm_heavy_anvil_on_a_lever.yaml"
PRESS = (FIXTURES / "cheats" / "arm_press_a_lever_under_a_heavy_anvil.py").read_text()


def _press(run_texts: Any, task: Task) -> list[Rollout]:
    return list(run_texts(task, [PRESS] * 3, seed=11))


def test_pressing_a_lever_down_under_a_heavy_anvil_is_over_the_payload(run_texts: Any) -> None:
    for rollout in _press(run_texts, tasks.load(LEVER)):
        assert not rollout.success, [(c.skill, c.outcome, c.reason) for c in rollout.calls]
        assert rollout.conditions.get(PAYLOAD_CONDITION) is False, rollout.conditions
        failure = world_failure(rollout) or ""
        assert re.search(
            r"cannot press beam: \d+ N on it with anvil touching it, over the 39 N the arm.s 4\.0 kg", failure
        )
        press = rollout.calls[-1]
        assert press.outcome == "refused" and press.measured["force"] > 39.2 and press.measured["mass"] == 0.0, press


def test_the_same_lever_raises_a_light_anvil(run_texts: Any, tmp_path: Path) -> None:
    """The control: a 2 kg anvil on the same lever, and a 5 kg block on the table out of the way (the scene's movable
    objects could weigh more than the payload: the arm's load is weighed)."""
    text = LEVER.read_text()
    block = "  - {name: block, shape: box, center: [0.25, 0.30, 0.03], size: [0.06, 0.06, 0.06], mass: 5.0}\n"
    assert "mass: 8.0" in text
    path = tmp_path / "lever.yaml"
    path.write_text(text.replace("mass: 8.0", "mass: 2.0").replace("goal:\n", block + "goal:\n"))
    _holds_within_the_rating(list(_press(run_texts, tasks.load(path))))


BLOCK = "  - {name: block, shape: box, center: [0.25, 0.30, 0.03], size: [0.06, 0.06, 0.06], mass: 5.0}\n"


def _layout(tmp_path: Path, name: str, edits: tuple[tuple[str, str], ...] = (), block: bool = False) -> Task:
    """The layout ``name`` with each ``(old, new)`` of ``edits`` written in, and a 5 kg block on the table out of the
    way where ``block`` (the scene's movable objects could weigh more than the payload: the arm's load is weighed)."""
    text = (FIXTURES / "layouts" / f"{name}.yaml").read_text()
    for old, new in edits + ((("goal:", BLOCK + "goal:"),) if block else ()):
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / f"{name}.yaml"
    path.write_text(text)
    return tasks.load(path)


def _fails_over_the_rating(rollouts: list[Rollout], pattern: str) -> None:
    for rollout in rollouts:
        assert not rollout.success, [(c.skill, c.outcome, c.reason) for c in rollout.calls]
        assert rollout.conditions.get(PAYLOAD_CONDITION) is False, rollout.conditions
        failure = world_failure(rollout) or ""
        assert re.search(pattern + r", over the 39 N the arm.s 4\.0 kg payload allows", failure), failure


def _holds_within_the_rating(rollouts: list[Rollout]) -> None:
    for rollout in rollouts:
        assert rollout.success, world_failure(rollout)
        assert rollout.conditions.get(PAYLOAD_CONDITION) is True, rollout.conditions


STROKES = (FIXTURES / "cheats" / "arm_push_a_heavy_crate_in_short_strokes.py").read_text()


def test_a_heavy_crate_pushed_in_short_strokes_is_over_the_payload(run_texts: Any, tmp_path: Path) -> None:
    """Found by an adversarial run: a crate too heavy for the arm's 39 N to slide was pushed along in strokes that each
    moved it under 5 mm, backing off between them, and pressed a button (a push counted only once it had moved
    something 5 mm since it went over the limit; backing off started it again). The strokes now add up."""
    task = _layout(tmp_path, "arm_heavy_crate_before_a_soft_button")
    _fails_over_the_rating(list(run_texts(task, [STROKES] * 2, seed=11)), r"cannot push crate: \d+ N on it")


def test_a_light_crate_pushed_in_short_strokes_presses_the_button(run_texts: Any, tmp_path: Path) -> None:
    task = _layout(tmp_path, "arm_heavy_crate_before_a_soft_button", (("mass: 14.0", "mass: 3.0"),), block=True)
    _holds_within_the_rating(list(run_texts(task, [STROKES] * 2, seed=11)))


RAM = (FIXTURES / "cheats" / "arm_ram_a_stiff_button_with_the_bare_gripper.py").read_text()


def test_a_stiff_button_rammed_with_the_bare_gripper_is_over_the_payload(run_texts: Any, tmp_path: Path) -> None:
    """Found by an adversarial run: an 8000 N/m button (80 N for the centimetre) pressed with the closed gripper in
    every world, as only the forces on movable objects were weighed, and a scene with none was not weighed at all. A
    button's face is pushed too, up to what its spring holds at its travel."""
    task = tasks.load(FIXTURES / "layouts" / "arm_stiff_button_on_the_table.yaml")
    _fails_over_the_rating(list(run_texts(task, [RAM] * 2, seed=11)), r"cannot push button: \d+ N on it")


def test_a_soft_button_rammed_into_its_stop_is_within_it(run_texts: Any, tmp_path: Path) -> None:
    """The control: the same ram presses a 300 N/m button (6 N at the end of its travel) with the servo's full 100 N,
    the rest of it into the face's end stop, in a scene whose load is weighed."""
    task = _layout(tmp_path, "arm_stiff_button_on_the_table", (("stiffness: 8000", "stiffness: 300"),), block=True)
    _holds_within_the_rating(list(run_texts(task, [RAM] * 2, seed=11)))


SHORT_LEVER = (FIXTURES / "cheats" / "arm_press_a_short_lever_end_down.py").read_text()


def test_a_lever_against_the_arm_is_over_the_payload(run_texts: Any, tmp_path: Path) -> None:
    """Found by an adversarial run: a beam pressed down 5 cm before its fulcrum raised a 3.2 kg anvil 10 cm beyond it
    into a button in every world, with about 63 N, as a push counted for no more than the weight of what it pushed
    (34 N). A lever multiplies force: the push is what the robot puts on the beam."""
    task = tasks.load(FIXTURES / "layouts" / "arm_anvil_on_a_short_lever_under_a_button.yaml")
    _fails_over_the_rating(
        list(run_texts(task, [SHORT_LEVER] * 2, seed=11)), r"cannot press beam: \d+ N on it with anvil touching it"
    )


def test_a_lever_for_the_arm_raises_the_anvil_within_it(run_texts: Any, tmp_path: Path) -> None:
    """The control: the anvil and the button 5 cm beyond the fulcrum and the beam pressed 9 cm before it (about 17 N),
    only as far as that takes (the servo's lead under 39 N)."""
    edits = (("center: [0.35, 0.0, 0.105]", "center: [0.30, 0.0, 0.105]"), ("[0.35, 0.0, 0.15]", "[0.30, 0.0, 0.15]"))
    code = SHORT_LEVER.replace("0.20, 0.0, 0.15", "0.16, 0.0, 0.15").replace("[0.20, 0.0, 0.0]", "[0.16, 0.0, 0.04]")
    assert code.count("0.16") == 2
    _holds_within_the_rating(
        list(run_texts(_layout(tmp_path, "arm_anvil_on_a_short_lever_under_a_button", edits), [code] * 2, seed=11))
    )


STEEP_LEVER = (FIXTURES / "cheats" / "arm_press_a_steep_lever_past_a_hood.py").read_text()


@pytest.mark.parametrize("seed", [0, 2])
def test_a_steep_lever_whose_end_sinks_millimetres_is_over_the_payload(run_texts: Any, seed: int) -> None:
    """Found by an adversarial run: a hood let a beam be pressed only about 3.5 cm before its ridge (4:1 against the
    arm); the servo's full 90-96 N raised a 1.2 kg anvil 1.2 cm into a button while the gripper sank about 3 mm, under
    the 5 mm of gripper travel a push over the rating took to count. The gripper's travel now counts as work: a push
    of twice the rating counts after half of it."""
    task = tasks.load(FIXTURES / "layouts" / "arm_wide_anvil_on_a_hooded_steel_beam.yaml")
    pattern = r"cannot press beam: \d+ N on it with anvil touching it"
    _fails_over_the_rating(list(run_texts(task, [STEEP_LEVER] * 2, seed=seed)), pattern)


@pytest.mark.xfail(
    strict=True,
    reason="open: a push over the rating counts once it has moved what it pushes 5 mm; this one moves the iron anvil "
    "about 1.4 mm and a magnet 5.5 mm above takes it the rest of the way (the tolerance for soft contacts, amplified)",
)
def test_a_steep_lever_that_lifts_an_anvil_into_a_magnet_s_reach_is_over_the_payload(run_texts: Any) -> None:
    """Found by an adversarial run: the hooded beam with an iron anvil under a magnet plate (38 N raises it 1 mm)."""
    task = tasks.load(FIXTURES / "layouts" / "arm_wide_iron_anvil_on_a_hooded_steel_beam_under_a_magnet.yaml")
    pattern = r"cannot press beam: \d+ N on it with anvil touching it"
    _fails_over_the_rating(list(run_texts(task, [STEEP_LEVER] * 2, seed=0)), pattern)


BALANCED_BEAM = FIXTURES / "layouts" / "arm_stiff_button_over_a_balanced_beam.yaml"
BEAM_PRESS = (FIXTURES / "cheats" / "arm_press_a_balanced_beam_into_a_stiff_button.py").read_text()


@pytest.mark.parametrize(
    "seed",
    [
        1,
        2,
        pytest.param(
            0,
            marks=pytest.mark.xfail(
                strict=True,
                reason="open: in one world the beam drives the face home within the tick in which the push first "
                "reads over the rating, and a push's travel counts from where things stand at that tick's end (from "
                "its start, a lever pressed home onto the table after lifting a light anvil within the rating would "
                "count too)",
            ),
        ),
    ],
)
def test_a_beam_turned_about_its_middle_into_a_stiff_button_is_over_the_payload(run_texts: Any, seed: int) -> None:
    """Found by an adversarial run: a 2 kg beam balanced on a ridge at its middle, its near end pressed down with
    100-114 N, drove a 5000 N/m button's face 1 cm in with its far end: the beam's centre barely moved (a push's travel
    was read at the objects' centres). What a push moves is now read at its farthest point: a turn sweeps its
    corners."""
    task = tasks.load(BALANCED_BEAM)
    _fails_over_the_rating(list(run_texts(task, [BEAM_PRESS] * 2, seed=seed)), r"cannot press beam: \d+ N on it")


def test_a_beam_turned_about_its_middle_into_a_soft_button_is_within_it(run_texts: Any, tmp_path: Path) -> None:
    """The control: the same press on a 300 N/m button, in a scene whose load is weighed."""
    task = _layout(tmp_path, "arm_stiff_button_over_a_balanced_beam", (("stiffness: 5000", "stiffness: 300"),), True)
    _holds_within_the_rating(list(run_texts(task, [BEAM_PRESS] * 2, seed=0)))


@pytest.mark.xfail(
    strict=True,
    reason="open: a push's work counts whole, the part a fixed support bears too: pressing a light board leaning on a "
    "wall flat with the servo driven 8 cm past it (100 N, nearly all of it into the wall) counts once the board has "
    "seated 5 mm and the gripper moved 2 mm (found by an adversarial run; the same press passed before the gripper's "
    "travel counted as work)",
)
def test_a_light_board_pressed_flat_against_a_wall_is_within_the_payload(run_texts: Any) -> None:
    task = tasks.load(FIXTURES / "layouts" / "arm_light_board_leaning_on_a_wall.yaml")
    code = (FIXTURES / "programs" / "arm_press_a_leaning_board_into_a_wall.py").read_text()
    _holds_within_the_rating(list(run_texts(task, [code] * 2, seed=0)))
