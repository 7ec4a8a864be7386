"""Analytic scene geometry against small hand-made solids whose answers are known in closed form."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
import pytest

from robotool.task import geometry
from robotool.task.geometry import Part


@dataclass(frozen=True)
class Solid:
    """A minimal object for :func:`geometry.object_parts` (the Solid protocol), without a task file."""

    shape: str
    center: tuple[float, float, float]
    size: tuple[float, float, float]
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: Literal["x", "y", "z"] = "z"
    thickness: float = 0.02


def box(center: tuple[float, float, float], size: tuple[float, float, float], yaw: float = 0.0) -> list[Part]:
    return geometry.object_parts(Solid("box", center, size, (0.0, 0.0, yaw)))


def at(*points: tuple[float, float]) -> np.ndarray:
    return np.array(points, dtype=float)


def test_rotation_is_roll_then_pitch_then_yaw_about_fixed_axes() -> None:
    assert np.allclose(geometry.rotation_matrix((0.0, 0.0, 0.0)), np.eye(3))
    assert np.allclose(geometry.rotation_matrix((0.0, 0.0, 90.0)) @ [1, 0, 0], [0, 1, 0])
    assert np.allclose(geometry.rotation_matrix((90.0, 0.0, 0.0)) @ [0, 1, 0], [0, 0, 1])
    assert np.allclose(geometry.rotation_matrix((0.0, 90.0, 0.0)) @ [0, 0, 1], [1, 0, 0])
    # roll first: y -> z, then yaw leaves z alone; x is only yawed: x -> y
    both = geometry.rotation_matrix((90.0, 0.0, 90.0))
    assert np.allclose(both @ [0, 1, 0], [0, 0, 1]) and np.allclose(both @ [1, 0, 0], [0, 1, 0])
    r = geometry.rotation_matrix((17.0, -40.0, 123.0))
    assert np.allclose(r @ r.T, np.eye(3)) and math.isclose(np.linalg.det(r), 1.0)


def test_vertical_lines_through_a_box_enter_at_its_bottom_and_leave_at_its_top() -> None:
    (part,) = box((0.0, 0.0, 0.5), (1.0, 1.0, 1.0))
    low, high = part.vertical_interval(at((0.0, 0.0), (0.49, -0.49), (0.51, 0.0)))
    assert np.allclose(low[:2], 0.0) and np.allclose(high[:2], 1.0)
    assert np.isnan(low[2]) and np.isnan(high[2])


def test_a_box_turned_45_degrees_reaches_its_corner_along_x() -> None:
    (part,) = box((0.0, 0.0, 0.5), (1.0, 1.0, 1.0), yaw=45.0)
    reach = math.sqrt(0.5)  # half the diagonal
    low, _ = part.vertical_interval(at((reach - 0.01, 0.0), (reach + 0.01, 0.0), (0.6, 0.3)))
    assert not np.isnan(low[0]) and np.isnan(low[1]) and np.isnan(low[2])  # |x| + |y| > reach misses


def test_a_lying_cylinder_is_round_across_its_axis() -> None:
    (part,) = geometry.object_parts(Solid("cylinder", (0.0, 0.0, 0.1), (0.6, 0.2, 0.2), axis="x"))
    assert part.kind == "cylinder" and np.allclose(part.half, [0.1, 0.1, 0.3])
    low, high = part.vertical_interval(at((0.25, 0.0), (0.0, 0.06), (0.0, 0.11), (0.31, 0.0)))
    assert np.allclose([low[0], high[0]], [0.0, 0.2])
    assert np.allclose([low[1], high[1]], [0.1 - 0.08, 0.1 + 0.08])  # sqrt(0.1^2 - 0.06^2) = 0.08
    assert np.isnan(low[2]) and np.isnan(low[3])  # beside it, past its end


def test_a_standing_cylinder_uses_its_smaller_width_as_diameter() -> None:
    (part,) = geometry.object_parts(Solid("cylinder", (1.0, 0.0, 0.15), (0.2, 0.3, 0.3)))
    assert np.allclose(part.half, [0.1, 0.1, 0.15])
    low, high = part.vertical_interval(at((1.09, 0.0), (1.0, 0.12)))
    assert np.allclose([low[0], high[0]], [0.0, 0.3]) and np.isnan(low[1])


def test_a_hook_is_a_handle_and_a_head_at_the_far_end() -> None:
    handle, head = geometry.object_parts(Solid("hook", (0.0, 0.0, 0.01), (0.4, 0.2, 0.02), thickness=0.02))
    assert np.allclose(handle.center, [0.0, -0.09, 0.01]) and np.allclose(handle.half, [0.2, 0.01, 0.01])
    assert np.allclose(head.center, [0.19, 0.0, 0.01]) and np.allclose(head.half, [0.01, 0.1, 0.01])


def test_boxes_not_turned_are_crossed_exactly_as_the_general_crossing_crosses_them() -> None:
    """A box whose rotation is the identity takes a shorter way through :meth:`PartStack.intervals`; its values are
    the general crossing's to the last bit, on its sides and corners too (the planner compares heights exactly)."""
    rng = np.random.default_rng(3)
    parts = [Part("box", rng.normal(size=3), np.abs(rng.normal(size=3)) + 0.01, np.eye(3)) for _ in range(12)]
    parts.append(Part("box", np.zeros(3), np.full(3, 0.2), geometry.rotation_matrix((0.0, 0.0, 30.0))))
    parts.append(Part("cylinder", np.ones(3), np.full(3, 0.3), np.eye(3)))
    stack = geometry.PartStack.of([[p] for p in parts])
    assert stack.upright.tolist() == list(range(12))
    corners = [p.center[:2] + p.half[:2] * (sx, sy) for p in parts[:12] for sx in (-1, 1) for sy in (-1, 1)]
    xy = np.concatenate([rng.normal(size=(400, 2)), corners])
    low, high = stack.intervals(xy)
    every = np.arange(12).repeat(len(xy))
    general_low, general_high = stack._crossings(every, np.tile(xy, (12, 1)))
    assert np.array_equal(low[:12].ravel(), general_low, equal_nan=True)
    assert np.array_equal(high[:12].ravel(), general_high, equal_nan=True)
    assert np.isfinite(low[:12]).any() and np.isnan(low[:12]).any()


def test_surface_height_is_the_highest_top_under_a_point_or_the_ground() -> None:
    low_box = box((0.0, 0.0, 0.1), (1.0, 1.0, 0.2))
    tall_box = box((0.25, 0.0, 0.25), (0.5, 0.5, 0.5))
    xy = at((-0.4, 0.0), (0.25, 0.0), (2.0, 0.0))
    assert np.allclose(geometry.surface_height(xy, [low_box, tall_box]), [0.2, 0.5, 0.0])
    # a body whose bottom is at 0.3 m can rest only on what is at most that high
    assert np.allclose(geometry.surface_height(xy, [low_box, tall_box], below=np.full(3, 0.3)), [0.2, 0.2, 0.0])


def test_height_profile_samples_the_surface_along_a_segment() -> None:
    step = box((1.0, 0.0, 0.05), (0.5, 1.0, 0.1))
    s, z = geometry.height_profile(np.array([0.0, 0.0]), np.array([2.0, 0.0]), [step], step=0.25)
    assert np.allclose(s, np.arange(0.0, 2.01, 0.25))
    assert np.allclose(z, [0, 0, 0, 0.1, 0.1, 0.1, 0, 0, 0])  # over x in [0.75, 1.25]


def test_footprint_grid_covers_the_bounds_within_its_sample_limits() -> None:
    grid = geometry.footprint_grid(box((0.0, 0.0, 0.1), (0.2, 0.04, 0.2)), spacing=0.01)
    assert np.allclose(grid.min(axis=0), [-0.1, -0.02]) and np.allclose(grid.max(axis=0), [0.1, 0.02])
    assert len(np.unique(grid[:, 0])) == 21 and len(np.unique(grid[:, 1])) == 5
    coarse = geometry.footprint_grid(box((0.0, 0.0, 0.1), (10.0, 0.001, 0.2)), spacing=0.01, max_per_axis=61)
    assert len(np.unique(coarse[:, 0])) == 61 and len(np.unique(coarse[:, 1])) == 3


@pytest.mark.parametrize(
    ("z", "gap", "penetration", "into"),
    [
        (0.1, 0.0, 0.0, ""),  # resting on the ground
        (0.15, 0.05, -0.05, ""),  # floating 5 cm up
        (0.08, -0.02, 0.02, "ground"),  # sunk 2 cm into the floor
    ],
)
def test_resting_contact_measures_a_gap_or_a_penetration(z: float, gap: float, penetration: float, into: str) -> None:
    contact = geometry.resting_contact(box((0.0, 0.0, z), (0.2, 0.2, 0.2)), {}, z)
    assert math.isclose(contact.gap, gap, abs_tol=1e-9)
    assert math.isclose(contact.penetration, penetration, abs_tol=1e-9) and contact.into == into


def test_resting_contact_names_the_solid_an_object_sinks_into() -> None:
    table = box((0.0, 0.0, 0.25), (1.0, 1.0, 0.5))
    cup = box((0.0, 0.0, 0.53), (0.1, 0.1, 0.1))  # bottom at 0.48: 2 cm into the table top
    contact = geometry.resting_contact(cup, {"table": table}, 0.53)
    assert math.isclose(contact.penetration, 0.02, abs_tol=1e-9) and contact.into == "table"
    on_top = geometry.resting_contact(box((0.0, 0.0, 0.55), (0.1, 0.1, 0.1)), {"table": table}, 0.55)
    assert math.isclose(on_top.gap, 0.0, abs_tol=1e-9) and on_top.into == ""


def test_overlap_depth_is_the_smallest_penetration_along_a_separating_axis() -> None:
    (a,) = box((0.0, 0.0, 0.5), (1.0, 1.0, 1.0))
    (b,) = box((0.9, 0.0, 0.5), (1.0, 1.0, 1.0))
    (c,) = box((1.3, 0.0, 0.5), (1.0, 1.0, 1.0))
    assert math.isclose(geometry.overlap_depth(a, b), 0.1, abs_tol=1e-9)
    assert math.isclose(geometry.overlap_depth(a, c), -0.3, abs_tol=1e-9)
    # turned 45 degrees, b's corner reaches sqrt(0.5) toward a: apart by 1.3 - 0.5 - sqrt(0.5)
    (turned,) = box((1.3, 0.0, 0.5), (1.0, 1.0, 1.0), yaw=45.0)
    assert math.isclose(geometry.overlap_depth(a, turned), 0.5 + math.sqrt(0.5) - 1.3, abs_tol=1e-9)
    assert geometry.solids_overlap([a], [c, b]) == pytest.approx(0.1)


def test_distance_to_parts_is_zero_inside_and_euclidean_outside() -> None:
    parts = box((0.0, 0.0, 0.5), (1.0, 1.0, 1.0))
    assert geometry.distance_to_parts(parts, (0.2, -0.3, 0.9)) == 0.0
    assert geometry.distance_to_parts(parts, (0.8, 0.0, 0.5)) == pytest.approx(0.3)
    assert geometry.distance_to_parts(parts, (0.8, 0.9, 0.5)) == pytest.approx(0.5)  # 0.3-0.4-0.5 from an edge
    rod = geometry.object_parts(Solid("cylinder", (0.0, 0.0, 0.5), (0.2, 0.2, 1.0)))
    assert geometry.distance_to_parts(rod, (0.3, 0.4, 0.5)) == pytest.approx(0.4)  # 0.5 from the axis, radius 0.1
    assert geometry.distance_to_parts(rod, (0.0, 0.0, 1.2)) == pytest.approx(0.2)  # above the top face


@pytest.mark.parametrize(
    ("rpy", "expected"),
    [
        ((0, 0, 0), [2.0, 0.5, 0.1]),
        ((0, 0, 90), [0.5, 2.0, 0.1]),
        ((0, 0, -88), [0.5, 2.0, 0.1]),
        ((0, 0, 2), [2.0, 0.5, 0.1]),  # a perturbation's small turn changes nothing
        ((90, 0, 0), [2.0, 0.1, 0.5]),  # tipped onto its long edge
        ((0, 0, 180), [2.0, 0.5, 0.1]),
    ],
)
def test_axis_aligned_size_matches_the_box_axes_to_the_nearest_world_axes(
    rpy: tuple[float, float, float], expected: list[float]
) -> None:
    size = geometry.axis_aligned_size((2.0, 0.5, 0.1), geometry.rotation_matrix(rpy))
    assert size.tolist() == pytest.approx(expected)
