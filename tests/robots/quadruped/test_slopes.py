"""Slopes against the friction of their surface: the feet stand only on a slope that friction holds."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from fixtures.paths import FIXTURES

from robotool import sim, tasks
from robotool.robots.quadruped.terrain import SPACING, first_steep, steepness
from robotool.sandbox import start_sessions
from robotool.sim.backend import Perturbation
from robotool.sim.backend_choice import make_sim

FEET = np.array([[-0.2, -0.1], [-0.2, 0.1], [0.2, -0.1], [0.2, 0.1]])  # x-y of four feet walking along x


def _read(surface: Callable[[np.ndarray, np.ndarray], np.ndarray], geoms: np.ndarray | None = None) -> np.ndarray:
    """:func:`steepness` (4, n) along four feet walking 1 m along x over heights ``surface(x, y)`` (one geom, or
    ``geoms`` (4, n))."""
    t = np.arange(0.0, 1.0, SPACING)
    points = FEET[:, None, :] + t[None, :, None] * np.array([1.0, 0.0])
    hit = np.zeros(points.shape[:2], dtype=int) if geoms is None else geoms
    return steepness(surface(points[..., 0], points[..., 1])[None], hit[None], points[None])[0]


@pytest.mark.parametrize(
    ("surface", "degrees"),
    [
        (lambda x, y: np.tan(np.radians(10)) * x, 10.0),  # up the walk's path
        (lambda x, y: np.tan(np.radians(4)) * y, 4.0),  # across it: the four feet's plane
        (lambda x, y: 0.0 * x, 0.0),
    ],
)
def test_a_plane_reads_its_steepest_slope_under_every_foot(
    surface: Callable[[np.ndarray, np.ndarray], np.ndarray], degrees: float
) -> None:
    tangent = _read(surface)
    assert np.degrees(np.arctan(np.nanmax(tangent))) == pytest.approx(degrees, abs=0.01)
    assert np.degrees(np.arctan(np.nanmin(tangent))) == pytest.approx(degrees, abs=0.01)


def test_a_step_or_a_change_of_object_is_no_slope() -> None:
    """A step is an edge (the scan's), also between the front and the rear feet, and a run over two geoms reads no
    slope; the flat either side reads 0."""
    step = _read(lambda x, y: np.where(x > 0.3, 0.1, 0.0))
    assert np.isnan(step[2:, 6:15]).all() and np.isnan(step[:2, 46:55]).all() and np.nanmax(step) == 0.0
    left = np.repeat(np.array([[0], [1], [0], [1]]), 100, axis=1)  # the left feet on another geom a step higher
    sideways = _read(lambda x, y: np.where(y > 0.0, 0.1, 0.0), left)
    assert np.nanmax(sideways) == 0.0
    seam = _read(lambda x, y: 0.0 * x, np.where(np.arange(100) < 50, 0, 1)[None].repeat(4, axis=0))
    assert np.isnan(seam[:, 46:55]).all() and np.nanmax(seam) == 0.0


def test_the_first_slope_too_steep_for_its_friction_is_found_with_its_angle_and_limit() -> None:
    tangent = np.array([[0.0, 0.1, np.nan, 0.2, 0.3], [0.1, 0.1, 0.1, 0.1, 0.1]])
    index, angle, holds = first_steep(tangent, np.array([[0.15] * 5, [0.1] * 5]))
    assert index.tolist() == [3, 5]
    assert angle[0] == pytest.approx(np.degrees(np.arctan(0.2))) and holds[0] == pytest.approx(
        np.degrees(np.arctan(0.15))
    )


def _run(layout: str, program: str) -> list:
    text = (FIXTURES / "cheats" / f"{program}.py").read_text()
    scene = sim.build(tasks.load(FIXTURES / "layouts" / f"{layout}.yaml"))
    return sim.run_sessions(scene, start_sessions([text] * 3, "quadruped"), seed=0)


@pytest.mark.parametrize(
    ("program", "layout"),
    [
        ("walk_up_an_icy_ramp_onto_the_sofa", "icy_ramp_onto_a_sofa"),
        ("stop_halfway_up_an_icy_ramp", "icy_ramp_onto_a_sofa"),  # the robot stopped on the ice and stayed
        ("walk_onto_an_icy_mat_sloping_sideways", "icy_mat_sloping_sideways"),
    ],
)
def test_a_walk_onto_a_slope_its_friction_cannot_hold_is_refused_where_it_starts(program: str, layout: str) -> None:
    """The frictionless feet and the body's x-y servo would hold the robot on any slope: the walk is refused before
    the slope, with the slope and the steepest its friction holds (in every perturbed world: its friction scaled)."""
    for rollout in _run(layout, program):
        assert not rollout.success
        walk = rollout.calls[-1]
        assert walk.outcome == "refused" and "slope" in walk.measured, (walk.outcome, walk.reason)
        assert walk.measured["slope"] > walk.measured["limit"] + 1.0, walk.measured
        assert "its surface's friction holds" in (walk.reason or "")


def test_a_ramp_of_ordinary_friction_is_walked_up() -> None:
    """The control: the same 10 degree ramp at the default friction (0.5) carries the robot onto the sofa."""
    rollouts = _run("wooden_ramp_onto_a_sofa", "walk_up_an_icy_ramp_onto_the_sofa")
    assert all(r.success for r in rollouts), [(c.outcome, c.reason) for r in rollouts for c in r.calls]


def test_each_worlds_friction_scale_is_how_its_surfaces_friction_was_scaled() -> None:
    scene = sim.build(tasks.load(FIXTURES / "layouts" / "icy_ramp_onto_a_sofa.yaml"))
    perturbation = Perturbation.sample(scene, 3, 0)
    world_sim = make_sim(scene, 3, backend="mujoco", perturbation=perturbation)
    ramp = scene.model.geom("icy_ramp__geom0").id
    scaled = [m.geom_friction[ramp, 0] / scene.model.geom_friction[ramp, 0] for m in world_sim.models]
    assert world_sim.friction_scale == pytest.approx(scaled)
    assert not np.allclose(scaled, 1.0)
