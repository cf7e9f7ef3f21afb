"""Seed 000's large-angle model (phi a rotation vector of any size) with EKF / UKF / CKF.

* Its continuous dynamics at a 10 deg yaw error agree with the exact nonlinear error propagation
  (nav_error_reference.py); its EKF Jacobian agrees with central differences of its propagation.
* Open loop on a 2 g stroke-like specific force with a 10 deg yaw error, velocity errors
  generated in closed form from two exact INS integrations: the nonlinear filters converge with
  consistent innovations (mean NIS ~ m = 3), while the linear KF's small-angle model cannot
  explain the along-track velocity error f (1 - cos psi) and its NIS is an order of magnitude
  too large (inconsistent), even though its attitude moves the right way.
* In the engine, closed loop on a calm sea (no heading information before the stroke), all three
  converge from a 10 deg yaw misalignment during the 2 g stroke to within 3 sigma, below 1'.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support.nav_error_reference import Point, context, error_rate, points

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.filters import (
    CubatureKalmanFilter,
    ExtendedKalmanFilter,
    KalmanFilter,
    UnscentedKalmanFilter,
)
from alignment_core.estimation.filters.base import numerical_jacobian
from alignment_core.estimation.models import Propagation
from alignment_core.estimation.models.seed000 import Seed000LargeAngle, Seed000Linear
from alignment_core.units import ARCMIN, DEG

CFG = FilterConfig(model='seed000_large_angle', algorithm='ekf')
BIG = np.array([2.0, -1.5, 10.0]) * DEG


@pytest.mark.parametrize('k', range(3))
def test_nonlinear_dynamics_match_the_exact_error_propagation_at_large_angle(k):
    p: Point = points()[k]
    h = 1e-4
    m = Seed000LargeAngle(CFG)
    dv = np.array([0.1, -0.2, 0.05])
    # the model is driven by the erroneous INS's specific force, C_est f^b
    c = context(p, h)
    c.f_n = Rotation.from_rotvec(-BIG).as_matrix() @ p.f_n
    fun, _ = m.propagator(c)
    x = np.concatenate([BIG, dv])
    rate_model = (fun(x) - x) / h
    ref = error_rate(p, phi=BIG, dv=dv)
    # neglected: d(w_en) from dV (1e-8 rad/s) and the discretisation over h (f |phi| w_in h)
    np.testing.assert_allclose(rate_model[0:3], ref['phi'], rtol=0, atol=1e-7)
    np.testing.assert_allclose(rate_model[3:6], ref['dv'], rtol=0, atol=2e-6)
    # the linear model's error at this angle is of order f (1 - cos 10 deg): ~ 1e-2 |f|
    lin = Seed000Linear(CFG).continuous(c) @ x
    assert np.max(np.abs(lin[3:6] - ref['dv'])) > 1e-3 * np.linalg.norm(p.f_n)


def test_ekf_jacobian_equals_central_differences_of_the_propagation():
    c = context(points()[1])
    fun, jac = Seed000LargeAngle(CFG).propagator(c)
    x = np.concatenate([BIG, [0.3, -0.1, 0.2]])
    np.testing.assert_allclose(jac(x), numerical_jacobian(fun, x, np.full(6, 1e-6)), rtol=1e-6, atol=1e-10)


def _open_loop(seed: int, seconds: float = 1.0):
    """Level, stationary frame (w_in = 0), f^n = 2 g horizontal + g up. The erroneous INS has
    C_est = exp(-[phi x]) C, so V_est - V = (C_est - C) f^b t = (exp(-[phi x]) - I) f^n t exactly."""
    rng = np.random.default_rng(seed)
    h, sv = 0.01, 0.01
    f_n = np.array([19.6 * np.cos(0.5), 19.6 * np.sin(0.5), 9.8])
    phi = np.array([0.3, -0.2, 10.0]) * DEG
    c_err = Rotation.from_rotvec(-phi).as_matrix()
    ctx = Propagation(c_nb=np.eye(3), f_n=c_err @ f_n, w_ie=np.zeros(3), w_en=np.zeros(3), v_n=np.zeros(3),
                      lat=0.7, height=0.0, h=h)
    fun, jac = Seed000LargeAngle(CFG).propagator(ctx)
    phi_lin = Seed000Linear(CFG).transition(ctx)
    qd = Seed000Linear(CFG).process_noise(h)
    p0 = np.diag(np.r_[DEG ** 2, DEG ** 2, (15.0 * DEG) ** 2, np.full(3, 0.01 ** 2)])
    filters = {'kf': KalmanFilter(np.zeros(6), p0), 'ekf': ExtendedKalmanFilter(np.zeros(6), p0),
               'ukf': UnscentedKalmanFilter(np.zeros(6), p0), 'ckf': CubatureKalmanFilter(np.zeros(6), p0)}
    hm = np.hstack([np.zeros((3, 3)), np.eye(3)])
    r = np.eye(3) * sv ** 2
    nis = {k: [] for k in filters}
    for k in range(1, int(round(seconds / h)) + 1):
        z = (c_err - np.eye(3)) @ f_n * (k * h) + rng.standard_normal(3) * sv
        for name, f in filters.items():
            if name == 'kf':
                f.predict(phi_lin, qd)
            else:
                f.predict_nonlinear(fun, qd, jac)
            nis[name].append(f.update(z, hm, r).nis)
    return {name: (f.x[0:3] - phi, np.sqrt(np.diag(f.P)[0:3]), float(np.mean(nis[name])))
            for name, f in filters.items()}


@pytest.mark.parametrize('seed', [1, 2])
def test_open_loop_nonlinear_filters_are_consistent_where_the_kf_is_not(seed):
    """100 updates of a 3-vector: for a consistent filter the mean NIS is chi2(300) / 100, within
    [2.3, 3.8] with probability > 0.999; starting from a 15 deg yaw prior the first few updates
    are the least accurate, so the bound used is [2, 4.5]. The KF's must exceed 20."""
    out = _open_loop(seed)
    for name in ('ekf', 'ukf', 'ckf'):
        err, sig, nis = out[name]
        assert 2.0 < nis < 4.5, (name, nis)
        assert np.all(np.abs(err) < 3.0 * sig), (name, err, sig)
        assert abs(err[2]) < 0.3 * DEG                      # from 10 deg
    assert out['kf'][2] > 20.0


@pytest.fixture(scope='module')
def calm_sea_large_yaw():
    # seed 000's filter: no known-event launch noise, the default 5 mm/s parked allowance (the
    # catapult scenario's own tuning is for the 15-state filter), and the launch taken at the first
    # LDV sample: a nonlinear model has no transition matrices for the delay-aware update, so the
    # two matches that wait for a 3-sample launch confirmation would meet the live error state
    # (known limitation, docs/engine.md; it moves these filters' tilt by ~0.1')
    ov = {'ship.sea_state': 0, 'duration_s': 10.0, 'aircraft.catapult.launch_time_s': 6.0,
          'aircraft.misalignment_arcmin': [15.0, -10.0, 600.0], 'filter.init_yaw_sigma_deg': 10.0,
          'filter.model': 'seed000_large_angle', 'filter.launch_accel_noise_mps2': 0.0,
          'filter.parked_velocity_sigma_mps': 0.005, 'filter.launch_confirm_samples': 1}
    return ov


@pytest.mark.parametrize('algorithm', ['ekf', 'ukf', 'ckf'])
def test_engine_converges_from_a_10_degree_yaw_error(calm_sea_large_yaw, algorithm):
    sc = scenario.load('catapult_paper', {**calm_sea_large_yaw, 'filter.algorithm': algorithm})
    res = pipeline.run(sc)
    t_rel = max(t.t_ns for t in res.truth if t.on_deck)
    before = [e for e in res.estimates if e.t_ns <= sc.t0_ns + 5.9e9][-1]
    e = [e for e in res.estimates if e.t_ns <= t_rel][-1]
    truth = np.array(sc.aircraft.misalignment_arcmin) * ARCMIN
    err = e.misalignment - truth
    assert before.misalignment_sigma[2] > 2.0 * DEG          # no heading information before the stroke
    assert abs(err[2]) < 3.0 * e.misalignment_sigma[2] and abs(err[2]) < 1.0 * ARCMIN
    # tilt: the 6 states have no accelerometer bias, so 100 ug tilts them by up to ~0.35' per axis
    assert np.all(np.abs(err[0:2]) < 1.0 * ARCMIN)
