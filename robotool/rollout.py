"""What one world's run of a program produced: the skill-call trace and the goal's conditions."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, Field

Outcome = Literal["done", "stalled", "timeout", "refused", "fell", "error"]


class SkillCall(BaseModel):
    """One skill call in a world: arguments, how it ended and why, in simulated seconds."""

    skill: str
    args: list[Any]
    outcome: Outcome
    reason: str | None = None
    measured: dict[str, float] = Field(
        default_factory=dict, description="values behind a refusal or clamp, e.g. {'gap': 0.40}"
    )
    result: Any = None
    started: float = 0.0
    ended: float = 0.0


class Rollout(BaseModel):
    """One program in one perturbed world, from start to end."""

    world: int
    seed: int
    success: bool
    conditions: dict[str, bool] = Field(default_factory=dict, description="the goal's named sub-conditions at the end")
    calls: list[SkillCall] = Field(default_factory=list)
    touched: list[str] = Field(default_factory=list, description="objects the robot moved or met")
    sim_time: float = 0.0
    error: str | None = Field(None, description="why the world failed outside the goal, if it did")
    output: str = Field("", description="what the program printed")
