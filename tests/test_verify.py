"""Candidates are compared in the same perturbed worlds, in one batch."""

from __future__ import annotations

from fixtures.reference import program

from robotool import tasks
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
    reason = failure_reason(rollouts)
    assert reason is not None and reason.startswith("2/2 worlds failed; world 0: goal not reached")
