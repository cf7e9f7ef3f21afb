"""Statistical sanity of the harness (Monte Carlo NEES / NIS of the KF against chi-square bands)
and the moments the sigma-point rules must reproduce by construction."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from alignment_core.estimation.filters import (
    CubatureKalmanFilter,
    ExtendedKalmanFilter,
    KalmanFilter,
    UnscentedKalmanFilter,
)

RUNS = 200


def _cv_model(dt=0.1, q=0.1, r=0.25):
    """Two axes of constant velocity, white-acceleration noise q, positions measured."""
    f1 = np.array([[1.0, dt], [0.0, 1.0]])
    q1 = q * np.array([[dt ** 3 / 3, dt ** 2 / 2], [dt ** 2 / 2, dt]])
    phi = np.kron(np.eye(2), f1)
    qd = np.kron(np.eye(2), q1)
    h = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
    return phi, qd, h, r * np.eye(2), np.diag([4.0, 1.0, 4.0, 1.0])


def test_kf_nees_and_nis_in_their_95_percent_bands():
    """For a correct model each run's NEES at step k is chi2(n) and its NIS chi2(m), independent
    across runs: the average over N runs times N is chi2(N n) (resp. chi2(N m)). Checked at three
    steps chosen beforehand (1, 10, 50); N = 200, n = 4, m = 2."""
    phi, qd, h, r, p0 = _cv_model()
    n, m, steps = 4, 2, 50
    rng = np.random.default_rng(42)
    lq, lr, l0 = np.linalg.cholesky(qd), np.linalg.cholesky(r), np.linalg.cholesky(p0)
    nees = np.empty((RUNS, steps))
    nis = np.empty((RUNS, steps))
    for i in range(RUNS):
        x = l0 @ rng.standard_normal(n)                  # truth ~ N(0, P0), filter starts at 0
        kf = KalmanFilter(np.zeros(n), p0)
        for k in range(steps):
            x = phi @ x + lq @ rng.standard_normal(n)
            kf.predict(phi, qd)
            res = kf.update(h @ x + lr @ rng.standard_normal(m), h, r)
            e = x - kf.x
            nees[i, k] = e @ np.linalg.solve(kf.P, e)
            nis[i, k] = res.nis
    for k in (0, 9, 49):
        lo, hi = chi2.ppf([0.025, 0.975], RUNS * n) / RUNS
        assert lo < nees[:, k].mean() < hi, (k, nees[:, k].mean(), lo, hi)
        lo, hi = chi2.ppf([0.025, 0.975], RUNS * m) / RUNS
        assert lo < nis[:, k].mean() < hi, (k, nis[:, k].mean(), lo, hi)


MU, SIG = 1.5, 0.7


def _square_moments(f):
    """Propagate x ~ N(MU, SIG^2) through x^2 (plus zero process noise)."""
    f.predict_nonlinear(lambda x: x ** 2, np.zeros((1, 1)), jac=lambda x: np.array([[2.0 * x[0]]]))
    return f.x[0], f.P[0, 0]


def test_sigma_point_rules_reproduce_their_theoretical_moments():
    """y = x^2, x ~ N(mu, s^2): E y = mu^2 + s^2, var y = 4 mu^2 s^2 + 2 s^4.
    UKF with alpha = 1, beta = 0, kappa = 3 - n = 2 matches the Gaussian's 4th moment: exact mean
    and variance. CKF (third-degree rule) integrates x^2 exactly but not x^4: exact mean, variance
    4 mu^2 s^2 (the missing 2 s^4 is the rule's degree limit). EKF: mean mu^2, variance 4 mu^2 s^2."""
    p0 = np.array([[SIG ** 2]])
    x0 = np.array([MU])
    mean_true = MU ** 2 + SIG ** 2
    var_true = 4 * MU ** 2 * SIG ** 2 + 2 * SIG ** 4
    m, v = _square_moments(UnscentedKalmanFilter(x0, p0, alpha=1.0, beta=0.0, kappa=2.0))
    assert m == pytest.approx(mean_true, rel=1e-13) and v == pytest.approx(var_true, rel=1e-13)
    m, v = _square_moments(CubatureKalmanFilter(x0, p0))
    assert m == pytest.approx(mean_true, rel=1e-13) and v == pytest.approx(4 * MU ** 2 * SIG ** 2, rel=1e-13)
    m, v = _square_moments(ExtendedKalmanFilter(x0, p0))
    assert m == pytest.approx(MU ** 2, rel=1e-13) and v == pytest.approx(4 * MU ** 2 * SIG ** 2, rel=1e-13)


def test_cubature_rule_integrates_cubics_exactly_in_several_dimensions():
    """Third-degree spherical-radial rule: E[f(x)] exact for every polynomial of degree <= 3 in
    x ~ N(m, P). f(x) = x^T A x + (b^T x)^3: E = tr(A P) + m^T A m + (b^T m)^3 + 3 (b^T m)(b^T P b)."""
    rng = np.random.default_rng(3)
    n = 5
    a = rng.standard_normal((n, n))
    p = a @ a.T / n + 0.3 * np.eye(n)
    mean = rng.standard_normal(n)
    big_a = rng.standard_normal((n, n))
    b = rng.standard_normal(n)
    ckf = CubatureKalmanFilter(mean, p)
    pts, wm, _ = ckf.sigma_points(mean, p)
    vals = np.array([x @ big_a @ x + (b @ x) ** 3 for x in pts])
    bm, bpb = b @ mean, b @ p @ b
    expected = np.trace(big_a @ p) + mean @ big_a @ mean + bm ** 3 + 3 * bm * bpb
    assert wm @ vals == pytest.approx(expected, rel=1e-12)
    assert wm.size == 2 * n and np.allclose(wm, 1.0 / (2 * n))
