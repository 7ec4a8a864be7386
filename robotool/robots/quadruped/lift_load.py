"""The load of the quadruped's lift and tilt motors, put on what the feet stand on.

The lift motor (on the world-anchored z slide) and the pitch and roll motors push the body from the world. A real
robot's legs would carry that force and those torques down to what its feet stand on, so each tick, in every world
where they act, their reaction is put, as downward forces (``xfrc_applied``), on the movable bodies under the feet:
under each foot a downward ray finds the solid within the legs' reach (a foot over a gap stands on nothing; a cloth
is limp, the load goes to what carries it: :meth:`.rays.Rays.surface`), and the forces at those points sum to the
lift's force and balance the tilt torques about the centre of mass (the least forces that do; none pulls up). A
foot's load grows no faster than the whole weight in :data:`LOAD_TIME`, as a leg takes it (the force is held through
a control tick, and would otherwise fling a light body), and a support that sinks away from a foot faster than
:data:`YIELD_SPEED` bears nothing that tick: the lift and the tilt motors let go there, and the body goes down with
what it stood on. A board balanced on a pillar thus tips under a robot the lift carries onto its edge, as it would
under the robot's weight; fixed bodies bear the load without it being applied.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from robotool.robots.quadruped.body import GRAVITY, BodyIds
from robotool.robots.quadruped.rays import Rays
from robotool.robots.quadruped.support import centre_of_mass, feet
from robotool.robots.quadruped.terrain import FOOT_RADIUS
from robotool.sim.backend import BatchedSim, BatchState, quat_to_mat

LOAD_TIME = 0.5  # s a foot takes to put the whole weight on what it stands on (its load grows at most that fast)
YIELD_SPEED = 0.05  # m/s: a support that sinks faster than this under a foot leaves it, and bears nothing that tick


@dataclass(frozen=True)
class MotorFacts:
    """The lift, pitch and roll motors' force law (an affine servo on its joint, clamped) and where the load goes."""

    gain: np.ndarray  # (3,) force per unit of control
    bias: np.ndarray  # (3, 3) constant, per unit of joint position, per unit of joint velocity
    ctrl_range: np.ndarray  # (3, 2) the controls' range (+-inf: unlimited)
    force_range: np.ndarray  # (3, 2) the forces' range (+-inf: unlimited)
    movable: np.ndarray  # (nbody,) bool: the bodies a force moves (not welded to the world)
    body_com: np.ndarray  # (nbody, 3) each body's centre of mass in its own frame
    reach: float  # m below a foot's bottom that a surface bears it

    @classmethod
    def of(cls, model: mujoco.MjModel, ids: BodyIds, reach: float) -> MotorFacts:
        act = ids.actuator[2:]
        limited = model.actuator_ctrllimited[act].astype(bool)[:, None]
        forced = model.actuator_forcelimited[act].astype(bool)[:, None]
        unlimited = np.array([-np.inf, np.inf])
        return cls(
            gain=model.actuator_gainprm[act, 0].copy(),
            bias=model.actuator_biasprm[act, :3].copy(),
            ctrl_range=np.where(limited, model.actuator_ctrlrange[act], unlimited),
            force_range=np.where(forced, model.actuator_forcerange[act], unlimited),
            movable=model.body_weldid != 0,
            body_com=model.body_ipos.copy(),
            reach=reach,
        )


@dataclass
class LoadState:
    """Per world (index first): what each foot's load rested on at the last tick."""

    body: np.ndarray  # (nworld, 4) the body under each foot (-1: none)
    anchor: np.ndarray  # (nworld, 4, 3) the point under the foot, in that body's frame
    height: np.ndarray  # (nworld, 4) m: that point's height then
    load: np.ndarray  # (nworld, 4) N: the load put there

    @classmethod
    def empty(cls, nworld: int) -> LoadState:
        return cls(
            body=np.full((nworld, 4), -1),
            anchor=np.zeros((nworld, 4, 3)),
            height=np.zeros((nworld, 4)),
            load=np.zeros((nworld, 4)),
        )


class LiftLoad:
    """Puts the lift's and the tilt motors' reaction on the movable bodies under the feet (state: :class:`LoadState`;
    it writes ``sim.xfrc_applied`` anew every tick)."""

    def __init__(self, sim: BatchedSim, rays: Rays, ids: BodyIds, reach: float):
        self.sim, self.rays, self.ids = sim, rays, ids
        self.facts = MotorFacts.of(sim.scene.model, ids, reach)
        self.state = LoadState.empty(sim.nworld)
        self.dt = sim.scene.control_dt
        self.ramp = ids.masses.sum() * GRAVITY / LOAD_TIME * self.dt  # N a foot's load grows by in a tick

    def clear(self, worlds: np.ndarray) -> None:
        """No load in ``worlds`` (their motors are off)."""
        self.sim.xfrc_applied[worlds] = 0.0
        self.state.body[worlds], self.state.load[worlds] = -1, 0.0

    def motor_loads(self, state: BatchState, worlds: np.ndarray) -> np.ndarray:
        """(k, 3) the lift's force (N, up) and the pitch and roll motors' torques (N m) in ``worlds`` as the
        controls now set them."""
        f, ids = self.facts, self.ids
        ctrl = np.clip(self.sim.ctrl[worlds][:, ids.actuator[2:]], f.ctrl_range[:, 0], f.ctrl_range[:, 1])
        q, qd = state.qpos[worlds][:, ids.qpos[2:]], state.qvel[worlds][:, ids.qvel[2:]]
        force = f.gain * ctrl + f.bias[:, 0] + f.bias[:, 1] * q + f.bias[:, 2] * qd
        return np.clip(force, f.force_range[:, 0], f.force_range[:, 1])

    def apply(self, state: BatchState, worlds: np.ndarray) -> np.ndarray:
        """Set ``xfrc_applied`` in ``worlds``: the reaction of their motors' loads on what their feet stand on.
        Returns the worlds where a support that should bear some of it sank away: the lift cannot carry the body
        on it there."""
        s, f, ids = self.state, self.facts, self.ids
        loads = self.motor_loads(state, worlds)
        acting = (loads[:, 0] > 0.0) | (loads[:, 1:] != 0.0).any(axis=1)
        self.clear(worlds[~acting])
        worlds, loads = worlds[acting], loads[acting]
        self.sim.xfrc_applied[worlds] = 0.0
        if not worlds.size:
            return worlds
        centres = feet(state, ids)[worlds]
        _, solid, geom = self.rays.surface(worlds, centres[:, :, :2], centres[:, :, 2].max(axis=1))
        stands = (geom >= 0) & (centres[:, :, 2] - FOOT_RADIUS - solid <= f.reach)
        points = np.concatenate([centres[:, :, :2], np.where(stands, solid, centres[:, :, 2])[:, :, None]], axis=2)
        body = np.where(stands, self.sim.scene.model.geom_bodyid[np.maximum(geom, 0)], -1)
        wanted = self._foot_forces(
            loads, points, stands, centre_of_mass(state, ids)[worlds], state.xmat(ids.body)[worlds]
        )
        w = np.repeat(worlds, 4)
        pos, rot = self._pose(state, w, s.body[worlds].reshape(-1))
        before = np.einsum("nij,nj->ni", rot, s.anchor[worlds].reshape(-1, 3)) + pos
        sinking = (s.body[worlds] == body) & (s.height[worlds] - before[:, 2].reshape(-1, 4) > YIELD_SPEED * self.dt)
        applied = np.where(sinking, 0.0, np.minimum(wanted, s.load[worlds] + self.ramp))
        pos, rot = self._pose(state, w, body.reshape(-1))
        s.anchor[worlds] = np.einsum("nji,nj->ni", rot, points.reshape(-1, 3) - pos).reshape(-1, 4, 3)
        s.body[worlds], s.height[worlds], s.load[worlds] = body, points[:, :, 2], applied
        pushed = stands & f.movable[np.maximum(body, 0)] & (applied > 0.0)
        kk, foot = np.nonzero(pushed)
        w, b = worlds[kk], body[kk, foot]
        com = state.xpos[w, b] + np.einsum("nij,nj->ni", quat_to_mat(state.xquat[w, b]), f.body_com[b])
        wrench = np.zeros((len(w), 6))
        wrench[:, 2] = -applied[kk, foot]
        wrench[:, 3:] = np.cross(points[kk, foot] - com, wrench[:, :3])
        np.add.at(self.sim.xfrc_applied, (w, b), wrench)
        return worlds[(sinking & (wanted > 0.0)).any(axis=1)]

    @staticmethod
    def _pose(state: BatchState, worlds: np.ndarray, bodies: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Position (n, 3) and rotation (n, 3, 3) of ``bodies`` (n,; -1: the world's frame) in ``worlds`` (n,)."""
        b = np.maximum(bodies, 0)
        return state.xpos[worlds, b], quat_to_mat(state.xquat[worlds, b])

    @staticmethod
    def _foot_forces(
        loads: np.ndarray, points: np.ndarray, stands: np.ndarray, com: np.ndarray, body_axes: np.ndarray
    ) -> np.ndarray:
        """(k, 4) the upward forces at ``points`` (k, 4, 3) of the feet that ``stands`` that sum to the lift's force
        and whose moments about ``com`` (k, 3) are the tilt torques (about the body's y and x axes, ``body_axes``
        (k, 3, 3)): the least such forces, none negative."""
        torque = loads[:, 1, None] * body_axes[:, :, 1] + loads[:, 2, None] * body_axes[:, :, 0]
        arm = points[:, :, :2] - com[:, None, :2]
        system = np.stack([np.ones(arm.shape[:2]), arm[:, :, 1], -arm[:, :, 0]], axis=1) * stands[:, None, :]
        target = np.stack([loads[:, 0], torque[:, 0], torque[:, 1]], axis=1)
        forces = np.einsum("kfi,ki->kf", np.linalg.pinv(system), target)
        return np.maximum(forces, 0.0) * stands
