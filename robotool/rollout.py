"""What one world's run of a program produced: the skill-call trace, typed events and the goal's conditions."""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, Field

from robotool.bugs import InternalError
from robotool.vocabulary import SkillOutcome

EventKind = Literal[
    "clamped",
    "grasped",
    "grasp_failed",
    "pushed_out",
    "stalled",
    "timeout",
    "refused",
    "fell",
    "broke",
    "passed_through",
]
GraspFailure = Literal["nothing_between", "one_finger", "too_wide", "on_top", "not_between", "weak_grip", "slipped"]

DISTANCES: frozenset[str] = frozenset({"gap", "step", "drop", "distance", "remaining", "outside_workspace"})
"""Keys of :attr:`SkillCall.measured` whose values are distances in metres: a gap, step or drop at a refusal,
how far short of its goal a motion stopped, how far outside the workspace a target was, how far a grasp was
from the nearest graspable point."""
NOTABLE_DISTANCE = 0.01
"""m: a measured distance at least this large says something went wrong (smaller ones are control noise)."""


def notable_distances(measured: dict[str, float]) -> dict[str, float]:
    """The distances (see :data:`DISTANCES`) among a call's ``measured`` values of at least :data:`NOTABLE_DISTANCE`."""
    return {k: v for k, v in measured.items() if k in DISTANCES and v >= NOTABLE_DISTANCE}


class SkillCall(BaseModel):
    """One skill call in a world: arguments, how it ended and why, in simulated seconds."""

    skill: str
    args: list[Any]
    outcome: SkillOutcome
    reason: str | None = None
    measured: dict[str, float] = Field(
        default_factory=dict, description="values behind a refusal or clamp, e.g. {'gap': 0.40}"
    )
    result: Any = None
    started: float = 0.0
    ended: float = 0.0


class Event(BaseModel):
    """Something that happened in a world, with typed fields; failure reasons are rendered from these.

    ``kind`` says what happened: a motion target ``clamped`` to a limit, a grasp that held ``object``
    (``grasped``) or held nothing (``grasp_failed``, with its ``cause``), an object ``pushed_out`` of
    the robot's reach, a skill that ``stalled``, ran out of time (``timeout``) or was ``refused``, the
    robot ``fell``, or a fragile ``object`` that ``broke`` in a fall (``measured``: ``fall`` and
    ``max_drop``; ``detail``: what it landed on), or an ``object`` that ``passed_through`` a solid (``detail``: which;
    the simulator's soft contact gave way). ``call`` is the index of the skill call it happened in
    (None outside calls), ``limit`` the robot limit involved (e.g. ``workspace``), ``measured`` the
    numbers in SI units and ``detail`` the controller's own words, if any.
    """

    kind: EventKind
    time: float = 0.0
    call: int | None = None
    object: str | None = None
    limit: str | None = None
    cause: GraspFailure | None = None
    measured: dict[str, float] = Field(default_factory=dict)
    detail: str | None = None

    def describe(self, calls: list[SkillCall]) -> str:
        """One clause for a failure reason, e.g. ``call 4 move_to_position: clamped 0.119 m at the workspace edge``
        (``call 4:`` alone where ``calls`` no longer holds that call: a search keeps the calls of its best few
        candidates only)."""
        where = ""
        if self.call is not None:
            skill = f" {calls[self.call].skill}" if 0 <= self.call < len(calls) else ""
            where = f"call {self.call + 1}{skill}: "
        m = self.measured
        if self.kind == "clamped":
            target = _point(m, "target_")
            clamped = _point(m, "clamped_")
            text = f"clamped {m.get('outside_workspace', 0.0):.3f} m at the {self.limit or 'limit'} edge"
            if target and clamped:
                text += f" (target {target} -> {clamped})"
        elif self.kind == "grasped":
            text = f"holds {self.object}"
        elif self.kind == "grasp_failed" and self.cause == "slipped":
            text = self._slipped()
        elif self.kind == "grasp_failed":
            text = f"held nothing: {self._grasp_failure()}"
        elif self.kind == "pushed_out":
            text = (
                f"{self.object} was pushed {m.get('pushed', 0.0):.3f} m, to {m.get('outside', 0.0):.3f} m "
                f"outside the {self.limit or 'workspace'}" + (f" at {_point(m, '')}" if _point(m, "") else "")
            )
        elif self.kind == "fell":
            text = "the robot fell" + (f": {self.detail}" if self.detail else "")
        elif self.kind == "passed_through":
            text = f"{self.object} passed through {self.detail} (a solid cannot: the contact gave way)"
        elif self.kind == "broke" and "strike_speed" in m:
            text = (
                f"{self.object} broke: {self.detail or 'something hard'} met it at {m['strike_speed']:.2f} m/s "
                f"(faster than {m.get('max_speed', 0.0):.2f} m/s, the speed a fall of {m.get('max_drop', 0.0):.2f} m "
                "lands at, breaks it)"
            )
        elif self.kind == "broke":
            text = (
                f"{self.object} broke: it fell {m.get('fall', 0.0):.2f} m"
                + (f" onto {self.detail}" if self.detail else "")
                + f" (a fall of more than {m.get('max_drop', 0.0):.2f} m onto something hard breaks it)"
            )
        else:
            text = self.kind + (f": {self.detail}" if self.detail else "")
        return where + text

    def _grasp_failure(self) -> str:
        m, obj = self.measured, self.object
        if self.cause == "too_wide":
            return (
                f"{obj} is {m.get('width', 0.0):.3f} m across the fingers, wider than their "
                f"{m.get('opening', 0.0):.3f} m opening"
            )
        if self.cause == "weak_grip":
            return self._weak_grip()
        if self.cause == "on_top":
            return f"the fingers rested on top of {obj} instead of closing on its sides"
        if self.cause == "one_finger":
            return f"only one finger touched {obj}"
        if self.cause == "not_between" and "span" in m:
            return (
                f"{obj} was not between the fingers: beside them it spans {m['span']:.3f} m across, past their "
                f"{m.get('gap', 0.0):.3f} m gap, so they pressed on its face, not on its sides"
            )
        if self.cause == "not_between":
            return f"{obj} was not between the fingers"
        if obj is None:
            return "the fingers closed on nothing"
        return (
            f"the fingers closed on nothing; the nearest graspable point ({obj}'s) is "
            f"{m.get('nearest', 0.0):.3f} m from the gripper centre"
        )

    def _slipped(self) -> str:
        """Which load made a held object slip out of the grip, against what the grip holds."""
        m, obj = self.measured, self.object
        loads = {
            "force": f"{m.get('force', 0.0):.1f} N on the pads, more than the {m.get('most_force', 0.0):.0f} N their "
            "friction holds",
            "twist": f"{m.get('twist', 0.0):.2f} N m about the fingers' closing axis, more than the "
            f"{m.get('most_twist', 0.0):.2f} N m its {1000 * m.get('depth', 0.0):.0f} mm deep grip holds",
            "tilt": f"{m.get('tilt', 0.0):.2f} N m across the fingers, more than the {m.get('most_tilt', 0.0):.2f} N m "
            f"its {1000 * m.get('width', 0.0):.0f} mm wide grip holds",
        }
        worst = (
            "force"  # past the pads' friction it slid out at once
            if m.get("force", 0.0) > m.get("most_force", np.inf)
            else max(("twist", "tilt"), key=lambda k: m.get(k, 0.0) / max(m.get(f"most_{k}", 0.0), 1e-9))
        )
        return (
            f"{obj} slipped out of the grip: its load ({obj}'s weight, what it carries and what it met) put "
            f"{loads[worst]}" + ("" if worst == "force" else f", past that for {m.get('for', 0.0):.1f} s in all")
        )

    def _weak_grip(self) -> str:
        """What the fingers' grip on ``object`` measured and what its load needed."""
        m, obj = self.measured, self.object
        joined = int(m.get("joined", 0))
        load = f"{m.get('weight', 0.0):.2f} N" + (f" ({obj} and {joined} joined to it)" if joined else "")
        lever = f"{load} whose centre lies {m.get('lever', 0.0):.3f} m from the pads"
        if m.get("weight", 0.0) > m.get("most_weight", np.inf):
            return f"{obj} with what is joined to it weighs {load}, more than the grip's {m['most_weight']:.0f} N"
        if m.get("width", 0.0) < m.get("need_width", 0.0):
            return (
                f"grip {1000 * m['width']:.0f} mm wide on {obj} across the fingers; needs "
                f"{1000 * m['need_width']:.0f} mm for the {lever}"
            )
        depth, need = 1000 * m.get("depth", 0.0), 1000 * m.get("need_depth", 0.0)
        if m.get("need_depth", 0.0) > m.get("edge_depth", 0.0) + 1e-9:
            return f"grip {depth:.0f} mm deep on {obj} across the pads; needs {need:.0f} mm for the {lever}"
        return (
            f"grip {depth:.0f} mm deep on {obj} across the pads, a pinch at its edge; needs {need:.0f} mm, half "
            f"of what the pads could cover, to hold the {lever}"
        )


def _point(measured: dict[str, float], prefix: str) -> str:
    keys = [f"{prefix}{a}" for a in "xyz"]
    if not all(k in measured for k in keys):
        return ""
    return "[" + ", ".join(f"{measured[k]:.3f}" for k in keys) + "]"


class Rollout(BaseModel):
    """One program in one perturbed world, from start to end."""

    world: int
    seed: int
    success: bool
    conditions: dict[str, bool] = Field(default_factory=dict, description="the goal's named sub-conditions at the end")
    calls: list[SkillCall] = Field(default_factory=list)
    events: list[Event] = Field(default_factory=list, description="what happened, in time order")
    touched: list[str] = Field(default_factory=list, description="objects the robot moved or met")
    sim_time: float = 0.0
    error: str | None = Field(None, description="why the world failed outside the goal, if it did")
    internal_error: InternalError | None = Field(
        None, description="a bug in robotool ended the world (its controller raised): not the program's failure"
    )
    output: str = Field("", description="what the program printed")
