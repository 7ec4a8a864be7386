"""Reading height profiles against the limits, and the geometry of pushing (no physics)."""

from __future__ import annotations

import numpy as np
import pytest

from robotool.embodiments import QuadrupedLimits
from robotool.sim.quadruped_push import Leg, legs, push_pose, route, rule_violation
from robotool.sim.quadruped_terrain import scan

LIMITS = QuadrupedLimits()
SPACING = 0.01


def profile(*pieces: tuple[float, float]) -> np.ndarray:
    """Heights from (length, height) pieces, sampled every SPACING."""
    return np.concatenate([np.full(round(length / SPACING), height) for length, height in pieces])


@pytest.mark.parametrize(
    ("pieces", "violation", "measured", "edge"),
    [
        ([(0.7, 0.0), (0.5, 0.12), (0.5, 0.24), (0.5, 0.34)], None, 0.0, np.inf),  # a staircase
        ([(0.7, 0.0), (0.5, 0.34)], "step", 0.34, 0.7),
        ([(0.7, 0.34), (0.4, 0.0), (0.6, 0.34)], "gap", 0.40, 0.7),
        ([(0.7, 0.34), (0.08, 0.0), (0.6, 0.34)], None, 0.0, np.inf),  # a small gap is stepped over
        ([(0.7, 0.34), (0.6, 0.0)], None, 0.0, np.inf),  # a 0.34 m step down is allowed
        ([(0.7, 0.5), (0.6, 0.0)], "drop", 0.5, 0.7),
        ([(0.7, 0.34), (0.3, 0.25), (0.6, 0.34)], None, 0.0, np.inf),  # a shallow dip is walked through
        ([(0.7, 0.34), (0.3, 0.2), (0.6, 0.34)], "gap", 0.3, 0.7),  # a deeper one is a gap
    ],
)
def test_scan_finds_the_first_violated_limit(
    pieces: list[tuple[float, float]], violation: str | None, measured: float, edge: float
) -> None:
    heights = profile(*pieces)
    result = scan(heights, SPACING, LIMITS, footprint=(2, 63), feet=float(heights[0]))
    assert result.violation == violation
    assert result.measured == pytest.approx(measured, abs=SPACING)
    assert result.edge == pytest.approx(edge, abs=SPACING)


def test_scan_starts_from_the_surface_under_the_feet_not_an_edge_beside_them() -> None:
    heights = profile((0.6, 0.34), (0.1, 0.41), (0.6, 0.41))  # a board starts under the body's edge
    assert scan(heights[::-1], SPACING, LIMITS, footprint=(2, 63), feet=0.34).violation is None
    assert scan(heights, SPACING, LIMITS, footprint=(2, 63), feet=0.34).level[0] < 0.41


def test_push_legs_go_shorter_axis_first_and_skip_tiny_ones() -> None:
    assert legs(np.array([1.0, 0.0]), np.array([1.95, 0.65])) == [Leg(1, 0.65), Leg(0, 1.95)]
    assert legs(np.array([1.0, 0.0]), np.array([1.01, 0.65])) == [Leg(1, 0.65)]


def test_push_pose_stands_behind_the_object_and_ends_where_its_face_lands() -> None:
    half = np.array([0.325, 0.15])
    start, end = push_pose(np.array([0.8, -0.3]), np.array([1.2, 0.3]), Leg(0, 1.95), half, 0.0)
    assert start == pytest.approx([0.8 - 0.325 - 0.03, 0.0])
    assert end[0] - start[0] == pytest.approx(0.95 + 0.03)


def test_route_goes_around_the_object() -> None:
    lo, hi = np.array([0.0, 0.0]), np.array([1.0, 1.0])
    assert len(route(np.array([-0.5, 0.5]), np.array([-0.5, 2.0]), lo, hi)) == 1
    path = route(np.array([0.5, -0.5]), np.array([0.5, 1.5]), lo, hi)
    assert len(path) == 3 and all(p[0] in (0.0, 1.0) for p in path[:2])


@pytest.mark.parametrize(
    ("changes", "reason"),
    [
        ({}, None),
        ({"movable": False}, "fixed"),
        ({"under_robot": True}, "standing on it"),
        ({"mass": 10.0}, "mass 10.0 kg exceeds"),
        ({"robot_support_movable": "surfboard"}, "stands on surfboard"),
        ({"object_support": 0.34}, "not on the robot's surface"),
    ],
)
def test_push_rules(changes: dict[str, object], reason: str | None) -> None:
    args: dict[str, object] = {
        "movable": True,
        "mass": 3.0,
        "under_robot": False,
        "robot_support_movable": None,
        "object_support": 0.0,
        "robot_support": 0.0,
        "limits": LIMITS,
    }
    result = rule_violation(**(args | changes))  # type: ignore[arg-type]
    assert (result is None) if reason is None else (result is not None and reason in result[0])
