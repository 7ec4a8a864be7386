"""A compiled task (:class:`Scene`): the MuJoCo model and the tables that map task objects to its bodies."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import mujoco
import numpy as np

from robotool.task.task_model import Task

START_KEY = "start"  # the model's keyframe that holds the actuators' activations at the start, where it has one


@dataclass(frozen=True)
class Scene:
    """A compiled task: the model and the ids that map objects to bodies (the robot's embodiment is
    :func:`robotool.sim.build.embodiment_for` of the task).

    ``object_body[i]`` is the body of ``object_names[i]``; ``body_object[b]`` the object index of
    body ``b`` (-1 for the world and the robot; a button's face maps to the button). ``grasp_local``
    holds each object's graspable point in its body frame.
    """

    task: Task
    model: mujoco.MjModel
    object_names: tuple[str, ...]
    object_body: np.ndarray
    body_object: np.ndarray
    robot_body: np.ndarray
    grasp_local: np.ndarray
    control_substeps: int
    nconmax: int
    njmax: int

    @cached_property
    def control_dt(self) -> float:
        """Seconds between control ticks (read once: the model's timestep does not change)."""
        return self.control_substeps * self.model.opt.timestep

    @cached_property
    def initial_act(self) -> np.ndarray:
        """Each actuator activation at the start (na,): the :data:`START_KEY` keyframe's, where the embodiment adds
        one (filtered servos that start holding their first reference, not pulled from 0 towards it), else 0."""
        key = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_KEY, START_KEY)
        return self.model.key_act[key].copy() if key >= 0 else np.zeros(self.model.na)

    def object_index(self, name: str) -> int:
        """Index of a task object by name (KeyError listing the objects otherwise)."""
        try:
            return self.object_names.index(name)
        except ValueError:
            raise KeyError(f"no object named {name!r}; objects: {', '.join(self.object_names)}") from None
