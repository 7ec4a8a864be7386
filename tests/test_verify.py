"""Candidates are compared in the same perturbed worlds, in one batch."""

from __future__ import annotations

from fixtures.reference import program

from robotool import tasks
from robotool.rollout import Rollout, SkillCall
from robotool.solution import Candidate, rank
from robotool.verify import failure_reason, run_codes

GRASP = program("milk_reaching_direct")


def test_every_candidate_meets_the_same_worlds() -> None:
    task = tasks.load("milk_reaching_near")
    first, second = run_codes(task, [GRASP, GRASP], worlds=2, seed=5)
    assert [r.seed for r in first] == [5, 6] == [r.seed for r in second]
    for a, b in zip(first, second, strict=True):
        assert a.calls == b.calls and a.success == b.success
    assert first[0].calls[0].result != first[1].calls[0].result  # the two worlds differ from each other


def test_failure_reason_names_the_first_failed_world() -> None:
    task = tasks.load("milk_reaching")
    (rollouts,) = run_codes(task, [GRASP], worlds=2)
    failure = failure_reason(rollouts)
    assert failure is not None and (failure.stage, failure.kind) == ("simulation", "worlds_failed")
    assert (failure.failed_worlds, failure.worlds, failure.world) == (2, 2, 0)
    assert rollouts[0].error is None and failure.reason.startswith("goal not reached")
    assert str(failure) == f"2/2 worlds failed; world 0: {failure.reason}"  # the words people read


def _candidate(index: int, rollouts: list[Rollout]) -> Candidate:
    return Candidate(index=index, code="pass", rollouts=rollouts)


def _world(success: bool, conditions: dict[str, bool], done: int, touched: int) -> Rollout:
    calls = [SkillCall(skill="move_to_position", args=[], outcome="done") for _ in range(done)]
    return Rollout(
        world=0, seed=0, success=success, conditions=conditions, calls=calls, touched=[f"o{i}" for i in range(touched)]
    )


def test_failed_candidates_rank_by_how_far_they_got_before_objects_touched() -> None:
    crashed_early = _candidate(0, [_world(False, {"held": False, "lifted": False}, done=0, touched=0)])
    held_it = _candidate(1, [_world(False, {"held": True, "lifted": False}, done=4, touched=2)])
    moved_more = _candidate(2, [_world(False, {"held": False, "lifted": False}, done=3, touched=1)])
    assert [c.index for c in rank([crashed_early, moved_more, held_it])] == [1, 2, 0]


def test_successful_candidates_still_prefer_fewer_objects_and_calls() -> None:
    tool_use = _candidate(0, [_world(True, {"held": True}, done=6, touched=2)])
    direct = _candidate(1, [_world(True, {"held": True}, done=3, touched=1)])
    failed = _candidate(2, [_world(False, {"held": True, "lifted": False}, done=9, touched=0)])
    assert [c.index for c in rank([tool_use, failed, direct])] == [1, 0, 2]


def test_a_candidate_failure_renders_each_kind_as_people_read_it() -> None:
    from robotool.solution import CandidateFailure

    assert str(CandidateFailure(stage="coder", kind="no_reply", reason="no code block")) == "coder: no code block"
    assert str(CandidateFailure(stage="repair", kind="no_reply", reason="empty")) == "repair: empty"
    assert str(CandidateFailure(stage="planner", kind="fault", reason="KeyError: 'x'")) == "planner: KeyError: 'x'"
    rejected = CandidateFailure(stage="search", kind="rejected", reason="line 2: import is not allowed")
    assert str(rejected) == "planner produced invalid code: line 2: import is not allowed"
    worlds = CandidateFailure(stage="simulation", kind="worlds_failed", reason="goal not reached: held",
                              failed_worlds=1, worlds=3, world=2)
    assert str(worlds) == "1/3 worlds failed; world 2: goal not reached: held"
    assert CandidateFailure.model_validate_json(worlds.model_dump_json()) == worlds  # a record, not a text
