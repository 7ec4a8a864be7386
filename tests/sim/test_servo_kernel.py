"""The compiled servo law (:mod:`robotool.sim.servo_kernel`) gives the forces numpy's steps give, to the bit."""

from __future__ import annotations

import numpy as np

from robotool.sim.servo_kernel import summed_forces

H, STEPS = 0.002, 25  # s a physics step, steps a control tick


def test_the_compiled_servo_law_matches_numpy_to_the_bit() -> None:
    rng = np.random.default_rng(7)
    for nworld in (1, 3, 64):
        held, q, qd = (rng.normal(0.0, s, (nworld, 3)) for s in (40.0, 0.3, 1.0))
        bias = np.stack([np.zeros(3), -rng.uniform(50, 2000, 3), -rng.uniform(1, 200, 3)], axis=1)
        lo, hi = np.sort(rng.normal(0.0, 60.0, (3, 2)), axis=1).T
        effective = rng.uniform(5.0, 40.0, 3)
        q[0, 0] = np.nan  # a NaN stays NaN through the clamps, as numpy keeps it
        got = summed_forces(held, q, qd, bias, np.stack([lo, hi], axis=1), effective, H, STEPS)
        expected = np.zeros(q.shape)  # the law stepped with numpy, as the simulator steps it
        for _ in range(STEPS):
            force = np.minimum(np.maximum(held + bias[:, 1] * q + bias[:, 2] * qd, lo), hi)
            expected += force
            qd = qd + H * force / effective
            q = q + qd * H
        np.testing.assert_array_equal(got, expected)
        assert np.isnan(got[0, 0])
