"""The arm's own goal kind, ``grasped``, as named sub-conditions over batched state."""

from __future__ import annotations

import numpy as np

from robotool.robots.arm.arm_body import GRIPPER_BODY, graspable_points, held_objects
from robotool.robots.arm.arm_skills import ArmLimits
from robotool.sim.backend import BatchState
from robotool.sim.compiled_scene import Scene
from robotool.sim.embodiment import ReadAtTicks


class GraspedGoal(ReadAtTicks):
    """``grasped: obj``: the gripper holds ``obj`` and its graspable point is still at the gripper."""

    def __init__(self, scene: Scene):
        self.scene = scene
        self.index = scene.object_index(scene.task.goal.object)
        limits = scene.task.limits
        assert isinstance(limits, ArmLimits)  # the arm's tasks carry the arm's limits
        self.radius = limits.grasp_radius

    def update(self, state: BatchState, active: np.ndarray, credited: np.ndarray) -> None:
        """Nothing to remember: the goal holds at the end."""

    def conditions(self, state: BatchState) -> dict[str, np.ndarray]:
        name = self.scene.object_names[self.index]
        gripper = self.scene.model.body(GRIPPER_BODY).id
        point = graspable_points(self.scene, state)[:, self.index]
        offset = np.linalg.norm(point - state.xpos[:, gripper], axis=1)
        return {
            f"{name}_held": held_objects(self.scene, state) == self.index,
            f"{name}_in_gripper": offset <= 2 * self.radius,
        }
