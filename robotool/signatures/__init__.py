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

__all__ = [
    "Analyze",
    "AnalyzedConcept",
    "Calculate",
    "Code",
    "KeyConcept",
    "ObjectRole",
    "Plan",
    "PlanStep",
    "StepParameters",
    "scene_context",
    "validation_notes",
]
