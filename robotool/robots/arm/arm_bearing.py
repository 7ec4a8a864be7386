"""What the robot's bodies bear of the objects they touch: the force their contacts put on each object, read from the
simulation's contact forces (C MuJoCo: ``mj_contactForce`` per contact; mujoco_warp: ``contact_force``, both the
solver's forces in the contact frame turned into world axes).

Only the contacts between a robot body and an object's body are read, and only in the worlds asked for (those where
the robot touches a movable object), so a scene whose gripper touches nothing pays nothing. The force on an object is
the one the robot's geom puts on it: a contact's force acts along its normal, from its first geom to its second, on
the second geom (its reaction on the first).
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from robotool.sim.backend import BatchedSim


def robot_forces(sim: BatchedSim, worlds: np.ndarray, robot: np.ndarray, owner: np.ndarray) -> np.ndarray:
    """(k, nobject, 3) N: the force the robot's bodies (``robot``: (nbody,) bool) put on each object through their
    contacts in ``worlds`` (k,) after the last step, in world axes (``owner``: each body's object, -1 for none)."""
    worlds = np.asarray(worlds, dtype=int).reshape(-1)
    out = np.zeros((len(worlds), int(owner.max(initial=-1)) + 1, 3))
    if not worlds.size or out.shape[1] == 0:
        return out
    backend: Any = sim  # the backends' own data: C MuJoCo's per-world models and datas, or mujoco_warp's batch
    if hasattr(backend, "datas"):
        for k, w in enumerate(worlds.tolist()):
            _mujoco_forces(backend.models[w], backend.datas[w], robot, owner, out[k])
        return out
    _warp_forces(backend, worlds, robot, owner, out)
    return out


def _pairs(geom_body: np.ndarray, geom: np.ndarray, robot: np.ndarray, owner: np.ndarray) -> tuple[np.ndarray, ...]:
    """Of contacts between geoms ``geom`` (n, 2): which join a robot body to an object's body, that object, and the
    sign of the force on it (+1: it is the second geom)."""
    b1, b2 = geom_body[geom[:, 0]], geom_body[geom[:, 1]]
    first = robot[b1] & ~robot[b2] & (owner[b2] >= 0)  # the robot's geom first: the force on the object is +f
    second = robot[b2] & ~robot[b1] & (owner[b1] >= 0)
    mine = np.flatnonzero(first | second)
    obj = np.where(first[mine], owner[b2[mine]], owner[b1[mine]])
    return mine, obj, np.where(first[mine], 1.0, -1.0)


def _mujoco_forces(
    model: mujoco.MjModel, data: mujoco.MjData, robot: np.ndarray, owner: np.ndarray, out: np.ndarray
) -> None:
    if not data.ncon:
        return
    con = data.contact
    mine, obj, sign = _pairs(model.geom_bodyid, con.geom, robot, owner)
    frames = con.frame.reshape(-1, 3, 3)
    wrench = np.zeros(6)
    for c, i, s in zip(mine.tolist(), obj.tolist(), sign.tolist(), strict=True):
        if con.efc_address[c] < 0:
            continue
        mujoco.mj_contactForce(model, data, c, wrench)
        out[i] += s * (wrench[:3] @ frames[c])


def _warp_forces(sim: Any, worlds: np.ndarray, robot: np.ndarray, owner: np.ndarray, out: np.ndarray) -> None:
    import mujoco_warp as mjw
    import warp as wp

    d, geom_body = sim.d, sim.scene.model.geom_bodyid
    nacon = int(d.nacon.numpy()[0])
    if not nacon:
        return
    worldid, geom = d.contact.worldid.numpy()[:nacon], d.contact.geom.numpy()[:nacon]
    row = np.full(sim.nworld, -1)
    row[worlds] = np.arange(len(worlds))
    mine, obj, sign = _pairs(geom_body, geom, robot, owner)
    keep = row[worldid[mine]] >= 0
    mine, obj, sign = mine[keep], obj[keep], sign[keep]
    if not mine.size:
        return
    with wp.ScopedDevice(sim.device):
        ids: Any = wp.array(mine.astype(np.int32), dtype=int)
        force: Any = wp.zeros(len(mine), dtype=wp.spatial_vector)
        mjw.contact_force(sim.m, d, ids, True, force)
        world_force = np.asarray(force.numpy(), dtype=float)[:, :3]
    np.add.at(out, (row[worldid[mine]], obj), sign[:, None] * world_force)
