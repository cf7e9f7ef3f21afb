"""Strapdown mechanisation against trajectories whose attitude and velocity are known in
closed form. The IMU output is built from the trajectory itself (Earth rate, transport rate,
Coriolis and normal gravity included) and integrated over each interval with 5-point
Gauss-Legendre quadrature, so the increments are exact to round-off for these smooth motions.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core.geometry import earth
from alignment_core.geometry.euler import euler_to_dcm
from alignment_core.geometry.rotations import quat_mul, quat_to_dcm, rotvec_to_quat
from alignment_core.navigation.strapdown import NavState, Strapdown
from alignment_core.units import G0

GL_X, GL_W = np.polynomial.legendre.leggauss(5)
GL_U = 0.5 * (GL_X + 1.0)            # nodes on [0, 1]
GL_W = 0.5 * GL_W                    # weights summing to 1

LAT0, LON0, H0 = np.radians(40.0), np.radians(116.0), 0.0


def increments(rate_fn, force_fn, t_edges):
    """(dtheta, dv) (K, 3) over the K intervals between t_edges, from omega_ib^b(t), f^b(t)."""
    h = np.diff(t_edges)
    t = t_edges[:-1, None] + GL_U[None, :] * h[:, None]              # (K, 5)
    w = rate_fn(t.ravel()).reshape(t.shape + (3,))
    f = force_fn(t.ravel()).reshape(t.shape + (3,))
    return (h[:, None] * np.einsum('kjc,j->kc', w, GL_W),
            h[:, None] * np.einsum('kjc,j->kc', f, GL_W))


def run(state, dth, dv, h):
    sd = Strapdown(state)
    q = np.empty((len(dth), 4))
    v = np.empty((len(dth), 3))
    for k in range(len(dth)):
        sd.update(dth[k], dv[k], h)
        q[k] = sd.s.q_nb
        v[k] = sd.s.v_n
    return sd.s, q, v


def attitude_error(c_true, q_est):
    """Angle (rad) of C_true^T C_est for stacks (K, 3, 3) and (K, 4)."""
    c_est = Rotation.from_quat(q_est).as_matrix()
    return np.linalg.norm(Rotation.from_matrix(np.swapaxes(c_true, -1, -2) @ c_est).as_rotvec(), axis=-1)


# ----- building blocks -----

def test_quaternion_helpers():
    rng = np.random.default_rng(1)
    for _ in range(10):
        a, b = rng.standard_normal(3), rng.standard_normal(3)
        qa, qb = rotvec_to_quat(a), rotvec_to_quat(b)
        ca, cb = Rotation.from_rotvec(a).as_matrix(), Rotation.from_rotvec(b).as_matrix()
        np.testing.assert_allclose(quat_to_dcm(qa), ca, atol=1e-14)
        np.testing.assert_allclose(quat_to_dcm(quat_mul(qa, qb)), ca @ cb, atol=1e-14)
    # the small-angle series agrees with the exact map across its switch-over
    for a in (1e-7, 9.9e-7, 1.01e-6, 1e-5):
        v = np.array([0.6, -0.8, 0.0]) * a
        np.testing.assert_allclose(rotvec_to_quat(v), Rotation.from_rotvec(v).as_quat(), atol=1e-17)


# ----- (a) at rest on the rotating Earth -----

def test_stationary_600s_stays_put():
    """At rest: omega_ib^b = C_n^b omega_ie^n, f^b = -C_n^b g^n. The mechanisation must hold
    attitude, zero velocity and position (the algorithm is exact here: only round-off)."""
    h, n = 0.01, 60000                                     # 600 s at 100 Hz
    lat, lon, hgt = LAT0, LON0, 120.0
    c_bn = euler_to_dcm(np.radians(2.0), np.radians(-3.0), np.radians(40.0))
    w_ib = c_bn.T @ earth.omega_ie_n(lat)
    f_b = -c_bn.T @ earth.gravity_n(lat, hgt)
    dth = np.tile(w_ib * h, (n, 1))
    dv = np.tile(f_b * h, (n, 1))
    q0 = Rotation.from_matrix(c_bn).as_quat()
    end, q, v = run(NavState(q_nb=q0, v_n=np.zeros(3), lat=lat, lon=lon, h=hgt), dth, dv, h)
    assert attitude_error(np.broadcast_to(c_bn, (n, 3, 3)), q).max() < 1e-9
    assert np.abs(v).max() < 1e-6
    r_m, r_n = earth.radii(lat)
    assert abs(end.lat - lat) * r_m < 1e-4
    assert abs(end.lon - lon) * r_n * np.cos(lat) < 1e-4
    assert abs(end.h - hgt) < 1e-4


# ----- (b) rotations with closed-form attitude -----

def _rest_imu(c_bn_fn, w_nb_fn, lat, hgt):
    """IMU output of a body rotating (C_b^n(t), omega_nb^b(t)) at a fixed point on Earth."""
    w_ie = earth.omega_ie_n(lat)
    g = earth.gravity_n(lat, hgt)

    def rate(t):
        return w_nb_fn(t) + np.einsum('kji,j->ki', c_bn_fn(t), w_ie)

    def force(t):
        return np.einsum('kji,j->ki', c_bn_fn(t), -g)
    return rate, force


def _coning():
    """Classic coning: C_b^n(t) = Rz(W t) Rx(beta) Rz(-W t), whose body rate is
    omega = W (-sin b sin Wt, sin b cos Wt, cos b - 1). The attitude is periodic, but the
    integrated rate drifts by W (1 - cos b) about z: without coning compensation that is
    2.4e-4 rad/s here (7e-3 rad in 30 s)."""
    wc, beta = 2.0 * np.pi * 1.0, np.radians(0.5)
    rx_b = Rotation.from_rotvec([beta, 0.0, 0.0]).as_matrix()

    def rz(a):
        return Rotation.from_rotvec(np.outer(a, [0.0, 0.0, 1.0])).as_matrix()

    def c_bn(t):
        return rz(wc * t) @ rx_b @ rz(-wc * t)

    def w_nb(t):
        return wc * np.stack([-np.sin(beta) * np.sin(wc * t), np.sin(beta) * np.cos(wc * t),
                              np.full_like(t, np.cos(beta) - 1.0)], axis=-1)
    return c_bn, w_nb, 30.0, 0.0


def _constant_rate():
    """Constant omega_nb^b = w from rest: C_b^n(t) = C0 exp(t [w x]) (about two turns)."""
    w = np.array([0.3, -0.2, 0.5])
    c0 = euler_to_dcm(np.radians(5.0), np.radians(-10.0), np.radians(120.0))

    def c_bn(t):
        return c0 @ Rotation.from_rotvec(np.outer(t, w)).as_matrix()

    def w_nb(t):
        return np.broadcast_to(w, (len(t), 3))
    return c_bn, w_nb, 20.0, 50.0


_ROTATIONS = {'coning': _coning, 'constant_rate': _constant_rate}
_rotation_cache: dict = {}


def rotation_run(name):
    """Attitude and velocity errors of a rotation at rest on Earth (lat 40 deg)."""
    if name not in _rotation_cache:
        c_bn, w_nb, t_end, hgt = _ROTATIONS[name]()
        h = 0.01
        rate, force = _rest_imu(c_bn, w_nb, LAT0, hgt)
        t_edges = np.arange(int(round(t_end / h)) + 1) * h
        dth, dv = increments(rate, force, t_edges)
        q0 = Rotation.from_matrix(c_bn(np.array([0.0]))[0]).as_quat()
        _, q, v = run(NavState(q_nb=q0, v_n=np.zeros(3), lat=LAT0, lon=LON0, h=hgt), dth, dv, h)
        _rotation_cache[name] = (attitude_error(c_bn(t_edges[1:]), q), np.abs(v).max(axis=-1))
    return _rotation_cache[name]


@pytest.mark.parametrize('name', list(_ROTATIONS))
def test_rotation_attitude_closed_form(name):
    att, _ = rotation_run(name)
    assert att.max() < 1e-8, f'attitude error {att.max():.3g} rad'


@pytest.mark.parametrize('name', list(_ROTATIONS))
def test_rotation_at_rest_keeps_zero_velocity(name):
    """The vehicle does not move: velocity must stay zero. The exact body-frame velocity
    increment over an interval is dv + dtheta x dv / 2 + sculling + dtheta x (dtheta x dv) / 6
    + O(h^4); dropping the last term leaves -(h^3/6) w x (w x f) per step, which for a
    steady rotation accumulates to (h^2/6)|w x (w x f)| T (1.5e-5 m/s for the coning case,
    5e-4 m/s for the 0.62 rad/s turn)."""
    _, vel = rotation_run(name)
    assert vel.max() < 1e-6, f'velocity error {vel.max():.3g} m/s'


# ----- (c) constant acceleration along a straight line -----

def _straight_line(accel, yaw, t_end, h, lat0=LAT0, hgt=H0):
    """Level body at constant yaw, ground velocity v^n(t) = a u t along the body x axis, at
    constant height. Truth: C_b^n constant, v(T) = a T u, lat(t) = lat0 + a u_N t^2 / (2 R_M)
    (R_M varies by ~1e-6 over the 900 m run: the latitude is right to ~2e-10 rad, which moves
    Earth rate and gravity by < 1e-12). Exact IMU output: omega_ib^b = C^T (omega_ie + omega_en),
    f^b = C^T (a u + (2 omega_ie + omega_en) x v - g)."""
    c_bn = euler_to_dcm(0.0, 0.0, yaw)
    u = c_bn[:, 0]
    r_m, r_n = earth.radii(lat0)

    def state(t):
        v = np.outer(accel * t, u)
        lat = lat0 + accel * u[1] * t**2 / (2.0 * (r_m + hgt))
        return v, lat

    def rate(t):
        v, lat = state(t)
        return (earth.omega_ie_n(lat) + earth.omega_en_n(lat, hgt, v)) @ c_bn

    def force(t):
        v, lat = state(t)
        w_ie, w_en = earth.omega_ie_n(lat), earth.omega_en_n(lat, hgt, v)
        f_n = accel * u + np.cross(2.0 * w_ie + w_en, v) - earth.gravity_n(lat, hgt)
        return f_n @ c_bn
    t_edges = np.arange(int(round(t_end / h)) + 1) * h
    dth, dv = increments(rate, force, t_edges)
    st = NavState(q_nb=Rotation.from_matrix(c_bn).as_quat(), v_n=np.zeros(3), lat=lat0, lon=LON0,
                  h=hgt)
    return c_bn, u, t_edges, st, dth, dv


@pytest.mark.parametrize('accel,yaw_deg,t_end', [(2.0, 30.0, 30.0), (2.0 * G0, 120.0, 3.0)],
                         ids=['2mps2-30s', 'catapult-2g-3s'])
def test_constant_acceleration_straight_line(accel, yaw_deg, t_end):
    """v(T) = a T u to 1e-6 m/s. Coriolis, transport rate and gravity change along the run, so
    the mechanisation must evaluate them at mid-interval (second order): taken at the start
    of each interval they leave h/2 |(2 w_ie + w_en) x (v(T) - v(0))| ~ 3e-5 m/s here."""
    h = 0.01
    c_bn, u, t_edges, st, dth, dv = _straight_line(accel, np.radians(yaw_deg), t_end, h)
    end, q, v = run(st, dth, dv, h)
    v_true = np.outer(accel * t_edges[1:], u)
    assert attitude_error(np.broadcast_to(c_bn, (len(q), 3, 3)), q).max() < 1e-6
    # position: trapezoidal rule, exact for a linear velocity (the closed-form latitude above
    # is itself good to ~1e-3 m)
    r_m, _ = earth.radii(LAT0)
    assert (end.lat - LAT0) * r_m == pytest.approx(0.5 * accel * t_end**2 * u[1], abs=1e-2)
    assert end.h == pytest.approx(H0, abs=1e-2)
    err = np.abs(v - v_true).max()
    assert err < 1e-6, f"velocity error {err:.3g} m/s (|v| up to {accel * t_end:.1f} m/s)"
