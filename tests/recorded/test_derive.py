"""Derivations against closed forms: body velocity by rotation, body rate from attitudes,
rates from increments, the IMU rate from stamps."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core.recorded import derive


def test_body_velocity_rotates_into_the_body():
    c = Rotation.from_euler('z', [[90.0]], degrees=True).as_matrix()   # nose North
    assert derive.body_velocity(c, np.array([[0.0, 5.0, 1.0]]))[0] == pytest.approx([5.0, 0.0, 1.0])


def test_body_rate_of_a_constant_rotation_is_exact():
    # C(t) = C0 exp(t w): the body rate is w, the nav-frame rate C0 w (C0 not the identity)
    t = np.arange(50) * 10_000_000
    w = np.array([0.02, -0.05, 0.1])
    c0 = Rotation.from_euler('zyx', [60.0, -20.0, 15.0], degrees=True)
    c = (c0 * Rotation.from_rotvec(np.outer(t * 1e-9, w))).as_matrix()
    assert np.max(np.abs(derive.body_rate_from_attitude(t, c) - w)) < 1e-12      # round-off: eps / dt


def test_body_rate_of_a_roll_oscillation_and_uneven_stamps():
    # roll phi = A sin(W t) about the body x axis: omega = (A W cos(W t), 0, 0)
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.integers(9_000_000, 11_000_000, 400))
    a, om = 0.1, 2 * np.pi / 8.0
    ts = t * 1e-9
    c = Rotation.from_euler('z', 30.0, degrees=True).as_matrix() @ Rotation.from_rotvec(
        np.outer(a * np.sin(om * ts), [1.0, 0, 0])).as_matrix()
    w = derive.body_rate_from_attitude(t, c)
    assert np.max(np.abs(w[:, 0] - a * om * np.cos(om * ts))) < 1e-9
    assert np.max(np.abs(w[:, 1:])) < 1e-12


def test_rates_from_increments_and_the_rate():
    t = np.array([10, 20, 30, 45]) * 1_000_000
    inc = np.array([[1e-3, 0, 0], [1e-3, 0, 0], [1e-3, 0, 0], [1.5e-3, 0, 0]])
    assert derive.rates_from_increments(t, inc)[:, 0] == pytest.approx([0.1, 0.1, 0.1, 0.1])
    assert derive.rate_hz_of(np.arange(10) * 5_000_000) == 200.0
    assert derive.rate_hz_of(np.array([0, 5_000_100, 10_000_000, 15_000_000])) == 200.0   # jitter
    assert derive.rate_hz_of(np.arange(10) * 7_000_000) == pytest.approx(1e9 / 7e6)


def test_stencils_do_not_reach_across_a_gap():
    # C(t) = C0 exp(t w): body rate w (not C0 w), w1 before a 1 s gap, w2 after; and a lone attitude
    c0 = Rotation.from_euler('zyx', [40.0, 10.0, -5.0], degrees=True)
    w1, w2 = np.array([0.02, -0.05, 0.1]), np.array([-0.3, 0.2, 0.05])
    t1 = np.arange(20) * 10_000_000
    t2 = t1[-1] + 1_000_000_000 + np.arange(20) * 10_000_000
    r1 = c0 * Rotation.from_rotvec(np.outer(t1 * 1e-9, w1))
    r2 = r1[-1] * Rotation.from_rotvec(np.outer((t2 - t1[-1]) * 1e-9, w2))
    t = np.r_[t1, t2]
    c = np.concatenate([r1.as_matrix(), r2.as_matrix()])
    w = derive.body_rate_from_attitude(t, c)
    assert np.max(np.abs(w[:20] - w1)) < 1e-12 and np.max(np.abs(w[20:] - w2)) < 1e-12
    # a lone attitude 0.5 s after the first run, 0.51 s before the second: the difference to the nearer
    lone = r1[-1] * Rotation.from_rotvec(0.5 * w1)
    t = np.r_[t1, t1[-1] + 500_000_000, t2 + 10_000_000]
    c = np.concatenate([r1.as_matrix(), lone.as_matrix()[None], r2.as_matrix()])
    assert np.max(np.abs(derive.body_rate_from_attitude(t, c)[20] - w1)) < 1e-12


def test_attitude_noise_gain_of_the_stencil():
    # white attitude noise sigma per axis, even spacing dt: inside, the rate noise is
    # sigma sqrt(1 + 64 + 64 + 1) / (12 dt) (the central 5-point derivative); at the first sample
    # (one-sided, its own noise weighted -25/12) sigma sqrt(25^2 + 48^2 + 36^2 + 16^2 + 3^2) / (12 dt)
    rng = np.random.default_rng(7)
    sigma, dt = 1e-5, 0.01
    t = np.arange(20000) * 10_000_000
    c = Rotation.from_rotvec(rng.normal(0.0, sigma, (len(t), 3))).as_matrix()
    w = derive.body_rate_from_attitude(t, c)[2:-2]
    assert np.std(w) == pytest.approx(sigma * np.sqrt(130) / (12 * dt), rel=0.03)
    first = np.array([derive.body_rate_from_attitude(t[:5], Rotation.from_rotvec(
        rng.normal(0.0, sigma, (5, 3))).as_matrix())[0] for _ in range(1500)])
    assert np.std(first) == pytest.approx(sigma * np.sqrt(4490) / (12 * dt), rel=0.05)
