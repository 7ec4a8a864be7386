"""The batched-simulator protocol, its state view, per-world perturbations, and backend selection.

Two backends implement :class:`BatchedSim` over the same :class:`~robotool.sim.compiled_scene.Scene`:
``mujoco`` (C MuJoCo, one ``MjData`` and one ``MjModel`` copy per world, stepped on a thread pool;
:mod:`robotool.sim.backend_mujoco`) and ``warp`` (mujoco_warp, one ``Data`` with ``nworld`` worlds and a
captured graph for the substeps; :mod:`robotool.sim.backend_warp`). Controllers only use what is here.
"""

from __future__ import annotations

import ctypes.util
import functools
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import mujoco
import numpy as np

from robotool.task.scene import MASS_NOISE
from robotool.vocabulary import BackendName

if TYPE_CHECKING:
    from robotool.sim.compiled_scene import Scene

TOUCH_DISTANCE = 0.002  # m: bodies whose geoms are at most this far apart are touching


@dataclass(frozen=True)
class BatchState:
    """All worlds after the last step; numpy arrays with the world index first.

    ``touching[w, a, b]`` is True when bodies ``a`` and ``b`` have geoms within
    :data:`TOUCH_DISTANCE` (symmetric). ``failed[w]`` holds a reason for worlds whose physics
    cannot be trusted (buffer overflow, divergence), else None.
    """

    time: np.ndarray  # (nworld,)
    qpos: np.ndarray  # (nworld, nq)
    qvel: np.ndarray  # (nworld, nv)
    xpos: np.ndarray  # (nworld, nbody, 3)
    xquat: np.ndarray  # (nworld, nbody, 4)
    sensordata: np.ndarray  # (nworld, nsensordata)
    eq_active: np.ndarray  # (nworld, neq) bool
    touching: np.ndarray  # (nworld, nbody, nbody) bool
    failed: list[str | None]
    _derived: dict[Any, np.ndarray] = field(default_factory=dict, init=False, repr=False, compare=False)

    def xmat(self, body: int) -> np.ndarray:
        """Rotation matrices of one body in every world, (nworld, 3, 3) (computed once per state and body;
        read-only)."""
        return self.derived(("xmat", body), lambda: self.frames()[:, body].copy())

    def frames(self) -> np.ndarray:
        """Rotation matrices of every body in every world, (nworld, nbody, 3, 3) (computed once per state;
        read-only)."""
        nworld, nbody = self.xquat.shape[:2]
        return self.derived("frames", lambda: quat_to_mat(self.xquat.reshape(-1, 4)).reshape(nworld, nbody, 3, 3))

    def derived(self, key: Any, compute: Callable[[], np.ndarray]) -> np.ndarray:
        """``compute()``, a quantity of this state that several readers share, found once per state and ``key``
        (read-only)."""
        found = self._derived.get(key)
        if found is None:
            found = self._derived[key] = compute()
            found.flags.writeable = False
        return found


def quat_to_mat(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) of unit quaternions ``q`` (n, 4), w first."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    out = np.empty((len(q), 3, 3))
    out[:, 0, 0] = 1 - 2 * (y * y + z * z)
    out[:, 0, 1] = 2 * (x * y - w * z)
    out[:, 0, 2] = 2 * (x * z + w * y)
    out[:, 1, 0] = 2 * (x * y + w * z)
    out[:, 1, 1] = 1 - 2 * (x * x + z * z)
    out[:, 1, 2] = 2 * (y * z - w * x)
    out[:, 2, 0] = 2 * (x * z - w * y)
    out[:, 2, 1] = 2 * (y * z + w * x)
    out[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return out


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The cross products of 3-vectors ``a`` and ``b`` (..., 3, broadcast), each component's two products subtracted
    as ``np.cross`` subtracts them (the same numbers to the bit, without its argument handling)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    a0, a1, a2, b0, b1, b2 = a[..., 0], a[..., 1], a[..., 2], b[..., 0], b[..., 1], b[..., 2]
    np.subtract(a1 * b2, a2 * b1, out=out[..., 0])
    np.subtract(a2 * b0, a0 * b2, out=out[..., 1])
    np.subtract(a0 * b1, a1 * b0, out=out[..., 2])
    return out


class BatchedSim(Protocol):
    """``nworld`` copies of one scene stepped together.

    ``ctrl`` (nworld, nu), ``mocap_pos`` (nworld, nmocap, 3) and ``xfrc_applied`` (nworld, nbody, 6: a force and a
    torque on each body's centre of mass, world axes) are buffers the controllers write; the backend applies them
    before each step. ``body_mass`` and ``friction_scale`` are read-only.
    """

    scene: Scene
    nworld: int
    ctrl: np.ndarray
    mocap_pos: np.ndarray
    xfrc_applied: np.ndarray
    body_mass: np.ndarray
    """(nworld, nbody) each world's body masses, perturbations included (kg)."""
    friction_scale: np.ndarray
    """(nworld,) how much each world's perturbation scales every surface's friction."""

    def state(self) -> BatchState:
        """The state after the last :meth:`step`."""

    def step(self, nstep: int, active: np.ndarray) -> None:
        """Advance by ``nstep`` physics steps; worlds where ``active`` is False may be left as they are."""

    def set_weld(self, worlds: np.ndarray, eq: int, active: bool) -> None:
        """Activate weld ``eq`` at the current relative pose of its two bodies, or deactivate it."""

    def set_geom_pos(self, worlds: np.ndarray, geom: int, pos: np.ndarray) -> None:
        """Move geom ``geom`` to ``pos`` in its body's frame in ``worlds``."""

    def weld_load(self, worlds: np.ndarray, eq: int) -> np.ndarray:
        """(k, 6) the load weld ``eq`` carries in ``worlds`` after the last step: the force (N) and the torque (N m,
        about the origin of the weld's second body) that the second body puts on the first, in world axes, from the
        weld's constraint force; zeros where the weld is off."""

    def contact_normals(self, world: int) -> np.ndarray:
        """(nbody, nbody, 3) after the last step in ``world``: for each pair of bodies that touch (geoms within
        :data:`TOUCH_DISTANCE`), the sum of their contacts' unit normals pointing from the first body to the second
        (antisymmetric); zeros for the pairs that do not touch. Which way one body presses on another."""

    def contact_forces(self, worlds: np.ndarray, first: np.ndarray) -> np.ndarray:
        """(k, nbody, 3) N after the last step in ``worlds`` (k,): the force the bodies flagged in ``first`` ((nbody,)
        bool) put on each other body through their contacts, in world axes (the solver's contact forces; zeros for
        the bodies they do not touch and for the flagged ones)."""

    def contact_points(self, world: int, first: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """After the last step in ``world``: where the bodies flagged in ``first`` ((nbody,) bool) touch the others
        (geoms within :data:`TOUCH_DISTANCE`), as contact positions (n, 3) in world axes, the other body of each (n,)
        and each contact's unit normal (n, 3; its sign as the contact list has it)."""

    def geom_poses(self, worlds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every geom's position (nworld, ngeom, 3) and rotation matrix (nworld, ngeom, 9) after the last step, current
        in ``worlds`` (the other worlds' rows may be stale); read-only."""

    def rays(
        self,
        worlds: np.ndarray,
        pnt: np.ndarray,
        vec: np.ndarray,
        exclude_body: int | np.ndarray = -1,
        skip_group: int = -1,
        from_inside: bool = False,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Cast rays (k, nray, 3) from ``pnt`` along ``vec`` in ``worlds`` (k,: each at most once) against their
        current geoms.

        Returns the distance in units of ``|vec|`` (inf where nothing is hit) and the geom hit
        (-1 where none), both (k, nray). Geoms of ``exclude_body`` (one body for every ray, or
        (k, nray): each ray's own; -1: none) and geoms in geom group ``skip_group`` are ignored. With
        ``from_inside``, a ray that starts inside a geom it may hit (not a plane; the last of several in geom order)
        meets it at distance 0, where ``mj_ray`` would meet it where it leaves it.
        """


@dataclass(frozen=True)
class Perturbation:
    """Per-world changes to the scene: friction and mass scales, and start-pose offsets.

    ``offset[w, i]`` is (dx, dy, dyaw in radians) for movable object ``i`` (zeros for fixed ones).
    """

    friction_scale: np.ndarray  # (nworld,)
    mass_scale: np.ndarray  # (nworld, nobject)
    offset: np.ndarray  # (nworld, nobject, 3)

    @classmethod
    def none(cls, scene: Scene, nworld: int) -> Perturbation:
        """No change in any world."""
        nobj = len(scene.object_names)
        return cls(np.ones(nworld), np.ones((nworld, nobj)), np.zeros((nworld, nobj, 3)))

    @classmethod
    def sample(
        cls,
        scene: Scene,
        nworld: int,
        seed: int,
        *,
        friction: float = 0.2,
        mass: float = MASS_NOISE,
        shift: float = 0.005,
        yaw_deg: float = 2.0,
    ) -> Perturbation:
        """Uniform relative friction and mass noise and small pose noise of movable objects, seeded."""
        rng = np.random.default_rng(seed)
        nobj = len(scene.object_names)
        movable = np.array([o.movable for o in scene.task.objects], dtype=float)
        offset = np.concatenate(
            [
                rng.uniform(-shift, shift, (nworld, nobj, 2)),
                rng.uniform(-1, 1, (nworld, nobj, 1)) * np.radians(yaw_deg),
            ],
            axis=2,
        )
        return cls(
            friction_scale=rng.uniform(1 - friction, 1 + friction, nworld),
            mass_scale=1 + movable * rng.uniform(-mass, mass, (nworld, nobj)),
            offset=offset * movable[None, :, None],
        )

    @classmethod
    def for_seeds(cls, scene: Scene, seeds: Sequence[int]) -> Perturbation:
        """World ``w`` perturbed from ``seeds[w]`` alone, so equal seeds give equal worlds in any batch."""
        worlds = [cls.sample(scene, 1, seed) for seed in seeds]
        return cls(
            friction_scale=np.concatenate([w.friction_scale for w in worlds]),
            mass_scale=np.concatenate([w.mass_scale for w in worlds]),
            offset=np.concatenate([w.offset for w in worlds]),
        )

    def apply_to_model(
        self,
        scene: Scene,
        model: mujoco.MjModel,
        world: int,
        *,
        friction: np.ndarray,
        mass: np.ndarray,
        inertia: np.ndarray,
    ) -> None:
        """Write world ``world``'s friction, mass and inertia into per-world model arrays."""
        friction[:, 0] = scene.model.geom_friction[:, 0] * self.friction_scale[world]
        mass[:] = scene.model.body_mass
        inertia[:] = scene.model.body_inertia
        for i, body in enumerate(scene.object_body):
            mass[body] *= self.mass_scale[world, i]
            inertia[body] *= self.mass_scale[world, i]

    def initial_qpos(self, scene: Scene) -> np.ndarray:
        """Start configurations (nworld, nq): ``qpos0`` with the movable objects' pose offsets."""
        model = scene.model
        qpos = np.tile(model.qpos0, (len(self.friction_scale), 1))
        for i, name in enumerate(scene.object_names):
            if not scene.task.objects[i].movable:
                continue
            adr = model.jnt_qposadr[model.joint(f"{name}__free").id]
            qpos[:, adr : adr + 2] += self.offset[:, i, :2]
            half = self.offset[:, i, 2] / 2
            dq = np.stack([np.cos(half), 0 * half, 0 * half, np.sin(half)], axis=1)
            for w in range(qpos.shape[0]):
                out = np.zeros(4)
                mujoco.mju_mulQuat(out, dq[w], qpos[w, adr + 3 : adr + 7])
                qpos[w, adr + 3 : adr + 7] = out
        return qpos


def weld_relpose(xpos: np.ndarray, xquat: np.ndarray, body1: int, body2: int) -> np.ndarray:
    """Weld ``eq_data`` (12 values) that holds body2 at its current pose relative to body1."""
    data = np.zeros(12)
    rot1 = np.zeros(9)
    mujoco.mju_quat2Mat(rot1, xquat[body1])
    data[3:6] = rot1.reshape(3, 3).T @ (xpos[body2] - xpos[body1])
    inv = np.zeros(4)
    mujoco.mju_negQuat(inv, xquat[body1])
    mujoco.mju_mulQuat(data[6:10], inv, xquat[body2])
    data[10] = 1.0  # torquescale
    return data


def weld_load_from_rows(rows: np.ndarray, xquat2: np.ndarray) -> np.ndarray:
    """The load (force, torque; see :meth:`BatchedSim.weld_load`) from a weld's six constraint-force rows (k, 6) and
    the orientation (k, 4) of its second body: the rows hold the force in world axes, then twice the torque in the
    second body's frame (its rotation error is a quaternion's vector part, half the angle; torquescale 1)."""
    rows = np.asarray(rows, dtype=float).reshape(-1, 6)
    torque = np.einsum("kij,kj->ki", quat_to_mat(np.asarray(xquat2, dtype=float).reshape(-1, 4)), rows[:, 3:]) / 2
    return np.concatenate([rows[:, :3], torque], axis=1)


def geom_groups(skip_group: int) -> np.ndarray:
    """The ray geom-group mask (6,) that leaves out group ``skip_group`` (-1: none left out)."""
    groups = np.ones(6, dtype=np.uint8)
    if skip_group >= 0:
        groups[skip_group] = 0
    return groups


def touching_from_contacts(
    nbody: int, geom_body: np.ndarray, world: np.ndarray, geom: np.ndarray, dist: np.ndarray, nworld: int
) -> np.ndarray:
    """(nworld, nbody, nbody) touching matrix from a flat contact list."""
    out = np.zeros((nworld, nbody, nbody), dtype=bool)
    near = dist <= TOUCH_DISTANCE
    w, b1, b2 = world[near], geom_body[geom[near, 0]], geom_body[geom[near, 1]]
    out[w, b1, b2] = True
    out[w, b2, b1] = True
    return out


def normals_from_contacts(
    nbody: int, geom_body: np.ndarray, geom: np.ndarray, dist: np.ndarray, normal: np.ndarray
) -> np.ndarray:
    """(nbody, nbody, 3) summed unit normals between touching bodies (see :meth:`BatchedSim.contact_normals`) from
    one world's contacts: geom pairs (n, 2), distances (n,) and normals from the first geom to the second (n, 3)."""
    out = np.zeros((nbody, nbody, 3))
    near = dist <= TOUCH_DISTANCE
    b1, b2, n = geom_body[geom[near, 0]], geom_body[geom[near, 1]], np.asarray(normal, dtype=float)[near]
    np.add.at(out, (b1, b2), n)
    np.add.at(out, (b2, b1), -n)
    return out


def contacts_from(geom_body: np.ndarray, geom: np.ndarray, first: np.ndarray) -> tuple[np.ndarray, ...]:
    """Of contacts between geoms ``geom`` (n, 2): those that join a body flagged in ``first`` to one that is not, that
    other body, and the sign of the contact's force on it (+1: its geom is the contact's second, which the force acts
    on; -1: the first, which bears its reaction)."""
    b1, b2 = geom_body[geom[:, 0]], geom_body[geom[:, 1]]
    onto_second, onto_first = first[b1] & ~first[b2], first[b2] & ~first[b1]
    index = np.flatnonzero(onto_second | onto_first)
    other = np.where(onto_second[index], b2[index], b1[index])
    return index, other, np.where(onto_second[index], 1.0, -1.0)


def points_from_contacts(
    geom_body: np.ndarray, geom: np.ndarray, dist: np.ndarray, pos: np.ndarray, normal: np.ndarray, first: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One world's contacts (geom pairs (n, 2), distances (n,), positions and normals (n, 3)) that join a body flagged
    in ``first`` to another, within :data:`TOUCH_DISTANCE` (see :meth:`BatchedSim.contact_points`): their positions,
    other bodies and normals."""
    near = np.flatnonzero(np.asarray(dist) <= TOUCH_DISTANCE)
    index, other, _ = contacts_from(geom_body, np.asarray(geom)[near].reshape(-1, 2), first)
    picked = near[index]
    return np.asarray(pos, dtype=float)[picked].reshape(-1, 3), other, np.asarray(normal, dtype=float)[picked]


@functools.cache
def cuda_driver_found() -> bool:
    """Whether this machine has an NVIDIA CUDA driver (without loading Warp)."""
    return ctypes.util.find_library("cuda") is not None or os.path.exists("/proc/driver/nvidia/version")


def default_backend() -> BackendName:
    """``warp`` when Warp sees a CUDA device, else ``mujoco`` (Warp is not even loaded without a driver)."""
    if not cuda_driver_found():
        return "mujoco"
    try:
        import warp as wp
    except ImportError:
        return "mujoco"
    wp.config.log_level = wp.LOG_ERROR
    wp.init()
    return "warp" if wp.get_cuda_device_count() > 0 else "mujoco"
