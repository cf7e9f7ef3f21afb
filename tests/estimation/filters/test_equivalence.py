"""On a linear-Gaussian model every filter of the bank computes the same conditional mean and
covariance as the Kalman filter: the factored filters are algebraically identical, the fading
filters reduce to it with the fading switched off, and the sigma-point rules integrate the
linear maps exactly (and so does the EKF's linearisation). Any difference beyond round-off is a
bug. Also: the vectorised Carlson, Bierman and Thornton steps against the textbook loops, and the
KF's selection fast path against the plain Joseph formulas."""
from __future__ import annotations

import numpy as np
import pytest
from support.filter_problems import random_linear_problem, sqrt_psd

from alignment_core.estimation.filters import (
    CarlsonFilter,
    CubatureKalmanFilter,
    ExtendedKalmanFilter,
    FadingMemoryFilter,
    KalmanFilter,
    SqrtFadingFilter,
    StrongTrackingFilter,
    UDFilter,
    UnscentedKalmanFilter,
)

TOL = 1e-9

LINEAR = {
    'carlson': lambda x0, p0: CarlsonFilter(x0, p0),
    'ud': lambda x0, p0: UDFilter(x0, p0),
    'combined lam=1': lambda x0, p0: SqrtFadingFilter(x0, p0, gamma=np.inf),
    'stf beta huge': lambda x0, p0: StrongTrackingFilter(x0, p0, beta=1e12),
    'stf multiple beta huge': lambda x0, p0: StrongTrackingFilter(x0, p0, beta=1e12,
                                                                  alpha=np.linspace(1.0, 4.0, x0.size)),
    'fading lam=1': lambda x0, p0: FadingMemoryFilter(x0, p0, lam=1.0),
    'fading test never fires': lambda x0, p0: FadingMemoryFilter(x0, p0, gamma=1e12),
    'ekf linear api': lambda x0, p0: ExtendedKalmanFilter(x0, p0),
    'ukf linear api': lambda x0, p0: UnscentedKalmanFilter(x0, p0),
    'ckf linear api': lambda x0, p0: CubatureKalmanFilter(x0, p0),
}
NONLINEAR = {
    'ekf (given jacobians)': lambda x0, p0: ExtendedKalmanFilter(x0, p0),
    'ukf alpha=1 kappa=0': lambda x0, p0: UnscentedKalmanFilter(x0, p0),
    'ukf alpha=0.5 beta=2 kappa=1': lambda x0, p0: UnscentedKalmanFilter(x0, p0, alpha=0.5, beta=2.0, kappa=1.0),
    'ckf': lambda x0, p0: CubatureKalmanFilter(x0, p0),
}


def _assert_same(f, ref, label, tol=TOL):
    scale_x = max(1.0, np.abs(ref.x).max())
    scale_p = np.abs(ref.P).max()
    assert np.abs(f.x - ref.x).max() <= tol * scale_x, label
    assert np.abs(f.P - ref.P).max() <= tol * scale_p, label


def _run(make, n, m, selection, nonlinear=False, jac=True, steps=25, seed=0, nis_rel=1e-8):
    """Two predicts per update; measurements from a simulated truth of the same model. Returns
    the filter and a KF run alongside; asserts agreement after every update."""
    rng = np.random.default_rng(seed + 100 * n + m)
    phi, qd, h, r, p0, x0 = random_linear_problem(rng, n, m, selection)
    truth = x0 + np.linalg.cholesky(p0) @ rng.standard_normal(n)
    lq, lr = sqrt_psd(qd), np.linalg.cholesky(r)
    kf, f = KalmanFilter(x0, p0), make(x0, p0)
    for k in range(steps):
        for _ in range(2):
            truth = phi @ truth + lq @ rng.standard_normal(n)
            kf.predict(phi, qd)
            if nonlinear:
                f.predict_nonlinear(lambda x: phi @ x, qd, jac=(lambda x: phi) if jac else None)
            else:
                f.predict(phi, qd)
        z = h @ truth + lr @ rng.standard_normal(m)
        r_kf = kf.update(z, h, r)
        if nonlinear:
            r_f = f.update_nonlinear(z, lambda x: h @ x, r, jac=(lambda x: h) if jac else None)
        else:
            r_f = f.update(z, h, r)
        assert r_f.accepted and r_kf.accepted
        assert r_f.nis == pytest.approx(r_kf.nis, rel=nis_rel)
        yield k, f, kf


@pytest.mark.parametrize('n,m', [(12, 3), (21, 6)])
@pytest.mark.parametrize('selection', [False, True], ids=['dense H', 'selecting H'])
@pytest.mark.parametrize('name', list(LINEAR))
def test_linear_api_equals_kf(name, n, m, selection):
    for _k, f, kf in _run(LINEAR[name], n, m, selection):
        _assert_same(f, kf, name)
    assert f.diagnostics()['updates'] == 25 and f.diagnostics()['predicts'] == 50


@pytest.mark.parametrize('n,m', [(12, 3), (21, 6)])
@pytest.mark.parametrize('name', list(NONLINEAR))
def test_nonlinear_api_on_linear_model_equals_kf(name, n, m):
    for _k, f, kf in _run(NONLINEAR[name], n, m, selection=False, nonlinear=True):
        _assert_same(f, kf, name)


@pytest.mark.parametrize('n,m', [(12, 3), (21, 6)])
def test_ekf_numerical_jacobian_on_linear_model(n, m):
    """Central differences of a linear map are exact up to round-off eps |f(x)| / h per Jacobian
    entry. With steps h = 1e-3 sigma and states a few sigma_0 from zero while sigma shrinks to
    ~0.03 sigma_0, that is eps * 3 / 3e-5 ~ 2e-11, times |P| n ~ 1e-9 relative in P: tolerance 1e-8."""
    for _k, f, kf in _run(NONLINEAR['ekf (given jacobians)'], n, m, selection=False, nonlinear=True, jac=False,
                          nis_rel=1e-7):
        _assert_same(f, kf, 'ekf numerical jacobian', tol=1e-8)


# ----- the vectorised factored steps against the textbook loops -----

def carlson_loop(z, r, h, x, c):
    """Grewal & Andrews, carlson.m (scalar measurement, P = C C^T, C upper triangular)."""
    c = c.copy()
    x = x.copy()
    n = x.size
    w = np.zeros(n)
    alpha, delta = r, z
    for j in range(n):
        delta -= h[j] * x[j]
        sigma = sum(c[i, j] * h[i] for i in range(j + 1))
        beta = alpha
        alpha = alpha + sigma ** 2
        gamma = np.sqrt(alpha * beta)
        eta, zeta = beta / gamma, sigma / gamma
        w[j] = 0.0
        for i in range(j + 1):
            tau = c[i, j]
            c[i, j] = eta * c[i, j] - zeta * w[i]
            w[i] += tau * sigma
    return x + (delta / alpha) * w, c


def bierman_loop(z, r, h, x, u, d):
    """Grewal & Andrews, bierman.m (scalar measurement, P = U D U^T)."""
    u, d, x = u.copy(), d.copy(), x.copy()
    a = u.T @ h
    b = d * a
    dz = z - h @ x
    alpha = r
    gamma = 1.0 / alpha
    for j in range(x.size):
        beta = alpha
        alpha = alpha + a[j] * b[j]
        lam = -a[j] * gamma
        gamma = 1.0 / alpha
        d[j] = beta * gamma * d[j]
        for i in range(j):
            beta = u[i, j]
            u[i, j] = beta + b[i] * lam
            b[i] = b[i] + b[j] * beta
    return x + gamma * dz * b, u, d


def thornton_loop(phi, u_in, d_in, g, dq):
    """Grewal & Andrews, thornton.m (MWGS time update of U D U^T; Qd = G diag(dq) G^T)."""
    n, q = g.shape
    g = g.copy()
    u = np.eye(n)
    d = np.zeros(n)
    phiu = phi @ u_in
    for i in range(n - 1, -1, -1):
        d[i] = sum(phiu[i, j] ** 2 * d_in[j] for j in range(n)) + sum(g[i, j] ** 2 * dq[j] for j in range(q))
        for j in range(i):
            s = sum(phiu[i, k] * d_in[k] * phiu[j, k] for k in range(n)) + \
                sum(g[i, k] * dq[k] * g[j, k] for k in range(q))
            u[j, i] = s / d[i]
            phiu[j] -= u[j, i] * phiu[i]
            g[j] -= u[j, i] * g[i]
    return u, d


@pytest.mark.parametrize('seed', [0, 1])
def test_carlson_and_bierman_scalar_updates_match_textbook_loops(seed):
    rng = np.random.default_rng(seed)
    n = 9
    phi, qd, h, r, p0, x0 = random_linear_problem(rng, n, 1)
    z, rr = 1.7, float(r[0, 0])
    cf = CarlsonFilter(x0, p0)
    x_ref, c_ref = carlson_loop(z, rr, h[0], x0, cf.S)
    cf.update(np.array([z]), h, np.array([[rr]]))
    np.testing.assert_allclose(cf.S, c_ref, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(cf.x, x_ref, rtol=1e-12, atol=1e-13)
    uf = UDFilter(x0, p0)
    x_ref, u_ref, d_ref = bierman_loop(z, rr, h[0], x0, uf.U, uf.D)
    uf.update(np.array([z]), h, np.array([[rr]]))
    np.testing.assert_allclose(uf.U, u_ref, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(uf.D, d_ref, rtol=1e-12)
    np.testing.assert_allclose(uf.x, x_ref, rtol=1e-12, atol=1e-13)


@pytest.mark.parametrize('diagonal_q', [True, False])
def test_thornton_time_update_matches_textbook_loop(diagonal_q):
    rng = np.random.default_rng(3)
    n = 8
    phi, qd, h, r, p0, x0 = random_linear_problem(rng, n, 2)
    if diagonal_q:
        qd = np.diag(np.r_[np.diag(qd)[:5], 0.0, 0.0, 0.0])    # singular Qd: bias-like states
    uf = UDFilter(x0, p0)
    qdd = np.diag(qd)
    if diagonal_q:
        g, dq = np.eye(n)[:, :5], qdd[:5]
    else:
        w, v = np.linalg.eigh(qd)
        g, dq = v, w
    u_ref, d_ref = thornton_loop(phi, uf.U, uf.D, g, dq)
    uf.predict(phi, qd)
    np.testing.assert_allclose(uf.U, u_ref, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(uf.D, d_ref, rtol=1e-10)
    # and the definition: U D U^T = Phi P Phi^T + Qd, U unit upper triangular
    np.testing.assert_allclose(uf.P, phi @ p0 @ phi.T + qd, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(np.diag(uf.U), 1.0)
    np.testing.assert_array_equal(np.tril(uf.U, -1), 0.0)


def test_carlson_factor_is_upper_triangular_and_time_update_exact():
    rng = np.random.default_rng(4)
    n = 10
    phi, qd, h, r, p0, x0 = random_linear_problem(rng, n, 3)
    qd[:, 7:] = 0.0
    qd[7:, :] = 0.0                                          # singular Qd
    cf = CarlsonFilter(x0, p0)
    cf.predict(phi, qd)
    np.testing.assert_array_equal(np.tril(cf.S, -1), 0.0)
    assert np.all(np.diag(cf.S) > 0)
    np.testing.assert_allclose(cf.P, phi @ p0 @ phi.T + qd, rtol=1e-12, atol=1e-12)
    cf.update(rng.standard_normal(3), h, r)                  # correlated R: whitened
    np.testing.assert_array_equal(np.tril(cf.S, -1), 0.0)


def _joseph_reference(x, p, z, h, r):
    """The filter's documented update written out plainly (the pre-optimisation code)."""
    y = z - h @ x
    ph = p @ h.T
    s = h @ ph + r
    s_inv = np.linalg.inv(s)
    k = ph @ s_inv
    ikh = np.eye(x.size) - k @ h
    pn = ikh @ p @ ikh.T + k @ r @ k.T
    return x + k @ y, 0.5 * (pn + pn.T), float(y @ s_inv @ y)


@pytest.mark.parametrize('n,m', [(12, 3), (21, 6)])
def test_kf_with_a_selecting_h_is_the_textbook_update(n, m):
    """A 0/1 H: the kernels' products over H's non-zero cells and the O(m n^2) Joseph form,
    50 predicts and updates against the dense products written out, to rounding (relative to
    |P|: the recursion does not amplify it) and the same NIS to 1e-12."""
    rng = np.random.default_rng(5)
    phi, qd, h, r, p0, x0 = random_linear_problem(rng, n, m, selection=True)
    kf = KalmanFilter(x0, p0)
    x, p = x0.copy(), p0.copy()
    for _ in range(50):
        kf.predict(phi, qd)
        x, p = phi @ x, phi @ p @ phi.T + qd
        z = rng.standard_normal(m)
        res = kf.update(z, h, r)
        x, p, nis = _joseph_reference(x, p, z, h, r)
        np.testing.assert_allclose(kf.x, x, rtol=0.0, atol=1e-13 * np.abs(x).max())
        np.testing.assert_allclose(kf.P, p, rtol=0.0, atol=1e-13 * np.abs(p).max())
        assert res.nis == pytest.approx(nis, rel=1e-12)
