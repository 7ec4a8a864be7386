"""The RoboTool program and the paper's ablations, as switches of the same stages."""

from __future__ import annotations

from dataclasses import dataclass

from robotool.vocabulary import MethodName


@dataclass(frozen=True)
class MethodStages:
    """Which optional LM stages a method runs (the Coder always does)."""

    analyzer: bool
    planner: bool
    calculator: bool


STAGES_BY_METHOD: dict[MethodName, MethodStages] = {
    "robotool": MethodStages(analyzer=True, planner=True, calculator=True),
    "no_analyzer": MethodStages(analyzer=False, planner=True, calculator=True),
    "no_calculator": MethodStages(analyzer=True, planner=True, calculator=False),
    "planner_coder": MethodStages(analyzer=False, planner=True, calculator=False),
    "coder": MethodStages(analyzer=False, planner=False, calculator=False),
}
"""Every LM method and the stages it runs, in table order."""


def method_stages(method: str) -> MethodStages | None:
    """The stages of ``method`` (any name a record or the command line holds); None for a method without LM stages."""
    return next((stages for name, stages in STAGES_BY_METHOD.items() if name == method), None)


def runs_analyzer(method: str) -> bool:
    """Whether ``method`` is an LM method whose program runs the Analyzer."""
    stages = method_stages(method)
    return stages is not None and stages.analyzer
