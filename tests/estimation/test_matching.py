"""The reference a master sample gives the slave (estimation/matching.py)."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.estimation.matching import reference_velocities


def test_reference_velocities_are_the_rigid_body_velocity_of_the_spot():
    """A point at lever arm r on a body turning at w_b moves at v_b + w_b x r (plus the LDV's
    relative velocity), in nav axes through C_m: against scipy's rotation matrix and numpy's
    cross product; the compiled kernel equals its interpreted form bit for bit."""
    rng = np.random.default_rng(5)
    for _ in range(50):
        q = Rotation.random(random_state=rng).as_quat()
        w_b, v_b = rng.normal(0.0, 0.05, 3), rng.normal(0.0, 10.0, 3)
        r, v_rel = rng.normal(0.0, 50.0, 3), rng.normal(0.0, 1.0, 3)
        c_m, u_n, v_ref = reference_velocities(q, w_b, v_b, r, v_rel)
        c_true = Rotation.from_quat(q).as_matrix()
        u_true = c_true @ (np.cross(w_b, r) + v_rel)
        np.testing.assert_allclose(c_m, c_true, rtol=0.0, atol=1e-15)
        np.testing.assert_allclose(u_n, u_true, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(v_ref, c_true @ v_b + u_true, rtol=0.0, atol=1e-12)
        for got, want in zip((c_m, u_n, v_ref), reference_velocities.py_func(q, w_b, v_b, r, v_rel)):
            assert got.tobytes() == want.tobytes()
