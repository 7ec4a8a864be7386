"""The compiled servo law (:mod:`robotool.sim.servo_kernel`) gives the forces numpy's steps give, to the bit."""

from __future__ import annotations

import numpy as np

from robotool.sim.servo_kernel import summed_forces


def _numpy_law(
    held: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    bias: np.ndarray,
    force_range: np.ndarray,
    effective: np.ndarray,
    h: float,
    steps: int,
) -> np.ndarray:
    """The servo law stepped with numpy, as the simulator steps it (the reference the kernel must match)."""
    total = np.zeros(q.shape)
    for _ in range(steps):
        force = np.minimum(np.maximum(held + bias[:, 1] * q + bias[:, 2] * qd, force_range[:, 0]), force_range[:, 1])
        total += force
        qd = qd + h * force / effective
        q = q + qd * h
    return total


def test_the_compiled_servo_law_matches_numpy_to_the_bit() -> None:
    rng = np.random.default_rng(7)
    for nworld in (1, 3, 64):
        held, q, qd = (rng.normal(0.0, s, (nworld, 3)) for s in (40.0, 0.3, 1.0))
        bias = np.stack([np.zeros(3), -rng.uniform(50, 2000, 3), -rng.uniform(1, 200, 3)], axis=1)
        force_range = np.sort(rng.normal(0.0, 60.0, (3, 2)), axis=1)
        effective = rng.uniform(5.0, 40.0, 3)
        q[0, 0] = np.nan  # a NaN stays NaN through the clamps, as numpy keeps it
        expected = _numpy_law(held, q, qd, bias, force_range, effective, 0.002, 25)
        got = summed_forces(held, q, qd, bias, force_range, effective, 0.002, 25)
        np.testing.assert_array_equal(got, expected)
        assert np.isnan(got[0, 0])
