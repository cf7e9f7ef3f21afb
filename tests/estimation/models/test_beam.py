"""The beam LDV's measurement (models/beam.py): the three velocity rows become their projection on
the line of sight (H row = u^T H_vel, R = u^T R_vel u, z = u^T z_vel), the rows after them are
kept; a beam sample's deck velocity along the track keeps its projection on the beam."""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.models.base import Measurement
from alignment_core.estimation.models.beam import project_on_beam, track_velocity

RNG = np.random.default_rng(5)


def _unit(v):
    return np.asarray(v, dtype=float) / np.linalg.norm(v)


def test_projection_of_velocity_rows_and_the_rows_after_them():
    n = 16
    h = RNG.standard_normal((6, n))              # 3 velocity rows, 3 further (rate) rows
    z = RNG.standard_normal(6)
    a = RNG.standard_normal((6, 6))
    r = a @ a.T
    u = _unit([0.3, -0.9, 0.2])
    out = project_on_beam(Measurement(z, h, r), u)
    assert out.z.shape == (4,) and out.h.shape == (4, n) and out.r.shape == (4, 4)
    assert abs(out.z[0] - u @ z[:3]) < 1e-14
    np.testing.assert_allclose(out.h[0], u @ h[:3], rtol=0, atol=1e-15)
    assert abs(out.r[0, 0] - u @ r[:3, :3] @ u) < 1e-12
    np.testing.assert_array_equal(out.z[1:], z[3:])
    np.testing.assert_array_equal(out.h[1:], h[3:])
    np.testing.assert_allclose(out.r[1:, 1:], r[3:, 3:], rtol=0, atol=1e-15)
    np.testing.assert_allclose(out.r[0, 1:], u @ r[:3, 3:], rtol=0, atol=1e-12)


def test_isotropic_velocity_noise_projects_to_its_variance():
    """R_vel = (sigma_ldv^2 + sigma_master^2) I: the beam row's variance is the same sum."""
    out = project_on_beam(Measurement(np.zeros(3), np.eye(3, 15, 3), 2.0e-4 * np.eye(3)), _unit([1.0, 2.0, -2.0]))
    assert out.r.shape == (1, 1) and abs(out.r[0, 0] - 2.0e-4) < 1e-18


def test_track_velocity_keeps_the_beam_reading():
    u = _unit([-0.99, -0.1, -0.05])
    psi = 0.1
    v = track_velocity(-30.0 * u, u, psi)
    t = np.array([np.cos(psi), -np.sin(psi), 0.0])
    assert abs(float(v @ u) + 30.0) < 1e-12 and np.linalg.norm(np.cross(v, t)) < 1e-12
    across = _unit([0.1, 1.0, 0.0])                                   # 84 deg off the track
    np.testing.assert_array_equal(track_velocity(2.0 * across, across, 0.0), 2.0 * across)
