"""Test fixture: a third robot from outside the package, a point robot that slides a small puck on the ground.

It is a plug-in as a user would write one: a module with a ``ROBOT`` record, named in ``ROBOTOOL_ROBOTS`` (or
an entry point in the group ``robotool.robots``). One motion skill, ``move_to(position)``, drives the puck on
two slide joints with force-limited position servos to [x, y]; one query, ``get_position(name)``. Its goal kind
is ``robot_on``, with its own tracker: the puck's centre lies over the named object's footprint.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import mujoco
import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from robotool.concepts import KeyConcept
from robotool.robots import PictureSettings, RobotType
from robotool.robots.skills import POSITION, QUERY_NAME, SkillSpec
from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.compiled_scene import Scene
from robotool.sim.embodiment import QueryError, SkillEnd, world_mask
from robotool.task_model import Task
from robotool.task_problem import Problem

PUCK_BODY = "robot_puck"
PUCK_HEIGHT = 0.02  # m
HOVER = 0.02  # m between the ground and the puck's underside: it glides over mats, not over boxes
SERVO_KP, SERVO_KV, SERVO_FORCE = 400.0, 40.0, 50.0  # N/m, N s/m, N
ARRIVED = 0.01  # m


class PointLimits(BaseModel):
    """The point robot's limits."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    radius: float = Field(0.05, gt=0, description="puck radius, m")
    speed: float = Field(0.3, gt=0, description="sliding speed, m/s")


SKILLS = (
    SkillSpec(name="get_position", params=QUERY_NAME, returns="[x, y, z]", kind="query",
              semantics="Centre of the named object (or 'robot') right now, in metres."),
    SkillSpec(name="move_to", params=POSITION, returns="None", kind="motion",
              semantics="Slide the puck in a straight line until its centre is over [x, y]; z is ignored."),
)


class PointEmbodiment:
    """The puck on two slide joints (x, y) with position servos."""

    control_substeps = 25

    def __init__(self, limits: PointLimits):
        self.limits = limits

    def add_to_spec(self, spec: mujoco.MjSpec, task: Task) -> None:
        x, y = task.robot.position  # type: ignore[misc]
        body = spec.worldbody.add_body(name=PUCK_BODY, pos=[x, y, HOVER + PUCK_HEIGHT / 2])
        for axis, (name, start) in enumerate((("robot_x", x), ("robot_y", y))):
            direction = [0.0, 0.0, 0.0]
            direction[axis] = 1.0
            body.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=direction, ref=start)  # qpos: absolute
            spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT,
                              gainprm=[SERVO_KP] + [0] * 9, biasprm=[0, -SERVO_KP, -SERVO_KV] + [0] * 7,
                              biastype=mujoco.mjtBias.mjBIAS_AFFINE, forcerange=[-SERVO_FORCE, SERVO_FORCE],
                              forcelimited=mujoco.mjtLimited.mjLIMITED_TRUE)
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[self.limits.radius, PUCK_HEIGHT / 2, 0], mass=1.0)

    def controller(self, sim: BatchedSim) -> PointController:
        return PointController(sim, self.limits)


class PointController:
    """Moves the servo setpoint toward the target at the robot's speed; done once the puck is there."""

    def __init__(self, sim: BatchedSim, limits: PointLimits):
        self.sim, self.limits = sim, limits
        model = sim.scene.model
        self.body = model.body(PUCK_BODY).id
        self.qadr = [model.jnt_qposadr[model.joint(n).id] for n in ("robot_x", "robot_y")]
        self.act = [model.actuator(n).id for n in ("robot_x", "robot_y")]
        self.target: dict[int, np.ndarray] = {}
        self.deadline: dict[int, float] = {}
        start = sim.scene.task.robot.position
        sim.ctrl[:, self.act] = np.asarray(start)

    def start(self, state: BatchState, worlds: np.ndarray, skill: str, args: tuple[Any, ...]) -> list[SkillEnd]:
        for w in worlds:
            target = np.asarray(args[0][:2], dtype=float)
            distance = float(np.linalg.norm(target - state.xpos[w, self.body, :2]))
            self.target[int(w)] = target
            self.deadline[int(w)] = float(state.time[w]) + distance / self.limits.speed + 2.0
        return []

    def tick(self, state: BatchState, worlds: np.ndarray | None = None) -> list[SkillEnd]:
        ends = []
        step = self.limits.speed * self.sim.scene.control_dt
        ticked = world_mask(self.sim.nworld, worlds)
        for w, target in list(self.target.items()):
            if not ticked[w]:
                continue
            here = state.xpos[w, self.body, :2]
            if np.linalg.norm(here - target) <= ARRIVED:
                ends.append(SkillEnd(world=w, outcome="done"))
            elif state.time[w] > self.deadline[w]:
                ends.append(SkillEnd(world=w, outcome="timeout", reason="the puck did not reach its target in time",
                                     measured={"distance": float(np.linalg.norm(here - target))}))
            else:
                setpoint = self.sim.ctrl[w, self.act]
                delta = target - setpoint
                length = float(np.linalg.norm(delta))
                self.sim.ctrl[w, self.act] = target if length <= step else setpoint + delta * (step / length)
                continue
            del self.target[w], self.deadline[w]
        return ends

    def query(self, state: BatchState, world: int, skill: str, args: tuple[Any, ...]) -> Any:
        name = args[0]
        if name == "robot":
            return state.xpos[world, self.body].tolist()
        scene = self.sim.scene
        if name not in scene.object_names:
            raise QueryError(f"no object named {name!r}")
        return state.xpos[world, scene.object_body[scene.object_index(name)]].tolist()


class PuckOnGoal:
    """``robot_on: obj``: the puck's centre lies over ``obj``'s footprint (its task-file box)."""

    def __init__(self, scene: Scene):
        self.obj = scene.task.object(scene.task.goal.object)
        self.body = scene.model.body(PUCK_BODY).id

    def update(self, state: BatchState, active: np.ndarray) -> None:
        """Nothing to remember: the goal holds at the end."""

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        centre, half = np.asarray(self.obj.center[:2]), np.asarray(self.obj.size[:2]) / 2
        inside = np.all(np.abs(state.xpos[:, self.body, :2] - centre) <= half, axis=1)
        return {f"robot_over_{self.obj.name}": inside}


def _check_robot(task: Task) -> list[Problem]:
    if task.robot.position is None:
        return [Problem(path="robot.position", message="a point robot needs a start [x, y]")]
    return []


def _describe(task: Task) -> list[str]:
    limits = task.limits
    assert isinstance(limits, PointLimits)
    return [f"The robot is a puck of radius {limits.radius} m that slides at {limits.speed} m/s; "
            f"it starts at x-y {list(task.robot.position or ())}."]


def _key_concepts(task: Task) -> list[KeyConcept]:
    return []


def _goal_trackers() -> Mapping[str, Callable[[Scene], Any]]:
    return {"robot_on": PuckOnGoal}


ROBOT = RobotType(
    name="point",
    article="a",
    limits=PointLimits,
    skills=SKILLS,
    goals=frozenset({"robot_on"}),
    embodiment=PointEmbodiment,
    goal_trackers=_goal_trackers,
    describe=_describe,
    key_concepts=_key_concepts,
    check_robot=_check_robot,
    planar=True,
    start_xy=lambda task: task.robot.position or (0.0, 0.0),
    view=PictureSettings(turn=-30.0, elevation=-45.0, floor_square=0.1),
)
