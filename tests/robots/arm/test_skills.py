"""The arm in the lockstep runner on the C backend: reference programs, tool-free failures, trace."""

from __future__ import annotations

from typing import Any

import pytest
from fixtures.reference import REFERENCE, TOOL_FREE, program

from robotool import sandbox, sim
from robotool.program_session import ProgramEnded, SkillReply, SkillRequest

WORLDS = 10
ARM_TASKS = ["button_pressing", "can_grasping", "milk_reaching", "milk_reaching_near"]


@pytest.mark.parametrize("task_name", ARM_TASKS)
def test_reference_program_solves_perturbed_worlds(sim_scene: Any, run_texts: Any, task_name: str) -> None:
    rollouts = run_texts(sim_scene(task_name), [program(REFERENCE[task_name])] * WORLDS, seed=3)
    assert sum(r.success for r in rollouts) >= 9, [(r.conditions, r.error) for r in rollouts]
    assert all(r.error is None for r in rollouts)
    goal = sim_scene(task_name).task.goal.object
    assert goal in rollouts[0].touched


@pytest.mark.parametrize("task_name", [t for t in ARM_TASKS if t in TOOL_FREE])
def test_tool_free_program_fails_at_the_workspace_clamp(sim_scene: Any, run_texts: Any, task_name: str) -> None:
    rollouts = run_texts(sim_scene(task_name), [program(TOOL_FREE[task_name])] * 3, seed=0)
    assert not any(r.success for r in rollouts)
    for r in rollouts:
        clamped = [c for c in r.calls if "outside_workspace" in c.measured]
        assert clamped and "clamped to" in clamped[0].reason
        assert clamped[0].measured["clamped_x"] == pytest.approx(0.45)
        assert not all(r.conditions.values())


def test_same_seed_gives_identical_rollouts(sim_scene: Any, run_texts: Any) -> None:
    scene = sim_scene("button_pressing")
    code = program(REFERENCE["button_pressing"])
    runs = [run_texts(scene, [code] * 3, seed=5) for _ in range(2)]
    assert [r.model_dump() for r in runs[0]] == [r.model_dump() for r in runs[1]]
    other = run_texts(scene, [code] * 3, seed=6)
    assert [r.calls[0].result for r in other] != [r.calls[0].result for r in runs[0]]


def test_queries_answer_from_the_current_state(sim_scene: Any) -> None:
    seen: dict[str, Any] = {}

    def program(robot: Any) -> None:
        seen["range"] = robot.get_workspace_range()
        seen["size"] = robot.get_size("milk")
        seen["before"] = robot.get_center("milk")
        robot.move_to_position([0.3, 0.0, 0.2])
        seen["grasp"] = robot.get_graspable_point("milk")

    (r,) = sim.run_programs(sim_scene("milk_reaching_near"), [program], perturb=False)
    assert seen["range"] == [[-0.3, 0.45], [-0.45, 0.45], [0.0, 0.5]]
    assert seen["size"] == pytest.approx([0.044, 0.044, 0.16])
    assert seen["before"] == pytest.approx([0.38, 0.12, 0.08], abs=2e-3)
    assert seen["grasp"] == pytest.approx([0.38, 0.12, 0.135], abs=2e-3)
    assert [c.skill for c in r.calls][-2:] == ["move_to_position", "get_graspable_point"]
    assert (
        r.error is None
        and not r.success
        and r.conditions == {"milk_held": False, "milk_in_gripper": False, "nothing_passed_through": True}
    )


def test_errors_end_only_their_own_world(sim_scene: Any) -> None:
    def bad_name(robot: Any) -> None:
        robot.get_center("unicorn")

    def bad_args(robot: Any) -> None:
        robot.move_to_position([1.0, "x", 0.0])

    def crashes(robot: Any) -> None:
        raise RuntimeError("boom")

    scene = sim_scene("milk_reaching_near")
    sessions = [
        *sim.trusted_sessions(scene.task, [bad_name, bad_args, crashes]),
        *sandbox.start_sessions([program(REFERENCE["milk_reaching_near"])], "arm"),
    ]
    rollouts = sim.run_sessions(scene, sessions)
    assert "unicorn" in rollouts[0].error and rollouts[0].calls[0].outcome == "error"
    assert "position" in rollouts[1].calls[0].reason and rollouts[1].error.startswith("SkillCallError")
    assert rollouts[2].error == "RuntimeError: boom" and not rollouts[2].calls
    assert rollouts[3].success and rollouts[3].error is None


def test_blocked_motion_stalls_and_runaway_programs_are_capped(sim_scene: Any) -> None:
    def push_into_table(robot: Any) -> None:
        g = robot.get_graspable_point("hammer")
        robot.move_to_position(g)
        robot.close_gripper()
        robot.move_to_position([g[0], g[1], 0.0])

    def loops(robot: Any) -> None:
        while True:
            robot.move_to_position([0.1, 0.0, 0.3])

    scene = sim_scene("milk_reaching")
    stalled, capped = sim.run_programs(scene, [push_into_table, loops], max_skill_calls=5)
    assert stalled.calls[-1].outcome == "stalled" and "blocked" in stalled.calls[-1].reason
    assert capped.error == "more than 5 skill calls"
    (timed,) = sim.run_programs(scene, [loops], max_sim_time=1.0)
    assert "time" in timed.error and timed.sim_time == pytest.approx(1.0, abs=0.05)


class _Scripted:
    """A minimal ProgramSession that replays fixed requests (no thread): the runner takes any session."""

    def __init__(self, requests: list[SkillRequest]):
        self.requests, self.replies = list(requests), []

    def resume(self, reply: SkillReply | None) -> None:
        self.replies.append(reply)

    def wait(self) -> SkillRequest | ProgramEnded:
        return self.requests.pop(0) if self.requests else ProgramEnded(output="bye")

    def close(self) -> None:
        pass


def test_runner_accepts_any_program_session(sim_scene: Any) -> None:
    session = _Scripted([SkillRequest("get_center", ("lock",)), SkillRequest("open_gripper", ())])
    (r,) = sim.run_sessions(sim_scene("milk_reaching"), [session], perturb=False)
    assert session.replies[0] is None and session.replies[1].value == pytest.approx([0.35, 0.05, 0.01], abs=2e-3)
    assert [c.outcome for c in r.calls] == ["done", "done"] and r.output == "bye"


def test_grasp_as_the_last_call_counts(sim_scene) -> None:
    """Regression: a program ending right after close_gripper is judged on the state after the grasp."""

    def grasp_and_stop(robot: Any) -> None:
        p = robot.get_graspable_point("milk")
        robot.open_gripper()
        robot.move_to_position([p[0], p[1], p[2] + 0.08])
        robot.move_to_position(p)
        robot.close_gripper()

    (r,) = sim.run_programs(sim_scene("milk_reaching_near"), [grasp_and_stop], perturb=False)
    assert r.success, r.conditions
    assert "milk" in r.touched
