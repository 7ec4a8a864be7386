"""Reading the terrain ahead of the quadruped from downward-ray height profiles.

A profile holds the surface height every ``spacing`` metres along the walking direction, from the
robot's rear edge (index 0) to its front edge at the goal, taking at each distance the highest hit
across the body's width. :func:`scan` starts on the surface the robot stands on (the highest under
its footprint, samples ``footprint[0]`` to ``footprint[1]``, but no higher than its feet) and checks
the embodiment's limits ahead of the footprint, where the surface changes:

- a rise is a step up; over ``max_step_up`` it is refused (``step``);
- a dip deeper than a climbable step is a gap when the surface comes back up within the profile, and
  its width is checked against ``max_gap`` (``gap``); otherwise it is a step down, checked against
  ``max_step_down`` (``drop``);
- anything else (a slope, a small step down) is followed.

``edge`` is the distance from the profile start where the offending change begins, so the robot can
stop with its front there. ``lift`` is the highest accepted surface up to the edge, which the lift
motor uses to carry the body over steps.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from robotool.embodiments import QuadrupedLimits

Violation = Literal["step", "gap", "drop"]
RISE = 0.015  # m: a change smaller than this is the same surface (noise, slopes between samples)
TOLERANCE = 0.01  # m: measurement slack allowed over a limit (ray sampling and pose noise)


@dataclass(frozen=True)
class Scan:
    """What one profile says: the first violated limit (if any) and the accepted heights."""

    violation: Violation | None
    measured: float  # the step height, gap width or drop depth behind the violation, m
    edge: float  # distance along the profile where the violation starts, m (inf when none)
    level: np.ndarray  # accepted surface height at each sample (NaN from the edge on)


def scan(
    heights: np.ndarray, spacing: float, limits: QuadrupedLimits, footprint: tuple[int, int], feet: float
) -> Scan:
    """Check one height profile (n,) ahead of the footprint against the limits (module docstring).

    ``feet`` is the height of the robot's feet.
    """
    n = heights.shape[0]
    level = np.full(n, np.nan)
    current = min(feet + RISE, float(heights[footprint[0] : footprint[1] + 1].max()))
    level[: footprint[1] + 1] = current
    k = footprint[1] + 1
    while k < n:
        h = float(heights[k])
        if h - current > RISE:
            if h - current > limits.max_step_up + TOLERANCE:
                return Scan("step", h - current, k * spacing, level)
            current = h
        elif current - h > limits.max_step_up:
            back = np.flatnonzero(heights[k:] >= current - limits.max_step_up)
            if back.size:
                width = back[0] * spacing
                if width > limits.max_gap + TOLERANCE:
                    return Scan("gap", width, k * spacing, level)
                level[k : k + back[0]] = current
                k += int(back[0])
                continue
            if current - h > limits.max_step_down + TOLERANCE:
                return Scan("drop", current - h, k * spacing, level)
            current = h
        else:
            current = h
        level[k] = current
        k += 1
    return Scan(None, 0.0, float("inf"), level)


def describe(violation: Violation, measured: float, limits: QuadrupedLimits) -> str:
    """The refusal reason for a violated limit, with the measured value and the limit."""
    limit, what = {
        "step": (limits.max_step_up, "step up"),
        "gap": (limits.max_gap, "gap"),
        "drop": (limits.max_step_down, "drop"),
    }[violation]
    return f"{what} of {measured:.2f} m exceeds the limit of {limit:.2f} m"
