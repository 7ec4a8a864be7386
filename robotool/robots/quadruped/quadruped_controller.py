"""The quadruped embodiment: its skills over batched worlds and its queries.

:class:`QuadrupedController` is the composition that implements the
:class:`~robotool.sim.embodiment.SkillController` contract; each job is a component with its own per-world state
dataclass:

- :mod:`.plans` makes each motion skill's plan of straight moves (a walk, a push with its approach, follow-throughs
  and corrections);
- :mod:`.move_runner` runs the plans' moves in every world at once (:class:`~.move_runner.MoveState`);
- :mod:`.terrain_following` reads the feet's paths, sets where a move must stop and why, and drives the legs and the
  lift over edges (:class:`~.terrain_following.TerrainState`);
- :mod:`.referee` judges falls, shoves, rams, crushes and the push rules (:class:`~.referee.RefereeState`);
- :mod:`.lift_load` puts the reaction of the lift, the tilt motors and the x-y and yaw servos on what the feet stand
  on (:class:`~.lift_load.LoadState`);
- :mod:`.rays` casts the downward rays, :mod:`.sensing` reads the batched state.

The tunables are in :mod:`.quadruped_config`. Nothing here reads the task's category or name: limits come from
``task.robot.limits`` and the terrain from the simulated geoms.
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from robotool.robots.quadruped.body import add_body
from robotool.robots.quadruped.lift_load import LiftLoad
from robotool.robots.quadruped.move_runner import MoveRunner
from robotool.robots.quadruped.plans import Plans
from robotool.robots.quadruped.quadruped_config import QUADRUPED, QuadrupedConfig
from robotool.robots.quadruped.quadruped_skills import QuadrupedLimits
from robotool.robots.quadruped.rays import Rays
from robotool.robots.quadruped.referee import FALL_CONDITION, Referee
from robotool.robots.quadruped.sensing import SceneFacts, Senses
from robotool.robots.quadruped.stance import Stance
from robotool.robots.quadruped.support import feet
from robotool.robots.quadruped.terrain import FOOT_RADIUS, quarter_turns
from robotool.robots.quadruped.terrain_following import TerrainFollowing
from robotool.rollout import Event
from robotool.sim.backend import BatchedSim, BatchState
from robotool.sim.embodiment import QueryError, SkillController, SkillEnd, size_now, world_mask
from robotool.task.task_model import Task


class QuadrupedEmbodiment:
    """The quadruped (Go1-sized) with the limits of one task."""

    control_substeps = 25  # 20 Hz: the lift motor must react within a step's approach

    def __init__(self, limits: QuadrupedLimits, config: QuadrupedConfig = QUADRUPED):
        self.limits, self.config = limits, config

    def add_to_spec(self, spec: mujoco.MjSpec, task: Task) -> None:
        """Add the robot body and its actuators (see :mod:`robotool.robots.quadruped.body`)."""
        add_body(spec, task)

    def controller(self, sim: BatchedSim) -> QuadrupedController:
        return QuadrupedController(sim, self.limits, self.config)


class QuadrupedController(SkillController):
    """Runs the quadruped's skills in every world of one batched simulator: the composition of its components."""

    def __init__(self, sim: BatchedSim, limits: QuadrupedLimits, config: QuadrupedConfig = QUADRUPED):
        self.sim, self.limits = sim, limits
        self.senses = Senses(sim, SceneFacts.of(sim.scene, limits))
        rays = Rays(sim, limits, self.senses.facts, config)
        self.terrain = TerrainFollowing(self.senses, rays, limits, config)
        self.referee = Referee(self.senses, rays, limits, config)
        self.moves = MoveRunner(self.senses, self.terrain, config, on_push=self.referee.push_started)
        self.plans = Plans(self.senses, rays, self.referee, limits, config)
        self.load = LiftLoad(sim, rays, self.senses.facts.ids, self.senses.facts.reach)
        self.stance = Stance(self.senses, rays, config)

    def world_states(self) -> tuple[Any, ...]:
        """The per-world state of the move runner, the terrain following, the referee, the lift's load and the stance
        read at the goal."""
        return (self.moves.state, self.terrain.state, self.referee.state, self.load.state, self.stance.state)

    def start(self, state: BatchState, worlds: np.ndarray, skill: str, args: tuple[Any, ...]) -> list[SkillEnd]:
        """Begin a motion skill; pushes that break a rule, and any motion of a fallen robot, are refused at once."""
        self.senses.state = state
        failures = self.referee.state.failures
        ends = []
        for w in np.asarray(worlds, dtype=int).reshape(-1):
            if failures[w] is not None:
                ends.append(SkillEnd(world=int(w), outcome="refused", reason=f"the robot has fallen ({failures[w]})"))
                continue
            if skill == "push_to_position":
                plan = self.plans.push(w, *args)
            elif skill == "turn_to_heading":
                plan = self.plans.turn(w, args[0])
            else:
                plan = self.plans.walk(w, args[0])
            end = self.moves.begin(w, plan)
            if end is not None:
                ends.append(end)
        return ends

    def robot_conditions(self, state: BatchState, worlds: list[int]) -> dict[str, list[bool]]:
        """The referee's conditions (:meth:`~.referee.Referee.conditions`): not fallen, shoved nothing, and, with a
        fragile object, stood on none; as the goal of ``worlds`` is read, a robot left standing where it would slide
        (:mod:`.stance`) has fallen too."""
        self.stance.read(state, worlds)
        conditions = self.referee.conditions()
        stood = self.stance.holds()
        conditions[FALL_CONDITION] = [a and b for a, b in zip(conditions[FALL_CONDITION], stood, strict=True)]
        return conditions

    def robot_events(self, world: int) -> list[Event]:
        """A rule the robot broke in ``world`` while no skill ran, which no skill's refusal tells (a ram coasting on
        after the program ended), and a fall off a slope read as the goal was (:meth:`.stance.Stance.events`)."""
        untold = self.referee.state.untold[world]
        return ([] if untold is None else [untold]) + self.stance.events(world)

    def tick(self, state: BatchState, worlds: np.ndarray | None = None) -> list[SkillEnd]:
        """Report finished skills, falls and shoves, and write the controls for the next interval, with the reaction
        of the motors and servos on what the feet stand on (in ``worlds``, every world when None)."""
        self.senses.state = state
        mask = world_mask(self.sim.nworld, worlds)
        ends = self.referee.judge(mask, self.moves)
        worlds = np.flatnonzero(mask & self.moves.state.moving & np.array([f is None for f in state.failed]))
        self.load.clear(np.flatnonzero(mask & ~world_mask(self.sim.nworld, worlds)))
        if worlds.size:
            self.moves.drive(worlds, ends)
            self.terrain.let_go(self.load.apply(state, worlds))
        return ends

    def query(self, state: BatchState, world: int, skill: str, args: tuple[Any, ...]) -> Any:
        """``get_position`` / ``get_size`` of an object or of ``robot``, from the current state."""
        name, scene = args[0], self.senses.scene
        if name == "robot":
            if skill == "get_size":
                sx, sy, sz = self.limits.body_size
                return [sy, sx, sz] if quarter_turns(self.senses.yaw(world)) % 2 else [sx, sy, sz]
            centres = feet(state, self.senses.facts.ids)[world]
            x, y = centres[:, :2].mean(axis=0)
            return [float(x), float(y), float(centres[:, 2].mean() - FOOT_RADIUS + self.senses.facts.height / 2)]
        try:
            index = scene.object_index(name)
        except KeyError as e:
            raise QueryError(str(e.args[0])) from None
        if skill == "get_size":
            return size_now(scene, state, world, index)
        return [float(v) for v in self.senses.centers(state)[world, index]]
