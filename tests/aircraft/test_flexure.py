"""Deck flexure: the second-order Gauss-Markov process has the configured variance and
correlation time (its autocorrelation sigma^2 e^{-beta t} (1 + beta t), beta = 2.146/tau,
is 1/e of sigma^2 at t = tau), and the aircraft truth with flexure stays consistent with its
ideal increments (strapdown from the true initial state)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support.ins_consistency import ATT_TOL, NOISE_OFF, VEL_TOL, integrate

from alignment_core import pipeline
from alignment_core.aircraft.deck_flexure import FlexureConfig, FlexureProcess
from alignment_core.config import scenario
from alignment_core.gauss_markov import gm2_discrete
from alignment_core.samples import ShipBatch
from alignment_core.units import ARCMIN

FLEX = {'aircraft.flexure.enabled': True}


def acf(x, nlag):
    x = x - x.mean()
    n = len(x)
    f = np.fft.rfft(x, 2 * n)
    r = np.fft.irfft(f * np.conj(f))[:nlag] / (n - np.arange(nlag))
    return r


def corr_time(r, dt):
    rho = r / r[0]
    j = int(np.flatnonzero(rho < np.exp(-1.0))[0])
    return dt * (j - 1 + (rho[j - 1] - np.exp(-1.0)) / (rho[j - 1] - rho[j]))


@pytest.mark.parametrize('sigma,tau', [(3.0, 3.0), (5.0, 1.0)])
def test_variance_and_correlation_time(sigma, tau):
    rate = 10.0
    proc = FlexureProcess(FlexureConfig(enabled=True, sigma_arcmin=sigma, tau_s=tau, static_arcmin=0.0),
                          seed=7, rate_hz=rate)
    th, thd = proc.generate(300_000)                      # 30000 s, about 10^4 tau
    th = th / ARCMIN
    for ax in range(3):
        assert np.std(th[:, ax]) == pytest.approx(sigma, rel=0.1)
        r = acf(th[:, ax], int(5 * tau * rate))
        assert corr_time(r, 1 / rate) == pytest.approx(tau, rel=0.1)
    beta = 2.146 / tau
    assert np.std(thd / ARCMIN) == pytest.approx(beta * sigma, rel=0.1)


def test_double_peak_and_static():
    proc = FlexureProcess(FlexureConfig(enabled=True, sigma_arcmin=3.0, tau_s=5.0, sigma2_arcmin=2.0,
                                        tau2_s=0.5, static_arcmin=3.0), seed=3, rate_hz=10.0)
    th, _ = proc.generate(200_000)
    dyn = (th - proc.static) / ARCMIN
    assert np.var(dyn) == pytest.approx(3.0**2 + 2.0**2, rel=0.1)
    assert np.all(np.abs(proc.static) > 0) and np.all(np.abs(proc.static / ARCMIN) < 15.0)


def test_van_loan_matches_stationary_lyapunov():
    phi, qd, p = gm2_discrete(1.0, 3.0, 0.01)
    np.testing.assert_allclose(phi @ p @ phi.T + qd, p, rtol=1e-9, atol=1e-12)


def test_increments_consistent_with_flexed_truth_300s():
    sc = scenario.load('deck_paper', {**NOISE_OFF, **FLEX, 'ship.sea_state': 5, 'duration_s': 300.0,
                                'aircraft.lever_arm_m': [60.0, -15.0, 20.0]})
    ships = ShipBatch.of(pipeline.ship_samples(sc))
    stage = pipeline.SlaveImuStage(sc)
    truth, imu = stage.run_batch(ships)
    # the truth attitude is the ship's times exp(mu) exp(theta_k); the run's flexure from a fresh
    # stage of the same scenario (the run keeps only its recent rows)
    th, _ = pipeline.SlaveImuStage(sc).kin.flex.generate(len(ships))
    mu = np.asarray(sc.aircraft.misalignment_arcmin) * ARCMIN
    rel = (Rotation.from_rotvec(mu) * Rotation.from_rotvec(th)).as_matrix()
    got = Rotation.from_quat(ships.q_nb).inv() * Rotation.from_quat(truth['q_nb'])
    np.testing.assert_allclose(got.as_matrix(), rel, atol=1e-12)
    assert np.abs(th - stage.kin.flex.static).max() > 2 * ARCMIN    # it really flexes
    att, vel = integrate(sc, truth, imu)
    assert att.max() < ATT_TOL, f'attitude error {att.max():.3g} rad'
    assert vel.max() < VEL_TOL, f'velocity error {vel.max():.3g} m/s'


def test_catapult_with_flexure_and_vibration():
    sc = scenario.load('catapult_paper', {**NOISE_OFF, **FLEX, 'duration_s': 4.0,
                                    'aircraft.catapult.launch_time_s': 1.0, 'aircraft.catapult.stroke_s': 2.0,
                                    'aircraft.vibration.enabled': True, 'aircraft.vibration.mode': 'motion'})
    ship_list = pipeline.ship_samples(sc)
    truth, imu = pipeline.SlaveImuStage(sc).run_batch(ShipBatch.of(ship_list))
    att, vel = integrate(sc, truth, imu)
    assert att.max() < ATT_TOL and vel.max() < VEL_TOL, (att.max(), vel.max())
    stage = pipeline.SlaveImuStage(sc)
    out = [stage.step(s) for s in ship_list]
    np.testing.assert_allclose([o[0].q_nb for o in out], truth['q_nb'], atol=1e-15)
    np.testing.assert_allclose([o[1].accel for o in out[1:]], [s.accel for s in imu], rtol=0, atol=1e-10)
    np.testing.assert_allclose([o[1].gyro for o in out[1:]], [s.gyro for s in imu], rtol=0, atol=1e-14)


def test_truth_misalignment_is_the_mounting_plus_the_flexure():
    """The truth is the IMU's attitude relative to the master's: the mounting turned by the deck's
    flexure (static 3' and dynamic 3' 1-sigma per axis by default): off the mounting by
    arcminutes, within 5 sigma of both."""
    sc = scenario.load('catapult_paper', {**FLEX, 'duration_s': 1.0})
    res = pipeline.run(sc)
    mu = np.asarray(sc.aircraft.misalignment_arcmin) * ARCMIN
    off = np.array([t.misalignment for t in res.truth if t.on_deck]) - mu
    flex = sc.aircraft.flexure
    assert np.max(np.abs(off)) > 0.1 * ARCMIN
    assert np.max(np.abs(off)) < 5 * np.hypot(flex.static_arcmin, flex.sigma_arcmin) * ARCMIN


def test_reading_the_process_in_pieces_gives_the_same_samples_as_at_once():
    """The node reads the flexure a sample at a time, the batch all at once: the recursion's
    chunks (its noise drawn a block at a time) must not show in the samples."""
    cfg = FlexureConfig(enabled=True, sigma_arcmin=3.0, tau_s=5.0, sigma2_arcmin=2.0, tau2_s=0.5,
                        change_at_s=40.0, change_factor=2.0)
    whole = FlexureProcess(cfg, seed=5, rate_hz=100.0).generate(9000)
    pieces = FlexureProcess(cfg, seed=5, rate_hz=100.0)
    parts = [pieces.at(np.arange(a, min(a + 37, 9000))) for a in range(0, 9000, 37)]
    for i in range(2):
        np.testing.assert_array_equal(np.concatenate([p[i] for p in parts]), whole[i])


def test_the_compiled_recursion_is_the_numpy_loop_bit_for_bit():
    """deck_flexure._propagate against the loop it replaced, x <- x @ phi_t + noise_j @ L^T in
    numpy, step by step, for two processes: the same numbers to the last bit."""
    from alignment_core.aircraft.deck_flexure import _propagate
    rng = np.random.default_rng(4)
    x0 = rng.standard_normal((2, 3, 2))
    phi_t = np.stack([gm2_discrete(1.0, 5.0, 0.01)[0].T, gm2_discrete(2.0, 0.5, 0.01)[0].T])
    l_t = rng.standard_normal((2, 2, 2)) * 1e-3
    noise = rng.standard_normal((50, 2, 3, 2))
    x, expected = x0.copy(), []
    for j in range(50):
        x = x @ phi_t + noise[j] @ l_t
        expected.append(x)
    np.testing.assert_array_equal(_propagate(x0, phi_t, noise @ l_t), np.array(expected))
