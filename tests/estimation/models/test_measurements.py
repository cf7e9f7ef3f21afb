"""Measurement models against finite differences of the measurement written out from the
geometry (independently of the models): seed 003's attitude match through the mounting, the
lever-arm states' columns, seed 001's Doppler velocity."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation
from support.nav_error_reference import expm_so3, log_so3, skew

from alignment_core.estimation.config import FilterConfig
from alignment_core.estimation.models import Corrections, Match
from alignment_core.estimation.models.lever_arm import LeverArmStates
from alignment_core.estimation.models.seed001 import Seed001Doppler
from alignment_core.estimation.models.seed002 import Seed002Horizontal
from alignment_core.estimation.models.seed003 import Seed003VelocityAttitude
from alignment_core.estimation.models.velocity_matching import VelocityMatching
from alignment_core.navigation.strapdown import NavState
from alignment_core.units import ARCMIN

C_M = Rotation.from_euler('ZYX', [33.0, 2.5, -4.0], degrees=True).as_matrix()   # true ship attitude
MU = np.array([15.0, -10.0, -30.0]) * ARCMIN                                      # true mounting


W_M = np.array([0.02, -0.01, 0.005])
R_ARM = np.array([40.0, -10.0, 15.0])


def _match(c_m_est, c_a_est, w_m=W_M, r=R_ARM):
    u = c_m_est @ np.cross(w_m, r)
    q = Rotation.from_matrix(c_a_est).as_quat()
    return Match(c_m=c_m_est, w_m=w_m, r=r, u_n=u, v_ref=np.zeros(3), z_vel=np.zeros(3),
                 r_vel=np.eye(3) * 1e-4, ins=NavState(q_nb=q, v_n=np.zeros(3), lat=0.7, lon=2.0, h=0.0))


def _attitude_z(phi, dmu, theta, phi_m, mu_est):
    """The attitude measurement from its definition: the slave INS attitude (error phi) against
    the master's reported attitude (error phi_m) carried through the estimated mounting."""
    c_a_true = C_M @ expm_so3(mu_est + dmu) @ expm_so3(theta)
    c_a_est = expm_so3(-phi) @ c_a_true
    c_m_est = expm_so3(-phi_m) @ C_M
    return log_so3((c_a_est @ expm_so3(-mu_est) @ c_m_est.T).T), c_a_est, c_m_est


def test_seed003_attitude_measurement_and_h():
    mu_est = MU + np.array([4.0, -3.0, 5.0]) * ARCMIN           # the filter's current mounting estimate
    m = Seed003VelocityAttitude(FilterConfig(), master_states=True)
    corr = Corrections(mu=mu_est)
    x0 = dict(phi=np.array([1e-3, -2e-3, 3e-3]), dmu=MU - mu_est, theta=np.array([2.0, -1.0, 1.5]) * ARCMIN,
              phi_m=np.array([0.2, -0.1, 0.4]) * ARCMIN)
    # the model forms the same z as the definition
    z, c_a_est, c_m_est = _attitude_z(mu_est=mu_est, **x0)
    meas = m.measurement(_match(c_m_est, c_a_est), corr)
    np.testing.assert_allclose(meas.z[3:6], z, rtol=0, atol=1e-15)
    # H against central differences of the definition at the estimate (all errors zero)
    zero = {k: np.zeros(3) for k in x0}
    _, c_a0, c_m0 = _attitude_z(mu_est=mu_est, **zero)
    h = m.measurement(_match(c_m0, c_a0), corr).h
    blocks = {'phi': slice(0, 3), 'dmu': slice(12, 15), 'theta': slice(15, 18), 'phi_m': slice(21, 24)}
    d = 1e-6
    for name, sl in blocks.items():
        num = np.empty((3, 3))
        for j in range(3):
            e = np.zeros(3)
            e[j] = d
            zp = _attitude_z(mu_est=mu_est, **{**zero, name: e})[0]
            zm = _attitude_z(mu_est=mu_est, **{**zero, name: -e})[0]
            num[:, j] = (zp - zm) / (2 * d)
        # dmu enters through exp(mu_est + dmu) exp(-mu_est) = exp(J_l(mu_est) dmu): H drops the
        # difference J_l - exp([mu_est x]) ~ |mu_est| / 2 (documented second-order term)
        tol = np.linalg.norm(mu_est) if name == 'dmu' else 1e-8
        np.testing.assert_allclose(h[3:6, sl], num, rtol=0, atol=tol)
    # rows and columns that must be empty: velocity rows see dV (and phi_m through u); no eps, nabla, theta'
    np.testing.assert_array_equal(h[0:3, 3:6], np.eye(3))
    assert not np.any(h[3:6, 3:12]) and not np.any(h[:, 18:21])


def test_lever_arm_columns_are_the_velocity_change_of_a_longer_arm():
    """z = v_slave - v_ref: the slave truly moves with C_m (w x r_true); the reference used
    r_used. d z / d r_true by central differences, velocity rows of each base model."""
    w = np.array([0.02, -0.01, 0.005])
    r_used = np.array([40.0, -10.0, 15.0])

    def z(dr):
        return C_M @ np.cross(w, r_used + dr) - C_M @ np.cross(w, r_used)
    num = np.stack([(z(e) - z(-e)) / 2.0 for e in np.eye(3)], axis=1)
    cfg = FilterConfig()
    for base, rows in ((VelocityMatching(cfg, True), [0, 1, 2]), (Seed002Horizontal(cfg), [0, 1])):
        m = LeverArmStates(base, 1.0)
        h = m.measurement(_match(C_M, C_M, w_m=w, r=r_used), Corrections()).h
        np.testing.assert_allclose(h[:, -3:], num[rows], rtol=1e-12, atol=1e-15)
        np.testing.assert_array_equal(h[:, :-3], base.measurement(_match(C_M, C_M, w_m=w, r=r_used),
                                                                  Corrections()).h)


def test_seed001_doppler_h_against_the_radar_geometry():
    """The radar reports C^T v_D with v_D = (1 + dC) R_U(eps_D) V + dVd u (u the horizontal
    track); the SINS resolves it with its erroneous attitude; z = (V_SINS - C_est v_D^b)_(E,N)."""
    c = Rotation.from_euler('ZYX', [-60.0, 3.0, 25.0], degrees=True).as_matrix()
    v = np.array([-52.0, 30.0, 2.5])

    def z(x):
        phi, dv = x[0:3], np.array([x[3], x[4], 0.0])
        dvd, eps_d, dc = x[10], x[11], x[12]
        u = np.array([v[0], v[1], 0.0]) / np.hypot(v[0], v[1])
        v_d = (1.0 + dc) * (expm_so3(np.array([0.0, 0.0, eps_d])) @ v) + dvd * u
        v_b = c.T @ v_d
        return ((v + dv) - expm_so3(-phi) @ c @ v_b)[0:2]
    steps = np.array([1e-5] * 3 + [1e-2] * 2 + [1e-6] * 5 + [1e-2, 1e-5, 1e-5])
    num = np.stack([(z(steps[j] * e) - z(-steps[j] * e)) / (2 * steps[j]) for j, e in enumerate(np.eye(13))], axis=1)
    h = Seed001Doppler.measurement_matrix(v)
    np.testing.assert_allclose(h, num, rtol=1e-7, atol=1e-9)
    # straight flight: phi_U and eps_D are seen only as their difference
    np.testing.assert_allclose(h[:, 2], -h[:, 11], rtol=0, atol=0)


def test_skew_helper_is_the_cross_product():
    a, b = np.array([1.0, -2.0, 0.5]), np.array([0.3, 0.7, -1.1])
    np.testing.assert_allclose(skew(a) @ b, np.cross(a, b))
