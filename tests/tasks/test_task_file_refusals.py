"""Task files an adversarial run found accepted, silently changed or crashing the simulator (exit 70): each is now
refused with one line naming the field, through the loader the command line uses."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from robotool import tasks
from robotool.sim.build import build
from robotool.task.describe import describe
from robotool.task.scene import MAX_BUTTON_STIFFNESS, MIN_BUTTON_STIFFNESS
from robotool.task.task_file import TaskFileError
from robotool.task.task_model import Task

ARM = """\
format: 1
name: t
category: no_tool
instruction: Lift the cube.
robot: {{type: arm{limits}}}
objects:
  - {{name: {name}, shape: box, center: [0.3, 0.0, {z}], size: {size}{extra}}}
  - {{name: table, shape: box, center: [0.0, 0.4, 0.05], size: [0.2, 0.2, 0.1], movable: false}}
goal: {{lifted: {{object: {name}, height: 0.1}}}}
"""
QUADRUPED = """\
format: 1
name: t
category: no_tool
instruction: Get onto the sofa.
robot: {{type: quadruped, position: [0.0, 0.0], limits: {limits}}}
objects:
  - {{name: sofa, shape: box, center: [0.0, 0.0, 0.17], size: [1.0, 0.9, 0.34], movable: false}}
goal: {{robot_on: sofa}}
"""


def _arm(name: str = "cube", extra: str = "", limits: str = "", side: float = 0.04) -> str:
    """A task with an arm, a movable cube (of ``side``, resting on the ground) and a fixed table."""
    return ARM.format(
        name=name, extra=extra, limits=f", limits: {{{limits}}}" if limits else "", z=side / 2, size=[side] * 3
    )


def _load(tmp_path: Path, text: str, suffix: str = ".yaml") -> Task:
    path = tmp_path / f"task{suffix}"
    path.write_text(text)
    return tasks.load(path)


def _refusal(tmp_path: Path, text: str, suffix: str = ".yaml") -> str:
    with pytest.raises(TaskFileError) as refused:
        _load(tmp_path, text, suffix)
    return str(refused.value)


@pytest.mark.parametrize(
    ("name", "why"),
    [
        ("world", "'world' is reserved"),
        ("robot_foot0", "names starting with 'robot'"),
        ("robot_gripper", "names starting with 'robot'"),
        ("robotic_arm", "names starting with 'robot'"),
        ("b__face", "'_' stands only singly"),
        ("_cube", "'_' stands only singly"),
        ("cube_", "'_' stands only singly"),
    ],
)
def test_a_name_the_simulator_uses_is_refused(tmp_path: Path, name: str, why: str) -> None:
    refusal = _refusal(tmp_path, _arm(name))
    assert f"objects[0].name: '{name}'" in refusal and why in refusal


def test_names_like_the_reserved_ones_but_not_them_load(tmp_path: Path) -> None:
    for name in ("my_robot", "worlds", "cube_2"):
        assert _load(tmp_path, _arm(name)).objects[0].name == name


@pytest.mark.parametrize(
    ("limits", "problem"),
    [
        ("{body_size: [0, 0.3, 0.3]}", "robot.limits.body_size[0]: a limit lies between 0.001 and 1000"),
        ("{body_size: [0.65, -0.3, 0.3]}", "robot.limits.body_size[1]: a limit lies between"),
        ("{body_size: [.nan, 0.3, 0.3]}", "robot.limits.body_size[0]: must be a finite number (got nan)"),
        ("{body_size: [0.65, 0.3, .inf]}", "robot.limits.body_size[2]: must be a finite number (got inf)"),
        ("{mass: .inf}", "robot.limits.mass: must be a finite number"),
        ("{mass: 1.0e+300}", "robot.limits.mass: a limit lies between 0.001 and 1000 (m or kg; got 1e+300)"),
        ("{max_step_up: .inf}", "robot.limits.max_step_up: must be a finite number"),
        ("{max_gap: true}", "robot.limits.max_gap: a number is needed, not a boolean"),
        # no torso above the legs: the build failed (exit 70)
        ("{body_size: [0.65, 0.3, 0.05]}", "robot.limits.body_size: the body's height (z) must be at least 0.06 m"),
    ],
)
def test_quadruped_limits_are_finite_positive_and_bounded(tmp_path: Path, limits: str, problem: str) -> None:
    assert problem in _refusal(tmp_path, QUADRUPED.format(limits=limits))


@pytest.mark.parametrize(
    ("limits", "problem"),
    [
        ("workspace_min: [.nan, -0.45, 0.0]", "robot.limits.workspace_min[0]: must be a finite number"),
        ("workspace_max: [0.45, .inf, 0.5]", "robot.limits.workspace_max[1]: must be a finite number"),
        ("workspace_min: [-1.0e+300, -0.45, 0.0]", "workspace_min[0]: an end of a range lies within ±1000 m"),
        (
            "workspace_min: [0.5, 0.5, 0.5], workspace_max: [0, 0, 0]",
            "robot.limits.workspace_min[0]: must be below workspace_max[0] (0.5 is not below 0)",
        ),
        ("workspace_max: [0.45, 0.45, 0.0]", "robot.limits.workspace_min[2]: must be below workspace_max[2]"),
        ("max_payload: .inf", "robot.limits.max_payload: must be a finite number"),
    ],
)
def test_arm_workspace_and_payload_are_finite_bounded_and_ordered(tmp_path: Path, limits: str, problem: str) -> None:
    assert problem in _refusal(tmp_path, _arm(limits=limits))


def test_limits_within_the_bounds_load(tmp_path: Path) -> None:
    task = _load(tmp_path, _arm(limits="workspace_min: [-1000, -1000, -1000], workspace_max: [1000, 1000, 1000]"))
    assert task.limits.workspace_max == (1000.0, 1000.0, 1000.0)  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("side", "extra", "problem"),
    [
        (1e-300, ", mass: 1", "size[0]: 1e-300 is below the smallest length (m) a task file may give, 0.0001"),
        (1e-9, ", mass: 1", "size[0]: 1e-09 is below the smallest length"),
        (0.04, ", mass: 1.0e-300", "mass: 1e-300 is below the smallest mass (kg) a task file may give, 0.001"),
        (0.001, "", ": it weighs 3e-07 kg at the default 300 kg/m^3 of its volume"),
    ],
)
def test_tiny_sizes_and_masses_are_refused(tmp_path: Path, side: float, extra: str, problem: str) -> None:
    assert f"objects[0](cube){problem}" in _refusal(tmp_path, _arm(extra=extra, side=side)).replace(").", ")", 1)


def _with_button(extra: str) -> str:
    """The arm task with a button on the ground (``extra``: its further keys) after the table."""
    button = f"{{name: button, shape: button, center: [0.5, 0.0, 0.04], size: [0.06, 0.06, 0.08]{extra}}}"
    return _arm().replace("goal:", f"  - {button}\ngoal:")


RANGE = "a button's spring stiffness lies between 1 and 15000 N/m"


@pytest.mark.parametrize(
    ("extra", "problem"),
    [
        (", stiffness: 1.0e+300", f".stiffness: {RANGE} (got 1e+300)"),
        (", stiffness: 30000", f".stiffness: {RANGE} (got 30000)"),
        (", stiffness: 1.0e-300", f".stiffness: {RANGE} (got 1e-300)"),
        (", stiffness: -5", f".stiffness: {RANGE} (got -5)"),
        (", stiffness: .inf", ".stiffness: Input should be a finite number (got inf)"),
        (", stiffness: true", ".stiffness: a number is needed, not a boolean (got true)"),
        (", travel: 1.0e+300", ".travel: Input should be less than or equal to 1000 (got 1e+300)"),
        (
            ", travel: 0.5",
            ": button travel 0.5 m must exceed the 0.01 m that counts as pressed and be at most half the button's "
            "length (0.03 m)",
        ),
    ],
)
def test_a_buttons_spring_and_travel_are_bounded(tmp_path: Path, extra: str, problem: str) -> None:
    """A stiffness of 1e300 N/m loaded and ran, a button nothing could press, and one stiffer than the simulator's
    step follows blows the simulation up: each is refused in one line naming the key and the range."""
    assert _refusal(tmp_path, _with_button(extra)) == f"{tmp_path / 'task.yaml'}: objects[2](button){problem}"


@pytest.mark.parametrize("stiffness", [MIN_BUTTON_STIFFNESS, MAX_BUTTON_STIFFNESS])
def test_the_softest_and_stiffest_springs_load_and_read_in_the_description(tmp_path: Path, stiffness: float) -> None:
    said = describe(_load(tmp_path, _with_button(f", stiffness: {stiffness}")))
    assert f"counts as pressed after 0.01 m of travel, against a spring of {stiffness:g} N/m;" in said


def test_the_stiffest_button_allowed_springs_back_stably_in_the_simulator(tmp_path: Path) -> None:
    """Its face pushed to the end of its travel and let go returns to rest; a stiffer spring than the simulator's
    step follows (30000 N/m) blew the simulation up."""
    model = build(_load(tmp_path, _with_button(f", stiffness: {MAX_BUTTON_STIFFNESS}, travel: 0.03"))).model
    data = mujoco.MjData(model)
    face = model.joint("button__travel").qposadr[0]
    data.qpos[face] = 0.03
    mujoco.mj_step(model, data, nstep=1000)
    assert not data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number and np.isfinite(data.qvel).all()
    assert abs(data.qpos[face]) < 0.001


@pytest.mark.parametrize(
    ("size", "mass", "problem"),
    [("[30.0, 0.5, 0.004]", 3.0, "a cloth is at most 20 m long"), ("[2.0, 0.5, 0.004]", 0.01, "at least 0.01 kg per")],
)
def test_a_cloth_too_long_or_too_light_is_refused(tmp_path: Path, size: str, mass: float, problem: str) -> None:
    text = QUADRUPED.format(limits="{}").replace(
        "goal:", f"  - {{name: rag, shape: cloth, center: [0.0, 2.0, 0.002], size: {size}, mass: {mass}}}\ngoal:"
    )
    assert problem in _refusal(tmp_path, text)


def test_the_smallest_and_lightest_objects_allowed_build_in_the_simulator(tmp_path: Path) -> None:
    """MuJoCo refuses a body whose mass or inertia is under 1e-15; the bounds keep every one far above it."""
    objects = [
        "{name: grain, shape: box, center: [0.3, -0.3, 0.00005], size: [0.0001, 0.0001, 0.0001], mass: 0.001}",
        "{name: pin, shape: cylinder, center: [0.35, -0.3, 0.00005], size: [0.0001, 0.0001, 0.0001], mass: 0.001}",
        "{name: clip, shape: hook, center: [0.4, -0.3, 0.00005], size: [0.00021, 0.00021, 0.0001], thickness: 0.0001, "
        "mass: 0.001}",
        "{name: thread, shape: cloth, center: [0.0, -0.8, 0.00005], size: [20.0, 0.0001, 0.0001], mass: 0.2}",
    ]
    text = _arm().replace("  - {name: table", "".join(f"  - {o}\n" for o in objects) + "  - {name: table")
    build(_load(tmp_path, text))


def test_a_key_given_twice_is_refused_with_its_lines(tmp_path: Path) -> None:
    text = _arm(extra=", mass: 0.25").replace("objects:", "category: no_tool\nobjects:")
    text = text.replace(", mass: 0.25}", ",\n     mass: 0.25,\n     mass: 99}")
    refusal = _refusal(tmp_path, text)
    assert "key 'category' given twice (lines 3 and 6)" in refusal
    assert "objects[0](cube): key 'mass' given twice (lines 9 and 10)" in refusal


def test_a_key_given_twice_in_json_is_refused_naming_where(tmp_path: Path) -> None:
    text = '{"format": 1, "name": "t", "name": "u", "objects": [{"name": "cube", "mass": 1, "mass": 2}]}'
    refusal = _refusal(tmp_path, text, ".json")
    assert "name: key 'name' given twice; give each key once" not in refusal  # the key is named once, at its mapping
    assert "key 'name' given twice" in refusal and "objects[0](cube): key 'mass' given twice" in refusal


def test_a_yaml_merge_key_may_still_be_overridden(tmp_path: Path) -> None:
    text = _arm().replace("robot: {type: arm}", "base: &arm {type: arm}\nrobot: {<<: *arm, type: arm}")
    assert "unknown key 'base'" in _refusal(tmp_path, text)  # not a repeated 'type'


@pytest.mark.parametrize(
    ("edit", "problem"),
    [
        (("format: 1", "format: true"), "format: the format is the integer 1 (got true)"),
        (("format: 1", "format: 1.0"), "format: the format is the integer 1 (got 1.0)"),
        (("movable: false", 'movable: "off"'), "(table).movable: Input should be a valid boolean (got 'off')"),
        (("movable: false", 'movable: "no"'), "objects[1](table).movable: Input should be a valid boolean"),
        (("movable: false", "movable: 0"), "objects[1](table).movable: Input should be a valid boolean (got 0)"),
        (("height: 0.1", "height: true"), "goal.lifted.height: a number is needed, not a boolean"),
    ],
)
def test_booleans_and_integers_are_not_coerced(tmp_path: Path, edit: tuple[str, str], problem: str) -> None:
    assert problem in _refusal(tmp_path, _arm().replace(*edit))


def test_real_yaml_and_json_booleans_still_load(tmp_path: Path) -> None:
    assert not _load(tmp_path, _arm().replace("movable: false", "movable: no")).objects[1].movable
    data = tasks.load("milk_reaching").model_dump(mode="json", exclude_defaults=True)
    data["objects"][0]["magnetic"] = True
    assert _load(tmp_path, json.dumps({**data, "format": 1}), ".json").objects[0].magnetic


@pytest.mark.parametrize(
    ("extra", "problem"),
    [
        (", mass: 5.0", "objects[1](table): 'mass' applies to movable objects only"),
        (", graspable_point: [0.0, 0.4, 0.1]", "objects[1](table): 'graspable_point' applies to movable objects only"),
    ],
)
def test_a_fixed_objects_mass_or_graspable_point_is_refused(tmp_path: Path, extra: str, problem: str) -> None:
    assert problem in _refusal(tmp_path, _arm().replace("movable: false}", f"movable: false{extra}}}"))


def test_a_fixed_thin_box_keeps_its_mass_which_makes_it_a_plate(tmp_path: Path) -> None:
    text = _arm().replace(
        "{name: table, shape: box, center: [0.0, 0.4, 0.05], size: [0.2, 0.2, 0.1], movable: false}",
        "{name: plate, shape: box, center: [0.0, 0.4, 0.001], size: [0.2, 0.2, 0.002], movable: false, mass: 0.6}",
    )
    assert not _load(tmp_path, text).object("plate").is_sheet


def test_a_lowered_goal_height_is_bounded(tmp_path: Path) -> None:
    text = _arm().replace("lifted: {object: cube, height: 0.1}", "lowered: {object: cube, height: 1.0e+300}")
    assert "goal.lowered.height: Input should be less than or equal to 1000" in _refusal(tmp_path, text)


def test_an_upper_case_json_suffix_is_read_as_json(tmp_path: Path) -> None:
    text = '{\n\t"format": 1, "name": "t", "category": "no_tool", "instruction": "x", "robot": {"type": "arm"},\n'
    text += '\t"objects": [{"name": "cube", "shape": "box", "center": [0.3, 0, 0.02], "size": [0.04, 0.04, 0.04]}],\n'
    text += '\t"goal": {"grasped": "cube"}\n}\n'  # a tab is valid JSON, not valid YAML
    assert _load(tmp_path, text, ".JSON").name == "t"


@pytest.mark.parametrize(
    ("line", "problem"),
    [
        ("1: 2", "task.yaml: key 1 (a number): keys must be strings"),
        ("null: 2", "task.yaml: key null (an empty key): keys must be strings"),
        ("true: 2", "task.yaml: key true (a boolean): keys must be strings"),
    ],
)
def test_a_key_that_is_not_text_is_named_as_a_key(tmp_path: Path, line: str, problem: str) -> None:
    assert problem in _refusal(tmp_path, _arm() + line + "\n")


def test_a_named_pipe_is_refused_before_it_is_opened(tmp_path: Path) -> None:
    """A named pipe with no writer made ``robotool describe`` wait for ever."""
    fifo = tmp_path / "task.yaml"
    os.mkfifo(fifo)
    result = subprocess.run(
        [sys.executable, "-m", "robotool", "describe", str(fifo)], capture_output=True, text=True, timeout=120
    )
    refusal = f"error: {fifo}: not a regular file (a named pipe); give a task file\n"
    assert (result.returncode, result.stderr) == (2, refusal)


def test_a_reserved_name_exits_2_without_a_traceback(tmp_path: Path) -> None:
    path = tmp_path / "task.yaml"
    path.write_text(_arm("world"))
    result = subprocess.run(
        [sys.executable, "-m", "robotool", "describe", str(path)], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 2 and "Traceback" not in result.stderr and "'world' is reserved" in result.stderr
