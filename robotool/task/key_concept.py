"""A ground-truth key concept: one quantity that decides whether a task needs a tool, against its limit."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

ConceptKind = Literal[
    "workspace_excess", "climb_height", "drop_height", "gap_width", "mass", "fall_height", "lift_height", "other"
]


class KeyConcept(BaseModel):
    """One quantity that decides feasibility, compared with the limit it must respect."""

    name: str = Field(description="what is measured, naming the objects, e.g. 'gap between sofa_1 and sofa_2'")
    kind: ConceptKind = Field(
        "other",
        description=(
            "workspace_excess | climb_height | drop_height | gap_width | mass | fall_height | lift_height | other"
        ),
    )
    value: float = Field(description="the measured value")
    unit: str = Field("m", description="SI unit of value and limit: m or kg")
    limit: float = Field(description="the robot or object limit it is compared with")
    limit_name: str = Field(description="which limit, e.g. 'max_gap' or 'workspace'")
    satisfied: bool = Field(description="true when the value respects the limit without a tool")
