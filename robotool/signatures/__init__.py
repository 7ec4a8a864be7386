"""Typed DSPy signatures, one per stage of the RoboTool program, and their output models.

The stages' records are DSPy-free (:mod:`~robotool.signatures.models`: plan steps, parameters, key concepts;
:mod:`~robotool.signatures.traces`: what a failed run looked like); only the signatures themselves import DSPy.
Names load on first use, so the LM-free planner can read the records without loading DSPy.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from robotool.signatures.analyzer import Analyze
    from robotool.signatures.calculator import Calculate
    from robotool.signatures.coder import Code
    from robotool.signatures.models import (
        AnalyzedConcept,
        KeyConcept,
        ObjectRole,
        PlanStep,
        StepParameters,
        scene_context,
        validation_notes,
    )
    from robotool.signatures.planner import Plan
    from robotool.signatures.repair import Repair
    from robotool.signatures.traces import FailureTrace, RepairScope, TracedCall

_WHERE = {
    "Analyze": "analyzer",
    "AnalyzedConcept": "models",
    "Calculate": "calculator",
    "Code": "coder",
    "FailureTrace": "traces",
    "KeyConcept": "models",
    "ObjectRole": "models",
    "Plan": "planner",
    "PlanStep": "models",
    "Repair": "repair",
    "RepairScope": "traces",
    "StepParameters": "models",
    "TracedCall": "traces",
    "scene_context": "models",
    "validation_notes": "models",
}

__all__ = [
    "Analyze",
    "AnalyzedConcept",
    "Calculate",
    "Code",
    "FailureTrace",
    "KeyConcept",
    "ObjectRole",
    "Plan",
    "PlanStep",
    "Repair",
    "RepairScope",
    "StepParameters",
    "TracedCall",
    "scene_context",
    "validation_notes",
]


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(import_module(f"robotool.signatures.{_WHERE[name]}"), name)
    raise AttributeError(f"module 'robotool.signatures' has no attribute {name!r}")
