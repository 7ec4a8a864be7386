"""Failure classes from rollout traces: the paper's tool-use, logical and numerical errors.

Definitions used here. The *target* is the goal's object; *tools* are the task's movable objects
other than the target, plus the instance's reference tools (which may be fixed, e.g. boxes to climb
as stairs). A world *used* a tool when the program named it in a skill call (a query such
as ``get_position("box_1")`` or a motion such as ``push_to_position("box_1", ...)``) or the gripper
held it (a ``grasped`` event). Everything here reads typed fields (outcomes, events, measured values),
never the text of a reason. The *needed tools* are the instance's reference tools when known (built-in
tasks, generated instances), otherwise any tool.

A failed world is classified by the first rule that applies:

1. ``invalid`` — the world ended with an error (the program raised, broke a sandbox limit, the
   simulation failed) or a call ended in ``error``. Runs whose program never ran (unparsable reply,
   code the sandbox rejected) are ``invalid`` too.
2. ``tool_use`` — the task needs a tool and the program used none of the needed tools, or the task
   needs no tool and the program used one that its reference solution does not use.
3. The first abnormal call decides: ``refused`` (a limit was violated: a step out of order or a
   constraint ignored) or ``fell`` (it walked off its support) -> ``logical``; ``stalled``, ``timeout``,
   or an event the robot counts as numerical (``RobotType.feedback.numerical_events``, e.g. a target ``clamped`` to a
   workspace or a grasp that held nothing, ``grasp_failed``) -> ``numerical``.
4. No abnormal call: ``logical`` when the program made no motion call or left a needed tool unused
   (a missing step); otherwise ``numerical`` (right objects, every step done, the goal missed by
   distance).

A world that reached the goal has no class (None); nor has a world that a bug in robotool ended (its
``internal_error``: a controller raised), which is neither a success nor a program's failure.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from typing import Literal

from pydantic import BaseModel, ConfigDict

from robotool import robots
from robotool.rollout import Event, Rollout, SkillCall
from robotool.task.task_model import Task

FailureClass = Literal["tool_use", "logical", "numerical", "invalid"]
FAILURE_CLASSES: tuple[FailureClass, ...] = ("tool_use", "logical", "numerical", "invalid")


class TaskFacts(BaseModel):
    """What the classifier needs to know about a task instance."""

    model_config = ConfigDict(frozen=True)

    target: str
    tools: frozenset[str]
    needed: frozenset[str] | None
    needs_tool: bool
    motion_skills: frozenset[str]
    robot: str

    @classmethod
    def of(cls, task: Task, *, needs_tool: bool, needed: frozenset[str] | None = None) -> TaskFacts:
        """Facts of ``task``; ``needed`` are its reference tools when known."""
        target = task.goal.object
        robot = robots.get(task.embodiment)
        movable = frozenset(o.name for o in task.objects if o.movable and o.name != target)
        return cls(
            target=target,
            needs_tool=needs_tool,
            needed=needed,
            tools=movable | (needed or frozenset()),
            motion_skills=frozenset(s.name for s in robot.skills if s.kind == "motion"),
            robot=robot.name,
        )


def tools_used(rollout: Rollout, facts: TaskFacts) -> set[str]:
    """The tools a world's program named in a skill call or held in the gripper."""
    named = {a for call in rollout.calls for a in call.args if isinstance(a, str)}
    held = {e.object for e in rollout.events if e.kind == "grasped" and e.object is not None}
    return (named | held) & facts.tools


def _numerical_symptom(call: SkillCall, events: Sequence[Event], facts: TaskFacts) -> bool:
    """A stall, a timeout, or one of the robot's numerical events (a target clamped to a limit, a missed grasp)."""
    numerical = robots.get(facts.robot).feedback.numerical_events
    return call.outcome in ("stalled", "timeout") or any(e.kind in numerical for e in events)


def classify(rollout: Rollout, facts: TaskFacts) -> FailureClass | None:
    """The failure class of one world (None when it reached the goal or an internal error ended it); rules in the
    module docstring."""
    if rollout.success or rollout.internal_error is not None:
        return None
    if rollout.error is not None or any(c.outcome == "error" for c in rollout.calls):
        return "invalid"
    used = tools_used(rollout, facts)
    if facts.needs_tool and not used & (facts.tools if facts.needed is None else facts.needed):
        return "tool_use"
    if not facts.needs_tool and used - (facts.needed or frozenset()):
        return "tool_use"
    for k, call in enumerate(rollout.calls):
        if call.outcome in ("refused", "fell"):
            return "logical"
        if _numerical_symptom(call, [e for e in rollout.events if e.call == k], facts):
            return "numerical"
    moved = any(c.skill in facts.motion_skills for c in rollout.calls)
    if not moved or (facts.needed is not None and not facts.needed <= used):
        return "logical"
    return "numerical"


def run_class(classes: Sequence[FailureClass | None]) -> FailureClass | None:
    """A run's class from its worlds': the most common failure (ties in FAILURE_CLASSES order)."""
    counts = Counter(c for c in classes if c is not None)
    if not counts:
        return None
    return max(FAILURE_CLASSES, key=lambda c: (counts[c], -FAILURE_CLASSES.index(c)))
