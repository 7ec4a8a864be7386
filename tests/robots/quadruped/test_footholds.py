"""Footholds narrower than a foot (:mod:`robotool.robots.quadruped.footholds`): which surfaces the rays hit may be
too narrow for a foot, as they lie, and where a foot over them comes down."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from robotool.robots.quadruped.footholds import Footholds, comes_down_to, side_points
from robotool.robots.quadruped.terrain import FOOT_RADIUS
from robotool.sim.backend import BatchState

GEOMS = """
<mujoco><worldbody>
  <geom name="floor" type="plane" size="5 5 0.1"/>
  <body name="wide_box" pos="0 0 0.1"><geom type="box" size="0.3 0.2 0.1"/></body>
  <body name="blade_on_edge" pos="1 0 0.1"><geom type="box" size="0.5 0.002 0.1"/></body>
  <body name="board_on_its_side" pos="2 0 0.2" euler="90 0 0"><geom type="box" size="0.5 0.2 0.01"/></body>
  <body name="box_on_a_corner" pos="3 0 0.2" euler="30 0 0"><geom type="box" size="0.3 0.3 0.3"/></body>
  <body name="upright_drum" pos="4 0 0.2"><geom type="cylinder" size="0.2 0.2"/></body>
  <body name="thin_post" pos="5 0 0.2"><geom type="cylinder" size="0.02 0.2"/></body>
  <body name="lying_roller" pos="6 0 0.05" euler="90 0 0"><geom type="cylinder" size="0.05 0.3"/></body>
  <body name="ball" pos="7 0 0.1"><geom type="sphere" size="0.1"/></body>
  <body name="pipe" pos="8 0 0.05" euler="0 90 0"><geom type="capsule" size="0.05 0.3"/></body>
</worldbody></mujoco>
"""
NARROW = {
    "floor": False,
    "wide_box": False,
    "blade_on_edge": True,
    "board_on_its_side": True,  # its 2 cm edge on top
    "box_on_a_corner": True,  # no face level on top: a ridge
    "upright_drum": False,
    "thin_post": True,  # a 4 cm top
    "lying_roller": True,
    "ball": True,
    "pipe": True,
}


def _state(model: mujoco.MjModel) -> BatchState:
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    nbody = model.nbody
    return BatchState(
        time=np.zeros(1),
        qpos=data.qpos[None].copy(),
        qvel=data.qvel[None].copy(),
        xpos=data.xpos[None].copy(),
        xquat=data.xquat[None].copy(),
        sensordata=np.zeros((1, 0)),
        eq_active=np.zeros((1, 0), dtype=bool),
        touching=np.zeros((1, nbody, nbody), dtype=bool),
        failed=[None],
    )


def test_surfaces_whose_top_may_be_narrower_than_a_foot_are_told_as_they_lie() -> None:
    model = mujoco.MjModel.from_xml_string(GEOMS)
    names = [model.geom(i).name or model.body(model.geom_bodyid[i]).name for i in range(model.ngeom)]
    geoms = np.array([[-1, *range(model.ngeom)]])
    narrow = Footholds.of(model).narrow(_state(model), np.array([0]), geoms)
    assert not narrow[0, 0]  # a ray that hit nothing
    assert dict(zip(names, narrow[0, 1:].tolist(), strict=True)) == NARROW


@pytest.mark.parametrize(
    ("sides", "down_to"),
    [
        ([0.34, 0.34, 0.0, 0.01], 3),  # a blade along the path: the higher of the readings across it
        ([0.0, 0.02, 0.34, 0.34], 1),  # a slat across the path: the higher of the readings along it
        ([0.0, 0.05, 0.01, 0.0], 1),  # a post's top: the highest of all
        ([0.34, 0.0, 0.34, 0.0], -1),  # a corner: the surface carries the foot on two sides
        ([0.34, 0.0, 0.0, 0.34], -1),  # an edge and a corner the other way
        ([0.34 - FOOT_RADIUS, 0.34, 0.34 - FOOT_RADIUS, 0.34 - FOOT_RADIUS], -1),  # a 45 degree ridge still carries
        ([0.34, 0.34, 0.34, 0.34], -1),  # flat
    ],
)
def test_a_foot_over_a_narrow_top_comes_down_beside_it(sides: list[float], down_to: int) -> None:
    assert comes_down_to(np.array(0.34), np.array(sides)) == down_to


def test_side_points_lie_a_foot_radius_along_and_across_each_path() -> None:
    u = np.array([[[0.6, 0.8]]])
    sides = side_points(np.array([[[1.0, 2.0], [3.0, 4.0]]]), u)
    assert sides.shape == (1, 2, 4, 2)
    offsets = sides - np.array([[[1.0, 2.0], [3.0, 4.0]]])[:, :, None, :]
    np.testing.assert_allclose(np.linalg.norm(offsets, axis=-1), FOOT_RADIUS)
    np.testing.assert_allclose(offsets[0, 0, 0], FOOT_RADIUS * u[0, 0])  # ahead
    np.testing.assert_allclose(offsets[0, 0, 2] @ u[0, 0], 0.0, atol=1e-12)  # across
