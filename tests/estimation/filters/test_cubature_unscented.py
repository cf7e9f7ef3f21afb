"""The cubature rule is the unscented transform with alpha = 1, beta = 0, kappa = 0 (lambda = 0:
points x +- sqrt(n) L e_i, the centre weight 0 for the mean and the covariance), so the two
filters agree on any nonlinear problem; and a vectorized callable gives the per-point numbers."""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.filters import CubatureKalmanFilter, ExtendedKalmanFilter, UnscentedKalmanFilter


def fun(x):
    return np.array([x[0] + 0.1 * np.sin(x[1]), x[1] * np.cos(0.2 * x[0]), 0.9 * x[2] + 0.05 * x[0] * x[1]])


def hfun(x):
    return np.array([np.hypot(x[0], x[1]), np.arctan2(x[1], x[0] + 3.0)])


def batch(f):
    def g(xs):
        return np.array([f(x) for x in xs])
    g.vectorized = True
    return g


def run(filt, f=fun, h=hfun):
    rng = np.random.default_rng(3)
    qd, r = np.diag([1e-3, 2e-3, 1e-3]), np.diag([0.01, 0.02])
    for _ in range(20):
        filt.predict_nonlinear(f, qd)
        filt.update_nonlinear(hfun(rng.normal(size=3)) + rng.normal(size=2) * 0.1, h, r)
    return filt.x, filt.P


X0, P0 = np.array([1.0, 0.5, -0.3]), np.diag([0.5, 0.3, 0.2])


def test_ckf_equals_ukf_with_alpha_1_beta_0_kappa_0():
    xc, pc = run(CubatureKalmanFilter(X0, P0))
    xu, pu = run(UnscentedKalmanFilter(X0, P0, alpha=1.0, beta=0.0, kappa=0.0))
    np.testing.assert_allclose(xc, xu, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(pc, pu, rtol=1e-10, atol=1e-14)
    # and differs from the default UKF (beta = 2 weights the centre point's covariance)
    xd, pd = run(UnscentedKalmanFilter(X0, P0))
    assert np.max(np.abs(pd - pc)) > 1e-6


def test_vectorized_callables_give_the_same_numbers():
    for make in (CubatureKalmanFilter, UnscentedKalmanFilter, ExtendedKalmanFilter):
        x1, p1 = run(make(X0, P0))
        x2, p2 = run(make(X0, P0), batch(fun), batch(hfun))
        np.testing.assert_allclose(x2, x1, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(p2, p1, rtol=1e-9, atol=1e-12)
