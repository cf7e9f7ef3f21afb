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
    t = np.arange(50) * 10_000_000
    w = np.array([0.02, -0.05, 0.1])
    c = Rotation.from_rotvec(np.outer(t * 1e-9, w)).as_matrix()
    assert np.max(np.abs(derive.body_rate_from_attitude(t, c) - w)) < 1e-14


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
