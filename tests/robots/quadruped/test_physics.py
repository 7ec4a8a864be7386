"""The quadruped's weight rests on its feet, it tips and falls when they lose support, goals wait for the world to
settle. Contact forces are read from the C backend's own data (a test-only look inside the backend)."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np
import pytest

from robotool import sim, tasks
from robotool.robots.quadruped.body import ROBOT_GROUP
from robotool.robots.quadruped.quadruped_controller import QuadrupedController
from robotool.robots.quadruped.support import CYCLE, feet, supported
from robotool.robots.quadruped.terrain import FOOT_RADIUS
from robotool.sim import lockstep as runner
from robotool.sim.backend_choice import make_sim
from robotool.sim.backend_mujoco import MujocoSim
from robotool.sim.build import embodiment_for
from robotool.task.task_file import parse_task

GRAVITY = 9.81
SETTLING_TICKS = 4  # control ticks at the start of a move while the legs take their stance
STANDING_TICKS = 20  # control ticks measured standing after the last move


def feet_load(sim_: MujocoSim, world: int, feet_ids: np.ndarray) -> float:
    """Total normal force (N) of the contacts between the robot's feet and anything else in one world."""
    model, data = sim_.models[world], sim_.datas[world]
    total, force = 0.0, np.zeros(6)
    for i in range(data.ncon):
        con = data.contact[i]
        bodies = model.geom_bodyid[con.geom]
        if np.isin(bodies, feet_ids).sum() == 1:
            mujoco.mj_contactForce(model, data, i, force)
            total += force[0]
    return total


def foot_gaps(sim_: MujocoSim, world: int, state: Any, ids: Any) -> np.ndarray:
    """Height (m) of each foot's bottom above the surface straight under it."""
    model, data = sim_.models[world], sim_.datas[world]
    groups = np.ones(6, dtype=np.uint8)
    groups[ROBOT_GROUP] = 0
    hit = np.zeros(1, dtype=np.int32)
    out = []
    for centre in feet(state, ids)[world]:
        out.append(mujoco.mj_ray(model, data, centre, np.array([0.0, 0.0, -1.0]), groups, 1, -1, hit) - FOOT_RADIUS)
    return np.array(out)


def walk_and_measure(task: Any, moves: list[tuple[str, tuple[float, ...]]], measure_from: int) -> dict[str, list]:
    """Run motion skills one after another in one unperturbed world; from move ``measure_from`` on, record the
    feet's load and gaps at every tick where the lift is off."""
    scene = sim.build(task)
    sim_ = make_sim(scene, 1)
    assert isinstance(sim_, MujocoSim)
    controller = embodiment_for(scene.task).controller(sim_)
    sim_.step(round(runner.SETTLE_TIME / scene.model.opt.timestep), np.ones(1, dtype=bool))
    assert isinstance(controller, QuadrupedController)
    ids = controller.senses.facts.ids
    out: dict[str, list] = {"load": [], "gap": [], "lift": []}
    mass = float(sim_.body_mass[0, scene.robot_body].sum())
    for k, (skill, args) in enumerate(moves):
        state = sim_.state()
        ends = controller.start(state, np.array([0]), skill, args)
        for tick in range(400):
            if ends:
                break
            sim_.step(scene.control_substeps, np.ones(1, dtype=bool))
            state = sim_.state()
            ends = controller.tick(state)
            if k >= measure_from and tick >= SETTLING_TICKS:
                carried = not np.isnan(controller.terrain.state.lift[0])
                out["lift"].append(carried)
                if not carried:
                    out["load"].append(feet_load(sim_, 0, ids.feet) / (mass * GRAVITY))
                    out["gap"].append(foot_gaps(sim_, 0, state, ids).max())
        assert ends and ends[0].outcome == "done", ends
    for _ in range(STANDING_TICKS):  # and standing where it stopped
        sim_.step(scene.control_substeps, np.ones(1, dtype=bool))
        controller.tick(sim_.state())
        out["load"].append(feet_load(sim_, 0, ids.feet) / (mass * GRAVITY))
        out["gap"].append(foot_gaps(sim_, 0, sim_.state(), ids).max())
    sim_.close()
    return out


def _sofas(gap_widening: float = 0.0) -> Any:
    """sofa_traversing without the board and the cloth, sofa_2 moved ``gap_widening`` further away."""
    data = tasks.load("sofa_traversing").model_dump(mode="json", exclude_defaults=True)
    objects = {o["name"]: o for o in data["objects"] if o["name"] not in ("surfboard", "strip_of_cloth")}
    objects["sofa_2"]["center"][0] += gap_widening
    data["objects"] = list(objects.values())
    return parse_task(data)


@pytest.mark.parametrize(
    ("task", "moves", "measure_from"),
    [
        ("sofa_climbing", [("walk_to_position", ((0.45, 0.0, 0.0),))], 0),  # the floor
        (_sofas(), [("walk_to_position", ((-0.1, -0.2, 0.0),))], 0),  # a sofa
        (
            "cube_lifting",
            [
                ("walk_to_position", ((2.335, -0.68, 0.0),)),
                ("climb_to_position", ((2.335, 0.0, 0.0),)),
                ("walk_to_position", ((1.8, 0.0, 0.0),)),
            ],
            2,
        ),  # up the lever board, chair still under it
    ],
)
def test_the_feet_carry_the_weight_while_standing_and_walking(task: Any, moves: list, measure_from: int) -> None:
    out = walk_and_measure(tasks.load(task) if isinstance(task, str) else task, moves, measure_from)
    load, gap = np.array(out["load"]), np.array(out["gap"])
    assert load.size > 20
    assert np.all(np.abs(load - 1.0) < 0.10), load.round(3)  # every tick, the whole weight through the feet
    assert np.all(gap < 0.005), gap.round(4)  # each foot on its surface


def test_a_robot_whose_centre_of_mass_leaves_its_support_falls_and_may_not_move_again() -> None:
    """Put the robot with its front half over a 0.6 m gap (its centre of mass 0.1 m past sofa_1's edge): it tips
    forward, the fall is reported with where and why, and a later motion skill is refused."""
    scene = sim.build(_sofas(gap_widening=0.2))
    sim_ = make_sim(scene, 1)
    assert isinstance(sim_, MujocoSim)
    controller = embodiment_for(scene.task).controller(sim_)
    data = sim_.datas[0]
    assert isinstance(controller, QuadrupedController)
    data.qpos[controller.senses.facts.ids.qpos[0]] = 0.85  # sofa_1 ends at x = 0.75
    mujoco.mj_forward(sim_.models[0], data)
    for _ in range(20):
        sim_.step(scene.control_substeps, np.ones(1, dtype=bool))
        controller.tick(sim_.state())
    reason = controller.referee.state.failures[0]
    assert reason is not None and reason.startswith("fell at [0.") and "no support under the front feet" in reason
    (end,) = controller.start(sim_.state(), np.array([0]), "walk_to_position", ((0.0, 0.0, 0.0),))
    assert end.outcome == "refused" and "the robot has fallen" in (end.reason or "")
    sim_.close()


def test_goals_are_read_after_the_world_settled(monkeypatch: pytest.MonkeyPatch) -> None:
    read_at: list[float] = []
    ended_at: list[float] = []
    original = runner._Run._read_goals

    def read_goals(self: Any, worlds: list[int], state: Any) -> None:
        for i in worlds:
            read_at.append(float(state.time[i] - self.t0[i]))
            ended_at.append(self.worlds[i].calls[-1].ended)
        original(self, worlds, state)

    monkeypatch.setattr(runner._Run, "_read_goals", read_goals)
    sim.run_programs(tasks.load("sofa_climbing"), [lambda robot: robot.walk_to_position([0.3, 0.0, 0.0])])
    assert read_at[0] >= ended_at[0] + runner.SETTLE_AFTER - 1e-6


def _crate_in_the_way() -> Any:
    """sofa_climbing's floor with a 0.4 m high crate (too high to climb) between the robot and x = 2."""
    data = tasks.load("sofa_climbing").model_dump(mode="json", exclude_defaults=True)
    data["objects"] = [o for o in data["objects"] if o["name"] != "box_1"]  # where the crate stands
    data["objects"].append(
        {
            "name": "crate",
            "shape": "box",
            "center": [1.0, 0.0, 0.2],
            "size": [0.4, 0.6, 0.4],
            "movable": False,
            "notes": "a tall crate",
        }
    )
    return parse_task(data)


def test_a_walk_goes_around_what_it_cannot_climb_or_refuses_naming_it() -> None:
    def around(robot: Any) -> None:
        robot.walk_to_position([1.8, 0.0, 0.0])

    def onto(robot: Any) -> None:
        robot.walk_to_position([1.0, 0.0, 0.4])

    around_run, onto_run = sim.run_programs(_crate_in_the_way(), [around, onto], perturb=False)
    (walk,) = around_run.calls
    assert walk.outcome == "done" and walk.result is None
    (refused,) = onto_run.calls
    assert refused.outcome == "refused" and "step up of 0.40 m" in refused.reason


def test_a_push_is_refused_when_the_robot_would_stand_over_a_drop() -> None:
    """The vase lies 0.15 m from the sofa's +y edge: to push it toward -y the robot would stand beyond that edge."""

    def program(robot: Any) -> None:
        robot.push_to_position("glass_vase", [3.0, 0.3, 0.39])

    data = tasks.load("vase_lowering").model_dump(mode="json", exclude_defaults=True)
    data["robot"]["position"] = [3.0, 0.0]  # on the sofa, behind the vase
    (rollout,) = sim.run_programs(parse_task(data), [program], perturb=False)
    (push,) = rollout.calls
    assert push.outcome == "refused" and "no clear place to stand" in push.reason and "drop" in push.reason


def test_a_foot_may_cross_one_edge_after_another_over_a_narrow_tread() -> None:
    """Fixed steps of 0.08 m and 0.035 m, the lower one a 0.12 m tread (like a roller under a board): each front
    foot is carried over one edge, passes over the tread's level and is carried over the next. The travel over an
    edge counts from the last footing, not from the first edge (over both at once it is longer than one needs)."""
    data = tasks.load("sofa_climbing").model_dump(mode="json", exclude_defaults=True)
    steps = [(1.06, 0.12, 0.08), (1.52, 0.8, 0.115)]  # centre x, length along x, height
    data["objects"] += [
        {"name": f"step_{i}", "shape": "box", "center": [x, -1.0, h / 2], "size": [length, 0.6, h], "movable": False}
        for i, (x, length, h) in enumerate(steps)
    ]

    def program(robot: Any) -> None:
        robot.walk_to_position([0.5, -1.0, 0.0])
        robot.walk_to_position([1.7, -1.0, 0.0])

    (rollout,) = sim.run_programs(parse_task(data), [program], perturb=False)
    assert [c.outcome for c in rollout.calls] == ["done", "done"], [(c.outcome, c.reason) for c in rollout.calls]
    assert rollout.calls[-1].measured == {}


def test_the_centre_of_mass_is_supported_inside_the_polygon_of_the_touching_feet() -> None:
    """Weight on feet: at least three feet touch, and the centre of mass lies at least ``margin`` inside every edge
    of the polygon through the touching feet taken counter-clockwise (checked one world at a time here)."""
    rng = np.random.default_rng(4)
    n = 4000
    corners = np.array([[-0.2, -0.1], [-0.2, 0.1], [0.2, -0.1], [0.2, 0.1]])  # rear-right, rear-left, front-...
    foot_xy = np.concatenate([corners + rng.normal(0.0, 0.04, (n, 4, 2)), np.zeros((n, 4, 1))], axis=2)
    com = rng.uniform(-0.3, 0.3, (n, 3))
    touching = rng.random((n, 4)) < 0.75
    for margin in (0.0, 0.03):
        got = supported(com, foot_xy, touching, margin)
        for w in range(n):
            ring = [foot_xy[w, f, :2] for f in CYCLE if touching[w, f]]
            inside = len(ring) >= 3
            for a, b in zip(ring, ring[1:] + ring[:1], strict=True) if inside else ():
                edge, rel = b - a, com[w, :2] - a
                inside &= (edge[0] * rel[1] - edge[1] * rel[0]) / np.linalg.norm(edge) >= margin
            assert got[w] == inside, (w, margin)
        assert 0.05 < got.mean() < 0.5
