"""What the engine publishes (estimation/publication.py): the slave's odometry with its
covariances, and the published view that never carries a non-finite or absurd estimate and holds
the last good one at ERROR."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.health import ERROR, OK, WARN
from alignment_core.estimation.models import make_model
from alignment_core.estimation.models.base import DV, EPS
from alignment_core.estimation.outputs import Estimate
from alignment_core.estimation.publication import OdometryMaker, PublishGuard, prior_estimate
from alignment_core.geometry import earth, rotations
from alignment_core.navigation.strapdown import NavState
from alignment_core.units import DEG

LAT = 0.7
PLANE = earth.TangentPlane(LAT, 2.0, 0.0)


def _maker(model: str = 'vm15') -> tuple[OdometryMaker, int]:
    m = make_model(dataclasses.replace(FilterConfig(), model=model))
    return OdometryMaker(m, PLANE, 0.01, 0.001, 0.01), m.n


def test_velocity_and_rate_in_body_axes():
    """Yawed 90 deg (body x = nav north): v_n = (0, 10, 0) is v_b = (10, 0, 0). At rest the gyro
    measures the Earth rate, so the rate w.r.t. the nav frame is zero."""
    q = Rotation.from_euler('z', 90, degrees=True).as_quat()
    st = NavState(q_nb=q, v_n=np.array([0.0, 10.0, 0.0]), lat=LAT, lon=2.0, h=0.0)
    maker, n = _maker()
    c = Rotation.from_quat(q).as_matrix()
    w_ie = np.array([0.0, earth.OMEGA_IE * math.cos(LAT), earth.OMEGA_IE * math.sin(LAT)])
    w_en = earth.omega_en_n(LAT, 0.0, st.v_n)
    odo = maker.make(st, np.eye(n) * 1e-6, c.T @ (w_ie + w_en), np.zeros(3))
    np.testing.assert_allclose(odo.v_b, [10.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(odo.w_b, 0.0, atol=1e-18)
    np.testing.assert_allclose(odo.p_w, PLANE.from_geodetic(LAT, 2.0, 0.0), atol=1e-9)


def test_covariances_rotate_into_body_axes_and_unknown_is_minus_one():
    """Yawed 90 deg, nav velocity variances (E, N, U) = (1, 4, 9) are body (x, y, z) = (4, 1, 9);
    the pose's attitude block is P's phi block; no position states: position variances -1. The
    body rate's variance is ARW^2 / dt + the gyro bias variance of the eps states."""
    q = Rotation.from_euler('z', 90, degrees=True).as_quat()
    st = NavState(q_nb=q, v_n=np.zeros(3), lat=LAT, lon=2.0, h=0.0)
    maker, n = _maker()
    p = np.eye(n) * 1e-8
    p[3:6, 3:6] = np.diag([1.0, 4.0, 9.0])
    p[0:3, 0:3] = np.diag([1e-6, 2e-6, 3e-6])
    odo = maker.make(st, p, None, np.zeros(3))
    np.testing.assert_allclose(np.diag(odo.twist_cov)[:3], [4.0, 1.0, 9.0], atol=1e-12)
    np.testing.assert_array_equal(np.diag(odo.pose_cov)[:3], -1.0)
    np.testing.assert_array_equal(odo.pose_cov[3:, 3:], p[0:3, 0:3])
    arw = 0.001 * DEG / 60.0
    np.testing.assert_allclose(np.diag(odo.twist_cov)[3:], arw ** 2 / 0.01 + 1e-8, rtol=1e-12)


def test_a_model_without_vertical_velocity_reports_it_unknown_and_seed001_has_a_position():
    st = NavState(q_nb=np.array([0.0, 0.0, 0.0, 1.0]), v_n=np.zeros(3), lat=LAT, lon=2.0, h=0.0)
    maker, n = _maker('seed002_10')
    odo = maker.make(st, np.eye(n) * 1e-6, None, np.zeros(3))
    np.testing.assert_array_equal(np.diag(odo.twist_cov)[:3], -1.0)
    maker, n = _maker('seed001_13')
    odo = maker.make(st, np.eye(n) * 1e-12, None, np.zeros(3))       # 1e-6 rad of latitude
    r_m, _ = earth.radii(LAT)
    assert odo.pose_cov[1, 1] == pytest.approx(1e-12 * float(r_m) ** 2)
    assert odo.pose_cov[2, 2] == -1.0


def _numpy_odometry_parts(model, maker: OdometryMaker, st: NavState, p, gyro, bg):
    """The odometry's velocity, rate and covariances as numpy computes them (the formulas of
    OdometryMaker's docstring, as the engine computed them before its kernel)."""
    c = np.array(rotations.quat_to_dcm_f(tuple(st.q_nb.tolist()))).reshape(3, 3)
    w_in = earth.omega_ie_n(st.lat) + earth.omega_en_n(st.lat, st.h, st.v_n)
    v_b = c.T @ st.v_n
    w_b = np.zeros(3) if gyro is None else (gyro - bg) - c.T @ w_in
    pose = np.zeros((6, 6))
    pose[0, 0] = pose[1, 1] = pose[2, 2] = -1.0
    pose[3:, 3:] = p[model.attitude, model.attitude]
    dv = [i for i, k in enumerate(model.kinds) if k == DV]
    twist = np.zeros((6, 6))
    if len(dv) == 3:
        twist[:3, :3] = c.T @ p[np.ix_(dv, dv)] @ c
    else:
        twist[0, 0] = twist[1, 1] = twist[2, 2] = -1.0
    eps = [i for i, k in enumerate(model.kinds) if k == EPS]
    bias = np.diagonal(p)[eps] if len(eps) == 3 else np.full(3, maker._bias_var)
    twist[3:, 3:] = np.diag(maker._rate_var + bias)
    return v_b, w_b, pose, twist


@pytest.mark.parametrize('dtype', [np.float64, np.float32])
@pytest.mark.parametrize('model', ['vm15', 'vm12', 'seed002_10', 'seed003_21'])
def test_the_odometry_is_numpys_bit_for_bit(model, dtype):
    """The compiled odometry gives numpy's numbers exactly: the products through the same BLAS
    calls, the gyro noise added to a single-precision bias variance in single precision (as numpy
    adds a float to a float32 array); with and without a gyro sample."""
    maker, n = _maker(model)
    m = make_model(dataclasses.replace(FilterConfig(), model=model))
    rng = np.random.default_rng(7)
    for k in range(40):
        q = Rotation.random(random_state=k).as_quat()
        st = NavState(q_nb=q, v_n=rng.standard_normal(3) * 30.0, lat=float(rng.uniform(-1.4, 1.4)),
                      lon=float(rng.uniform(-3, 3)), h=float(rng.uniform(0, 50)))
        a = rng.standard_normal((n, n)) * 10.0 ** rng.uniform(-6, 0)
        p = (a @ a.T).astype(dtype)
        gyro = None if k % 4 == 0 else rng.standard_normal(3) * 0.1
        bg = rng.standard_normal(3) * 1e-5
        odo = maker.make(st, p, gyro, bg)
        for got, want in zip(odo[1:], _numpy_odometry_parts(m, maker, st, p, gyro, bg)):
            assert np.array_equal(got, want)


def _estimate(level=OK, mu=(1e-3, 2e-3, 3e-3), t=1, flags=(), sig=(1e-4, 1e-4, 1e-4)) -> Estimate:
    return Estimate(t_ns=t, misalignment=np.array(mu), misalignment_sigma=np.array(sig),
                    q_nb=np.array([0.0, 0.0, 0.0, 1.0]), attitude_cov=np.eye(3) * 1e-8, x=np.zeros(15),
                    sigma=np.ones(15), bias_gyro=np.zeros(3), bias_accel=np.zeros(3), nis=1.0, updates=t,
                    matching=True, level=level, flags=flags, healthy=level < ERROR)


def _prior(e: Estimate) -> Estimate:
    return prior_estimate(e, np.full(3, DEG), make_model(FilterConfig()).initial_covariance(), slice(0, 3))


@pytest.mark.parametrize('bad', [dict(mu=(math.nan, 0.0, 0.0)), dict(mu=(0.0, 0.0, 31.0 * DEG)),
                                 dict(sig=(1e-4, 31.0 * DEG, 1e-4)), dict(sig=(1e-4, 1e-4, 1e14 / 60 * DEG)),
                                 dict(level=ERROR, flags=('inconsistent',))])
def test_a_bad_estimate_is_never_published_the_last_good_one_is(bad):
    g = PublishGuard(30.0 * DEG)
    good = _estimate(t=1)
    assert g.publish(good, _prior) is good
    assert g.publish(_estimate(level=WARN, t=2), _prior).t_ns == 2          # WARN: published as it is
    out = g.publish(_estimate(t=3, **bad), _prior)
    assert out.t_ns == 3 and out.level == ERROR and not out.healthy and 'held' in out.flags
    np.testing.assert_array_equal(out.misalignment, [1e-3, 2e-3, 3e-3])


def test_before_any_good_estimate_the_prior_stands_in():
    out = PublishGuard(30.0 * DEG).publish(_estimate(mu=(math.inf, 0, 0)), _prior)
    np.testing.assert_array_equal(out.misalignment, 0.0)
    np.testing.assert_allclose(out.misalignment_sigma, DEG)
    assert 'absurd' in out.flags and out.level == ERROR


def test_after_a_breakdown_the_engines_own_hold_passes_unless_already_holding():
    g = PublishGuard(30.0 * DEG)
    g.publish(_estimate(t=1), _prior)
    b = _estimate(level=ERROR, flags=('breakdown',), mu=(5e-3, 0, 0), t=2)
    out = g.publish(b, _prior)
    np.testing.assert_array_equal(out.misalignment, b.misalignment)
    assert out.flags == ('breakdown', 'held')
    g.publish(_estimate(level=ERROR, flags=('inconsistent',), t=3), _prior)
    out = g.publish(_estimate(level=ERROR, flags=('breakdown',), mu=(9e-3, 0, 0), t=4), _prior)
    np.testing.assert_array_equal(out.misalignment, [1e-3, 2e-3, 3e-3])   # the view's own hold stays


def test_without_bias_states_the_rate_variance_takes_the_given_bias_variance():
    from alignment_core.estimation.publication import odometry_parts
    none = np.array([], dtype=np.int64)
    q, z = np.array([0.0, 0.0, 0.0, 1.0]), np.zeros(3)
    for fun in (odometry_parts, odometry_parts.py_func):
        _, _, pose, twist, parts_finite = fun(q, z, z, z, False, np.eye(6), np.arange(3), none, none, 2.0, 2.5)
        assert parts_finite
        np.testing.assert_array_equal(np.diag(twist), [-1.0, -1.0, -1.0, 2.5, 2.5, 2.5])
        np.testing.assert_array_equal(np.diag(pose), [-1.0, -1.0, -1.0, 1.0, 1.0, 1.0])
