"""The C MuJoCo backend: one ``MjModel`` copy and one ``MjData`` per world, stepped on a thread pool.

Each world owns a model copy because welds attach at a per-world relative pose (``eq_data``) and
perturbations change friction and mass per world. ``mj_step(m, d, nstep)`` releases the GIL, so
worker threads step disjoint chunks of worlds in parallel and gather their state into shared arrays.
After a world's masses are perturbed, its subtree masses are summed again: left at the nominal values, a perturbed
free body's subtree mass no longer matched its mass, the ``implicitfast`` integrator no longer treated its gyroscopic
forces implicitly, and an elongated object tumbling on the floor (a vase pushed off a sofa) gained energy until the
world diverged. The constraints' inverse weights stay those of the nominal model, as on the warp backend.
"""

from __future__ import annotations

import copy
import logging
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import mujoco
import numpy as np

from robotool.processes import cores
from robotool.sim import ray_cast
from robotool.sim.backend import (
    TOUCH_DISTANCE,
    BatchState,
    Perturbation,
    contacts_from,
    geom_groups,
    normals_from_contacts,
    points_from_contacts,
    weld_load_from_rows,
    weld_relpose,
)
from robotool.sim.compiled_scene import Scene

_LOG = logging.getLogger("robotool.sim")
# MuJoCo writes its warnings to MUJOCO_LOG.TXT in the working directory by default; route them to
# logging instead. Each world's warning counters still record them, and the runner fails the world.
mujoco.set_mju_user_warning(lambda message: _LOG.debug("MuJoCo: %s", message))

_WARNINGS = {
    mujoco.mjtWarning.mjWARN_BADQACC: "physics diverged (bad acceleration)",
    mujoco.mjtWarning.mjWARN_BADQVEL: "physics diverged (bad velocity)",
    mujoco.mjtWarning.mjWARN_BADQPOS: "physics diverged (bad position)",
    mujoco.mjtWarning.mjWARN_BADCTRL: "a controller produced a non-finite control",
    mujoco.mjtWarning.mjWARN_CNSTRFULL: "constraint buffer full",
    mujoco.mjtWarning.mjWARN_CONTACTFULL: "contact buffer full",
}
_EQUALITY_ROWS = {  # constraint rows of an active equality of each kind (others: searched for)
    int(mujoco.mjtEq.mjEQ_CONNECT): 3,
    int(mujoco.mjtEq.mjEQ_WELD): 6,
    int(mujoco.mjtEq.mjEQ_JOINT): 1,
    int(mujoco.mjtEq.mjEQ_TENDON): 1,
}
CHUNKS_PER_THREAD = 4  # worlds are handed out in this many chunks per thread, taken as threads free up
_WARNING_KINDS = list(_WARNINGS)
_WARNING_INDEX = np.array([int(k) for k in _WARNING_KINDS])
_NO_PAIRS = np.zeros((0, 2), dtype=np.int32)
_sharing = 1  # processes of this machine that simulate at once, this one included (see share_cores)


def share_cores(processes: int) -> None:
    """Declare this process one of ``processes`` that simulate at once on this machine (evaluator pool processes,
    test workers): each batch then steps its worlds on this process's share of the cores, at least one thread,
    instead of on every core (with every core busy, threads that wait for one cost more than they save: 15 % of a
    batch of eight legged-robot worlds on two cores)."""
    global _sharing
    _sharing = max(1, processes)


def _threads(nworld: int) -> int:
    """Threads to step ``nworld`` worlds on: this process's share of the cores, at most one a world."""
    return max(1, min(cores() // _sharing, nworld))


def subtree_masses(mass: np.ndarray, parent: np.ndarray) -> np.ndarray:
    """Each body's mass with all its descendants' (``parent``: each body's parent; parents come first)."""
    out = np.array(mass, dtype=float)
    for body in range(len(out) - 1, 0, -1):
        out[parent[body]] += out[body]
    return out


@dataclass
class _GeomPoses:
    """Each world's geom poses as its ``MjData`` holds them, copied for the ray casts (``fresh``: since the last
    step)."""

    xpos: np.ndarray  # (nworld, ngeom, 3)
    xmat: np.ndarray  # (nworld, ngeom, 9)
    fresh: np.ndarray  # (nworld,) bool

    @classmethod
    def empty(cls, nworld: int, ngeom: int) -> _GeomPoses:
        return cls(np.zeros((nworld, ngeom, 3)), np.zeros((nworld, ngeom, 9)), np.zeros(nworld, dtype=bool))


class MujocoSim:
    """:class:`~robotool.sim.backend.BatchedSim` on C MuJoCo (deterministic for a given seed)."""

    def __init__(
        self,
        scene: Scene,
        nworld: int,
        perturbation: Perturbation,
        *,
        njmax: int,
        nconmax: int,
        nthread: int | None = None,
    ):
        self.scene, self.nworld, self.njmax, self.nconmax = scene, nworld, njmax, nconmax
        self.models = [copy.copy(scene.model) for _ in range(nworld)]
        self.datas = [mujoco.MjData(m) for m in self.models]
        qpos0 = perturbation.initial_qpos(scene)
        for w, (m, d) in enumerate(zip(self.models, self.datas, strict=True)):
            perturbation.apply_to_model(scene, m, w, friction=m.geom_friction, mass=m.body_mass, inertia=m.body_inertia)
            m.body_subtreemass[:] = subtree_masses(m.body_mass, m.body_parentid)
            d.qpos[:] = qpos0[w]
            d.act[:] = scene.initial_act
            mujoco.mj_forward(m, d)
        model = scene.model
        self.body_mass = np.array([m.body_mass for m in self.models]).reshape(nworld, model.nbody)
        self.friction_scale = np.array(perturbation.friction_scale, dtype=float)
        self.ctrl = np.zeros((nworld, model.nu))
        self.mocap_pos = np.array([d.mocap_pos for d in self.datas]).reshape(nworld, model.nmocap, 3)
        self.xfrc_applied = np.zeros((nworld, model.nbody, 6))
        self._time = np.zeros(nworld)
        self._qpos = np.zeros((nworld, model.nq))
        self._qvel = np.zeros((nworld, model.nv))
        self._xpos = np.zeros((nworld, model.nbody, 3))
        self._xquat = np.zeros((nworld, model.nbody, 4))
        self._sensordata = np.zeros((nworld, model.nsensordata))
        self._eq_active = np.zeros((nworld, model.neq), dtype=bool)
        self._eq_rows = np.array([_EQUALITY_ROWS.get(int(t), -1) for t in model.eq_type], dtype=int)
        self._touching_geoms: list[np.ndarray] = [_NO_PAIRS] * nworld  # geom pairs within touching distance
        self._geom_body = model.geom_bodyid.copy()
        self._ray_geoms = ray_cast.RayGeoms.of(model)
        self._poses = _GeomPoses.empty(nworld, model.ngeom)
        self._failed: list[str | None] = [None] * nworld
        self._nthread = nthread or _threads(nworld)
        self._pool = ThreadPoolExecutor(self._nthread - 1) if self._nthread > 1 else None
        self._warnings = [d.warning.number for d in self.datas]  # views of each world's warning counters
        for w in range(nworld):
            self._eq_active[w] = self.datas[w].eq_active  # later changed only by set_weld, which keeps both
            self._gather(w)

    def _gather(self, w: int) -> None:
        d = self.datas[w]
        self._time[w] = d.time
        self._qpos[w] = d.qpos
        self._qvel[w] = d.qvel
        self._xpos[w] = d.xpos
        self._xquat[w] = d.xquat
        if self._sensordata.size:
            self._sensordata[w] = d.sensordata
        if d.ncon:  # the pairs only: the bodies' table is built for every world at once (_touching)
            con = d.contact
            self._touching_geoms[w] = con.geom[con.dist <= TOUCH_DISTANCE]
        else:
            self._touching_geoms[w] = _NO_PAIRS
        if self._failed[w] is None:
            self._failed[w] = self._failure(d, self._warnings[w])

    def _failure(self, d: mujoco.MjData, counts: np.ndarray) -> str | None:
        if counts.any() and counts[_WARNING_INDEX].any():
            return _WARNINGS[_WARNING_KINDS[int(np.flatnonzero(counts[_WARNING_INDEX])[0])]]
        if d.nefc > self.njmax:
            return f"constraint rows {d.nefc} over njmax {self.njmax}"
        if d.ncon > self.nconmax:
            return f"contacts {d.ncon} over nconmax {self.nconmax}"
        return None

    def _run(self, worlds: np.ndarray, nstep: int) -> None:
        mocap = self.mocap_pos.size > 0
        for w in worlds.tolist():
            m, d = self.models[w], self.datas[w]
            d.ctrl[:] = self.ctrl[w]
            d.xfrc_applied[:] = self.xfrc_applied[w]
            if mocap:
                d.mocap_pos[:] = self.mocap_pos[w]
            mujoco.mj_step(m, d, nstep)
            self._gather(w)

    def step(self, nstep: int, active: np.ndarray) -> None:
        """Step the active, non-failed worlds ``nstep`` times, in parallel chunks."""
        worlds = np.flatnonzero(np.asarray(active) & np.array([f is None for f in self._failed]))
        self._poses.fresh[worlds] = False
        if self._pool is None or worlds.size < 2:
            self._run(worlds, nstep)
            return
        chunks = iter(np.array_split(worlds, min(worlds.size, CHUNKS_PER_THREAD * self._nthread)))
        lock = threading.Lock()

        def drain() -> None:  # threads take chunks until none is left, so uneven worlds balance out
            while True:
                with lock:
                    chunk = next(chunks, None)
                if chunk is None:
                    return
                self._run(chunk, nstep)

        helpers = [self._pool.submit(drain) for _ in range(self._nthread - 1)]
        drain()  # the calling thread steps worlds too
        for future in helpers:
            future.result()

    def _touching(self) -> np.ndarray:
        """(nworld, nbody, nbody): which bodies touch in each world, from the geom pairs gathered after its last
        step (built here, for all worlds at once, and not per world in the stepping threads, where it held the GIL
        for most of a world's gathering)."""
        nbody = self.scene.model.nbody
        touching = np.zeros((self.nworld, nbody, nbody), dtype=bool)
        counts = [len(pairs) for pairs in self._touching_geoms]
        if sum(counts):
            world = np.repeat(np.arange(self.nworld), counts)
            bodies = self._geom_body[np.concatenate(self._touching_geoms)]
            touching[world, bodies[:, 0], bodies[:, 1]] = True
            touching[world, bodies[:, 1], bodies[:, 0]] = True
        return touching

    def state(self) -> BatchState:
        """Copies of the gathered state (safe to keep across steps)."""
        return BatchState(
            time=self._time.copy(),
            qpos=self._qpos.copy(),
            qvel=self._qvel.copy(),
            xpos=self._xpos.copy(),
            xquat=self._xquat.copy(),
            sensordata=self._sensordata.copy(),
            eq_active=self._eq_active.copy(),
            touching=self._touching(),
            failed=list(self._failed),
        )

    def set_weld(self, worlds: np.ndarray, eq: int, active: bool) -> None:
        """Attach (at the current relative pose) or detach weld ``eq`` in ``worlds``."""
        model = self.scene.model
        b1, b2 = model.eq_obj1id[eq], model.eq_obj2id[eq]
        for w in np.asarray(worlds, dtype=int).reshape(-1):
            d = self.datas[w]
            if active:
                self.models[w].eq_data[eq] = weld_relpose(d.xpos, d.xquat, b1, b2)
            d.eq_active[eq] = active
            self._eq_active[w, eq] = active

    def set_geom_pos(self, worlds: np.ndarray, geom: int, pos: np.ndarray) -> None:
        """Move geom ``geom`` in its body's frame, in each world's model copy."""
        for w in np.asarray(worlds, dtype=int).reshape(-1):
            self.models[w].geom_pos[geom] = pos

    def weld_load(self, worlds: np.ndarray, eq: int) -> np.ndarray:
        """The load weld ``eq`` carries in ``worlds`` (:meth:`BatchedSim.weld_load`), from each world's constraint
        rows: the equalities' rows come first, in order, so its rows follow those of the active equalities before it
        (checked against the rows' owner; searched for where that fails)."""
        worlds = np.asarray(worlds, dtype=int).reshape(-1)
        rows = np.zeros((len(worlds), 6))
        before = self._eq_rows[:eq]
        counted = bool((before >= 0).all())
        equality = mujoco.mjtConstraint.mjCNSTR_EQUALITY
        for k, w in enumerate(worlds.tolist()):
            if not self._eq_active[w, eq]:
                continue
            d = self.datas[w]
            start = int(before @ self._eq_active[w, :eq]) if counted else -1
            if 0 <= start <= d.nefc - 6 and d.efc_id[start] == eq and d.efc_type[start] == equality:
                rows[k] = d.efc_force[start : start + 6]
                continue
            mine = np.flatnonzero((d.efc_type == equality) & (d.efc_id == eq))
            if mine.size == 6:
                rows[k] = d.efc_force[mine]
        return weld_load_from_rows(rows, self._xquat[worlds, self.scene.model.eq_obj2id[eq]])

    def contact_normals(self, world: int) -> np.ndarray:
        """Which way touching bodies press on each other in ``world`` (:meth:`BatchedSim.contact_normals`), from its
        ``MjData``'s contacts."""
        d = self.datas[world]
        con = d.contact
        return normals_from_contacts(self.scene.model.nbody, self._geom_body, con.geom, con.dist, con.frame[:, :3])

    def contact_points(self, world: int, first: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where the bodies ``first`` touch the others in ``world`` (:meth:`BatchedSim.contact_points`), from its
        ``MjData``'s contacts."""
        con = self.datas[world].contact
        return points_from_contacts(self._geom_body, con.geom, con.dist, con.pos, con.frame[:, :3], first)

    def contact_forces(self, worlds: np.ndarray, first: np.ndarray) -> np.ndarray:
        """The force the bodies ``first`` put on the others through their contacts (:meth:`BatchedSim.contact_forces`),
        ``mj_contactForce`` on each such contact of each world's ``MjData``."""
        worlds = np.asarray(worlds, dtype=int).reshape(-1)
        out = np.zeros((len(worlds), self.scene.model.nbody, 3))
        wrench = np.zeros(6)
        for k, w in enumerate(worlds.tolist()):
            model, data = self.models[w], self.datas[w]
            con = data.contact
            index, other, sign = contacts_from(self._geom_body, con.geom, first)
            frames = con.frame.reshape(-1, 3, 3)
            for c, body, s in zip(index.tolist(), other.tolist(), sign.tolist(), strict=True):
                if con.efc_address[c] >= 0:  # (a contact beyond its margin has no force)
                    mujoco.mj_contactForce(model, data, c, wrench)
                    out[k, body] += s * (wrench[:3] @ frames[c])
        return out

    def rays(
        self,
        worlds: np.ndarray,
        pnt: np.ndarray,
        vec: np.ndarray,
        exclude_body: int | np.ndarray = -1,
        skip_group: int = -1,
        from_inside: bool = False,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Rays in ``worlds``, as ``mj_ray`` casts them (:mod:`robotool.sim.ray_cast`), all at once; distance inf and
        geom -1 where nothing is hit (0 and the geom a ray starts inside, ``from_inside``). The geoms are read where
        ``mj_ray`` reads them (each world's ``MjData``)."""
        worlds = np.asarray(worlds, dtype=int).reshape(-1)
        nray = pnt.shape[1]
        if len(pnt) != len(worlds):
            raise ValueError(f"rays for {len(pnt)} worlds in {len(worlds)} worlds")
        if not nray or not worlds.size:
            return np.full((len(worlds), nray), np.inf), np.full((len(worlds), nray), -1, dtype=int)
        per_ray = np.ndim(exclude_body) > 0
        index = self._ray_geoms.eligible(geom_groups(skip_group), -1 if per_ray else int(exclude_body))
        xpos, xmat = self.geom_poses(worlds)
        x, hit = ray_cast.cast(
            self._ray_geoms,
            index,
            xpos[worlds[:, None], index],
            xmat[worlds[:, None], index],
            np.asarray(pnt, dtype=np.float64),
            np.asarray(vec, dtype=np.float64),
            np.asarray(exclude_body) if per_ray else None,
            from_inside,
        )
        return np.where(x >= 0, x, np.inf), hit

    def geom_poses(self, worlds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every geom's position (nworld, ngeom, 3) and rotation (nworld, ngeom, 9) in the worlds asked for (the
        rest left stale), read once per step."""
        poses = self._poses
        for w in np.asarray(worlds)[~poses.fresh[worlds]].tolist():
            poses.xpos[w] = self.datas[w].geom_xpos
            poses.xmat[w] = self.datas[w].geom_xmat
            poses.fresh[w] = True
        return poses.xpos, poses.xmat

    def close(self) -> None:
        """Stop the worker threads."""
        if self._pool is not None:
            self._pool.shutdown()
