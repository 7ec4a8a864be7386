"""Planner repair: a failed program re-parameterised from what the simulator measured."""

from __future__ import annotations

from robotool import tasks
from robotool.planner.codegen import Point, Program
from robotool.planner.repair import repaired
from robotool.solution import Candidate
from robotool.verify import run_codes


def test_a_push_that_left_the_gap_too_wide_is_pushed_further_by_the_measured_gap() -> None:
    task = tasks.load("sofa_traversing")
    prog = Program()
    board = prog.query("get_position", "surfboard", (0.3, 0.0, 0.379))
    prog.motion("push_to_position", obj="surfboard", point=Point.at(board, (0.25, 0.0, 0.0)), intent="bridge the gap")
    prog.motion("walk_to_position", point=Point.at(None, (1.775, 0.0, 0.34)), objects=["sofa_2"], intent="cross")
    failed = Candidate(index=0, code=prog.code, rollouts=run_codes(task, [prog.code], worlds=2)[0])
    refusal = failed.rollouts[0].calls[-1]
    assert failed.success_rate == 0.0 and refusal.outcome == "refused" and "gap" in refusal.measured
    variants = repaired(task, prog, failed)
    assert len(variants) == 2 and all(v.code != prog.code for v in variants)
    further = variants[0]
    assert f"measured {refusal.measured['gap']:.3f} m" in further.sentences[-1] and "further" in further.sentences[-1]
    assert further.parameters[0].offset[0] > 0.25 + refusal.measured["gap"]  # the walk's own target is kept
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
