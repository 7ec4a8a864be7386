"""What a failed candidate's run looked like, as the Repair stage is shown it: DSPy-free records and their builder.

:func:`failure_trace` reads a candidate's typed rollout records (never reason text): the calls of its first failed
world up to the first that did not end ``done``, with their measured values, and the goal sub-conditions missed.
The search planner's re-parameterisation reads the same trace, so this module imports no DSPy.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal

from pydantic import BaseModel, Field

from robotool.rollout import Event, Rollout, notable_distances

RepairScope = Literal["plan", "parameters"]
"""What a repair may change: the plan steps and their numbers, or only the numbers (a numerical failure)."""


class TracedCall(BaseModel):
    """One skill call of a failed world, as the simulator recorded it."""

    number: int = Field(description="its position in the world's calls, from 1")
    skill: str
    args: list[Any] = Field(default_factory=list)
    outcome: str = Field(description="done, refused, stalled, timeout or error")
    reason: str | None = Field(None, description="why it did not end as asked, in the simulator's words")
    measured: dict[str, float] = Field(
        default_factory=dict, description="values the simulator measured, e.g. {'gap': 0.15} (m, kg)"
    )
    result: Any = Field(None, description="what a query returned")


class FailureTrace(BaseModel):
    """What happened when a candidate program ran: its first failed world up to the first failure, and the
    goal's sub-conditions."""

    worlds: int = Field(description="perturbed worlds the program ran in")
    failed_worlds: int = Field(description="worlds in which the goal was not reached")
    world: int = Field(description="the failed world shown")
    calls: list[TracedCall] = Field(
        default_factory=list, description="its skill calls up to and including the first that did not end 'done'"
    )
    calls_made: int = Field(0, description="skill calls the program made in that world in all")
    events: list[Event] = Field(
        default_factory=list,
        description="what happened during the calls shown: clamps, grasps that held nothing and why, objects "
        "pushed out of reach, stalls, refusals, falls",
    )
    error: str | None = Field(None, description="an error that ended the world (program or simulator), if any")
    conditions_missed: list[str] = Field(default_factory=list, description="goal sub-conditions not met at the end")
    conditions_met: list[str] = Field(default_factory=list, description="goal sub-conditions met at the end")
    scope: RepairScope = Field(
        "plan",
        description="'parameters' when the calls ran as planned and the failure was in numbers "
        "(a refusal or stall with measured values; a goal missed after every call was done, with some "
        "sub-condition met or a clamp or missed grasp measured)",
    )


def failure_trace(rollouts: Sequence[Rollout]) -> FailureTrace | None:
    """The trace of a candidate's first failed world, from its ``rollouts`` (None when none failed)."""
    failed = [r for r in rollouts if not r.success]
    if not failed:
        return None
    world = failed[0]
    calls = _calls_to_first_failure(world)
    last = calls[-1] if calls else None
    failing = last is not None and last.outcome != "done"
    met = [name for name, ok in world.conditions.items() if ok]
    measured_miss = failing and last is not None and bool(last.measured) and last.outcome in ("refused", "stalled")
    missed_by = not failing and (bool(met) or any(notable_distances(call.measured) for call in world.calls))
    numerical = world.error is None and bool(world.calls) and (measured_miss or missed_by)
    return FailureTrace(
        worlds=len(rollouts),
        failed_worlds=len(failed),
        world=world.world,
        calls=calls,
        calls_made=len(world.calls),
        events=[e for e in world.events if e.call is None or e.call < len(calls)],
        error=world.error,
        conditions_missed=[name for name, ok in world.conditions.items() if not ok],
        conditions_met=met,
        scope="parameters" if numerical else "plan",
    )


def _calls_to_first_failure(world: Rollout) -> list[TracedCall]:
    traced = []
    for number, call in enumerate(world.calls, start=1):
        traced.append(
            TracedCall(
                number=number,
                skill=call.skill,
                args=call.args,
                outcome=call.outcome,
                reason=call.reason,
                measured=call.measured,
                result=call.result,
            )
        )
        if call.outcome != "done":
            break
    return traced
