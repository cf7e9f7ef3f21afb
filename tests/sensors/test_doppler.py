"""Doppler radar: reads the body-frame ground velocity with its modelled errors. Closed forms
on synthetic truth: level flight at constant velocity (V along x: reading
((1+k) V cos e + b)(cos(a + dD), sin(a + dD)), -(1+k) V sin e) and a coordinated turn in wind
(each error alone: scale (1+k) v; speed bias b along the horizontal track; drift-angle error a
rotation of the horizontal components only; boresight the rotation Rz(a) Ry(e) of the whole
vector); noise 1-sigma a + b |v|; own rate and latency; batch Inputs carry it when enabled."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.sensors.doppler_radar import DopplerConfig, DopplerRadarModel, DopplerStage
from alignment_core.units import ARCMIN

OFF = dict(scale_factor_ppm=0.0, bias_mps=0.0, boresight_azimuth_arcmin=0.0, boresight_pitch_arcmin=0.0,
           drift_angle_arcmin=0.0)


def test_level_flight_constant_velocity():
    cfg = DopplerConfig(enabled=True, scale_factor_ppm=1000.0, bias_mps=0.05, boresight_azimuth_arcmin=5.0,
                        boresight_pitch_arcmin=4.0, drift_angle_arcmin=3.0, noise_mps=0.02, noise_per_speed=0.001)
    m = DopplerRadarModel(cfg, seed=21)
    V = 60.0
    n = 40000
    out = m.measure_batch(np.arange(n), np.tile([V, 0.0, 0.0], (n, 1)))
    z = np.array([s.v_b for s in out])
    k, b, a, e, d = m.scale, m.bias, m.azimuth, m.pitch, m.drift
    s_h = (1 + k) * V * np.cos(e) + b
    want = np.array([s_h * np.cos(a + d), s_h * np.sin(a + d), -(1 + k) * V * np.sin(e)])
    sigma = 0.02 + 0.001 * V
    np.testing.assert_allclose(z.mean(axis=0), want, atol=4 * sigma / np.sqrt(n))
    np.testing.assert_allclose(z.std(axis=0), sigma, rtol=0.03)
    assert all(s.sigma == pytest.approx(sigma) for s in out[:5])
    # the drawn constants are of the configured size (seed 21: not all tiny)
    assert abs(k) > 1e-5 and abs(a) > 0.1 * ARCMIN


def coordinated_turn(n=600, V=60.0, rate_dps=5.4, wind=(8.0, -5.0)):
    """Body (FLU) ground velocities of a level coordinated turn in a steady wind: heading
    psi = rate t, bank atan(V rate / g), air velocity V along the body x axis."""
    t = np.arange(n) * 0.1
    rate = np.radians(rate_dps)
    psi = rate * t
    bank = np.arctan(V * rate / 9.81)
    c_nb = Rotation.from_euler('ZYX', np.c_[psi, np.zeros(n), np.full(n, -bank)])
    v_n = np.c_[V * np.cos(psi) + wind[0], V * np.sin(psi) + wind[1], np.zeros(n)]
    return c_nb.inv().apply(v_n)


@pytest.mark.parametrize('error', ['scale', 'bias', 'drift', 'boresight'])
def test_coordinated_turn_each_error_in_closed_form(error):
    v = coordinated_turn()
    assert np.ptp(v[:, 2]) > 1.0                    # banked in wind: a body-z component exists
    opts = dict(OFF)
    opts.update({'scale': dict(scale_factor_ppm=2000.0), 'bias': dict(bias_mps=0.2),
                 'drift': dict(drift_angle_arcmin=30.0),
                 'boresight': dict(boresight_azimuth_arcmin=20.0, boresight_pitch_arcmin=25.0)}[error])
    m = DopplerRadarModel(DopplerConfig(enabled=True, **opts), seed=4)
    got = m.reading(v)
    if error == 'scale':
        want = (1 + m.scale) * v
    elif error == 'bias':
        u = v[:, :2] / np.linalg.norm(v[:, :2], axis=1)[:, None]
        want = v + m.bias * np.c_[u, np.zeros(len(v))]
    elif error == 'drift':
        c, s = np.cos(m.drift), np.sin(m.drift)
        want = np.c_[c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1], v[:, 2]]
    else:
        want = Rotation.from_euler('ZY', [m.azimuth, m.pitch]).apply(v)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-10)
    assert np.max(np.abs(got - v)) > 1e-3                   # the error is really there


def test_speed_dependent_noise():
    cfg = DopplerConfig(enabled=True, **OFF, noise_mps=0.03, noise_per_speed=0.002)
    m = DopplerRadarModel(cfg, seed=1)
    for speed in (5.0, 150.0):
        v = np.tile([0.0, speed, 0.0], (20000, 1))
        z = np.array([s.v_b for s in m.measure_batch(np.arange(len(v)), v)])
        assert np.std(z - v) == pytest.approx(0.03 + 0.002 * speed, rel=0.03)


def test_rate_latency_and_batch_inputs():
    cfg = DopplerConfig(enabled=True, rate_hz=10.0, latency_s=0.05)
    t = 1_000_000_000 + np.arange(201, dtype=np.int64) * 10_000_000
    v = np.tile([60.0, 0.0, 0.0], (201, 1))
    out = DopplerStage(cfg, 3, 100.0, int(t[0])).run_batch(t, v)
    # measured every 100 ms over 2 s, stamped 50 ms later; the last one (2.05 s) never arrives
    assert [s.t_ns for s in out] == [int(t[0]) + k * 100_000_000 + 50_000_000 for k in range(20)]
    sc = scenario.load('catapult_paper', {'duration_s': 1.0})
    assert pipeline.simulate(sc).doppler is None
    sc = scenario.load('catapult_paper', {'duration_s': 1.0, 'doppler.enabled': True})
    inp = pipeline.simulate(sc)
    assert [d.t_ns for d in inp.doppler] == [sc.t0_ns + k * 100_000_000 for k in range(11)]
    # on the deck the radar sees the ship's ~10 kn plus the deck motion at the aircraft
    speed = np.linalg.norm([d.v_b for d in inp.doppler], axis=1)
    assert np.all(np.abs(speed - 5.14) < 1.5)
