"""Slave IMU extensions. Quantisation with carried residual: every output a whole number of
LSBs, each sample's error within one LSB, the running sum within half an LSB of the truth (so
a sub-LSB input is reproduced on average, where plain rounding would lose it). Rate random
walk: the bias change over a window T has variance sigma^2 T. g-sensitivity: a gyro bias G f,
linear in the specific force. last_bias is exactly what the output carries."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.sensors.imu import ImuConfig, ImuErrorModel
from alignment_core.units import ARCSEC, DPH, G0, UG

QUIET = dict(gyro_bias_dph=0.0, accel_bias_ug=0.0, arw_dpsh=0.0, vrw_ugpshz=0.0)


def test_quantisation_within_one_lsb_and_unbiased():
    qa, qv = 0.5 * ARCSEC, 1e-3
    m = ImuErrorModel(ImuConfig(**QUIET, angle_quantum_arcsec=0.5, velocity_quantum_mps=1e-3), seed=3)
    rng = np.random.default_rng(1)
    n, h = 20000, 0.01
    dth = rng.normal(0.0, 3 * qa, (n, 3)) + 0.37 * qa
    dv = rng.normal(0.0, 5 * qv, (n, 3)) + np.array([0.0, 0.0, 9.8 * h])
    g, a = m.measure_batch(dth, dv, np.full(n, h))
    out_th, out_v = g * h, a * h
    for out, true, q in ((out_th, dth, qa), (out_v, dv, qv)):
        lsb = out / q
        np.testing.assert_allclose(lsb, np.round(lsb), atol=1e-6)           # whole LSBs
        assert np.max(np.abs(out - true)) <= q * (1 + 1e-9)                  # one LSB per sample
        run = np.cumsum(out - true, axis=0)
        assert np.max(np.abs(run)) <= 0.5 * q * (1 + 1e-6)                  # carried residual
        assert abs(np.mean(out - true)) < q / n * 1.001                      # unbiased


def test_sub_lsb_input_survives_on_average():
    q = 1e-3
    m = ImuErrorModel(ImuConfig(**QUIET, velocity_quantum_mps=q), seed=0)
    n, h = 1000, 0.01
    dv = np.tile([0.3 * q, -0.05 * q, 0.0], (n, 1))
    _, a = m.measure_batch(np.zeros((n, 3)), dv, np.full(n, h))
    # plain rounding would output 0 every time; with the carry the mean is 0.3 / -0.05 LSB
    np.testing.assert_allclose(np.mean(a * h, axis=0), [0.3 * q, -0.05 * q, 0.0], atol=q / n)


def test_rate_random_walk_variance_grows_linearly():
    sg, sa = 0.02, 1.0                           # deg/h/sqrt(s), ug/sqrt(s)
    m = ImuErrorModel(ImuConfig(**QUIET, gyro_bias_rw_dphps=sg, accel_bias_rw_ugps=sa), seed=5)
    n, h = 200_000, 1.0
    g, a = m.measure_batch(np.zeros((n, 3)), np.zeros((n, 3)), np.full(n, h))
    assert np.all(g[0] == 0.0) and np.all(a[0] == 0.0)                     # starts at zero
    for y, s in ((g, sg * DPH), (a, sa * UG)):
        for w in (1, 10, 100):
            d = (y[w::w] - y[:-w:w]).ravel()                                # non-overlapping windows
            n_win = len(d)
            assert np.var(d) / (s**2 * w * h) == pytest.approx(1.0, abs=4 * np.sqrt(2 / n_win))


def test_g_sensitivity_is_linear_in_specific_force_and_has_its_sigma():
    k = 5.0                                      # deg/h per g
    cfg = ImuConfig(**QUIET, gyro_g_sensitivity_dphpg=k)
    h = 0.01
    f1, f2 = np.array([0.0, 0.0, G0]), np.array([2 * G0, 0.0, G0])
    m = ImuErrorModel(cfg, seed=9)
    g, _ = m.measure_batch(np.zeros((3, 3)), np.array([f1, f2, f1 + f2]) * h, np.full(3, h))
    np.testing.assert_allclose(g[2], g[0] + g[1], rtol=1e-12)
    np.testing.assert_allclose(m.last_bias[:, :3], g, rtol=1e-12)
    # over 300 seeds the response to 1 g along z has 1-sigma k deg/h per axis (+-15 %)
    resp = np.array([ImuErrorModel(cfg, s).measure_batch(np.zeros((1, 3)), f1[None] * h, np.array([h]))[0][0]
                     for s in range(300)])
    assert np.std(resp) / (k * DPH) == pytest.approx(1.0, abs=0.15)


def test_last_bias_is_what_the_output_carries():
    cfg = ImuConfig(gyro_bias_dph=0.05, accel_bias_ug=200.0, arw_dpsh=0.0, vrw_ugpshz=0.0,
                    gyro_bias_instability_dph=0.02, accel_bias_instability_ug=30.0, bias_corr_time_s=5.0,
                    gyro_bias_rw_dphps=0.01, accel_bias_rw_ugps=2.0, gyro_g_sensitivity_dphpg=1.0)
    m = ImuErrorModel(cfg, seed=4)
    rng = np.random.default_rng(2)
    n, h = 500, 0.01
    dth, dv = rng.normal(0, 1e-3, (n, 3)), rng.normal(0, 0.1, (n, 3))
    g, a = m.measure_batch(dth, dv, np.full(n, h))
    np.testing.assert_allclose(g - dth / h, m.last_bias[:, :3], atol=1e-15)
    np.testing.assert_allclose(a - dv / h, m.last_bias[:, 3:], atol=1e-14)


def test_stepping_equals_batch_with_every_effect_on():
    cfg = ImuConfig(gyro_bias_instability_dph=0.02, accel_bias_instability_ug=30.0, gyro_scale_ppm=50.0,
                    accel_nonorth_arcsec=10.0, gyro_bias_rw_dphps=0.01, accel_bias_rw_ugps=2.0,
                    gyro_g_sensitivity_dphpg=1.0, angle_quantum_arcsec=0.1, velocity_quantum_mps=1e-4)
    rng = np.random.default_rng(7)
    n = 300
    dth, dv = rng.normal(0, 1e-3, (n, 3)), rng.normal(0, 0.1, (n, 3))
    h = 0.01 + 1e-5 * rng.random(n)
    gb, ab = ImuErrorModel(cfg, 8).measure_batch(dth, dv, h)
    m = ImuErrorModel(cfg, 8)
    step = [m.measure(k, dth[k], dv[k], h[k]) for k in range(n)]
    np.testing.assert_array_equal(np.array([s.gyro for s in step]), gb)
    np.testing.assert_array_equal(np.array([s.accel for s in step]), ab)


def test_new_effects_do_not_change_the_default_streams():
    base = ImuErrorModel(ImuConfig(), 5)
    other = ImuErrorModel(ImuConfig(gyro_bias_rw_dphps=0.01, gyro_g_sensitivity_dphpg=1.0,
                                    angle_quantum_arcsec=0.1), 5)
    np.testing.assert_array_equal(base.gyro_bias, other.gyro_bias)
    np.testing.assert_array_equal(base.accel_bias, other.accel_bias)
