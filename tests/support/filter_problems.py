"""Test problems shared by the filter-bank tests (not a test module)."""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla

DEG = np.pi / 180.0
ARCMIN = DEG / 60.0
DPH = DEG / 3600.0
G = 9.80665


def random_spd(rng, n, scale=1.0):
    """Well-conditioned random SPD matrix (eigenvalues roughly in [0.5, 4] * scale)."""
    a = rng.standard_normal((n, n))
    return scale * (a @ a.T / n + 0.5 * np.eye(n))


def random_linear_problem(rng, n, m, selection=False):
    """(Phi, Qd, H, R, P0, x0) of a random linear-Gaussian model: Phi near identity, full Qd and
    R, H dense or (selection=True) picking m states."""
    phi = np.eye(n) + 0.05 * rng.standard_normal((n, n))
    qd = random_spd(rng, n, 1e-2)
    if selection:
        h = np.zeros((m, n))
        h[np.arange(m), rng.permutation(n)[:m]] = 1.0
    else:
        h = rng.standard_normal((m, n))
    r = random_spd(rng, m, 0.1)
    p0 = random_spd(rng, n)
    x0 = rng.standard_normal(n)
    return phi, qd, h, r, p0, x0


def seed003_model(dt=0.01, lat_deg=30.0, heading_deg=30.0, tau_flex_s=(5.0, 4.0, 6.0), sigma_flex_deg=1.2):
    """Seed 003's 21-state velocity + attitude matching model, ENU, SI units, discretised by
    Van Loan. State: phi (3, rad), dv (3, m/s), gyro drift (3, rad/s), accel bias (3, m/s^2),
    mounting misalignment mu (3, rad), flexure theta (3, rad), flexure rate (3, rad/s).
    A ship on a level sea (f^n = [0, 0, g], Earth rate at lat), body at a fixed heading (C = C_b^n):
        phi' = -w_ie x phi - C eps + w_g,    dv' = f^n x phi - 2 w_ie x dv + C nabla + w_a,
        eps' = nabla' = mu' = 0,             theta'' = -b^2 theta - 2 b theta' + w_f,
        b = 2.146 / tau,  E[w_f^2] = 4 b^3 sigma^2   (seed 003's second-order Markov flexure),
        z = [dv + v_v;  phi - C (mu + theta) + v_a].
    Seed 003's numbers: gyro noise 0.01 deg/h/sqrt(Hz), accel noise 0.0005 g/sqrt(Hz), master
    velocity error 0.1 m/s, master attitude error 1 arcmin, initial sigma 1 deg (attitude and
    mounting), 1 m/s, 0.2 deg/h, 0.002 g, flexure 1.2 deg. Flexure time constants (lost in the
    paper) 4-6 s. Returns (Phi, Qd, H, R, P0)."""
    n = 21
    lat = lat_deg * DEG
    w_ie = 7.292115e-5 * np.array([0.0, np.cos(lat), np.sin(lat)])
    f_n = np.array([0.0, 0.0, G])
    psi = heading_deg * DEG
    c = np.array([[np.cos(psi), -np.sin(psi), 0.0], [np.sin(psi), np.cos(psi), 0.0], [0.0, 0.0, 1.0]])

    def skew(v):
        return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])

    a = np.zeros((n, n))
    a[0:3, 0:3] = -skew(w_ie)
    a[0:3, 6:9] = -c
    a[3:6, 0:3] = skew(f_n)
    a[3:6, 3:6] = -2.0 * skew(w_ie)
    a[3:6, 9:12] = c
    b = 2.146 / np.asarray(tau_flex_s)
    a[15:18, 18:21] = np.eye(3)
    a[18:21, 15:18] = -np.diag(b ** 2)
    a[18:21, 18:21] = -np.diag(2.0 * b)
    sig_f = sigma_flex_deg * DEG
    qc = np.zeros(n)
    qc[0:3] = (0.01 * DPH) ** 2
    qc[3:6] = (0.0005 * G) ** 2
    qc[18:21] = 4.0 * b ** 3 * sig_f ** 2
    # Van Loan: expm([[-A, Qc], [0, A^T]] dt) = [[., Phi^-1 Qd], [0, Phi^T]]
    vl = sla.expm(np.block([[-a, np.diag(qc)], [np.zeros((n, n)), a.T]]) * dt)
    phi = vl[n:, n:].T
    qd = phi @ vl[:n, n:]
    qd = 0.5 * (qd + qd.T)
    h = np.zeros((6, n))
    h[0:3, 3:6] = np.eye(3)
    h[3:6, 0:3] = np.eye(3)
    h[3:6, 12:15] = -c
    h[3:6, 15:18] = -c
    r = np.diag(np.r_[np.full(3, 0.1 ** 2), np.full(3, ARCMIN ** 2)])
    p0 = np.diag(np.r_[np.full(3, DEG ** 2), np.full(3, 1.0), np.full(3, (0.2 * DPH) ** 2),
                       np.full(3, (0.002 * G) ** 2), np.full(3, DEG ** 2), np.full(3, sig_f ** 2),
                       b ** 2 * sig_f ** 2])
    return phi, qd, h, r, p0


def sqrt_psd(a):
    w, v = np.linalg.eigh(a)
    return v * np.sqrt(np.clip(w, 0.0, None))
