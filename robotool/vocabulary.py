"""The package's vocabulary, each word once: stages, methods, backends and skill outcomes.

They are ``Literal`` types (the type checker holds every use to them; their values are the strings results,
CLI choices and reports have always spelt), each with the tuple of its values, in order, for choices and loops.
Method records live with the methods (:mod:`robotool.program.methods`); a robot's own words (terrain kinds, say) live in
its package.
"""

from __future__ import annotations

from typing import Literal, TypeGuard, get_args

Stage = Literal["analyzer", "planner", "calculator", "coder"]
"""An LM stage of the program (the paper's four)."""
STAGES: tuple[Stage, ...] = get_args(Stage)


def is_stage(name: str) -> TypeGuard[Stage]:
    """Whether ``name`` (say, where a candidate failed) is an LM stage."""
    return name in STAGES


CallingStage = Literal[Stage, "repair"]
"""A stage that calls the language model: the program's four and the repair stage."""

FailureStage = Literal[Stage, "repair", "search", "simulation"]
"""Where a candidate failed: an LM stage, the repair stage, the search planner's code, or the simulated worlds."""

MethodName = Literal["robotool", "no_analyzer", "no_calculator", "planner_coder", "coder"]
"""The RoboTool program and the paper's ablations (their stages: :data:`robotool.program.methods.STAGES_BY_METHOD`)."""
PlannerMethod = Literal["search", "no_tool"]
"""The LM-free search planner, with every object (``search``) or the target alone (``no_tool``, the floor)."""

PLANNER_METHODS: tuple[PlannerMethod, ...] = get_args(PlannerMethod)

BackendName = Literal["mujoco", "warp"]
"""A batched simulator backend: MuJoCo on the CPU, MuJoCo Warp on a GPU."""
BACKENDS: tuple[BackendName, ...] = get_args(BackendName)

SkillOutcome = Literal["done", "stalled", "timeout", "refused", "fell", "error", "internal_error"]
"""How a skill call ended: ``error`` is the program's (bad arguments, a query that cannot be answered);
``internal_error`` is robotool's (the robot's controller raised: a bug, not the program's failure)."""

MoveEnd = tuple[SkillOutcome, str | None, dict[str, float]]
"""A motion's end inside a controller: its outcome, the reason (None when done) and the values behind it."""
