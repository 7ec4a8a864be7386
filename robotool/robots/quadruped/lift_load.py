"""The load of the quadruped's motors and servos, put on what the feet stand on.

The lift motor (on the world-anchored z slide), the pitch and roll motors, the x-y servos and the yaw servo push the
body from the world. A real robot's legs would carry that force and those torques down to what its feet stand on, so
each tick, in every moving world where they act, their reaction is put (``xfrc_applied``) on the movable bodies under
the feet: under each foot a downward ray finds the solid within the legs' reach (a foot over a gap stands on nothing;
a cloth is limp, the load goes to what carries it: :meth:`.rays.Rays.surface`). Fixed bodies bear it without it being
applied.

The lift's force and the tilt torques go down as the least downward forces at the feet that sum to the lift's force
and balance the tilt torques about the centre of mass (none pulls up). A foot's load grows no faster than the whole
weight in :data:`LOAD_TIME`, as a leg takes it (the force is held through a control tick, and would otherwise fling a
light body), and a support that sinks away from a foot faster than :data:`YIELD_SPEED` bears nothing that tick: the
lift and the tilt motors let go there, and the body goes down with what it stood on. A board balanced on a pillar thus
tips under a robot the lift carries onto its edge, as it would under the robot's weight.

The x-y servos' force and the yaw servo's torque (the stride, a push's shove, a turn) go back as the least horizontal
forces at the feet that touch their surfaces (within :data:`TOUCH`) that sum to the opposite force and torque, each
capped at what the foot's friction passes on: its load (its leg servo's press) times the friction it grips
(:meth:`.rays.Rays.grip`: a surface too slippery to push on is not pushed). The feet on fixed ground take what they
can first; what they cannot goes to the movable bodies under the others. While the lift carries the body across an
edge the legs do not stride, and the servos' reaction is not applied. A cart on free rollers thus rolls back under a
stride, and a push made standing on it pushes it back. All are read from the actuators' force laws and the controls
just set, and held through the tick: the servos' as their mean over it (:meth:`LiftLoad.servo_loads`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np

from robotool.robots.quadruped.body import GRAVITY, BodyIds
from robotool.robots.quadruped.rays import Rays
from robotool.robots.quadruped.support import centre_of_mass, feet
from robotool.robots.quadruped.terrain import FOOT_RADIUS
from robotool.sim.backend import BatchedSim, BatchState, cross

LOAD_TIME = 0.5  # s a foot takes to put the whole weight on what it stands on (its load grows at most that fast)
YIELD_SPEED = 0.05  # m/s: a support that sinks faster than this under a foot leaves it, and bears nothing that tick
TOUCH = 0.01  # m: a foot whose bottom is at most this far above its surface pushes on it sideways
SUBSTEPS = 25  # steps the servos' mean force over a tick is read in (the simulator's)
STILL = 1.0  # N (and N m): servos pushing less than this put nothing on the feet (nor are the rays cast for them)


@dataclass(frozen=True)
class ForceLaw:
    """Some actuators' force law: an affine servo on its joint, its control and force clamped."""

    gain: np.ndarray  # (n,) force per unit of control
    bias: np.ndarray  # (n, 3) constant, per unit of joint position, per unit of joint velocity
    ctrl_range: np.ndarray  # (n, 2) the controls' range (+-inf: unlimited)
    force_range: np.ndarray  # (n, 2) the forces' range (+-inf: unlimited)

    @classmethod
    def of(cls, model: mujoco.MjModel, act: np.ndarray) -> ForceLaw:
        limited = model.actuator_ctrllimited[act].astype(bool)[:, None]
        forced = model.actuator_forcelimited[act].astype(bool)[:, None]
        unlimited = np.array([-np.inf, np.inf])
        return cls(
            gain=model.actuator_gainprm[act, 0].copy(),
            bias=model.actuator_biasprm[act, :3].copy(),
            ctrl_range=np.where(limited, model.actuator_ctrlrange[act], unlimited),
            force_range=np.where(forced, model.actuator_forcerange[act], unlimited),
        )

    def force(self, ctrl: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """(k, n) the forces at controls ``ctrl``, joint positions ``q`` and velocities ``qd`` (k, n)."""
        force = self.held(ctrl) + self.bias[:, 1] * q + self.bias[:, 2] * qd
        return np.clip(force, self.force_range[:, 0], self.force_range[:, 1])

    def held(self, ctrl: np.ndarray) -> np.ndarray:
        """(k, n) the force's terms that depend on the controls ``ctrl`` (k, n) alone (its gain and its constant)."""
        return self.gain * np.clip(ctrl, self.ctrl_range[:, 0], self.ctrl_range[:, 1]) + self.bias[:, 0]


@dataclass(frozen=True)
class MotorFacts:
    """The force laws of the lift, pitch and roll motors, of the x, y and yaw servos and of the legs' servos, and
    where the load goes."""

    motors: ForceLaw  # lift, pitch, roll
    servos: ForceLaw  # x, y, yaw
    legs: ForceLaw  # the legs' servos, feet's order
    servo_ids: np.ndarray  # (3, 3) the x, y and yaw servos' actuators, then their joints' qpos, then their qvel
    inertia: np.ndarray  # (3,) the robot's mass (kg) along x and y and its moment of inertia about its yaw (kg m2)
    movable: np.ndarray  # (nbody,) bool: the bodies a force moves (not welded to the world)
    body_com: np.ndarray  # (nbody, 3) each body's centre of mass in its own frame
    reach: float  # m below a foot's bottom that a surface bears it

    @classmethod
    def of(cls, model: mujoco.MjModel, ids: BodyIds, reach: float) -> MotorFacts:
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        full = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, full)
        dofs = np.array([*ids.qvel[:2], ids.yaw_qvel])
        return cls(
            motors=ForceLaw.of(model, ids.actuator[2:]),
            servos=ForceLaw.of(model, np.array([*ids.actuator[:2], ids.yaw_actuator])),
            legs=ForceLaw.of(model, ids.leg_actuator),
            servo_ids=np.array(
                [[*ids.actuator[:2], ids.yaw_actuator], [*ids.qpos[:2], ids.yaw_qpos], [*ids.qvel[:2], ids.yaw_qvel]]
            ),
            inertia=full[dofs, dofs],
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
    load: np.ndarray  # (nworld, 4) N: the lift's load put there

    @classmethod
    def empty(cls, nworld: int) -> LoadState:
        return cls(
            body=np.full((nworld, 4), -1),
            anchor=np.zeros((nworld, 4, 3)),
            height=np.zeros((nworld, 4)),
            load=np.zeros((nworld, 4)),
        )


class LiftLoad:
    """Puts the reaction of the lift, the tilt motors and the x-y and yaw servos on the movable bodies under the feet
    (state: :class:`LoadState`; it writes ``sim.xfrc_applied`` anew every tick)."""

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
        ids = self.ids
        return self.facts.motors.force(
            self.sim.ctrl[worlds][:, ids.actuator[2:]],
            state.qpos[worlds][:, ids.qpos[2:]],
            state.qvel[worlds][:, ids.qvel[2:]],
        )

    def servo_loads(self, state: BatchState, worlds: np.ndarray) -> np.ndarray:
        """(k, 3) the mean force (N) of the x-y servos and torque (N m) of the yaw servo on the body in ``worlds``
        through the coming tick, as the controls now set them: their law followed along the motion it gives the body
        free of anything else (:data:`SUBSTEPS` steps; sampled at the tick's start, a servo's force that falls within
        it as the body catches up with its setpoint would be held through it)."""
        from robotool.sim import servo_kernel  # Warp loads on the first tick, not on every import

        law, (act, qpos, qvel) = self.facts.servos, self.facts.servo_ids
        ctrl, q, qd = self.sim.ctrl[worlds][:, act], state.qpos[worlds][:, qpos], state.qvel[worlds][:, qvel]
        h = self.dt / SUBSTEPS
        effective = self.facts.inertia - h * law.bias[:, 2]  # the simulator's implicitfast: the damping implicit
        total = servo_kernel.summed_forces(law.held(ctrl), q, qd, law.bias, law.force_range, effective, h, SUBSTEPS)
        return total / SUBSTEPS

    def apply(self, state: BatchState, worlds: np.ndarray) -> np.ndarray:
        """Set ``xfrc_applied`` in ``worlds``: the reaction of their motors' and servos' loads on what their feet
        stand on. Returns the worlds where a support that should bear some of the lift's load sank away: the lift
        cannot carry the body on it there."""
        s, f, ids = self.state, self.facts, self.ids
        loads, servo = self.motor_loads(state, worlds), self.servo_loads(state, worlds)
        lifting = (loads[:, 0] > 0.0) | (loads[:, 1:] != 0.0).any(axis=1)
        acting = lifting | (np.abs(servo) >= STILL).any(axis=1)
        if not acting.all():
            self.clear(worlds[~acting])
            worlds, loads, servo, lifting = worlds[acting], loads[acting], servo[acting], lifting[acting]
        self.sim.xfrc_applied[worlds] = 0.0
        if not worlds.size:
            return worlds
        centres = feet(state, ids)[worlds]
        top, solid, geom, cloth = self.rays.surface(worlds, centres[:, :, :2], centres[:, :, 2].max(axis=1))
        stands = (geom >= 0) & (centres[:, :, 2] - FOOT_RADIUS - solid <= f.reach)
        points = np.concatenate([centres[:, :, :2], np.where(stands, solid, centres[:, :, 2])[:, :, None]], axis=2)
        body = np.where(stands, self.sim.scene.model.geom_bodyid[np.maximum(geom, 0)], -1)
        arm = points[:, :, :2] - centre_of_mass(state, ids)[worlds][:, None, :2]  # (k, 4, 2) from the centre of mass
        axes = state.xmat(ids.body)[worlds]
        wanted = solved_where((loads != 0.0).any(axis=1), stands.shape, self._foot_forces, loads, arm, stands, axes)
        w = np.repeat(worlds, 4)
        pos, rot = self._pose(state, w, s.body[worlds].reshape(-1))
        before = np.einsum("nij,nj->ni", rot, s.anchor[worlds].reshape(-1, 3)) + pos
        sinking = (s.body[worlds] == body) & (s.height[worlds] - before[:, 2].reshape(-1, 4) > YIELD_SPEED * self.dt)
        applied = np.where(sinking, 0.0, np.minimum(wanted, s.load[worlds] + self.ramp))
        pos, rot = self._pose(state, w, body.reshape(-1))
        s.anchor[worlds] = np.einsum("nji,nj->ni", rot, points.reshape(-1, 3) - pos).reshape(-1, 4, 3)
        s.body[worlds], s.height[worlds], s.load[worlds] = body, points[:, :, 2], applied
        touch = stands & (centres[:, :, 2] - FOOT_RADIUS - top <= TOUCH)
        press = -f.legs.force(
            self.sim.ctrl[worlds][:, ids.leg_actuator],
            state.qpos[worlds][:, ids.leg_qpos],
            state.qvel[worlds][:, ids.leg_qvel],
        )
        grip = np.maximum(press, 0.0) * self.rays.friction(worlds, self.rays.grip(geom, cloth)) * touch
        grip[lifting] = 0.0  # the lift carries the body across an edge: the legs are not striding
        movable = stands & f.movable[np.maximum(body, 0)]
        fixed, on = touch & ~movable, touch & movable  # the feet on fixed ground take what they can first
        striding = ~lifting  # (while the lift carries the body no foot grips: the forces are zeros there)
        held = solved_where(striding & fixed.any(axis=1), points.shape, self._stride_forces, servo, arm, fixed, grip)
        moment = (arm[:, :, 0] * held[:, :, 1] - arm[:, :, 1] * held[:, :, 0]).sum(axis=1)
        rest = servo + np.concatenate([held[:, :, :2].sum(axis=1), moment[:, None]], axis=1)
        sideways = solved_where(striding & on.any(axis=1), points.shape, self._stride_forces, rest, arm, on, grip)
        sideways[:, :, 2] = -applied  # with the lift's load: the forces at the feet
        self._put(state, worlds, body, points, sideways * movable[:, :, None])
        return worlds[(sinking & (wanted > 0.0)).any(axis=1)]

    def _put(
        self, state: BatchState, worlds: np.ndarray, body: np.ndarray, points: np.ndarray, force: np.ndarray
    ) -> None:
        """Add the forces ``force`` (k, 4, 3) at ``points`` (k, 4, 3) to the bodies ``body`` (k, 4) in ``worlds``, as
        forces and torques about their centres of mass."""
        kk, foot = np.nonzero((force != 0.0).any(axis=2))
        if not kk.size:  # no foot stands on a movable body (most ticks): nothing to put
            return
        w, b = worlds[kk], body[kk, foot]
        com = state.xpos[w, b] + np.einsum("nij,nj->ni", state.frames()[w, b], self.facts.body_com[b])
        push = force[kk, foot]
        np.add.at(self.sim.xfrc_applied, (w, b), np.concatenate([push, cross(points[kk, foot] - com, push)], 1))

    @staticmethod
    def _pose(state: BatchState, worlds: np.ndarray, bodies: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Position (n, 3) and rotation (n, 3, 3) of ``bodies`` (n,; -1: the world's frame) in ``worlds`` (n,)."""
        b = np.maximum(bodies, 0)
        return state.xpos[worlds, b], state.frames()[worlds, b]

    @staticmethod
    def _foot_forces(loads: np.ndarray, arm: np.ndarray, stands: np.ndarray, body_axes: np.ndarray) -> np.ndarray:
        """(k, 4) the upward forces at the feet that ``stands`` that sum to the lift's force and whose moments about
        the centre of mass (the feet at ``arm`` (k, 4, 2) from it) are the tilt torques (about the body's y and x axes,
        ``body_axes`` (k, 3, 3)): the least such forces, none negative."""
        torque = loads[:, 1, None] * body_axes[:, :, 1] + loads[:, 2, None] * body_axes[:, :, 0]
        system = np.empty((len(arm), 3, 4))
        system[:, 0], system[:, 1], system[:, 2] = stands, arm[:, :, 1] * stands, -arm[:, :, 0] * stands
        target = np.empty((len(arm), 3))
        target[:, 0], target[:, 1:] = loads[:, 0], torque[:, :2]
        forces = np.einsum("kfi,ki->kf", np.linalg.pinv(system), target)
        return np.maximum(forces, 0.0) * stands

    @staticmethod
    def _stride_forces(servo: np.ndarray, arm: np.ndarray, touch: np.ndarray, grip: np.ndarray) -> np.ndarray:
        """(k, 4, 3) the horizontal forces at the feet that ``touch`` their surfaces that sum to the opposite of the
        x-y servos' force and whose moments about the centre of mass (the feet at ``arm`` (k, 4, 2) from it) are the
        opposite of the yaw servo's torque (``servo`` (k, 3)): the least such forces, each capped at its foot's
        ``grip`` (k, 4; N)."""
        on = touch.astype(float)
        system = np.zeros((len(on), 3, 8))  # the unknowns are each foot's x then y
        system[:, 0, :4], system[:, 1, 4:] = on, on
        system[:, 2, :4], system[:, 2, 4:] = -arm[:, :, 1] * on, arm[:, :, 0] * on
        solved = np.einsum("kfi,ki->kf", np.linalg.pinv(system), -servo)
        forces = np.zeros((*on.shape, 3))
        forces[:, :, 0], forces[:, :, 1] = solved[:, :4], solved[:, 4:]
        size = np.linalg.norm(forces, axis=2)
        return forces * (np.minimum(size, grip) / np.maximum(size, 1e-9))[:, :, None]


def solved_where(
    needed: np.ndarray, shape: tuple[int, ...], solve: Callable[..., np.ndarray], *args: np.ndarray
) -> np.ndarray:
    """``solve(*args)`` (k, ...) in the rows ``needed`` (k,) alone, zeros elsewhere, where the forces it solves for
    are zeros (nothing to balance, no foot to balance it, no grip), which add nothing; but in every row where an
    argument is not finite (a NaN spreads, or fails the solver, as it would there)."""
    out = np.zeros(shape)
    rows = np.flatnonzero(needed) if all(np.isfinite(a).all() for a in args) else np.arange(len(needed))
    if rows.size:
        out[rows] = solve(*(a[rows] for a in args))
    return out
