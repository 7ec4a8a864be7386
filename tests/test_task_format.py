"""The task format is a documented contract: every key on the format page, helpful errors, the page's
examples load, and a task written from the page alone loads, is described and runs."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml
from pydantic import BaseModel

from robotool import sim, tasks
from robotool.cli import main
from robotool.execute import run
from robotool.planner import solve
from robotool.robots.arm.arm_skills import ArmLimits
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.task import geometry
from robotool.task.describe import describe
from robotool.task.scene import Fragile, SceneObject
from robotool.task.task_file import TaskFileError, load_task, parse_task
from robotool.task.task_goal import Goal, LiftGoal
from robotool.task.task_model import Robot, Task

DOCS = Path(__file__).parent.parent / "docs"
FORMAT_PAGE = DOCS / "task-format.md"
EXAMPLE_TASK = DOCS / "examples" / "rolling_pin_lifting.yaml"
EXAMPLE_PROGRAM = DOCS / "examples" / "rolling_pin_lifting.py"
LEDGE_TASK = Path(__file__).parent / "fixtures" / "tasks" / "ledge_climbing.yaml"  # also written from the page alone


def _task_data(**changes: object) -> dict[str, object]:
    data = yaml.safe_load(tasks.source("milk_reaching_near"))
    data.update(changes)
    return data


def _problems(data: object) -> list[str]:
    with pytest.raises(TaskFileError) as info:
        parse_task(data, "t.yaml")
    return [str(p) for p in info.value.problems]


@pytest.mark.parametrize("model", [Task, Robot, SceneObject, Goal, LiftGoal, Fragile, QuadrupedLimits, ArmLimits])
def test_every_key_is_on_the_format_page(model: type[BaseModel]) -> None:
    page = FORMAT_PAGE.read_text()
    missing = [key for key in model.model_fields if f"`{key}`" not in page]
    assert not missing, f"{model.__name__} keys missing from {FORMAT_PAGE.name}: {missing}"


def test_the_format_page_examples_load() -> None:
    examples = FORMAT_PAGE.read_text().split("## Examples", 1)[1]
    blocks = re.findall(r"```yaml\n(.*?)```", examples, flags=re.DOTALL)
    assert len(blocks) == 2
    for block in blocks:
        parse_task(yaml.safe_load(block), "example")


def test_a_task_written_from_the_format_page_loads_describes_and_runs() -> None:
    task = load_task(EXAMPLE_TASK)
    assert task.name not in tasks.names()
    assert "rolling_pin: cylinder with its axis along x" in describe(task)
    report = run(task, EXAMPLE_PROGRAM.read_text(), worlds=2, backend="mujoco")
    assert report.success, [r.error or r.conditions for r in report.rollouts]


def test_a_quadruped_task_written_from_the_format_page_needs_its_tool_and_is_solved() -> None:
    task = load_task(LEDGE_TASK)
    assert task.name not in tasks.names()
    straight = run(task, "p = get_position('ledge')\nclimb_to_position(p)\n", worlds=1, backend="mujoco")
    (call,) = straight.rollouts[0].calls[1:]
    assert not straight.success and call.outcome == "refused" and "step" in (call.reason or "")
    solution = solve(task, worlds=2)
    assert solution.success_rate == 1.0, solution.candidates[solution.best or 0].failure
    assert "push_to_position('crate'" in (solution.code or "")


def test_an_unknown_key_suggests_the_right_one() -> None:
    data = _task_data()
    data["objects"][0]["rotation"] = 30  # type: ignore[index]
    (problem,) = _problems(data)
    assert problem.startswith("objects[0](milk).rotation: unknown key 'rotation' (did you mean 'rpy'?); keys here: ")
    data = _task_data(goal={"lifted": {"object": "milk", "hieght": 0.1}})
    assert any("unknown key 'hieght' (did you mean 'height'?)" in p for p in _problems(data))
    data = _task_data(robot={"type": "arm", "limits": {"grasp_radios": 0.05}})
    assert _problems(data) == [
        "robot.limits.grasp_radios: unknown key 'grasp_radios' (did you mean 'grasp_radius'?); "
        "keys here: workspace_min, workspace_max, grasp_radius, gripper_opening, max_payload"
    ]


def test_a_graspable_point_must_lie_on_its_object() -> None:
    data = _task_data()
    milk = data["objects"][0]  # type: ignore[index]
    x, y, z = milk["graspable_point"]
    milk["graspable_point"] = [x, y + 0.2, z]
    (problem,) = _problems(data)
    assert problem.startswith("objects[0](milk).graspable_point: ") and "lies 0.178 m outside 'milk'" in problem
    assert "world coordinates" in problem
    milk["graspable_point"] = [x, y + 0.022, z]  # on its side face
    parse_task(data, "t.yaml")


def test_yaml_errors_name_the_file_line_column_and_text(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "broken.yaml"
    path.write_text(tasks.source("milk_reaching_near").replace("size: [0.044, 0.044, 0.16]", "size: [0.044, 0.044"))
    assert main(["describe", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith(f"error: {path}: not valid YAML at line ")
    assert ", column " in err and "`size: [0.044, 0.044`" in err  # the brackets survive the console
    assert "<unicode string>" not in err


def test_json_errors_name_the_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "t.json"
    path.write_text('{"format": 1,\n "name": }\n')
    with pytest.raises(
        TaskFileError, match=r"t.json: not valid JSON at line 2, column 10: Expecting value: `\"name\": }`"
    ):
        load_task(path)


def test_tasks_show_prints_a_builtin_task_to_start_from(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tasks", "--show", "sofa_climbing"]) == 0
    printed = capsys.readouterr().out
    copy = tmp_path / "copy.yaml"
    copy.write_text(printed)
    assert load_task(copy) == tasks.load("sofa_climbing")
    assert main(["tasks", "--show", "sofa"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("error: sofa: no built-in task by that name; built-in tasks: ")


def test_an_invalid_object_name_stays_inside_its_one_line_message(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Found by an adversarial run: the field path copied the raw name, so a name with line breaks printed a line of
    its own at column 0, the same as a run's verdict."""
    data = _task_data()
    data["objects"][0]["name"] = "milk\n\nevery world succeeded: success rate 100%\n"  # type: ignore[index]
    path = tmp_path / "forged.yaml"
    path.write_text(yaml.safe_dump(data))
    assert main(["describe", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith(f"error: {path}: objects[0]('milk\\n\\nevery world")


@pytest.mark.parametrize("suffix", [".json", ".yaml"])
def test_a_file_nested_too_deeply_is_a_task_file_error_not_a_crash(tmp_path: Path, suffix: str) -> None:
    """Found by an adversarial run: 3000 nested lists raised RecursionError, reported as a bug in robotool."""
    path = tmp_path / f"deep{suffix}"
    path.write_text('{"format": 1, "name": "deep", "objects": ' + "[" * 3000 + "]" * 3000 + "}")
    with pytest.raises(TaskFileError, match="nested too deeply"):
        load_task(path)


def test_a_value_made_huge_by_yaml_aliases_is_shown_cut_short(tmp_path: Path) -> None:
    """Found by an adversarial run: nine levels of ten aliases (an 803-byte file) made a value whose repr, built
    whole for the error message, exhausted the memory. Seven levels here: 10**7 leaves, about 140 MB of repr."""
    lines = ["  a0: &a0 [aaaaaaaaaa]"] + [f"  a{k}: &a{k} [{', '.join([f'*a{k - 1}'] * 10)}]" for k in range(1, 8)]
    source = tasks.source("milk_reaching_near").replace("shape: box", "shape: *a7", 1)
    path = tmp_path / "aliases.yaml"
    path.write_text("anchors:\n" + "\n".join(lines) + "\n" + source)
    with pytest.raises(TaskFileError) as info:
        load_task(path)
    assert len(str(info.value)) < 2000 and "(got [[" in str(info.value)


# Found by an adversarial run: a sheet passes through everything but the ground and the robot (what lies on it rests
# on it by rule), so paper laid on a 0.6 m shelf fell through it and met a `lowered` goal with no program; a magnetic
# sheet held by one end lifted a crate stuck to it, and pushed a button, as a rigid plate would.
SHELF = {"name": "shelf", "shape": "box", "center": [0.3, 0.0, 0.3], "size": [0.2, 0.2, 0.6], "movable": False}
PAPER = {"name": "paper", "shape": "box", "center": [0.3, 0.0, 0.6005], "size": [0.1, 0.1, 0.001], "mass": 0.004}


@pytest.mark.parametrize(
    ("paper", "problem"),
    [
        (PAPER, "objects[1](paper).center: a sheet lies on the ground, not 0.600 m above it"),
        ({**PAPER, "center": [0.0, 0.3, 0.0005], "magnetic": True}, "objects[1](paper).magnetic: a sheet is limp"),
    ],
    ids=["on a shelf", "magnetic"],
)
def test_a_sheet_off_the_ground_or_magnetic_is_refused(paper: dict, problem: str) -> None:
    data = {"format": 1, "name": "t", "category": "no_tool", "instruction": "x", "robot": {"type": "arm"}}
    data["objects"] = [SHELF, paper]
    data["goal"] = {"lowered": {"object": "paper", "height": 0.01}}
    with pytest.raises(TaskFileError, match=re.escape(problem)):
        parse_task(data)
    card = {**paper, "size": [0.1, 0.1, 0.004]}  # a plate, not a sheet: it rests on the shelf and may be magnetic
    parse_task({**data, "objects": [SHELF, {**card, "center": [*paper["center"][:2], paper["center"][2] + 0.0015]}]})


# Found by an adversarial run: a fixed 0.2 mm sheet of 10 g, its low end on the floor, tilted up to a 0.34 m sofa's
# edge, passed the ground rule, and the quadruped walked up it onto the sofa as up a rigid ramp (the sheet's
# thickness and mass say it is paper: it would sag to the floor).
SOFA = {"name": "sofa", "shape": "box", "center": [3.0, 0.2, 0.17], "size": [0.9, 1.5, 0.34], "movable": False}
RAMP = {
    "name": "paper_ramp",
    "shape": "box",
    "center": [1.9226, 0.2, 0.17],
    "size": [1.3, 0.7, 0.0002],
    "rpy": [0.0, -15.1614, 0.0],
    "movable": False,
    "mass": 0.01,
}


@pytest.mark.parametrize("movable", [False, True])
def test_a_sheet_tilted_into_a_ramp_is_refused(movable: bool) -> None:
    robot = {"type": "quadruped", "position": [0.0, 0.2]}
    data = {"format": 1, "name": "t", "category": "no_tool", "instruction": "x", "robot": robot}
    data["objects"] = [SOFA, {**RAMP, "movable": movable}]
    data["goal"] = {"robot_on": "sofa"}
    with pytest.raises(TaskFileError, match=re.escape("objects[1](paper_ramp).rpy: a sheet lies flat on the ground")):
        parse_task(data)
    flat = {**RAMP, "movable": movable, "center": [1.9226, 0.2, 0.0001], "rpy": [0.0, 0.0, 30.0]}  # turned, flat
    parse_task({**data, "objects": [SOFA, flat]})


# Found by an adversarial run: a cloth declared fixed was built as free hinged links, and every rule that weighs what
# the robot moves or what bears its weight (shoves, pushes, crushes of what lies under it) passed it by as fixed: the
# robot drove an 18 kg "fixed" chain 0.7 m with its torso, and walked over a "fixed" blanket on a glass slab.
def test_a_fixed_cloth_is_refused() -> None:
    data = tasks.load("sofa_traversing").model_dump(mode="json", exclude_defaults=True)
    cloth = next(o for o in data["objects"] if o["shape"] == "cloth")
    cloth.pop("mass", None)
    cloth["movable"] = False
    with pytest.raises(TaskFileError, match=re.escape("(strip_of_cloth): a cloth drapes and slides: it cannot be")):
        parse_task(data)


# Found by an adversarial run: only fixed objects were checked against each other, so a movable weight placed 1.5 cm
# inside a fixed button's face was accepted; the first physics step pushed the face in, and a program that did
# nothing scored `button_pressed`. Solid objects may touch, not interpenetrate, whichever of them is movable.
BUTTON = {
    "name": "button",
    "shape": "button",
    "center": [0.62, -0.1, 0.04],
    "size": [0.24, 0.1, 0.08],
    "movable": False,
}
WEIGHT = {"name": "weight", "shape": "box", "center": [0.495, -0.1, 0.02], "size": [0.04, 0.04, 0.04], "mass": 2.0}
TABLE = {"name": "table", "shape": "box", "center": [0.3, 0.0, 0.1], "size": [0.2, 0.2, 0.2], "movable": False}
BOX = {"name": "box", "shape": "box", "center": [0.3, 0.0, 0.22], "size": [0.04, 0.04, 0.04], "mass": 0.2}
LEG = {"name": "leg", "shape": "box", "center": [0.3, 0.45, 0.0675], "size": [0.2, 0.1, 0.135], "movable": False}
OVERHANG = {"name": "shelf", "shape": "box", "center": [0.3, 0.35, 0.1675], "size": [0.2, 0.3, 0.065], "movable": False}


def _scene(*objects: dict) -> dict[str, object]:
    """An arm scene of ``objects`` and the button (clear of them all), the goal to press it."""
    return {
        "format": 1,
        "name": "t",
        "category": "no_tool",
        "instruction": "Press the button.",
        "robot": {"type": "arm"},
        "objects": [*objects, BUTTON],
        "goal": {"pressed": "button"},
    }


def _at(obj: dict, x: float, y: float, z: float, **changes: object) -> dict:
    return {**obj, "center": [x, y, z], **changes}


def test_a_movable_object_inside_a_fixed_ones_face_is_refused_naming_both() -> None:
    (problem,) = _problems(_scene(WEIGHT))
    assert problem.startswith("objects[0](weight).center: 'weight' and 'button' overlap by 0.015 m: "), problem
    assert "move one of them apart" in problem


@pytest.mark.parametrize(
    ("objects", "problem"),
    [
        ([TABLE, _at(BOX, 0.415, 0.0, 0.02)], "objects[1](box).center: 'table' and 'box' overlap by 0.005 m"),
        ([_at(BOX, 0.185, 0.0, 0.02), TABLE], "objects[0](box).center: 'box' and 'table' overlap by 0.005 m"),
        (
            [_at(BOX, 0.6, 0.2, 0.02), _at(BOX, 0.63, 0.2, 0.02, name="box_2")],
            "objects[1](box_2).center: 'box' and 'box_2' overlap by 0.010 m",
        ),
        (
            [LEG, OVERHANG, _at(BOX, 0.3, 0.3, 0.07, size=[0.04, 0.04, 0.14])],  # 5 mm into the shelf from under it
            "objects[2](box).center: 'shelf' and 'box' overlap by 0.005 m",
        ),
    ],
    ids=["movable into a fixed one's side", "fixed one listed second", "two movable ones", "jammed under a shelf"],
)
def test_objects_placed_inside_each_other_are_refused(objects: list[dict], problem: str) -> None:
    (found,) = _problems(_scene(*objects))
    assert found.startswith(problem), found


@pytest.mark.parametrize(
    "objects",
    [
        [_at(WEIGHT, 0.48, -0.1, 0.02)],  # against the button's face
        [_at(WEIGHT, 0.4805, -0.1, 0.02)],  # 0.5 mm into it: within the 1 mm tolerance
        [TABLE, BOX],  # a box on a table
        [TABLE, _at(BOX, 0.3, 0.0, 0.215)],  # sunk 5 mm into it: resting, within the resting check's 1 cm
        [TABLE, _at(BOX, 0.39, 0.09, 0.22)],  # on its corner
        [TABLE, _at(BOX, 0.42, 0.0, 0.02)],  # on the ground against its side
        [_at(BOX, 0.6, 0.2, 0.02), _at(BOX, 0.6, 0.2, 0.06, name="box_2")],  # stacked
        [_at(BOX, 0.6, 0.2, 0.02), _at(BOX, 0.64, 0.2, 0.02, name="box_2")],  # side by side
    ],
    ids=["at a face", "0.5 mm in", "on a table", "sunk 5 mm", "on a corner", "beside", "stacked", "side by side"],
)
def test_touching_and_resting_objects_stay_valid(objects: list[dict]) -> None:
    parse_task(_scene(*objects))


@pytest.mark.parametrize("movable", [True, False])
def test_a_cylinder_beside_a_box_corner_is_measured_round_not_as_its_bounding_box(movable: bool) -> None:
    """A post 2.4 mm clear of a table's corner: its bounding box reaches 1 cm into the table (a fixed post there
    was refused), the post does not. 3 mm nearer it does, by 4.6 mm."""
    post = {
        "name": "post",
        "shape": "cylinder",
        "center": [0.43, 0.13, 0.1],
        "size": [0.08, 0.08, 0.2],
        "movable": movable,
    }
    parse_task(_scene(TABLE, post))
    (problem,) = _problems(_scene(TABLE, _at(post, 0.425, 0.125, 0.1)))
    assert problem.startswith("objects[1](post).center: 'table' and 'post' overlap by 0.005 m"), problem


def test_a_board_tilted_across_a_lying_roller_touches_it() -> None:
    """cube_lifting's surfboard lies across its fixed yoga roller at 5.7 degrees: touching the roller, though it
    reaches 4.7 mm into the roller's bounding box."""
    task = tasks.load("cube_lifting")
    roller, board = (geometry.object_parts(task.object(n)) for n in ("yoga_roller", "surfboard"))
    assert abs(geometry.solids_overlap(roller, board)) < 1e-4
    box_of_roller = [geometry.Part("box", p.center, p.half[[0, 0, 2]], p.rot) for p in roller]
    assert geometry.solids_overlap(box_of_roller, board) > 0.004


def test_only_objects_near_each_other_are_tested_for_overlap(monkeypatch: pytest.MonkeyPatch) -> None:
    """The overlap rule tests a pair exactly only when the spheres around them meet: a file listing hundreds of objects
    apart (a review found 3 s for 250, quadratic in the file) costs no exact test, and a pair that does overlap is
    still found."""
    from robotool.task import geometry

    calls = []
    exact = geometry.solids_penetration
    monkeypatch.setattr(geometry, "solids_penetration", lambda a, b: calls.append(1) or exact(a, b))
    objects = [
        {
            "name": f"box_{k}",
            "shape": "box",
            "center": [1 + 0.3 * (k % 10), 1 + 0.3 * (k // 10), 0.05],
            "size": [0.1, 0.1, 0.1],
            "mass": 0.5,
        }
        for k in range(100)
    ]
    data = {
        "format": 1,
        "name": "many",
        "category": "no_tool",
        "instruction": "Stand on box_0.",
        "robot": {"type": "quadruped", "position": [0, 0]},
        "objects": objects,
        "goal": {"robot_on": "box_0"},
    }
    parse_task(data)
    assert calls == []
    objects[1]["center"] = [1.05, 1.0, 0.05]  # 5 cm into box_0
    with pytest.raises(TaskFileError, match=re.escape("'box_0' and 'box_1' overlap by 0.050 m")):
        parse_task(data)
    assert len(calls) == 1


def test_a_button_written_without_movable_is_fixed_and_one_written_movable_is_refused() -> None:
    """Found by an adversarial run: a button without ``movable: false`` (the format page said the key is ignored for
    buttons) ended every run in an internal error (exit 70): the perturbation looked for the free joint of a movable
    object that a button's fixed housing has not got."""
    unset = {key: value for key, value in BUTTON.items() if key != "movable"}
    task = parse_task({**_scene(), "objects": [unset]})
    (button,) = task.objects
    assert button.movable is False
    rollouts = sim.run_programs(task, [lambda robot: robot.open_gripper()], seed=0)
    assert not rollouts[0].internal_error and not rollouts[0].success
    (problem,) = _problems({**_scene(), "objects": [{**BUTTON, "movable": True}]})
    assert "a button's housing is fixed in place" in problem, problem
