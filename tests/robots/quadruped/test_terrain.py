"""Reading height profiles against the limits, and the geometry of pushing (no physics)."""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import pytest

from robotool import tasks
from robotool.robots.quadruped.push import (
    FACE_TURN,
    FACE_TURN_FROM,
    SIDE_MARGIN,
    TRIES_AT_ONCE,
    Leg,
    face_turn,
    first_clear_sweep,
    legs,
    push_poses,
    route,
    routes,
    rule_violation,
    sweep_problem,
    turned_feet_drop,
)
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.terrain import (
    FOOT_NAMES,
    FOOT_RADIUS,
    KINDS,
    check_walk,
    foot_support,
    scan_paths,
    survey_walk,
)
from robotool.task import geometry
from robotool.task.scene import SceneObject

LIMITS = QuadrupedLimits()
SPACING = 0.01


def profile(*pieces: tuple[float, float]) -> np.ndarray:
    """Heights from (length, height) pieces, sampled every SPACING."""
    return np.concatenate([np.full(round(length / SPACING), height) for length, height in pieces])


@pytest.mark.parametrize(
    ("pieces", "kind", "measured", "edge"),
    [
        ([(0.4, 0.0), (0.5, 0.12), (0.5, 0.24), (0.5, 0.34)], None, 0.0, None),  # a staircase
        ([(0.4, 0.0), (0.5, 0.34)], "step", 0.34, 0.4),
        ([(0.4, 0.34), (0.4, 0.0), (0.6, 0.34)], "gap", 0.40, 0.4),
        ([(0.4, 0.34), (0.08, 0.0), (0.6, 0.34)], None, 0.0, None),  # a small gap is stridden
        ([(0.4, 0.34), (0.12, 0.0), (0.6, 0.34)], "gap", 0.12, 0.4),  # just over the limit and its tolerance
        ([(0.4, 0.34), (0.02, 0.0), (0.6, 0.20)], None, 0.0, None),  # a slit narrower than a foot carries it
        ([(0.4, 0.34), (0.7, 0.0)], None, 0.0, None),  # a 0.34 m step down is allowed
        ([(0.4, 0.5), (0.7, 0.0)], "drop", 0.5, 0.4),
        ([(0.4, 0.34), (0.3, 0.25), (0.6, 0.34)], None, 0.0, None),  # a shallow dip is walked through
        ([(0.4, 0.34), (0.3, 0.2), (0.6, 0.34)], "gap", 0.3, 0.4),  # a deeper one is a gap
    ],
)
def test_scan_finds_the_first_broken_limit(
    pieces: list[tuple[float, float]], kind: str | None, measured: float, edge: float | None
) -> None:
    heights = profile(*pieces)
    result = scan_paths(heights[None], np.array([heights[0]]), LIMITS)
    assert result.kind[0] == (0 if kind is None else KINDS.index(kind) + 1)  # type: ignore[arg-type]
    assert result.measured[0] == pytest.approx(measured, abs=SPACING)
    if edge is not None:  # where the foot's centre meets it (a round foot meets a step its radius early)
        assert result.index[0] * SPACING == pytest.approx(edge, abs=FOOT_RADIUS + SPACING)


@pytest.mark.parametrize(
    "pieces",
    [
        [(0.4, 0.0), (0.5, 0.12), (0.5, 0.24), (0.5, 0.34)],
        [(0.4, 0.34), (0.4, 0.0), (0.6, 0.34)],
        [(0.4, 0.34), (0.08, 0.0), (0.6, 0.34)],
        [(0.4, 0.5), (0.7, 0.0)],
    ],
)
def test_a_path_with_missing_readings_leaves_the_others_as_they_read_alone(pieces: list[tuple[float, float]]) -> None:
    """A path whose rays met nothing (NaN) takes the NaN-aware reading; the paths beside it read as they do alone."""
    heights = profile(*pieces)
    alone = scan_paths(heights[None], np.array([heights[0]]), LIMITS)
    blind = np.full_like(heights, np.nan)
    together = scan_paths(np.stack([heights, blind]), np.array([heights[0], np.nan]), LIMITS)
    for field in ("index", "kind", "measured"):
        assert getattr(together, field)[0] == getattr(alone, field)[0], field
    np.testing.assert_array_equal(together.level[0], alone.level[0])
    np.testing.assert_array_equal(together.met[0], alone.met[0])


@pytest.mark.parametrize(
    ("pieces", "largest"),
    [
        ([(0.4, 0.0), (0.5, 0.10), (0.5, 0.20)], {"step": 0.10, "gap": 0.0, "drop": 0.0}),  # within the limits
        ([(0.4, 0.34), (0.08, 0.0), (0.6, 0.34)], {"step": 0.0, "gap": 0.08, "drop": 0.0}),  # stridden
        ([(0.4, 0.34), (0.4, 0.0), (0.6, 0.34)], {"step": 0.0, "gap": 0.40, "drop": 0.0}),  # the finding
        ([(0.4, 0.34), (0.7, 0.0)], {"step": 0.0, "gap": 0.0, "drop": 0.34}),
    ],
)
def test_scan_records_every_edge_met_within_its_limit_or_not(
    pieces: list[tuple[float, float]], largest: dict[str, float]
) -> None:
    heights = profile(*pieces)
    met = scan_paths(heights[None], np.array([heights[0]]), LIMITS).met[0].max(axis=0)
    assert dict(zip(KINDS, met, strict=True)) == pytest.approx(largest, abs=SPACING)


def test_survey_counts_what_the_feet_meet_up_to_the_goal() -> None:
    """A 0.08 m gap between two 0.34 m sofas is stridden; a 0.3 m step beyond the goal is not met."""

    def heights(xy: np.ndarray) -> np.ndarray:
        x = xy[:, 0]
        return np.where(x < 1.0, 0.34, np.where(x < 1.08, 0.0, np.where(x < 2.5, 0.34, 0.64)))

    survey = survey_walk(heights, np.array([0.0, 0.0]), np.array([1.6, 0.0]), LIMITS)
    assert survey.finding is None
    assert survey.largest == pytest.approx({"step": 0.0, "gap": 0.08, "drop": 0.0}, abs=SPACING)
    farther = survey_walk(heights, np.array([0.0, 0.0]), np.array([2.4, 0.0]), LIMITS)
    assert farther.finding is not None and farther.finding.kind == "step"
    assert farther.finding.measured == pytest.approx(0.30, abs=SPACING)


def test_paths_are_scanned_together_and_each_from_its_own_level() -> None:
    gap, stairs = profile((0.4, 0.34), (0.4, 0.0), (0.6, 0.34)), profile((0.4, 0.0), (0.5, 0.12), (0.5, 0.24))
    result = scan_paths(np.stack([gap, stairs, gap]), np.array([0.34, 0.0, 0.0]), LIMITS)
    assert list(result.kind) == [KINDS.index("gap") + 1, 0, KINDS.index("step") + 1]  # the last starts too low


def test_a_path_reads_the_same_alone_and_beside_paths_that_change() -> None:
    """A gentle slope (a nanometre a sample, as a tilted board reads) is followed sample by sample whatever the other
    paths in the scan meet: a world's terrain reading must not depend on the worlds scanned with it."""
    slope = 0.2 + 1e-9 * np.arange(150)
    stairs = profile((0.4, 0.0), (0.5, 0.12), (0.6, 0.24))
    alone = scan_paths(slope[None], slope[:1], LIMITS)
    together = scan_paths(np.stack([slope, stairs]), np.array([slope[0], 0.0]), LIMITS)
    np.testing.assert_array_equal(together.level[0], alone.level[0])
    np.testing.assert_array_equal(alone.level[0], foot_support(slope[None])[0])  # as the foot rests on it


def test_a_gap_already_entered_counts_from_its_edge() -> None:
    """A path that starts 0.2 m inside a gap (its feet held at the near level) measures the whole gap."""
    heights = profile((0.2, 0.0), (0.6, 0.34))
    result = scan_paths(heights[None], np.array([0.34]), LIMITS, into_gap=np.array([0.2]))
    assert result.kind[0] == KINDS.index("gap") + 1 and result.measured[0] == pytest.approx(0.4, abs=SPACING)


SOFAS = [geometry.object_parts(o) for o in tasks.load("sofa_traversing_small_gap").objects if o.name.startswith("sofa")]
WIDE = [geometry.object_parts(o) for o in tasks.load("sofa_traversing").objects if o.name.startswith("sofa")]


def heights_over(solids: list) -> Any:
    return lambda xy: geometry.surface_height(xy, solids)


@pytest.mark.parametrize(
    "waypoints",
    [
        [(1.7, 0.0)],  # straight
        [(1.7, 0.3)],  # diagonal
        [(x, 0.25 * (-1) ** k) for k, x in enumerate(np.arange(-0.3, 1.8, 0.1))],  # zig-zag
        [(x, 0.0) for x in np.arange(-0.35, 1.8, 0.05)],  # many short walks
    ],
)
def test_no_path_shape_crosses_a_wide_gap(waypoints: list[tuple[float, float]]) -> None:
    finding = check_walk(heights_over(WIDE), np.array([-0.4, 0.0]), [np.array(p) for p in waypoints], LIMITS)
    assert finding is not None and finding.kind in ("gap", "drop", "step")
    assert "exceeds the limit" in finding.describe() and finding.foot in FOOT_NAMES


def test_a_straight_walk_over_a_narrow_gap_is_fine() -> None:
    assert check_walk(heights_over(SOFAS), np.array([-0.4, 0.0]), [np.array([1.4, 0.0])], LIMITS) is None


def test_push_legs_go_shorter_axis_first_and_skip_tiny_ones() -> None:
    assert legs(np.array([1.0, 0.0]), np.array([1.95, 0.65])) == [Leg(1, 0.65), Leg(0, 1.95)]
    assert legs(np.array([1.0, 0.0]), np.array([1.01, 0.65])) == [Leg(1, 0.65)]


def test_push_pose_stands_behind_the_object_and_ends_where_its_face_lands() -> None:
    half = np.array([0.325, 0.15])
    start, end = push_poses(np.array([0.8, -0.3]), np.array([1.2, 0.3]), Leg(0, 1.95), half, np.array([0.0, 0.1]))
    assert start[0] == pytest.approx([0.8 - 0.325 - 0.03, 0.0])
    assert start[1] == pytest.approx([0.8 - 0.325 - 0.03, 0.1])  # shifted along the face
    assert end[:, 0] - start[:, 0] == pytest.approx([0.95 + 0.03] * 2)
    assert end[:, 1] == pytest.approx(start[:, 1])


@pytest.mark.parametrize(("overlap", "clear"), [(0.005, False), (-0.005, False), (-SIDE_MARGIN - 0.005, True)])
def test_a_push_sweep_keeps_the_whole_outline_clear(overlap: float, clear: bool) -> None:
    """A 0.16 m block beside the robot's flank: 5 mm inside its outline, or closer to it than the side margin the
    walk predictions keep, is in the way of the push (the robot would brush or shove it); past the margin it is not."""
    behind, end = np.array([0.0, 0.0]), np.array([0.0, 1.0])  # a push toward +y: the flank faces +x
    flank = LIMITS.body_size[0] / 2 - overlap
    block = {"name": "block", "shape": "box", "center": [flank + 0.25, 0.5, 0.08], "size": [0.5, 0.5, 0.16]}
    solids = [geometry.object_parts(SceneObject.model_validate(block))]
    problem = sweep_problem(heights_over(solids), behind, end, LIMITS, 0.0)
    assert (problem is None) == clear, problem


@pytest.mark.parametrize(
    ("offset", "turn"),
    [(0.0, 0.0), (FACE_TURN_FROM * 0.25 - 0.01, 0.0), (0.08, FACE_TURN), (-0.08, -FACE_TURN), (0.2, FACE_TURN)],
)
def test_a_push_lined_up_off_the_centre_turns_the_face_toward_the_centre_line(offset: float, turn: float) -> None:
    """A push toward +y of a chair 0.5 m wide with the robot ``offset`` to the -x side of its centre line (the centre
    to the robot's right): past a quarter of the half width the face turns counter-clockwise, its right end ahead, so
    that it meets the chair nearest the centre line first; to the other side, clockwise; nearer the line, flat."""
    lo, hi = np.array([-0.25, 0.5]), np.array([0.25, 0.9])
    start, end = np.array([-offset, 0.0]), np.array([-offset, 0.6])
    assert face_turn(start, end, lo, hi) == pytest.approx(turn)
    turned = face_turn(np.array([0.0, offset]), np.array([0.6, offset]), np.array([0.5, -0.25]), np.array([0.9, 0.25]))
    assert turned == pytest.approx(turn), "the same push turned a quarter clockwise (toward +x) turns the face alike"


def test_the_turned_feet_meet_a_drop_where_the_flat_feet_keep_to_the_platform() -> None:
    """Along a platform's edge (a drop of 0.3 m past it) 3 mm beyond the flat feet's centres, the feet of a body
    turned 2.5 degrees swing 5 mm over it at one end: a drop; the flat feet keep to the platform."""
    edge = LIMITS.body_size[0] / 2 - FOOT_RADIUS + 0.003  # 3 mm beyond the flat feet's centres

    def heights(xy: np.ndarray) -> np.ndarray:
        return np.where(xy[:, 0] > edge, -0.3, 0.0)

    start, end = np.array([0.0, 0.0]), np.array([0.0, 0.6])
    assert turned_feet_drop(heights, start, end, LIMITS, 0.0, 0.0) is None
    drop = turned_feet_drop(heights, start, end, LIMITS, FACE_TURN, 0.0)
    assert drop is not None and drop.kind == "drop", drop


def test_the_first_clear_push_sweep_is_the_first_one_sweep_problem_clears_read_a_few_at_a_time() -> None:
    """Sweeps across a floor with a block and a pit: :func:`first_clear_sweep` names the first one with no problem and
    the first drop before it, as :func:`sweep_problem` finds them one by one, reading a few sweeps in each call."""
    parts = [
        {"name": "block", "shape": "box", "center": [0.9, 0.5, 0.08], "size": [0.3, 0.3, 0.16]},
        {"name": "floor", "shape": "box", "center": [0.0, 0.5, -0.1], "size": [4.0, 3.0, 0.2]},
    ]
    solids = [geometry.object_parts(SceneObject.model_validate(p)) for p in parts]
    floor_with_pit = heights_over(solids)
    calls: list[int] = []

    def heights(xy: np.ndarray) -> np.ndarray:
        calls.append(len(xy))
        z = floor_with_pit(xy)
        return np.where(np.hypot(xy[:, 0] + 0.4, xy[:, 1] - 0.5) < 0.15, -0.3, z)  # a pit under some sweeps

    sweeps = [(np.array([x, 0.0]), np.array([x, 1.0])) for x in np.arange(-0.6, 1.4, 0.1)]
    problems = [sweep_problem(heights, behind, end, LIMITS, 0.0) for behind, end in sweeps]
    assert {p.kind for p in problems if p} == {"blocked", "drop"} and None in problems
    for start in range(len(sweeps)):
        calls.clear()
        clear, drop = first_clear_sweep(heights, sweeps[start:], LIMITS, 0.0)
        rest = problems[start:]
        want = next((k for k, p in enumerate(rest) if p is None), None)
        before = rest[: want if want is not None else len(rest)]
        drops = [(k, p) for k, p in enumerate(before) if p and p.kind == "drop"]
        assert clear == want and drop == (drops[0] if drops else None), (start, clear, want)
        assert len(calls) <= -(-len(rest) // TRIES_AT_ONCE)


def test_route_goes_around_the_object() -> None:
    lo, hi = np.array([0.0, 0.0]), np.array([1.0, 1.0])
    assert len(route(np.array([-0.5, 0.5]), np.array([-0.5, 2.0]), lo, hi)) == 1
    path = route(np.array([0.5, -0.5]), np.array([0.5, 1.5]), lo, hi)
    assert len(path) == 3 and all(p[0] in (0.0, 1.0) for p in path[:2])


def test_a_route_from_inside_the_box_first_steps_out_through_the_nearest_side() -> None:
    """Right behind an object it has just pushed and turned, the robot's centre lies inside the object's grown box:
    the way round starts by stepping out, instead of heading straight through the object."""
    lo, hi = np.array([0.0, 0.0]), np.array([1.0, 1.0])
    path = route(np.array([0.9, 0.5]), np.array([0.5, -0.5]), lo, hi)
    assert path[0][0] > 1.0 and path[0][1] == pytest.approx(0.5)  # out through the +x side, the nearest
    assert path[1] == pytest.approx([1.0, 0.0]) and path[-1] == pytest.approx([0.5, -0.5])
    ways = routes(np.array([0.9, 0.5]), np.array([0.5, -0.5]), lo, hi)
    assert len(ways) >= 2 and np.array_equal(ways[0], path)  # the other way round too, longer
    assert all(_crosses_none(way, lo, hi) for way in ways)


def _crosses_none(way: list[np.ndarray], lo: np.ndarray, hi: np.ndarray) -> bool:
    """Whether the path from its first waypoint on never passes through the box (sampled)."""
    for a, b in itertools.pairwise(way):
        for t in np.linspace(0.0, 1.0, 50)[1:-1]:
            p = a + t * (b - a)
            if np.all((p > lo + 1e-6) & (p < hi - 1e-6)):
                return False
    return True


@pytest.mark.parametrize(
    ("changes", "reason"),
    [
        ({}, None),
        ({"movable": False}, "fixed"),
        ({"under_robot": True}, "standing on it"),
        ({"mass": 10.0}, "10.0 kg, exceeds"),
        ({"mass": 12.0, "riders": ["cube"]}, "with cube riding on it, 12.0 kg, exceeds"),
        ({"mass": 22.0, "stuck": ["slab"]}, "its mass with slab stuck to it, 22.0 kg, exceeds"),
        ({"mass": 24.0, "riders": ["cube"], "stuck": ["slab"]}, "with cube riding on it and slab stuck to it, 24.0 kg"),
        ({"robot_support_movable": "surfboard"}, "stands on surfboard"),
        ({"object_support": 0.34}, "not on the robot's surface"),
    ],
)
def test_push_rules(changes: dict[str, object], reason: str | None) -> None:
    args: dict[str, object] = {
        "movable": True,
        "mass": 3.0,
        "riders": [],
        "stuck": [],
        "under_robot": False,
        "robot_support_movable": None,
        "object_support": 0.0,
        "robot_support": 0.0,
        "limits": LIMITS,
    }
    result = rule_violation(**(args | changes))  # type: ignore[arg-type]
    assert (result is None) if reason is None else (result is not None and reason in result[0])
