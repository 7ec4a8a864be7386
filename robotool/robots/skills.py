"""The two embodiments: their default limits and their parameterized skills.

Everything that describes what a robot can do lives here, so the scene validator, the description,
the sandbox allowlist and the simulator read one source of truth.
"""

from __future__ import annotations

import math
import reprlib
from dataclasses import dataclass
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

EmbodimentName = Literal["quadruped", "arm"]


class QuadrupedLimits(BaseModel):
    """Physical limits of a Unitree Go1-sized quadruped (metres, kilograms)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    body_size: tuple[float, float, float] = Field(
        (0.65, 0.30, 0.30), description="body bounding box x, y, z in metres"
    )
    mass: float = Field(12.0, gt=0, description="body mass in kg")
    max_step_up: float = Field(0.12, gt=0, description="highest step it can climb, m")
    max_gap: float = Field(0.10, gt=0, description="widest gap it can cross, m")
    max_step_down: float = Field(0.40, gt=0, description="deepest drop it can step down, m")
    max_push_mass: float = Field(5.0, gt=0, description="heaviest object it can push, kg")


class ArmLimits(BaseModel):
    """Limits of a Kinova Gen3-like arm with a translating two-finger gripper."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    workspace_min: tuple[float, float, float] = (-0.30, -0.45, 0.0)
    workspace_max: tuple[float, float, float] = (0.45, 0.45, 0.50)
    grasp_radius: float = Field(
        0.02, gt=0, description="how close the gripper must be to a graspable point, m"
    )
    gripper_opening: float = Field(
        0.06, gt=0, le=0.2, description="distance between the open fingers' inner faces, m"
    )


Limits = QuadrupedLimits | ArmLimits


class SkillSpec(BaseModel):
    """One parameterized skill: its Python signature and its exact meaning."""

    model_config = ConfigDict(frozen=True)

    name: str
    params: tuple[tuple[str, str], ...] = Field(
        description="(parameter name, type) pairs; types are 'name' or 'position'"
    )
    returns: str
    kind: Literal["query", "motion"]
    semantics: str

    @property
    def signature(self) -> str:
        """The call as a user writes it, e.g. ``walk_to_position(position)``."""
        return f"{self.name}({', '.join(p for p, _ in self.params)})"


_QUERY_NAME = (("name", "name"),)
_POSITION = (("position", "position"),)

QUADRUPED_SKILLS: tuple[SkillSpec, ...] = (
    SkillSpec(
        name="get_position",
        params=_QUERY_NAME,
        returns="[x, y, z]",
        kind="query",
        semantics="Centre of the named object (or 'robot') right now, in metres.",
    ),
    SkillSpec(
        name="get_size",
        params=_QUERY_NAME,
        returns="[x, y, z]",
        kind="query",
        semantics="Bounding-box size of the named object (or 'robot'), in metres.",
    ),
    SkillSpec(
        name="walk_to_position",
        params=_POSITION,
        returns="None",
        kind="motion",
        semantics=(
            "Walk in a straight line until the body centre is over [x, y]; z is ignored. "
            "The robot stops at the edge of any step up over its climb limit, gap over its gap "
            "limit or drop over its step-down limit, and the skill is refused."
        ),
    ),
    SkillSpec(
        name="climb_to_position",
        params=_POSITION,
        returns="None",
        kind="motion",
        semantics=(
            "Like walk_to_position, but used to step up onto a higher surface; the same "
            "step-up, gap and drop limits apply."
        ),
    ),
    SkillSpec(
        name="push_to_position",
        params=(("name", "name"), ("position", "position")),
        returns="None",
        kind="motion",
        semantics=(
            "Walk to the far side of the named object and push it until its centre is at "
            "[x, y] (z is ignored). Only movable objects up to the push mass limit, on the same "
            "surface as the robot, while the robot stands on the ground or a fixed object, and "
            "never the object under the robot."
        ),
    ),
)

ARM_SKILLS: tuple[SkillSpec, ...] = (
    SkillSpec(
        name="get_center",
        params=_QUERY_NAME,
        returns="[x, y, z]",
        kind="query",
        semantics="Centre of the named object right now, in metres.",
    ),
    SkillSpec(
        name="get_graspable_point",
        params=_QUERY_NAME,
        returns="[x, y, z]",
        kind="query",
        semantics="The point where the gripper can hold the named object right now.",
    ),
    SkillSpec(
        name="get_size",
        params=_QUERY_NAME,
        returns="[x, y, z]",
        kind="query",
        semantics="Bounding-box size of the named object, in metres.",
    ),
    SkillSpec(
        name="get_workspace_range",
        params=(),
        returns="[[x_min, x_max], [y_min, y_max], [z_min, z_max]]",
        kind="query",
        semantics="The box the gripper centre can reach.",
    ),
    SkillSpec(
        name="move_to_position",
        params=_POSITION,
        returns="None",
        kind="motion",
        semantics=(
            "Move the gripper centre in a straight line to [x, y, z] without rotating. A target "
            "outside the workspace is clamped to it. A held object moves with the gripper and "
            "pushes whatever it meets."
        ),
    ),
    SkillSpec(
        name="open_gripper",
        params=(),
        returns="None",
        kind="motion",
        semantics="Open the fingers and release whatever is held.",
    ),
    SkillSpec(
        name="close_gripper",
        params=(),
        returns="None",
        kind="motion",
        semantics=(
            "Close the fingers until they meet something or close fully; an object is held when both "
            "fingers close on its sides and it fits the opening, otherwise the call says why nothing is held."
        ),
    ),
)

SKILLS: dict[str, tuple[SkillSpec, ...]] = {"quadruped": QUADRUPED_SKILLS, "arm": ARM_SKILLS}
LIMITS_MODELS: dict[str, type[QuadrupedLimits] | type[ArmLimits]] = {
    "quadruped": QuadrupedLimits,
    "arm": ArmLimits,
}


def skills(embodiment: EmbodimentName) -> tuple[SkillSpec, ...]:
    """The skills of an embodiment, in the order the description lists them."""
    return SKILLS[embodiment]


def skill_names(embodiment: EmbodimentName) -> frozenset[str]:
    """Names of an embodiment's skills (the sandbox allowlist)."""
    return frozenset(s.name for s in SKILLS[embodiment])


class SkillArgumentError(ValueError):
    """A skill was called with arguments it cannot take; the message says which and why."""


MAX_DISTANCE_FROM_SCENE = 5.0
"""How far (m) a position argument may lie outside the box around the scene's objects, the robot and
its workspace: farther is refused as a mistake (a wrong unit, a runaway computation), never simulated."""


@dataclass(frozen=True)
class SceneBox:
    """The axis-aligned box (m) around a scene: its objects, the robot's start and the arm's workspace."""

    lo: tuple[float, float, float]
    hi: tuple[float, float, float]

    def distance(self, point: tuple[float, float, float]) -> float:
        """How far ``point`` lies outside the box (0 inside)."""
        gaps = (max(lo - p, 0.0, p - hi) for p, lo, hi in zip(point, self.lo, self.hi, strict=True))
        return math.sqrt(sum(g * g for g in gaps))


def check_call(
    embodiment: EmbodimentName, name: str, args: tuple[object, ...], scene: SceneBox | None = None
) -> tuple[object, ...]:
    """Check a skill call's arguments and return them normalized (positions as 3 floats).

    Raises :class:`SkillArgumentError` for an unknown skill, a wrong argument count, a name that
    is not a string, a position that is not three finite numbers, or (given the ``scene``'s box) a
    position more than :data:`MAX_DISTANCE_FROM_SCENE` outside it. A 2-number position gets z = 0.
    """
    spec = next((s for s in SKILLS[embodiment] if s.name == name), None)
    if spec is None:
        known = ", ".join(s.name for s in SKILLS[embodiment])
        raise SkillArgumentError(f"unknown skill {name!r} for the {embodiment} (skills: {known})")
    if len(args) != len(spec.params):
        raise SkillArgumentError(
            f"{spec.signature} takes {len(spec.params)} argument(s), got {len(args)}"
        )
    out: list[object] = []
    for (param, kind), value in zip(spec.params, args, strict=True):
        if kind == "name":
            if not isinstance(value, str):
                raise SkillArgumentError(f"{name}: {param} must be an object name, got {_shown(value)}")
            out.append(value)
            continue
        position = _position(name, param, value)
        if scene is not None and scene.distance(position) > MAX_DISTANCE_FROM_SCENE:
            shown = ", ".join(f"{v:.4g}" for v in position)
            raise SkillArgumentError(
                f"{name}: {param} [{shown}] is {scene.distance(position):.3g} m outside the scene (more than "
                f"{MAX_DISTANCE_FROM_SCENE:g} m); positions are in metres"
            )
        out.append(position)
    return tuple(out)


def _shown(value: object) -> str:
    """A short repr of a program's argument; an integer too long for decimal text is described instead."""
    try:
        return reprlib.repr(value)
    except ValueError:  # Python refuses to turn an integer of more than 4300 digits into text
        return f"a {type(value).__name__} too large to show"


def _position(skill: str, param: str, value: object) -> tuple[float, float, float]:
    try:
        items = [float(v) for v in value]  # type: ignore[attr-defined]
    except (TypeError, ValueError, OverflowError):
        raise SkillArgumentError(
            f"{skill}: {param} must be [x, y, z] in metres, got {_shown(value)}"
        ) from None
    if isinstance(value, str | bytes) or len(items) not in (2, 3):
        raise SkillArgumentError(f"{skill}: {param} must be [x, y, z] in metres, got {_shown(value)}")
    if not all(math.isfinite(v) for v in items):
        raise SkillArgumentError(f"{skill}: {param} must be finite, got {items}")
    if len(items) == 2:
        items.append(0.0)
    return (items[0], items[1], items[2])
