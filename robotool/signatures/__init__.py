"""Typed DSPy signatures, one per stage of the RoboTool program, and their output models."""

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
from robotool.signatures.repair import FailureTrace, Repair, RepairScope, TracedCall

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
