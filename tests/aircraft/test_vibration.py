"""Nose-gear vibration (seed 000) and the IMU output mode, against closed forms.

a(t) = A e^{-t/T} sin(w t + p) from the launch on the aircraft x and z axes (T the decay).
- Point samples at t_k = k h with w h = 2 pi (100 Hz at 100 Hz): sin(2 pi k + p) = sin p, so
  the samples are the aliased, slowly decaying A e^{-t_k/T} sin p.
- Increments: int_{t0}^{t1} a dt = A [e^{-t/T} (-(1/T) sin(w t + p) - w cos(w t + p))
  / (1/T^2 + w^2)]_{t0}^{t1}.
- Velocity error of point samples vs increments after the decay:
  sum_k h A e^{-k h/T} sin p - int_0^inf a = A sin p h e^{-h/T} / (1 - e^{-h/T})
  - A (sin p / T + w cos p) / (1/T^2 + w^2); about A T sin p = 0.71 m/s for 10 m/s^2, 45 deg
  ("tens of cm/s of false velocity per 10 m/s^2 peak").
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support.ins_consistency import ATT_TOL, NOISE_OFF, VEL_TOL, integrate

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.samples import ShipBatch

A, F, T, P = 10.0, 100.0, 0.1, 45.0
W = 2.0 * np.pi * F
SHORT = {**NOISE_OFF, 'duration_s': 4.0, 'aircraft.catapult.launch_time_s': 1.0,
         'aircraft.catapult.stroke_s': 2.0}
VIB = {'aircraft.vibration.enabled': True, 'aircraft.vibration.peak_mps2': A,
       'aircraft.vibration.frequency_hz': F, 'aircraft.vibration.decay_s': T,
       'aircraft.vibration.phase_deg': P}


def run(overrides):
    sc = scenario.load('catapult_paper', {**SHORT, **overrides})
    ships = ShipBatch.of(pipeline.ship_samples(sc))
    truth, imu = pipeline.SlaveImuStage(sc).run_batch(ships)
    tau = (np.array([s.t_ns for s in imu]) - sc.t0_ns) / 1e9
    return sc, truth, imu, tau, np.array([s.accel for s in imu]), np.array([s.gyro for s in imu])


def antiderivative(t):
    p = np.deg2rad(P)
    return A * np.exp(-t / T) * (-(1 / T) * np.sin(W * t + p) - W * np.cos(W * t + p)) / (1 / T**2 + W**2)


def test_point_samples_alias_to_decaying_constant():
    _, _, _, tau, base, gb = run({'imu.output': 'sample'})
    _, _, _, _, acc, g = run({'imu.output': 'sample', **VIB})
    t = tau - 1.0
    expect = np.where(t > 1e-9, A * np.exp(-np.maximum(t, 0) / T) * np.sin(np.deg2rad(P)), 0.0)
    d = acc - base
    np.testing.assert_allclose(d[:, 0], expect, atol=1e-9)
    np.testing.assert_allclose(d[:, 2], expect, atol=1e-9)
    np.testing.assert_allclose(d[:, 1], 0.0, atol=1e-12)
    np.testing.assert_array_equal(g, gb)


def test_increments_are_exact_integrals():
    sc, _, _, tau, base, _ = run({})
    _, _, _, _, acc, _ = run(VIB)
    h = 1.0 / sc.rate_hz
    t1 = np.maximum(tau - 1.0, 0.0)
    t0 = np.maximum(tau - h - 1.0, 0.0)
    expect = antiderivative(t1) - antiderivative(t0)
    d = (acc - base) * h
    np.testing.assert_allclose(d[:, 0], expect, atol=1e-12)
    np.testing.assert_allclose(d[:, 2], expect, atol=1e-12)
    # the total is the small true velocity change A (sin p / T + w cos p) / (1/T^2 + w^2)
    p = np.deg2rad(P)
    assert d[:, 0].sum() == pytest.approx(A * (np.sin(p) / T + W * np.cos(p)) / (1 / T**2 + W**2), rel=1e-6)


def test_false_velocity_point_vs_increment():
    sc, truth, imu_s, tau, _, _ = run({'imu.output': 'sample', **VIB})
    _, _, imu_i, _, _, _ = run(VIB)
    h, p = 1.0 / sc.rate_hz, np.deg2rad(P)
    q = np.exp(-h / T)
    pred = A * np.sin(p) * h * q / (1 - q) - A * (np.sin(p) / T + W * np.cos(p)) / (1 / T**2 + W**2)
    assert 0.1 < pred < 1.0                  # tens of cm/s per 10 m/s^2
    _, vel_s = integrate(sc, truth, imu_s)
    _, vel_i = integrate(sc, truth, imu_i)
    k = int(np.flatnonzero(np.isclose(tau, 2.0))[0])     # 1 s after the launch: decayed
    # x and z of the aircraft each take pred; the norm is sqrt(2) pred; accelerometer mode
    # leaves the truth unchanged, so the increments integrate to the (vibration-free) truth
    # up to the small true integral of the disturbance (its own closed form)
    v_inc = A * (np.sin(p) / T + W * np.cos(p)) / (1 / T**2 + W**2)
    assert vel_i[k] == pytest.approx(np.sqrt(2) * v_inc, rel=0.02)
    assert vel_s[k] == pytest.approx(np.sqrt(2) * (pred + v_inc), rel=0.02)


def test_motion_mode_consistent_with_truth():
    """Real airframe vibration: increments integrate to the truth (which carries it)."""
    sc, truth, imu, tau, _, _ = run({**VIB, 'aircraft.vibration.mode': 'motion'})
    _, truth0, _, _, _, _ = run({})
    v = Rotation.from_quat(truth['q_nb']).apply(truth['v_b'])
    v0 = Rotation.from_quat(truth0['q_nb']).apply(truth0['v_b'])
    assert np.abs(v - v0).max() > 1e-2                   # the truth moves
    att, vel = integrate(sc, truth, imu)
    assert att.max() < ATT_TOL, f'attitude error {att.max():.3g} rad'
    assert vel.max() < VEL_TOL, f'velocity error {vel.max():.3g} m/s'


@pytest.mark.parametrize('extra', [{'aircraft.vibration.mode': 'motion'}, {'imu.output': 'sample'}],
                         ids=['motion', 'sample'])
def test_batch_equals_step_with_vibration(extra):
    sc = scenario.load('catapult_paper', {**SHORT, **VIB, **extra})
    ship_list = pipeline.ship_samples(sc)
    _, imu_b = pipeline.SlaveImuStage(sc).run_batch(ShipBatch.of(ship_list))
    stage = pipeline.SlaveImuStage(sc)
    out = [stage.step(s)[1] for s in ship_list][1:]
    np.testing.assert_allclose([s.accel for s in out], [s.accel for s in imu_b], rtol=0, atol=1e-10)
    np.testing.assert_allclose([s.gyro for s in out], [s.gyro for s in imu_b], rtol=0, atol=1e-14)
