"""Sandboxed programs through the real lockstep runner on an arm task."""

from __future__ import annotations

from typing import Any

from fixtures.reference import program

from robotool.sandbox import SandboxLimits, start_sessions
from robotool.sim import run_programs, run_sessions

MILK_DIRECT = program("milk_reaching_direct")


def milk_direct(robot: Any) -> None:
    """MILK_DIRECT as a trusted callable."""
    p = robot.get_graspable_point("milk")
    robot.open_gripper()
    robot.move_to_position([p[0], p[1], p[2] + 0.08])
    robot.move_to_position(p)
    robot.close_gripper()
    robot.move_to_position([p[0], p[1], p[2] + 0.05])


def test_sandboxed_code_rolls_out_exactly_like_the_trusted_program(sim_scene) -> None:
    scene = sim_scene("milk_reaching_near")
    trusted = run_programs(scene, [milk_direct] * 3, seed=5)
    sandboxed = run_sessions(scene, start_sessions([MILK_DIRECT] * 3, "arm"), seed=5)
    assert all(r.success for r in sandboxed)
    assert [r.model_dump() for r in sandboxed] == [r.model_dump() for r in trusted]


def test_runaway_and_rejected_worlds_fail_alone_in_a_real_rollout(sim_scene) -> None:
    codes = [MILK_DIRECT, "open_gripper()\nwhile True:\n    pass\n", "import os\n", MILK_DIRECT]
    limits = SandboxLimits(cpu_s=0.5)
    rollouts = run_sessions(sim_scene("milk_reaching_near"), start_sessions(codes, "arm", limits), seed=5)
    assert [r.success for r in rollouts] == [True, False, False, True]
    assert rollouts[1].error == "CPU time limit exceeded (0.5 s)"
    assert [c.skill for c in rollouts[1].calls] == ["open_gripper"]
    assert rollouts[2].error is not None
    assert rollouts[2].error.startswith("program rejected: line 1: import of 'os'")
    assert rollouts[2].calls == []
