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
from alignment_core.estimation.outputs import Estimate
from alignment_core.estimation.publication import OdometryMaker, PublishGuard, prior_estimate
from alignment_core.geometry import earth
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
