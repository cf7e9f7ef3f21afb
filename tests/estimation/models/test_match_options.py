"""The matching options any model may take where physics allows (models/rate_matching.py,
master_delay.py, yaw_matching.py): their measurement rows against the geometry written out here,
and what each buys in the engine against a truth the simulation sets (a master latency the
filter is not told, a rigidly mounted aircraft on a rolling deck)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support.nav_error_reference import expm_so3

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.models import Corrections, Match
from alignment_core.estimation.models.base import RateInputs
from alignment_core.estimation.models.master_delay import MasterDelayState
from alignment_core.estimation.models.rate_matching import RateMatching
from alignment_core.estimation.models.seed003 import Seed003VelocityAttitude
from alignment_core.estimation.models.velocity_matching import VelocityMatching
from alignment_core.estimation.models.yaw_matching import YawMatching
from alignment_core.navigation.strapdown import NavState
from alignment_core.units import ARCMIN, DPH
from alignment_core.validation import ConfigError
from alignment_experiments.monte_carlo import RunSpec, run_one

C_M = Rotation.from_euler('ZYX', [33.0, 2.5, -4.0], degrees=True).as_matrix()   # true ship attitude
MU = np.array([15.0, -10.0, -30.0]) * ARCMIN                                      # true mounting
W_M = np.array([0.02, -0.03, 0.01])        # ship body rate w.r.t. nav, rad/s
W_IN = np.array([0.0, 5.2e-5, 5.6e-5])     # Earth + transport rate, nav axes
H = 0.01


def _rate_z(phi, eps, phi_m, theta_dot, model):
    """The rate measurement from its definition. Truth: the nav frame is held still and the ship
    turns at the constant inertial rate Omega = C_m w_m + w_in, so the aircraft (C_a = C_m
    exp(mu)) has the constant body rate C_a^T Omega, the same at every instant of the interval;
    its gyros add eps and the flexure rate. The filter knows C_a,est = exp(-[phi x]) C_a at the
    interval's end and the master's C_m,est = exp(-[phi_m x]) C_m."""
    omega = C_M @ W_M + W_IN
    c_a_end = expm_so3(omega * H / 2) @ C_M @ expm_so3(MU)        # the attitude at the interval's end
    w_true = c_a_end.T @ omega
    w_meas = w_true + eps + theta_dot
    c_a_est = expm_so3(-phi) @ c_a_end
    c_m_est = expm_so3(-phi_m) @ C_M
    w_n = c_m_est @ W_M
    rate = RateInputs(w_b=w_meas, dtheta=w_meas * H, omega_n=w_n + W_IN, w_n=w_n, w_dot_n=np.zeros(3), h=H)
    m = Match(c_m=c_m_est, w_m=W_M, r=np.zeros(3), u_n=np.zeros(3), v_ref=np.zeros(3), z_vel=np.zeros(3),
              r_vel=np.eye(3) * 1e-4, ins=NavState(q_nb=Rotation.from_matrix(c_a_est).as_quat(), v_n=np.zeros(3),
                                                   lat=0.7, lon=2.0, h=0.0), rate=rate)
    meas = model.measurement(m, Corrections())
    return meas.z[-3:], meas.h[-3:]


@pytest.mark.parametrize('base', ['vm15', 'seed003_24'])
def test_rate_rows_vanish_on_the_truth_and_h_is_the_derivative(base):
    cfg = FilterConfig(model=base)
    b = VelocityMatching(cfg, True) if base == 'vm15' else Seed003VelocityAttitude(cfg, True)
    model = RateMatching(b, arw=1e-6, sigma_w=1.0 * DPH)
    zero = {k: np.zeros(3) for k in ('phi', 'eps', 'phi_m', 'theta_dot')}
    z0, h = _rate_z(model=model, **zero)
    # limit: no error anywhere -> the gyros read exactly the predicted rate (mid-interval attitude)
    np.testing.assert_allclose(z0, 0.0, atol=1e-15)   # round-off of 0.04 rad/s
    cols = {'phi': model.i_phi, 'eps': model.i_eps, 'phi_m': model.i_phi_m, 'theta_dot': model.i_theta_dot}
    d = 1e-6
    for name, i in cols.items():
        if i is None:              # vm15 has no flexure rate: the truth's would be unmodelled
            continue
        num = np.stack([(_rate_z(model=model, **{**zero, name: d * e})[0]
                         - _rate_z(model=model, **{**zero, name: -d * e})[0]) / (2 * d) for e in np.eye(3)], axis=1)
        # exact to the neglected second order of the interval's rotation, (|Omega| h)^2 = 1.6e-7
        np.testing.assert_allclose(h[:, i:i + 3], num, rtol=1e-6, atol=2e-7 * np.abs(num).max())
    assert (model.i_theta_dot is None) == (base == 'vm15')


def test_delay_column_is_the_reference_rate_of_change():
    """dz/d(dt) for velocity + attitude + rate rows: the reference quantity reported dt late is
    q(t - dt), so z gains q' dt; q' written out: the spot acceleration, the master attitude's
    rotation (as phi_m = w_n dt, entering seed 003's rows as -phi_m) and the rate change."""
    cfg = FilterConfig(model='seed003_21')
    model = MasterDelayState(RateMatching(Seed003VelocityAttitude(cfg, False), 1e-6, 1e-5), 0.02)
    a_n, w_n, w_dot = np.array([0.3, -0.2, 0.1]), C_M @ W_M, np.array([1e-3, -2e-3, 5e-4])
    c_a = C_M @ expm_so3(MU)
    rate = RateInputs(w_b=c_a.T @ (w_n + W_IN), dtheta=np.zeros(3), omega_n=w_n + W_IN, w_n=w_n, w_dot_n=w_dot, h=H)
    m = Match(c_m=C_M, w_m=W_M, r=np.zeros(3), u_n=np.zeros(3), v_ref=np.zeros(3), z_vel=np.zeros(3),
              r_vel=np.eye(3) * 1e-4, ins=NavState(q_nb=Rotation.from_matrix(c_a).as_quat(), v_n=np.zeros(3),
                                                   lat=0.7, lon=2.0, h=0.0), w_n=w_n, a_n=a_n, rate=rate)
    h = model.measurement(m, Corrections(mu=MU)).h
    assert h.shape == (9, 22) and model.labels[-1] == 'dt_master'
    np.testing.assert_allclose(h[:, -1], np.concatenate([a_n, -w_n, c_a.T @ w_dot]), rtol=1e-12, atol=1e-18)


def test_appended_constants_propagate_as_the_identity_however_nested():
    """Random constants appended to a model (lever arm on master delay on vm15, the deck's stack)
    have dx' = 0 and no coupling: Phi is the base's Phi with an identity block, exactly."""
    from alignment_core.estimation.models import Propagation
    from alignment_core.estimation.models.lever_arm import LeverArmStates
    cfg = FilterConfig(model='vm15')
    base = VelocityMatching(cfg, True)
    model = LeverArmStates(MasterDelayState(base, 0.02), 1.0)
    p = Propagation(C_M, np.array([0.2, -0.1, 9.8]), W_IN, np.array([1e-6, 2e-6, 0.0]), np.array([0.1, 5.0, 0.0]),
                    0.7, 10.0, H)
    phi = model.transition(p)
    assert phi.shape == (19, 19)
    assert np.array_equal(phi[:15, :15], base.transition(p))
    assert np.array_equal(phi[15:, 15:], np.eye(4)) and not phi[15:, :15].any() and not phi[:15, 15:].any()


def test_appended_constants_on_a_base_without_a_compiled_transition():
    """The same for a base whose Phi is I + F h + (F h)^2 / 2 of its own F (seed003's velocity and
    attitude model): ErrorModel.transition_in places it in the identity."""
    from alignment_core.estimation.models import Propagation
    from alignment_core.estimation.models.lever_arm import LeverArmStates
    base = Seed003VelocityAttitude(FilterConfig(model='seed003_24'), True)
    model = LeverArmStates(MasterDelayState(base, 0.02), 1.0)
    p = Propagation(C_M, np.array([0.2, -0.1, 9.8]), W_IN, np.array([1e-6, 2e-6, 0.0]), np.array([0.1, 5.0, 0.0]),
                    0.7, 10.0, H)
    nb = base.n
    phi = model.transition(p)
    assert phi.shape == (nb + 4, nb + 4)
    assert np.array_equal(phi[:nb, :nb], base.transition(p))
    assert np.array_equal(phi[nb:, nb:], np.eye(4)) and not phi[nb:, :nb].any() and not phi[:nb, nb:].any()


def _stack(base_name: str, layers: str):
    """base (vm15, vm12, seed003_24) under the layers, innermost first ('d' delay, 'l' lever arm)."""
    from alignment_core.estimation.models.lever_arm import LeverArmStates
    cfg = FilterConfig(model=base_name)
    base = Seed003VelocityAttitude(cfg, True) if base_name == 'seed003_24' else \
        VelocityMatching(cfg, base_name == 'vm15')
    model = base
    for layer in layers:
        model = MasterDelayState(model, 0.02) if layer == 'd' else LeverArmStates(model, 1.0)
    return base, model


@pytest.mark.parametrize('dtype', [np.float64, np.float32])
@pytest.mark.parametrize('base_name,layers', [('vm15', 'dl'), ('vm12', 'dl'), ('vm12', 'd'), ('vm12', 'l'),
                                              ('seed003_24', 'dl'), ('vm15', 'ld')])
def test_stacked_states_measure_and_feed_back_as_their_layers(base_name, layers, dtype):
    """States appended to a base (the deck's stack: the lever arm on the master delay): H is the
    base's H, then each layer's columns in the order appended (the delay's: the spot acceleration
    on the velocity rows; the lever arm's: C_m [w_m x], the velocity change of a longer arm, on the
    velocity rows only); feedback is the base's on its states, the delay kept, the lever arm's
    error moved into the corrections and zeroed, the filter's state left as it was."""
    base, model = _stack(base_name, layers)
    nb = base.n
    a_n = np.array([0.3, -0.2, 0.1])
    c_a = C_M @ expm_so3(MU)

    def match():
        return Match(c_m=C_M, w_m=W_M, r=np.array([40.0, -10.0, 15.0]), u_n=np.array([0.1, 0.2, 0.0]),
                     v_ref=np.zeros(3), z_vel=np.array([0.01, -0.02, 0.003]), r_vel=np.eye(3) * 1e-4,
                     ins=NavState(q_nb=Rotation.from_matrix(c_a).as_quat(), v_n=np.array([0.5, 0.2, 0.0]),
                                  lat=0.7, lon=2.0, h=0.0), w_n=C_M @ W_M, a_n=a_n)
    h = model.measurement(match(), Corrections(mu=MU)).h
    assert h.shape[1] == model.n == nb + layers.count('d') + 3 * layers.count('l')
    assert np.array_equal(h[:, :nb], base.measurement(match(), Corrections(mu=MU)).h)
    longer = np.stack([C_M @ np.cross(W_M, e) for e in np.eye(3)], axis=1)
    col = nb
    for layer in layers:
        width = 1 if layer == 'd' else 3
        cols = h[:, col:col + width]
        if layer == 'd':
            np.testing.assert_allclose(cols[0:3, 0], a_n, rtol=1e-15, atol=0.0)
        else:
            np.testing.assert_allclose(cols[0:3], longer, rtol=1e-12, atol=1e-15)
            assert not cols[3:].any()
        col += width

    rng = np.random.default_rng(5)
    x = (rng.standard_normal(model.n) * 1e-3).astype(dtype)
    a = rng.standard_normal((model.n, model.n))
    p = (a @ a.T * 1e-6).astype(dtype)
    x_given = x.copy()
    m_all, m_base = match(), match()
    corr_all, corr_base = Corrections(mu=MU.copy()), Corrections(mu=MU.copy())
    x_new = model.feedback(x, p, m_all, m_all.ins, corr_all)
    x_base = base.feedback(x[:nb], p[:nb, :nb], m_base, m_base.ins, corr_base)
    assert np.array_equal(x, x_given) and x_new.shape == x.shape
    assert np.array_equal(x_new[:nb], x_base)
    col, dr = nb, np.zeros(3)
    for layer in layers:
        if layer == 'd':
            assert x_new[col] == x[col]
            col += 1
        else:
            assert not x_new[col:col + 3].any()
            dr = dr + x[col:col + 3]
            col += 3
    assert np.array_equal(corr_all.dr, dr)
    for f in ('bg', 'ba', 'mu'):
        assert np.array_equal(getattr(corr_all, f), getattr(corr_base, f))
    assert np.array_equal(m_all.ins.q_nb, m_base.ins.q_nb) and np.array_equal(m_all.ins.v_n, m_base.ins.v_n)


def test_yaw_matching_keeps_the_velocity_rows_and_the_heading_row():
    cfg = FilterConfig(model='seed003_24')
    full = Seed003VelocityAttitude(cfg, True)
    yaw = YawMatching(full)
    c_a = C_M @ expm_so3(MU + 1e-3)
    m = Match(c_m=C_M, w_m=W_M, r=np.zeros(3), u_n=np.array([0.1, 0.2, 0.0]), v_ref=np.zeros(3),
              z_vel=np.array([0.01, -0.02, 0.003]), r_vel=np.eye(3) * 1e-4,
              ins=NavState(q_nb=Rotation.from_matrix(c_a).as_quat(), v_n=np.zeros(3), lat=0.7, lon=2.0, h=0.0))
    a, b = full.measurement(m, Corrections(mu=MU)), yaw.measurement(m, Corrections(mu=MU))
    rows = [0, 1, 2, 5]
    np.testing.assert_array_equal(b.z, a.z[rows])
    np.testing.assert_array_equal(b.h, a.h[rows])
    np.testing.assert_array_equal(b.r, a.r[np.ix_(rows, rows)])
    assert yaw.attitude_rows == (2,)


@pytest.mark.parametrize('overrides,message', [
    ({'filter.attitude_match_axes': 'yaw'}, 'mounting yaw'),
    ({'filter.attitude_match_axes': 'roll'}, 'attitude_match_axes'),
    ({'filter.model': 'seed002_10', 'filter.rate_matching': True}, 'rate_matching needs'),
    ({'filter.rate_matching': True, 'filter.algorithm': 'stf'}, 'same rows at every update'),
    ({'filter.model': 'seed000_large_angle', 'filter.algorithm': 'ekf', 'filter.master_delay_state': True},
     'master_delay_state needs'),
    ({'filter.master_delay_sigma_ms': 0.0}, 'master_delay_sigma_ms'),
    ({'filter.rate_match_sigma_dph': -1.0}, 'rate_match_sigma_dph'),
])
def test_invalid_option_combinations_are_refused(overrides, message):
    with pytest.raises(ConfigError, match=message):
        scenario.load('deck_paper', overrides)


def _deck(extra: dict, seconds: float = 40.0):
    ov = tuple({'duration_s': seconds, **extra}.items())
    return run_one(RunSpec(0, 'x', 'deck_paper', ov, 3, score_at=seconds - 0.5))


def test_delay_state_estimates_a_master_latency_the_filter_is_not_told():
    """The master INS's data reach the filter 30 ms late (sensor stamps = validity + 30 ms) while
    filter.master_latency_s says 0. Matching the ship's 0.1-0.3 m/s^2 deck accelerations against
    a 30 ms-old reference costs several arcmin; the delay state finds the 30 ms (the simulated
    latency) and restores an error within the filter's own sigma."""
    late = {'master.latency_s': 0.03}
    blind = _deck(late)
    assert np.max(np.abs(blind.err) / blind.sigma) > 5.0          # the unmodelled lag: a biased filter
    sc = scenario.load('deck_paper', {'duration_s': 40.0, **late, 'filter.master_delay_state': True}, seed=3)
    res = pipeline.run(sc, keep_truth=False)
    i = res.filter.labels.index('dt_master')
    e = res.estimates[-1]
    assert abs(e.x[i] - 0.03) < max(3.0 * e.sigma[i], 1e-4)
    assert e.sigma[i] < 1e-3
    told = _deck({**late, 'filter.master_delay_state': True})
    assert np.all(np.abs(told.err) < 3.0 * told.sigma)


def test_rate_matching_on_a_rigid_mount_sharpens_the_misalignment_and_stays_consistent():
    """An aircraft rigid on the deck (no flexure in the truth) turns with the ship, so its gyros
    and the master's rates differ only by the misalignment across the ship's rotation, eps and
    noise: the rate rows see every axis within seconds, where velocity matching needs the deck's
    accelerations. Margin: the 1-sigma after 40 s at least 5 times smaller, and the error inside 3
    sigma on each axis."""
    vel = _deck({})
    rate = _deck({'filter.rate_matching': True})
    assert np.all(rate.sigma * 5.0 < vel.sigma)
    assert np.all(np.abs(rate.err) < 3.0 * rate.sigma)


def test_a_match_with_another_master_attitude_keeps_every_other_field():
    """Match.with_master_attitude is dataclasses.replace(m, c_m=...): every field, one added later
    too, carried over as the same object."""
    import dataclasses
    values = {f.name: object() for f in dataclasses.fields(Match)}
    m = Match(**values)
    c = object()
    out = m.with_master_attitude(c)
    assert out.c_m is c
    for f in dataclasses.fields(Match):
        if f.name != 'c_m':
            assert getattr(out, f.name) is values[f.name], f.name


@pytest.mark.parametrize('axes, picked', [((0, 1, 2), [0, 1, 2]), ((0, 1), [0, 1]), ((2,), [2]), ((1, 2), [1, 2])])
def test_rows_of_selects_the_axes_in_order(axes, picked):
    from alignment_core.estimation.models.base import rows_of
    a = np.arange(12.0).reshape(3, 4)
    assert np.array_equal(a[rows_of(axes)], a[picked])
