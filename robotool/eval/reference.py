"""Reference data the evaluator grades and compares against: the paper's published numbers and tools.

``PAPER_SUCCESS`` is the seed paper's Table 1 (success over 10 runs in simulation, plus the real-robot
row); ``PAPER_CONCEPT_ACCURACY`` is its Table 2 (the Analyzer's key-concept accuracy). Both are shown
as labelled reference rows next to measured rows; they are never mixed into measured averages.

``BUILTIN_TOOLS`` names, for each built-in task, the objects a working solution uses as tools (the
paper's solutions; empty for the discriminative variants that need no tool). Generated instances
carry their own (``Instance.tools``). The error classifier uses them to tell "never used the needed
tool" (tool-use error) from "used some of the tools but left a step out" (logical error).
"""

from __future__ import annotations

PAPER_TASKS: tuple[str, ...] = (
    "milk_reaching",
    "can_grasping",
    "button_pressing",
    "sofa_traversing",
    "sofa_climbing",
    "cube_lifting",
)
"""The paper's six tasks, in its column order."""

PAPER_SUCCESS: dict[str, tuple[float, ...]] = {
    "robotool": (0.9, 0.7, 0.8, 1.0, 1.0, 0.8),
    "no_analyzer": (0.0, 0.4, 0.2, 1.0, 0.7, 0.2),
    "no_calculator": (0.0, 0.1, 0.8, 0.3, 0.0, 0.3),
    "planner_coder": (0.0, 0.2, 0.5, 0.1, 0.0, 0.4),
    "coder": (0.0, 0.0, 0.0, 0.0, 0.0, 0.4),
    "RoboTool (real world)": (0.7, 0.7, 0.8, 0.7, 0.8, 0.9),
}
"""Table 1: method -> success per task in :data:`PAPER_TASKS` order."""

PAPER_SUCCESS_AVERAGE: dict[str, float] = {
    "robotool": 0.87,
    "no_analyzer": 0.42,
    "no_calculator": 0.25,
    "planner_coder": 0.20,
    "coder": 0.07,
    "RoboTool (real world)": 0.77,
}
"""Table 1's Average column as printed."""

PAPER_CONCEPT_ACCURACY: tuple[float, ...] = (1.0, 1.0, 0.9, 1.0, 0.8, 1.0)
"""Table 2: RoboTool's key-concept accuracy per task in :data:`PAPER_TASKS` order."""

BUILTIN_TOOLS: dict[str, frozenset[str]] = {
    "milk_reaching": frozenset({"hammer"}),
    "milk_reaching_near": frozenset(),
    "can_grasping": frozenset({"stick", "strip_of_paper"}),
    "button_pressing": frozenset({"magnetic_cube1", "magnetic_cube2", "magnetic_cube3"}),
    "sofa_traversing": frozenset({"surfboard"}),
    "sofa_traversing_small_gap": frozenset(),
    "sofa_climbing": frozenset({"box_1", "box_2"}),
    "sofa_climbing_low_sofa": frozenset(),
    "cube_lifting": frozenset({"chair", "surfboard"}),
    "vase_lowering": frozenset({"soft_cushion", "box_1", "box_2"}),  # the boxes are fixed stairs
}
"""Built-in task -> the objects its reference solution uses as tools."""


def paper_success(method: str) -> dict[str, float]:
    """The paper's Table 1 row of a method by task name (empty when the paper has none)."""
    return dict(zip(PAPER_TASKS, PAPER_SUCCESS.get(method, ()), strict=False))


def paper_concept_accuracy() -> dict[str, float]:
    """The paper's Table 2 by task name."""
    return dict(zip(PAPER_TASKS, PAPER_CONCEPT_ACCURACY, strict=True))
