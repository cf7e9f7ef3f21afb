"""Slave IMU error extensions: Allan deviation of the output recovers the angle and velocity
random walk and the Gauss-Markov bias instability (sigma_b, known correlation time Tc) within
10 %, by a least-squares fit of AVAR(tau) = N^2 / tau + sigma_b^2 g(tau), with the first-order
Markov AVAR g(tau) = (2 Tc / tau) [1 - Tc / (2 tau) (3 - 4 e^{-tau/Tc} + e^{-2 tau/Tc})].
Scale factor and non-orthogonality act as (I + S) on the ideal increments; defaults draw
nothing new (the existing 'slave_imu' stream is unchanged)."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.sensors.imu import ImuConfig, ImuErrorModel
from alignment_core.units import DPH, UG


def avar(y, h, ms):
    th = np.r_[0.0, np.cumsum(y * h)]
    out = []
    for m in ms:
        d = th[2 * m:] - 2 * th[m:-m] + th[:-2 * m]
        out.append(np.mean(d**2) / (2 * (m * h) ** 2))
    return np.array(out)


def gm_avar(tau, tc):
    x = tau / tc
    return (2 * tc / tau) * (1 - (3 - 4 * np.exp(-x) + np.exp(-2 * x)) / (2 * x))


def test_allan_recovers_arw_vrw_bias_instability():
    tc, h, n = 10.0, 0.1, 200_000
    cfg = ImuConfig(gyro_bias_dph=0.0, accel_bias_ug=0.0, arw_dpsh=0.002, vrw_ugpshz=20.0,
                    gyro_bias_instability_dph=0.05, accel_bias_instability_ug=50.0, bias_corr_time_s=tc)
    model = ImuErrorModel(cfg, seed=11)
    hh = np.full(n, h)
    z = np.zeros((n, 3))
    g, a = model.measure_batch(z, z, hh)
    ms = np.unique(np.round(np.logspace(1, np.log10(2000), 25)).astype(int))
    tau = ms * h
    design = np.c_[1 / tau, gm_avar(tau, tc)]
    for y, white, bi in ((g, cfg.arw, cfg.gyro_bias_instability_dph * DPH),
                         (a, cfg.vrw, cfg.accel_bias_instability_ug * UG)):
        for ax in range(3):
            av = avar(y[:, ax], h, ms)
            w = 1 / av                                     # relative-error weighting
            coef, *_ = np.linalg.lstsq(design * w[:, None], av * w, rcond=None)
            assert np.sqrt(coef[0]) == pytest.approx(white, rel=0.1)
            assert np.sqrt(coef[1]) == pytest.approx(bi, rel=0.1)


def test_scale_factor_and_nonorthogonality():
    cfg = ImuConfig(gyro_bias_dph=0.0, accel_bias_ug=0.0, arw_dpsh=0.0, vrw_ugpshz=0.0,
                    gyro_scale_ppm=100.0, accel_scale_ppm=200.0, gyro_nonorth_arcsec=10.0,
                    accel_nonorth_arcsec=20.0)
    m = ImuErrorModel(cfg, seed=2)
    dth = np.array([[0.01, -0.02, 0.03]])
    dv = np.array([[0.1, 0.05, -0.098]])
    g, a = m.measure_batch(dth, dv, np.array([0.01]))
    np.testing.assert_allclose(g[0] * 0.01, m.scale[0] @ dth[0], rtol=1e-12)
    np.testing.assert_allclose(a[0] * 0.01, m.scale[1] @ dv[0], rtol=1e-12)
    s = m.scale - np.eye(3)
    assert 0 < np.abs(np.diag(s[1])).max() < 1e-3 and np.abs(s[0]).max() > 0


def test_defaults_leave_stream_unchanged():
    base = ImuErrorModel(ImuConfig(), 5)
    assert base.gm is None and base.scale is None
    z = np.zeros((10, 3))
    g1, a1 = base.measure_batch(z, z, np.full(10, 0.01))
    other = ImuErrorModel(ImuConfig(gyro_bias_instability_dph=0.01, gyro_scale_ppm=1.0), 5)
    np.testing.assert_array_equal(base.gyro_bias, other.gyro_bias)
    g2, _ = other.measure_batch(z, z, np.full(10, 0.01))
    # the white noise and constant biases are the same draws; only the new terms differ
    assert np.abs(g2 - g1).max() < 1e-6
