"""The LM-free search planner: built-in tasks solved in simulation, no name dependence, typed stage outputs."""

from __future__ import annotations

import importlib
import re
from dataclasses import replace

import pytest
import yaml
from fixtures.paths import REPO

from robotool import tasks
from robotool.planner import solve
from robotool.planner.codegen import Point, Program
from robotool.robots.arm import arm_macros
from robotool.signatures.models import PlanStep, StepParameters
from robotool.solution import Solution
from robotool.task.task_file import parse_task
from robotool.task.task_model import Task

solve_module = importlib.import_module("robotool.planner.solve")  # the package re-exports solve() under this name

PLANNER = REPO / "robotool" / "planner"


def _renamed(task: Task, mirror_y: bool) -> Task:
    """The task with every object renamed (and the scene mirrored in y): only the geometry stays the same."""
    data = yaml.safe_load(task.to_yaml())
    names = {o["name"]: f"thing_{k}" for k, o in enumerate(data["objects"])}
    text = yaml.safe_dump(data)
    for old, new in sorted(names.items(), key=lambda kv: -len(kv[0])):
        text = re.sub(rf"\b{old}\b", new, text)
    data = yaml.safe_load(text)
    data["name"] = "renamed"
    if mirror_y:
        for obj in data["objects"]:
            obj["center"][1] = -obj["center"][1]
            if "graspable_point" in obj:
                obj["graspable_point"][1] = -obj["graspable_point"][1]
            if obj["shape"] == "hook":  # a reflected L is the same L turned over
                obj["rpy"] = [180.0, 0.0, 0.0]
        if data["robot"].get("position"):
            data["robot"]["position"][1] = -data["robot"]["position"][1]
    return parse_task(data)


def _check_consistent(solution: Solution, task: Task) -> None:
    best = next(c for c in solution.candidates if c.index == solution.best)
    assert solution.code == best.code and solution.success_rate == best.success_rate
    stages = solution.stages
    assert stages.key_concepts is not None and stages.object_roles is not None
    assert {r.name for r in stages.object_roles} == set(task.object_names)
    assert stages.steps and all(isinstance(s, PlanStep) for s in stages.steps)
    assert stages.parameters and all(isinstance(p, StepParameters) and 1 <= p.step <= len(stages.steps)
                                     for p in stages.parameters)
    motions = [line for line in (solution.code or "").splitlines() if "=" not in line.split("(")[0]]
    assert [line.split("(")[0] for line in motions] == [s.skill for s in stages.steps]
    assert stages.abstract_plan and any("search planner" in n for n in solution.notes)
    assert {"generate", "verify", "total"} <= set(solution.timings)


@pytest.mark.parametrize(
    "name", ["milk_reaching", "button_pressing", pytest.param("sofa_traversing", marks=pytest.mark.slow)]
)
def test_solves_builtin_tool_tasks(name: str) -> None:
    task = tasks.load(name)
    solution = solve(task, worlds=2)
    assert solution.method == "search"
    assert solution.success_rate == 1.0, solution.candidates[solution.best or 0].failure
    roles = {r.name: r.role for r in solution.stages.object_roles or []}
    assert any(role.startswith("tool") for role in roles.values())
    _check_consistent(solution, task)


def test_no_tool_variant_uses_no_tool() -> None:
    task = tasks.load("milk_reaching_near")
    solution = solve(task, worlds=2)
    assert solution.success_rate == 1.0
    assert {r.role for r in solution.stages.object_roles or []} <= {"target", "none"}


def test_renamed_and_mirrored_copy_is_solved() -> None:
    task = _renamed(tasks.load("milk_reaching"), mirror_y=True)
    solution = solve(task, worlds=2)
    assert solution.success_rate == 1.0, solution.candidates[solution.best or 0].failure
    assert "milk" not in (solution.code or "") and "hammer" not in (solution.code or "")


def test_tools_false_fails_on_a_tool_task() -> None:
    task = tasks.load("button_pressing")
    solution = solve(task, worlds=1, tools=False)
    assert solution.method == "no_tool"
    assert not solution.success and solution.success_rate == 0.0
    assert solution.candidates and all(c.failure for c in solution.candidates)
    used = {r.name for r in solution.stages.object_roles or [] if r.role != "none"}
    assert used <= {"button"}


def test_program_parameters_follow_queried_positions() -> None:
    prog = Program()
    ref = prog.query("get_center", "cube", (0.1, 0.2, 0.3))
    prog.motion("move_to_position", point=Point.at(ref, (0.0, 0.05, 0.1)), objects=["cube"], intent="above it")
    assert prog.code == "p1 = get_center('cube')\nmove_to_position([p1[0], p1[1] + 0.0500, p1[2] + 0.1000])\n"
    params = prog.parameters[0]
    assert params.relative_to == "cube" and params.offset == [0.0, 0.05, 0.1] and params.step == 1


def test_planner_source_names_no_task_or_family() -> None:
    from robotool.tasks.families import families

    source = "\n".join(p.read_text() for p in PLANNER.glob("*.py")).lower()
    words = set(tasks.names()) | set(families())
    for task_name in tasks.names():  # and their objects' names, which only a per-task branch would mention
        words |= {o.name for o in tasks.load(task_name).objects if "_" in o.name}
    found = sorted(w for w in words if re.search(rf"\b{re.escape(w)}\b", source))
    assert not found, f"the planner names {found}"


@pytest.mark.slow
@pytest.mark.parametrize(("family", "seed"), [("sofa_climbing", 1021), ("sofa_climbing", 1028)])
def test_solves_generated_staircases_that_once_failed(family: str, seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """Regression: a last step level with the target (1021) and a box that drifted along another's face (1028): the
    planner's first round (its best guess) reaches the goal. One round: the later rounds, which look for a program
    that holds in every world, cost 1028 a minute and this test asserts none of them."""
    search_macros = solve_module.robot_planner
    monkeypatch.setattr(solve_module, "robot_planner", lambda task: replace(search_macros(task), rounds=1))
    instance = tasks.generate(family, seed)
    solution = solve(instance.task, worlds=2, repair=False)
    assert len(solution.candidates) == 1
    assert solution.success, solution.candidates[0].failure if solution.candidates else solution.notes


@pytest.mark.slow
def test_a_chair_propping_a_lever_is_pushed_far_enough_out_to_leave_the_board_behind(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """cube_lifting 9302: the chair, pushed out from under the board's raised end off its centre (the body keeps clear
    of the board), turns and drags the board sideways; pushed 0.5 m beyond the board's side it stalled with the board
    still dragged in one of three worlds, and only a repair round (twice the time) found a program that held. The
    first round's best guess now pushes it far enough out to leave the board's end behind in every world."""
    search_macros = solve_module.robot_planner
    monkeypatch.setattr(solve_module, "robot_planner", lambda task: replace(search_macros(task), rounds=1))
    solution = solve(tasks.generate("cube_lifting", 9302).task, verify=0, repair=False)
    assert solution.success_rate == 1.0, [c.failure for c in solution.candidates]


def test_a_predicted_push_problem_is_a_typed_record_rendered_for_people() -> None:
    import numpy as np

    from robotool.planner.layout import Layout
    from robotool.robots.quadruped.predict import push_problem

    task = tasks.load("sofa_climbing")
    layout = Layout(task)
    block, _ = push_problem(layout, "box_2", np.array([3.0, 1.5]), task.limits, 0.0)
    assert block is not None and (block.kind, block.object, block.blocker) == ("collides", "box_2", "sofa")
    assert str(block) == "box_2 would run into sofa"
    behind_sofa = np.array([4.0, 0.0])  # the robot must cross the sofa to line the push up
    approach, _ = push_problem(layout, "box_1", np.array([1.0, 1.0]), task.limits, 0.0, here=behind_sofa)
    assert approach is not None and approach.kind == "approach" and approach.walk
    assert str(approach) == f"the way to push box_1: {approach.walk}"


@pytest.mark.slow
def test_solves_a_lever_turned_a_quarter() -> None:
    """Regression: in a cube_lifting scene turned a quarter the robot walks along the board flank first; the board
    used to be narrower than its feet are apart, and every program fell off it."""
    instance = tasks.generate("cube_lifting", 1003)
    solution = solve(instance.task, worlds=2)
    assert solution.success_rate == 1.0, solution.candidates[0].failure if solution.candidates else solution.notes


@pytest.mark.slow
def test_lowers_a_vase_lying_where_the_steps_lead_without_standing_on_it() -> None:
    """vase_lowering seed 1098: the vase lies where the steps lead onto the sofa, level with the top step. The walk
    onto the sofa was predicted fine with a foot on the vase (a fragile object was read as footing), and the
    simulator breaks the vase under it; the robot stops short of the vase and pushes it off from the step."""
    instance = tasks.generate("vase_lowering", 1098)
    solution = solve(instance.task, worlds=2)
    assert solution.success, solution.candidates[0].failure if solution.candidates else solution.notes


def _cane_task(yaw: float) -> Task:
    """A juice box 0.11 m beyond the workspace's -y wall and a cane lying flat, turned ``yaw`` degrees (at -90 its
    shaft runs along y, the way the fingers close; at 0, along x, like the hammer of milk_reaching)."""
    grasp = [-0.265, 0.0, 0.03] if yaw else [-0.1, -0.175, 0.03]
    return parse_task({
        "format": 1,
        "name": "juice_and_cane",
        "category": "tool_selection",
        "instruction": "Grasp the juice box.",
        "robot": {"type": "arm"},
        "objects": [
            {"name": "juice", "shape": "box", "center": [0.05, -0.56, 0.07], "size": [0.05, 0.04, 0.14],
             "mass": 0.2, "graspable_point": [0.05, -0.56, 0.12]},
            {"name": "cane", "shape": "hook", "center": [-0.2, -0.1, 0.015], "size": [0.4, 0.15, 0.03],
             "rpy": [0, 0, yaw], "mass": 0.3, "graspable_point": grasp},
        ],
        "goal": {"grasped": "juice"},
    })


def test_a_tool_wider_across_the_fingers_than_their_opening_is_not_planned_with() -> None:
    """Found on a held-out task file: the fingers close along y and open 6 cm, so a cane whose shaft runs along y
    cannot be held at it (the simulator says the fingers rest on top of it). The planner made hook programs with it
    anyway, each failing at the grasp; now it counts only what fits between the fingers as a tool. The same cane
    turned along x is still planned with."""
    from robotool.robots.arm.arm_candidates import candidates
    from robotool.robots.arm.arm_macros import Arm

    along_y, along_x = _cane_task(-90.0), _cane_task(0.0)
    assert not Arm(along_y).graspable(along_y.object("cane"))
    assert all("cane" not in p.objects for p in candidates(along_y, tools=True))
    assert Arm(along_x).graspable(along_x.object("cane"))


def test_a_hook_lands_where_it_is_clearest_of_the_other_objects() -> None:
    """On milk_reaching 8436 the hook's first two places along its head (the target nearest the handle, and in the
    middle) land it on the lock and on the stuffed toy; pressed down there and dragged, it slipped out of the grip in
    a fresh world. The places tried are now the two clearest, a quarter of the way along the head first."""
    task = tasks.generate("milk_reaching", 8436).task
    arm = arm_macros.Arm(task)
    hook, milk = task.object("hammer"), task.object("milk")
    clearance = {k: arm_macros.hook_way(arm, hook, milk, k).clearance for k in arm_macros.HOOK_LATERALS}  # type: ignore[union-attr]
    assert clearance[0.0] < 0 and clearance[0.5] < 0  # on the lock, on the toy
    chosen = arm_macros.hook_laterals(arm, hook, milk)
    assert chosen[0] == 0.25 and clearance[0.25] > 0.01
    assert clearance[chosen[1]] == max(v for k, v in clearance.items() if k != 0.25)


def test_a_press_clamped_at_the_workspace_edge_is_tried_after_one_that_presses_the_whole_way() -> None:
    """button_pressing 11102: a one-magnet chain reaches the button's face only at the workspace edge (the press is
    clamped there and fails in about one perturbed world in eight); the four-magnet chain that presses the whole way
    comes first."""
    from robotool.planner.search import order
    from robotool.robots.arm.arm_candidates import candidates

    programs = order(list(candidates(tasks.generate("button_pressing", 11102).task, True)))
    thin = [bool(p.thin) for p in programs]
    assert thin[0] is False and True in thin, thin
    assert thin == sorted(thin), thin  # every clamped press after every whole one
    assert any("past its face at the workspace edge" in note for p in programs for note in p.thin)


@pytest.mark.slow
def test_a_chain_pushed_into_the_next_magnet_with_slack_holds_in_a_world_the_planner_never_saw() -> None:
    """button_pressing 23000: the chain's end was pushed 4 mm into each next cube; in a perturbed world the planner had
    not seen (the benchmark's first fresh world), the chain stalled a few mm back against the third cube, its end
    stopped 0.1 mm short, the cube never stuck, and two cubes fell short of the button. Pushed 8 mm in, it holds."""
    from robotool.verify import failure_reason, run_codes

    task = tasks.generate("button_pressing", 23000).task
    solution = solve(task, worlds=3)
    assert solution.success and solution.code is not None
    (fresh,) = run_codes(task, [solution.code], worlds=1, seed=50_000)
    assert failure_reason(fresh) is None, failure_reason(fresh)
