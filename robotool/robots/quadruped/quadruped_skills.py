"""The quadruped's limits (what a task file may override) and its skills (what its programs may call)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field, field_validator

from robotool.robots.skills import HEADING, POSITION, QUERY_NAME, SkillSpec

BELLY_HEIGHT = 0.05  # m: the torso's underside above the feet's bottom (its faces push objects)
MIN_TORSO = 0.01  # m: the thinnest torso a body's height leaves above its legs


class QuadrupedLimits(BaseModel):
    """Physical limits of a Unitree Go1-sized quadruped (metres, kilograms)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    body_size: tuple[float, float, float] = Field((0.65, 0.30, 0.30), description="body bounding box x, y, z in metres")
    mass: float = Field(12.0, gt=0, description="body mass in kg")
    max_step_up: float = Field(0.12, gt=0, description="highest step it can climb, m")
    max_gap: float = Field(0.10, gt=0, description="widest gap it can cross, m")
    max_step_down: float = Field(0.40, gt=0, description="deepest drop it can step down, m")
    max_push_mass: float = Field(5.0, gt=0, description="heaviest object it can push, kg")

    @field_validator("body_size")
    @classmethod
    def _taller_than_its_legs(cls, size: tuple[float, float, float]) -> tuple[float, float, float]:
        """The legs hold the torso's underside :data:`BELLY_HEIGHT` up: a body no taller has no torso to build."""
        if not size[2] >= BELLY_HEIGHT + MIN_TORSO:
            raise ValueError(
                f"the body's height (z) must be at least {BELLY_HEIGHT + MIN_TORSO:g} m (its legs hold "
                f"its underside {BELLY_HEIGHT:g} m up)"
            )
        return size


QUADRUPED_SKILLS: tuple[SkillSpec, ...] = (
    SkillSpec(
        name="get_position",
        params=QUERY_NAME,
        returns="[x, y, z]",
        kind="query",
        semantics="Centre of the named object (or 'robot') right now, in metres.",
    ),
    SkillSpec(
        name="get_size",
        params=QUERY_NAME,
        returns="[x, y, z]",
        kind="query",
        semantics=(
            "Size of the named object (or 'robot') along x, y, z as it is turned right now (a quarter turn "
            "about z swaps x and y), in metres."
        ),
    ),
    SkillSpec(
        name="walk_to_position",
        params=POSITION,
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
        params=POSITION,
        returns="None",
        kind="motion",
        semantics=(
            "Like walk_to_position, but used to step up onto a higher surface; the same "
            "step-up, gap and drop limits apply."
        ),
    ),
    SkillSpec(
        name="turn_to_heading",
        params=HEADING,
        returns="None",
        kind="motion",
        semantics=(
            "Turn in place about the body's centre until its front faces heading degrees from +x "
            "(0: length along x; 90: along y, which swaps the body's x and y sizes); only quarter turns "
            "(0, 90, 180, 270) are possible. Refused where a foot would cross an edge on the way or the "
            "body would sweep into something."
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
