"""Task file validation: every problem is reported with its field path."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest
import yaml

from robotool import tasks
from robotool.task.task_file import TaskFileError, load_task, parse_task


def _base(name: str = "sofa_traversing") -> dict:
    return tasks.load(name).model_dump(mode="json")


def _edit(base: str, **changes):
    def make() -> dict:
        data = copy.deepcopy(_base(base))
        for path, value in changes.items():
            node = data
            keys = path.split("__")
            for key in keys[:-1]:
                node = node[int(key)] if key.isdigit() else node[key]
            last = keys[-1]
            if value is _DELETE:
                del node[last]
            elif last.isdigit():
                node[int(last)] = value
            else:
                node[last] = value
        return data

    return make


_DELETE = object()

# (case id, data factory, expected path fragment, expected message fragment)
MALFORMED = [
    ("unknown_shape", _edit("sofa_traversing", objects__0__shape="sphere"), "objects[0](sofa_1).shape", "sphere"),
    ("unknown_top_key", _edit("sofa_traversing", colour="red"), "colour", "unknown key"),
    (
        "unknown_object_key",
        _edit("sofa_traversing", objects__1__colour="red"),
        "objects[1](sofa_2).colour",
        "unknown key",
    ),
    ("wrong_type_center", _edit("sofa_traversing", objects__0__center="middle"), "objects[0](sofa_1).center", "tuple"),
    (
        "wrong_type_movable",
        _edit("sofa_traversing", objects__2__movable="perhaps"),
        "objects[2](strip_of_cloth).movable",
        "boolean",
    ),
    (
        "negative_size",
        _edit("sofa_traversing", objects__1__size=[0.6, -0.9, 0.34]),
        "objects[1](sofa_2).size[1]",
        "greater than 0",
    ),
    (
        "zero_size",
        _edit("sofa_traversing", objects__1__size=[0.6, 0.9, 0.0]),
        "objects[1](sofa_2).size[2]",
        "greater than 0",
    ),
    ("negative_mass", _edit("sofa_traversing", objects__3__mass=-3.0), "objects[3](surfboard).mass", "greater than 0"),
    (
        "nan_center",
        _edit("sofa_traversing", objects__3__center=[0.5, float("nan"), 0.379]),
        "objects[3](surfboard).center[1]",
        "finite",
    ),
    ("duplicate_names", _edit("sofa_traversing", objects__1__name="sofa_1"), "objects[1].name", "duplicate"),
    (
        "bad_name_chars",
        _edit("sofa_traversing", objects__3__name="Surf-Board"),
        "objects[3](Surf-Board).name",
        "lowercase",
    ),
    ("reserved_name", _edit("sofa_traversing", objects__3__name="robot"), "objects[3].name", "reserved"),
    (
        "goal_missing_object",
        _edit("sofa_traversing", goal={"robot_on": "sofa_9"}),
        "goal.robot_on",
        "no object named 'sofa_9'",
    ),
    (
        "goal_wrong_embodiment",
        _edit("sofa_traversing", goal={"grasped": "surfboard"}),
        "goal.grasped",
        "a quadruped cannot",
    ),
    ("arm_goal_robot_on", _edit("milk_reaching", goal={"robot_on": "milk"}), "goal.robot_on", "an arm cannot"),
    (
        "two_goals",
        _edit("sofa_traversing", goal={"robot_on": "sofa_2", "lifted": {"object": "surfboard", "height": 0.1}}),
        "goal",
        "exactly one",
    ),
    ("no_goal", _edit("sofa_traversing", goal={}), "goal", "exactly one"),
    ("pressed_not_button", _edit("milk_reaching", goal={"pressed": "milk"}), "goal.pressed", "not a button"),
    ("grasp_fixed", _edit("button_pressing", goal={"grasped": "button"}), "goal.grasped", "fixed"),
    ("fixed_overlap", _edit("sofa_traversing", objects__1__center=[1.0, 0.0, 0.17]), "objects[1](sofa_2)", "overlap"),
    (
        "floating",
        _edit("sofa_traversing", objects__3__center=[0.5, 0.0, 0.6]),
        "objects[3](surfboard).center",
        "floats",
    ),
    ("sunk", _edit("sofa_traversing", objects__3__center=[0.5, 0.0, 0.3]), "objects[3](surfboard).center", "sunk"),
    (
        "sunk_into_ground",
        _edit("milk_reaching", objects__0__center=[0.568, 0.01, 0.05]),
        "objects[0](milk).center",
        "sunk",
    ),
    ("start_over_gap", _edit("sofa_traversing", robot__position=[1.1, -0.35]), "robot.position", "not over a surface"),
    (  # an adversarial run: the settling gripper pressed such an object down before the program ran
        "inside_the_gripper",
        _edit("milk_reaching", objects__2__center=[0.1, 0.0, 0.175], objects__2__size=[0.04, 0.03, 0.35]),
        "objects[2](lock).center",
        "into the gripper",
    ),
    ("quadruped_without_start", _edit("sofa_traversing", robot__position=None), "robot.position", "start"),
    ("unknown_robot", _edit("sofa_traversing", robot__type="drone"), "robot.type", "drone"),
    (
        "unknown_limit",
        _edit("sofa_traversing", robot__limits={"max_jump": 1.0}),
        "robot.limits.max_jump",
        "unknown key",
    ),
    (
        "bad_limit_value",
        _edit("sofa_traversing", robot__limits={"max_gap": -0.1}),
        "robot.limits.max_gap",
        "greater than 0",
    ),
    ("bad_category", _edit("sofa_traversing", category="magic"), "category", "magic"),
    ("wrong_format", _edit("sofa_traversing", format=2), "format", "1"),
    ("axis_on_box", _edit("sofa_traversing", objects__3__axis="x"), "objects[3](surfboard)", "cylinders only"),
    ("missing_size", _edit("sofa_traversing", objects__3__size=_DELETE), "objects[3](surfboard).size", "missing"),
]


@pytest.mark.parametrize(("case", "make", "path", "message"), MALFORMED, ids=[m[0] for m in MALFORMED])
def test_malformed_task_names_the_field(case: str, make, path: str, message: str) -> None:
    with pytest.raises(TaskFileError) as info:
        parse_task(make(), source=case)
    problems = info.value.problems
    assert any(p.path.startswith(path) and message in p.message for p in problems), [str(p) for p in problems]


def test_every_problem_is_reported_at_once() -> None:
    data = _edit("sofa_traversing", objects__0__shape="sphere", objects__1__size=[0.6, 0.9, -1.0], category="magic")()
    with pytest.raises(TaskFileError) as info:
        parse_task(data)
    assert len(info.value.problems) == 3


def test_touching_fixed_objects_are_allowed() -> None:
    task = tasks.load("vase_lowering")  # box_2 touches the sofa and box_1
    assert not task.object("box_2").movable


@pytest.mark.parametrize("name", tasks.names())
def test_builtin_tasks_round_trip_through_yaml_and_json(name: str, tmp_path: Path) -> None:
    task = tasks.load(name)
    (tmp_path / "t.yaml").write_text(task.to_yaml())
    (tmp_path / "t.json").write_text(json.dumps(task.model_dump(mode="json")))
    assert load_task(tmp_path / "t.yaml") == task
    assert load_task(tmp_path / "t.json") == task


def test_unreadable_files_are_problems_not_tracebacks(tmp_path: Path) -> None:
    broken = tmp_path / "broken.yaml"
    broken.write_text("format: 1\nobjects: [\n")
    with pytest.raises(TaskFileError, match="not valid YAML"):
        load_task(broken)
    with pytest.raises(TaskFileError, match="file not found"):
        load_task(tmp_path / "missing.yaml")
    (tmp_path / "list.yaml").write_text(yaml.safe_dump([1, 2]))
    with pytest.raises(TaskFileError, match="mapping"):
        load_task(tmp_path / "list.yaml")


def test_defaults_fill_mass_and_grasp_point() -> None:
    task = tasks.load("milk_reaching")
    toy = task.object("stuffed_toy")
    assert toy.grasp_point == pytest.approx((0.45, -0.05, 0.05))
    data = _base("milk_reaching")
    del data["objects"][1]["mass"]
    toy = parse_task(data).object("stuffed_toy")
    assert toy.effective_mass == pytest.approx(300.0 * 0.08 * 0.05 * 0.05)


def test_limit_overrides_apply() -> None:
    data = _base("cube_lifting")
    data["robot"]["limits"] = {"mass": 1.0}
    task = parse_task(data)
    assert task.limits.mass == 1.0
    assert task.limits.max_step_up == 0.12
