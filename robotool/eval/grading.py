"""Key-concept accuracy (the paper's Table 2), graded against the ground truth from geometry.

Matching rule. A ground-truth concept (:func:`robotool.task.concepts.key_concepts`) is *recovered* when
some predicted concept has

- the same ``kind`` (workspace_excess, climb_height, drop_height, gap_width, mass, fall_height),
- a ``value`` within 10% of the true value or within an absolute tolerance, whichever is larger
  (0.02 m for lengths, 0.5 kg for masses), and
- the same ``satisfied`` verdict (the value respects the robot's limit, or not).

A run is *correct* when every ground-truth concept of its task is recovered; extra predicted
concepts are not penalized. A task's accuracy is the share of its runs that are correct. Every run
of a method with an Analyzer is graded: one whose Analyzer gave no usable reply, or that failed
before it did, predicted nothing and counts as wrong. Runs of methods without an Analyzer and
tasks without ground-truth concepts are not graded (``correct`` is None).
"""

from __future__ import annotations

from collections.abc import Sequence

from pydantic import BaseModel, Field

from robotool.task.concepts import KeyConcept

RELATIVE_TOLERANCE = 0.10
ABSOLUTE_TOLERANCE: dict[str, float] = {"m": 0.02, "kg": 0.5}


class ConceptGrade(BaseModel):
    """How a run's predicted key concepts compare with the ground truth."""

    truth: list[KeyConcept] = Field(default_factory=list)
    recovered: list[bool] = Field(default_factory=list, description="per ground-truth concept")
    correct: bool | None = Field(None, description="every ground-truth concept recovered; None: not graded")


def matches(truth: KeyConcept, predicted: KeyConcept) -> bool:
    """Whether ``predicted`` recovers ``truth`` (same kind, value within tolerance, same verdict)."""
    tolerance = max(RELATIVE_TOLERANCE * abs(truth.value), ABSOLUTE_TOLERANCE.get(truth.unit, 0.0))
    return (
        predicted.kind == truth.kind
        and predicted.satisfied == truth.satisfied
        and abs(predicted.value - truth.value) <= tolerance
    )


def grade(truth: Sequence[KeyConcept], predicted: Sequence[KeyConcept] | None) -> ConceptGrade:
    """Grade predicted concepts (None: the method has no Analyzer) against the ground truth."""
    recovered = [predicted is not None and any(matches(t, p) for p in predicted) for t in truth]
    correct = None if predicted is None or not truth else all(recovered)
    return ConceptGrade(truth=list(truth), recovered=recovered, correct=correct)
