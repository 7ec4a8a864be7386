"""Affine servos followed through a control tick, compiled: a Warp kernel on the CPU, one thread per servo and world.

Each servo's force (its held terms, plus its stiffness times the joint's position and its damping times the joint's
velocity, clamped to its range) drives its joint's free inertia step by step, the damping implicit as the simulator
steps it. Every product, sum and quotient rounds as numpy's elementwise operations round them, in the same order, and
without fused multiply-adds, so the forces are the same to the bit. Warp loads the first time it runs.
"""

from __future__ import annotations

import numpy as np
import warp as wp

from robotool.sim.warp_runtime import Float, Floats, Int, launch_on_cpu

wp.set_module_options({"fuse_fp": False})  # no fused multiply-adds: each product and sum rounds on its own


@wp.kernel
def _summed(
    held: Floats,
    q: Floats,
    qd: Floats,
    stiffness: Floats,
    damping: Floats,
    lo: Floats,
    hi: Floats,
    effective: Floats,
    h: Float,
    steps: Int,
    total: Floats,
):
    """One thread per servo and world, world-major (``held``, ``q``, ``qd`` and ``total`` flat over both)."""
    i = wp.tid()
    j = i % stiffness.shape[0]
    x = q[i]
    v = qd[i]
    acc = Float(0.0)
    for _step in range(steps):
        f = held[i] + stiffness[j] * x + damping[j] * v
        if f < lo[j]:  # (a NaN stays NaN, as numpy's maximum and minimum keep it)
            f = lo[j]
        if f > hi[j]:
            f = hi[j]
        acc = acc + f
        v = v + h * f / effective[j]
        x = x + v * h
    total[i] = acc


def summed_forces(
    held: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    bias: np.ndarray,
    force_range: np.ndarray,
    effective: np.ndarray,
    h: float,
    steps: int,
) -> np.ndarray:
    """(k, n) the sum of n servos' forces over ``steps`` steps of ``h`` s in k worlds, from their joints' positions
    ``q`` and velocities ``qd`` (k, n): each force is ``held`` (k, n) plus ``bias[:, 1]`` times the position plus
    ``bias[:, 2]`` times the velocity, clamped to ``force_range`` (n, 2); then the velocity gains ``h`` times the force
    over the ``effective`` inertia (n,) and the position ``h`` times the new velocity."""
    total = np.empty(np.shape(q))
    if total.size:
        per_servo = (bias[:, 1], bias[:, 2], *force_range.T, effective)
        flat = (np.ascontiguousarray(v, dtype=np.float64).reshape(-1) for v in (held, q, qd))
        servos = (np.ascontiguousarray(v, dtype=np.float64) for v in per_servo)
        launch_on_cpu(_summed, total.size, *flat, *servos, float(h), int(steps), total.reshape(-1))
    return total
