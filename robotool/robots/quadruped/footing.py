"""What the quadruped's feet stand on along a planned walk (no physics): a fragile object underfoot, or left and right
feet over surfaces too far apart; read by :mod:`.predict` on the planner's layout."""

from __future__ import annotations

import numpy as np

from robotool.planner.layout import Layout
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.terrain import FOOT_RADIUS, SPACING, foot_offsets, foot_paths


def straddle(
    layout: Layout, start: np.ndarray, goals: list[np.ndarray], limits: QuadrupedLimits, skip: list[str]
) -> str | None:
    """Where a walk along the body's length from ``start`` through ``goals`` first has a left foot and the right foot
    beside it over surfaces more than a step up apart, in words, or None: a body resting on surfaces that far apart
    rolls toward the lower side (it walked along a step's edge, its left feet on the step, and fell). A gap the feet
    stride (at most ``max_gap``) counts as the surface around it. On a walk across the body the left and right feet
    lead and trail, a step apart as they climb, and are not compared; nor are front and rear feet."""
    offsets = foot_offsets(limits)
    across = int(np.argmin(limits.body_size[:2]))  # the feet of a pair differ only in their offset on this axis
    pairs = [(a, b) for a in range(4) for b in range(a + 1, 4) if np.isclose(offsets[a], offsets[b])[1 - across]]
    stride = int(np.ceil((limits.max_gap / 2 + FOOT_RADIUS) / SPACING))
    here = np.asarray(start, dtype=float)
    for goal in goals:
        delta = goal - here
        length = float(np.linalg.norm(delta))
        if length > 1e-6 and abs(delta[across]) <= abs(delta[1 - across]):
            paths = foot_paths(here + offsets, delta / length, length)
            heights = layout.heights(paths.reshape(-1, 2), skip).reshape(paths.shape[:2])
            padded = np.pad(heights, ((0, 0), (stride, stride)), mode="edge")
            footing = np.lib.stride_tricks.sliding_window_view(padded, 2 * stride + 1, axis=1).max(axis=2)
            apart = np.stack([np.abs(footing[a] - footing[b]) for a, b in pairs])
            if apart.max() > limits.max_step_up:
                k, i = np.unravel_index(int(np.argmax(apart)), apart.shape)
                x, y = (paths[pairs[k][0], i] + paths[pairs[k][1], i]) / 2
                return (
                    f"the left and right feet would stand on surfaces {float(apart[k, i]):.2f} m apart (a step up is "
                    f"at most {limits.max_step_up:g} m), at [{x:.2f}, {y:.2f}] on the way to "
                    f"[{goal[0]:.2f}, {goal[1]:.2f}]"
                )
        here = goal
    return None


def fragile_footing(
    layout: Layout, start: np.ndarray, goals: list[np.ndarray], limits: QuadrupedLimits, skip: list[str]
) -> str | None:
    """The first fragile object a foot would stand on along the walk, in words (the robot's weight breaks it), or
    None: a fragile object is no footing, however low."""
    fragile = [o.name for o in layout.task.objects if o.fragile is not None and o.name not in skip]
    found = footing(layout, start, goals, limits, skip, fragile)
    if found is None:
        return None
    name, (x, y) = found
    return f"a foot would stand on {name}, which is fragile, at [{x:.2f}, {y:.2f}]"


def footing(
    layout: Layout,
    start: np.ndarray,
    goals: list[np.ndarray],
    limits: QuadrupedLimits,
    skip: list[str],
    names: list[str],
) -> tuple[str, np.ndarray] | None:
    """The first of ``names`` a foot would stand on along the walk from ``start`` through ``goals``, and where (None:
    none)."""
    if not names:
        return None
    rim = FOOT_RADIUS * np.array([[0.0, 0.0], [1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])
    here = np.asarray(start, dtype=float)
    for goal in goals:
        delta = goal - here
        length = float(np.linalg.norm(delta))
        direction = delta / length if length > 1e-6 else np.array([1.0, 0.0])
        points = (foot_paths(here + foot_offsets(limits), direction, length)[:, :, None, :] + rim).reshape(-1, 2)
        surface, tops = layout.tops(points, skip)
        for name in names:
            top = tops[name] if name in tops else layout.top_of(name, points)  # (a cloth is in no stack of solids)
            on = np.flatnonzero(np.isclose(top, surface, atol=1e-6))
            if on.size:
                return name, points[on[0]]
        here = goal
    return None
