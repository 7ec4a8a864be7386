"""Planner repair: a failed program re-parameterised from what the simulator measured."""

from __future__ import annotations

from robotool import tasks
from robotool.planner.codegen import Point, Program
from robotool.planner.reparameterise import repaired
from robotool.rollout import Rollout, SkillCall
from robotool.solution import Candidate
from robotool.verify import run_codes


def test_a_push_that_left_the_gap_too_wide_is_pushed_further_by_the_measured_gap() -> None:
    task = tasks.load("sofa_traversing")
    prog = Program()
    board = prog.query("get_position", "surfboard", (0.3, 0.0, 0.379))
    short = Point.at(board).with_axis(0, None, 0.55)  # the board's far end 0.15 m short of sofa_2
    prog.motion("push_to_position", obj="surfboard", point=short, intent="bridge the gap")
    prog.motion("walk_to_position", point=Point.at(None, (1.775, 0.0, 0.17)), objects=["sofa_2"], intent="cross")
    failed = Candidate(index=0, code=prog.code, rollouts=run_codes(task, [prog.code], worlds=2)[0])
    refusal = failed.rollouts[0].calls[-1]
    assert failed.success_rate == 0.0 and refusal.outcome == "refused" and "gap" in refusal.measured
    variants = repaired(task, prog, failed)
    assert len(variants) == 2 and all(v.code != prog.code for v in variants)
    further = variants[0]
    assert f"measured {refusal.measured['gap']:.3f} m" in further.sentences[-1] and "further" in further.sentences[-1]
    assert further.parameters[0].target[0] > 0.55 + refusal.measured["gap"]  # the walk's own target is kept
    assert further.lines[-1] == prog.lines[-1] and further.parameters[1] == prog.parameters[1]
    results = run_codes(task, [v.code for v in variants], worlds=2)
    assert [all(r.success for r in rollouts) for rollouts in results] == [True, False]


def test_no_evidence_means_no_variant() -> None:
    task = tasks.load("sofa_traversing")
    prog = Program()
    board = prog.query("get_position", "surfboard", (0.3, 0.0, 0.379))
    prog.motion("push_to_position", obj="surfboard", point=Point.at(board, (0.55, 0.0, 0.0)), intent="bridge the gap")
    print_only = Candidate(index=0, code="print('x')\n", rollouts=run_codes(task, ["print('x')\n"], worlds=1)[0])
    assert repaired(task, prog, print_only) == []


def test_a_drag_that_left_the_target_outside_the_workspace_is_re_aimed_by_the_measured_distance() -> None:
    task = tasks.load("can_grasping")
    prog = Program()
    paper = prog.query("get_graspable_point", "strip_of_paper", (0.3, 0.2, 0.0))
    prog.motion("move_to_position", point=Point.at(paper), objects=["strip_of_paper"], intent="reach the paper")
    prog.motion("move_to_position", point=Point.at(paper, (-0.31, 0.0, 0.0)), objects=["strip_of_paper", "can"],
                intent="drag the paper with the can on it")
    prog.motion("move_to_position", point=Point.at(None, (0.49, 0.06, 0.08)), objects=["can"], intent="reach the can")
    calls = [
        SkillCall(skill="get_graspable_point", args=["strip_of_paper"], outcome="done"),
        SkillCall(skill="move_to_position", args=[[0.3, 0.2, 0.0]], outcome="done", measured={"remaining": 0.001}),
        SkillCall(skill="move_to_position", args=[[0.0, 0.2, 0.0]], outcome="done", measured={"remaining": 0.0}),
        SkillCall(skill="move_to_position", args=[[0.49, 0.06, 0.08]], outcome="done",
                  measured={"outside_workspace": 0.044, "clamped_x": 0.45, "remaining": 0.0}),
    ]
    world = Rollout(world=0, seed=0, success=False, conditions={"can_held": False}, calls=calls)
    further, less = repaired(task, prog, Candidate(index=0, code=prog.code, rollouts=[world]))
    assert further.lines[2] == "move_to_position([p1[0] - 0.3840, p1[1], p1[2]])"  # along the drag, 0.044 + margin
    assert less.lines[2] == "move_to_position([p1[0] - 0.2360, p1[1], p1[2]])"
    assert further.parameters[1].target == [round(0.3 - 0.384, 4), 0.2, 0.0]
    assert further.lines[-1] == prog.lines[-1] and further.lines[1] == prog.lines[1]


def test_a_push_that_stopped_short_of_its_target_is_itself_aimed_further() -> None:
    """A prop pushed out from under a lever stopped 0.17 m short (it turned and slid off the line): the push itself
    is the motion to re-aim, further along its own direction by the shortfall and less far, as no earlier motion
    moved anything."""
    task = tasks.load("cube_lifting")
    prog = Program()
    prog.motion("walk_to_position", point=Point.at(None, (0.46, 0.55, 0.0)), intent="walk beside the chair")
    chair = prog.query("get_position", "chair", (0.462, 0.0, 0.115))
    prog.motion("push_to_position", obj="chair", point=Point.at(chair, (0.0, 0.9, 0.0)), intent="push it out")
    prog.motion("walk_to_position", point=Point.at(None, (0.6, 1.4, 0.0)), intent="walk on")
    calls = [
        SkillCall(skill="walk_to_position", args=[[0.46, 0.55, 0.0]], outcome="done"),
        SkillCall(skill="get_position", args=["chair"], outcome="done"),
        SkillCall(skill="push_to_position", args=["chair", [0.462, 0.9, 0.115]], outcome="stalled",
                  reason="chair stopped 0.17 m from the target", measured={"distance": 0.17}),
        SkillCall(skill="walk_to_position", args=[[0.6, 1.4, 0.0]], outcome="done"),
    ]
    world = Rollout(world=0, seed=0, success=False, conditions={"cube_lifted": False}, calls=calls)
    further, less = repaired(task, prog, Candidate(index=0, code=prog.code, rollouts=[world]))
    assert further.lines[2] == "push_to_position('chair', [p1[0], p1[1] + 1.1000, p1[2]])"  # 0.9 + 0.17 + margin
    assert less.lines[2] == "push_to_position('chair', [p1[0], p1[1] + 0.7000, p1[2]])"
    assert further.lines[0] == prog.lines[0] and further.lines[-1] == prog.lines[-1]
