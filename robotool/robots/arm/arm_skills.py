"""The arm's limits (what a task file may override) and its skills (what its programs may call)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

from robotool.robots.skills import POSITION, QUERY_NAME, SkillSpec


class ArmLimits(BaseModel):
    """Limits of a Kinova Gen3-like arm with a translating two-finger gripper."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    workspace_min: tuple[float, float, float] = (-0.30, -0.45, 0.0)
    workspace_max: tuple[float, float, float] = (0.45, 0.45, 0.50)
    grasp_radius: float = Field(0.02, gt=0, description="how close the gripper must be to a graspable point, m")
    gripper_opening: float = Field(0.06, gt=0, le=0.2, description="distance between the open fingers' inner faces, m")
    max_payload: float = Field(
        4.0,
        gt=0,
        description="heaviest load it carries off its support (the held object, what rides on it or is "
        "stuck to it), kg, its weight also the most force it pushes or presses with; a Kinova Gen3's rated "
        "payload at mid range",
    )


ARM_SKILLS: tuple[SkillSpec, ...] = (
    SkillSpec(
        name="get_center",
        params=QUERY_NAME,
        returns="[x, y, z]",
        kind="query",
        semantics="Centre of the named object right now, in metres.",
    ),
    SkillSpec(
        name="get_graspable_point",
        params=QUERY_NAME,
        returns="[x, y, z]",
        kind="query",
        semantics="The point where the gripper can hold the named object right now.",
    ),
    SkillSpec(
        name="get_size",
        params=QUERY_NAME,
        returns="[x, y, z]",
        kind="query",
        semantics=(
            "Size of the named object along x, y, z as it is turned right now (a quarter turn about z swaps x "
            "and y), in metres."
        ),
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
        params=POSITION,
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
