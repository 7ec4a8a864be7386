"""The quadruped's own goal kind, ``robot_on``, as named sub-conditions over batched state."""

from __future__ import annotations

import numpy as np

from robotool.robots.quadruped.body import BodyIds
from robotool.robots.quadruped.support import centre_of_mass, feet, feet_touching, supported
from robotool.sim.backend import BatchState
from robotool.sim.compiled_scene import Scene


class RobotOnGoal:
    """``robot_on: obj``: the robot's weight rests on ``obj``.

    Its centre of mass lies over the support of the feet that touch ``obj`` (at least three of them), and every foot
    touches something (none hangs over a gap).
    """

    def __init__(self, scene: Scene):
        self.scene = scene
        self.name = scene.task.goal.object
        self.index = scene.object_index(self.name)
        self.ids = BodyIds.of(scene.model)
        self.target = scene.body_object == self.index
        self.not_robot = ~scene.robot_body

    def update(self, state: BatchState, active: np.ndarray) -> None:
        """Nothing to remember: the goal holds at the end."""

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        on_target = feet_touching(state, self.ids, self.target)
        weight = supported(centre_of_mass(state, self.ids), feet(state, self.ids), on_target)
        standing = feet_touching(state, self.ids, self.not_robot).all(axis=1)
        return {f"robot_weight_on_{self.name}": weight, "robot_feet_all_supported": standing}
