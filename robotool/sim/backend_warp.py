"""The mujoco_warp backend: one ``Data`` with ``nworld`` worlds, substeps replayed from a captured graph.

Runs on Warp's ``cuda`` device when there is one, else on ``cpu`` (one thread; for development and
tests). Per-world friction, mass, inertia, weld ``eq_data`` and geom positions (sheet carriers) are
batched model fields. Controls are written in place (``assign``) so captured graphs see them. A world
whose sticky overflow flag is set (contacts or constraint rows over ``nconmax``/``njmax``) is marked failed.
"""

from __future__ import annotations

from typing import Any

import mujoco
import mujoco_warp as mjw
import numpy as np
import warp as wp

from robotool.sim import ray_cast
from robotool.sim.backend import (
    BatchState,
    Perturbation,
    contacts_from,
    geom_groups,
    normals_from_contacts,
    points_from_contacts,
    touching_from_contacts,
    weld_load_from_rows,
    weld_relpose,
)
from robotool.sim.compiled_scene import Scene
from robotool.sim.warp_runtime import init_warp

_BATCHED = ("geom_friction", "body_mass", "body_inertia", "eq_data", "geom_pos")
_OVERFLOWS = {int(f): f.name for f in mjw.OverflowType if int(f)}


class WarpSim:
    """:class:`~robotool.sim.backend.BatchedSim` on mujoco_warp."""

    def __init__(
        self,
        scene: Scene,
        nworld: int,
        perturbation: Perturbation,
        *,
        njmax: int,
        nconmax: int,
        device: str | None = None,
    ):
        init_warp()
        self.scene, self.nworld, self.njmax, self.nconmax = scene, nworld, njmax, nconmax
        self.device = device or ("cuda" if wp.get_cuda_device_count() else "cpu")
        model = scene.model
        mjd = mujoco.MjData(model)
        mjd.act[:] = scene.initial_act  # every world's, as put_data copies it
        mujoco.mj_forward(model, mjd)
        with wp.ScopedDevice(self.device):
            self.m = mjw.put_model(model, batch_sizes=dict.fromkeys(_BATCHED, nworld))
            self.m.opt.warn_overflow = 0  # overflowing worlds are reported as failed instead
            self.d = mjw.put_data(model, mjd, nworld=nworld, nconmax=nconmax, njmax=njmax)
            friction, mass, inertia = (
                self.m.geom_friction.numpy(),
                self.m.body_mass.numpy(),
                self.m.body_inertia.numpy(),
            )
            for w in range(nworld):
                perturbation.apply_to_model(scene, model, w, friction=friction[w], mass=mass[w], inertia=inertia[w])
            self.m.geom_friction.assign(friction)
            self.m.body_mass.assign(mass)
            self.m.body_inertia.assign(inertia)
            self.body_mass = mass.astype(float)
            self.friction_scale = np.array(perturbation.friction_scale, dtype=float)
            self.d.qpos.assign(perturbation.initial_qpos(scene).astype(np.float32))
            mjw.forward(self.m, self.d)
        self._eq_data = self.m.eq_data.numpy().copy()
        self._geom_pos = self.m.geom_pos.numpy().copy()
        self._eq_active = self.d.eq_active.numpy().copy()
        self.ctrl = np.zeros((nworld, model.nu))
        self.mocap_pos = np.tile(mjd.mocap_pos, (nworld, 1, 1))
        self.xfrc_applied = np.zeros((nworld, model.nbody, 6))
        self._graphs: dict[int, wp.Graph] = {}
        self._state = self._read()
        self._contacts: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None  # _contact_list
        self._geoms: tuple[np.ndarray, np.ndarray] | None = None  # the geoms' poses read back for geom_poses
        self._ray_geoms = ray_cast.RayGeoms.of(model)  # for the rays' starts inside geoms (``from_inside``)

    def _substeps(self, nstep: int) -> None:
        for _ in range(nstep):
            mjw.step(self.m, self.d)

    def step(self, nstep: int, active: np.ndarray) -> None:
        """Step every world ``nstep`` times (``active`` is ignored: the batch moves together)."""
        with wp.ScopedDevice(self.device):
            self.d.ctrl.assign(self.ctrl.astype(np.float32))
            self.d.xfrc_applied.assign(self.xfrc_applied.astype(np.float32))
            if self.scene.model.nmocap:
                self.d.mocap_pos.assign(self.mocap_pos.astype(np.float32))
            graph = self._graphs.get(nstep)
            if graph is None:
                self._substeps(nstep)  # loads the kernels; capture needs them loaded
                saved = {
                    k: getattr(self.d, k).numpy().copy() for k in ("qpos", "qvel", "act", "time", "qacc_warmstart")
                }
                with wp.ScopedCapture() as capture:
                    self._substeps(nstep)
                for key, value in saved.items():
                    getattr(self.d, key).assign(value)
                self._graphs[nstep] = graph = capture.graph
            else:
                wp.capture_launch(graph)
        self._state = self._read()
        self._contacts = self._geoms = None

    def _read(self) -> BatchState:
        d, model = self.d, self.scene.model
        nacon = int(d.nacon.numpy()[0])
        touching = touching_from_contacts(
            model.nbody,
            model.geom_bodyid,
            d.contact.worldid.numpy()[:nacon],
            d.contact.geom.numpy()[:nacon],
            d.contact.dist.numpy()[:nacon],
            self.nworld,
        )
        overflow = d.overflow.numpy()
        qpos, qvel = d.qpos.numpy().astype(float), d.qvel.numpy().astype(float)
        finite = np.isfinite(qpos).all(axis=1) & np.isfinite(qvel).all(axis=1)
        failed = [
            ("overflow: " + ", ".join(name for bit, name in _OVERFLOWS.items() if flags & bit))
            if flags
            else None
            if ok
            else "physics diverged (non-finite state)"
            for flags, ok in zip(overflow, finite, strict=True)
        ]
        return BatchState(
            time=d.time.numpy().astype(float),
            qpos=qpos,
            qvel=qvel,
            xpos=d.xpos.numpy().astype(float),
            xquat=d.xquat.numpy().astype(float),
            sensordata=d.sensordata.numpy().astype(float),
            eq_active=d.eq_active.numpy().astype(bool),
            touching=touching,
            failed=failed,
        )

    def state(self) -> BatchState:
        """The state read back after the last step."""
        return self._state

    def set_weld(self, worlds: np.ndarray, eq: int, active: bool) -> None:
        """Attach (at the current relative pose) or detach weld ``eq`` in ``worlds``."""
        model = self.scene.model
        b1, b2 = model.eq_obj1id[eq], model.eq_obj2id[eq]
        state = self._state
        for w in np.asarray(worlds, dtype=int).reshape(-1):
            if active:
                self._eq_data[w, eq] = weld_relpose(state.xpos[w], state.xquat[w], b1, b2)
            self._eq_active[w, eq] = active
            state.eq_active[w, eq] = active
        with wp.ScopedDevice(self.device):
            self.m.eq_data.assign(self._eq_data)
            self.d.eq_active.assign(self._eq_active)

    def set_geom_pos(self, worlds: np.ndarray, geom: int, pos: np.ndarray) -> None:
        """Move geom ``geom`` in its body's frame in ``worlds`` (a batched model field, written in place)."""
        self._geom_pos[np.asarray(worlds, dtype=int).reshape(-1), geom] = pos
        with wp.ScopedDevice(self.device):
            self.m.geom_pos.assign(self._geom_pos.astype(np.float32))

    def weld_load(self, worlds: np.ndarray, eq: int) -> np.ndarray:
        """The load weld ``eq`` carries in ``worlds`` (:meth:`BatchedSim.weld_load`), from the batch's constraint
        rows read back."""
        worlds = np.asarray(worlds, dtype=int).reshape(-1)
        efc = self.d.efc
        kind, owner, force = efc.type.numpy()[worlds], efc.id.numpy()[worlds], efc.force.numpy()[worlds]
        nefc = self.d.nefc.numpy()[worlds]
        rows = np.zeros((len(worlds), 6))
        for k in range(len(worlds)):
            n = min(int(nefc[k]), kind.shape[1])
            mine = np.flatnonzero((kind[k, :n] == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)) & (owner[k, :n] == eq))
            if mine.size == 6:
                rows[k] = force[k, mine]
        return weld_load_from_rows(rows, self._state.xquat[worlds, self.scene.model.eq_obj2id[eq]])

    def contact_normals(self, world: int) -> np.ndarray:
        """Which way touching bodies press on each other in ``world`` (:meth:`BatchedSim.contact_normals`), from the
        batch's contact list after the last step."""
        worldid, geom, dist, normal, _ = self._contact_list()
        mine = worldid == world
        return normals_from_contacts(
            self.scene.model.nbody, self.scene.model.geom_bodyid, geom[mine], dist[mine], normal[mine]
        )

    def contact_points(self, world: int, first: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where the bodies ``first`` touch the others in ``world`` (:meth:`BatchedSim.contact_points`), from the
        batch's contact list after the last step."""
        worldid, geom, dist, normal, pos = self._contact_list()
        mine = worldid == world
        bodies = self.scene.model.geom_bodyid
        return points_from_contacts(bodies, geom[mine], dist[mine], pos[mine], normal[mine], first)

    def _contact_list(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The batch's contacts after the last step: world, geom pair, distance, normal and position of each (read
        back once per step, whichever worlds ask)."""
        if self._contacts is None:
            contact, nacon = self.d.contact, int(self.d.nacon.numpy()[0])
            self._contacts = (
                contact.worldid.numpy()[:nacon],
                contact.geom.numpy()[:nacon],
                contact.dist.numpy()[:nacon],
                contact.frame.numpy()[:nacon][:, 0, :],
                contact.pos.numpy()[:nacon],
            )
        return self._contacts

    def contact_forces(self, worlds: np.ndarray, first: np.ndarray) -> np.ndarray:
        """The force the bodies ``first`` put on the others through their contacts (:meth:`BatchedSim.contact_forces`),
        ``mjw.contact_force`` on those contacts of the batch's list in ``worlds``, in world axes."""
        worlds = np.asarray(worlds, dtype=int).reshape(-1)
        out = np.zeros((len(worlds), self.scene.model.nbody, 3))
        nacon = int(self.d.nacon.numpy()[0])
        if not worlds.size or not nacon:
            return out
        row = np.full(self.nworld, -1)
        row[worlds] = np.arange(len(worlds))
        worldid = self.d.contact.worldid.numpy()[:nacon]
        index, other, sign = contacts_from(self.scene.model.geom_bodyid, self.d.contact.geom.numpy()[:nacon], first)
        asked = row[worldid[index]] >= 0
        index, other, sign = index[asked], other[asked], sign[asked]
        if not index.size:
            return out
        with wp.ScopedDevice(self.device):
            force: Any = wp.zeros(len(index), dtype=wp.spatial_vector)  # (a force, then a torque, per contact)
            mjw.contact_force(self.m, self.d, wp.array(index.astype(np.int32), dtype=int), True, force)
            world_force = np.asarray(force.numpy(), dtype=np.float64)[:, :3]
        np.add.at(out, (row[worldid[index]], other), sign[:, None] * world_force)
        return out

    def geom_poses(self, worlds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every geom's position and rotation matrix in every world (:meth:`BatchedSim.geom_poses`), read back once
        per step."""
        if self._geoms is None:
            nworld, ngeom = self.nworld, self.scene.model.ngeom
            self._geoms = (
                self.d.geom_xpos.numpy().astype(float).reshape(nworld, ngeom, 3),
                self.d.geom_xmat.numpy().astype(float).reshape(nworld, ngeom, 9),
            )
        return self._geoms

    def rays(
        self,
        worlds: np.ndarray,
        pnt: np.ndarray,
        vec: np.ndarray,
        exclude_body: int | np.ndarray = -1,
        skip_group: int = -1,
        from_inside: bool = False,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Rays in ``worlds`` with ``mjw.rays`` (cast in every world, the others' from the origin down, and read back
        for ``worlds``); distance inf and geom -1 where nothing is hit. Rays that leave out bodies of their own
        (``exclude_body`` (k, nray)) are cast once per body left out. With ``from_inside``, the rays' starts are
        tested against the geoms (:func:`~robotool.sim.ray_cast.inside`, on the CPU) and those that start inside
        one meet it at distance 0."""
        worlds = np.asarray(worlds, dtype=int).reshape(-1)
        nray = pnt.shape[1]
        if len(pnt) != len(worlds):
            raise ValueError(f"rays for {len(pnt)} worlds in {len(worlds)} worlds")
        if len(np.unique(worlds)) != len(worlds):  # one batch of rays per world: a second would overwrite the first
            raise ValueError(f"worlds {worlds.tolist()} name a world twice")
        start, direction = np.zeros((self.nworld, nray, 3)), np.zeros((self.nworld, nray, 3))
        direction[..., 2] = -1.0  # the other worlds' rays: from the origin, down (read back for none)
        start[worlds], direction[worlds] = pnt, vec
        if np.ndim(exclude_body) == 0:
            d, g = (a[worlds] for a in self._rays(start, direction, int(exclude_body), skip_group))
        else:
            exclude = np.asarray(exclude_body)
            d, g = np.zeros((len(worlds), nray)), np.zeros((len(worlds), nray), dtype=int)
            for body in np.unique(exclude):
                mine = exclude == body
                d_body, g_body = (a[worlds] for a in self._rays(start, direction, int(body), skip_group))
                d[mine], g[mine] = d_body[mine], g_body[mine]
        miss = d < 0
        dist, geom = np.where(miss, np.inf, d), np.where(miss, -1, g)
        if from_inside:
            candidates = self._ray_geoms.eligible(geom_groups(skip_group), -1)
            xpos, xmat = self.geom_poses(worlds)
            rows = worlds[:, None]
            left_out = np.broadcast_to(np.asarray(exclude_body), pnt.shape[:2])
            within = ray_cast.inside(
                self._ray_geoms, candidates, xpos[rows, candidates], xmat[rows, candidates], pnt, left_out
            )
            dist[within >= 0], geom[within >= 0] = 0.0, within[within >= 0]
        return dist, geom

    def _rays(
        self, start: np.ndarray, vec: np.ndarray, exclude_body: int, skip_group: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """``mjw.rays`` read back: distances (negative: nothing hit) and geoms."""
        nworld, nray = start.shape[:2]
        with wp.ScopedDevice(self.device):
            dist = wp.zeros((nworld, nray), dtype=float)
            geom = wp.zeros((nworld, nray), dtype=int)
            normal = wp.zeros((nworld, nray), dtype=wp.vec3)
            groups = wp.types.vector(6, wp.float32)(*(-1 if g else 0 for g in geom_groups(skip_group)))
            mjw.rays(
                self.m,
                self.d,
                wp.array(start.astype(np.float32), dtype=wp.vec3),
                wp.array(vec.astype(np.float32), dtype=wp.vec3),
                groups,
                True,
                wp.full(nray, exclude_body, dtype=int),
                dist,
                geom,
                normal,
            )
        return dist.numpy().astype(float), geom.numpy().astype(int)
