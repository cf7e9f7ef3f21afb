"""The tight form's Dryden turbulence model: an exact, stationary transition; the backward
projection; and the lag-window covariance against a Monte Carlo of the process itself."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from alignment_core.estimation.air_data import turbulence_model as tm


@pytest.mark.parametrize('ds', [0.01, 0.3, 2.0])
def test_transition_is_the_matrix_exponential_and_keeps_the_stationary_covariance(ds):
    """u' = -u + sqrt(2) n; (z, z')' = [[0, 1], [-1, -2]] (z, z') + (0, n): Phi = expm(A ds), and
    P = Phi P Phi^T + Q with P = diag(1, 1/4, 1/4, 1/4, 1/4) (the Lyapunov solution, q = 1)."""
    a = np.zeros((5, 5))
    a[0, 0] = -1.0
    for k in (1, 3):
        a[k:k + 2, k:k + 2] = [[0.0, 1.0], [-1.0, -2.0]]
    phi, q = tm.transition(np.array([ds, ds, ds]))
    np.testing.assert_allclose(phi, expm(a * ds), atol=1e-12)
    np.testing.assert_allclose(phi @ tm.STATIONARY @ phi.T + q, tm.STATIONARY, atol=1e-12)
    assert np.all(np.linalg.eigvalsh(q) > -1e-15)
    b = np.zeros((5, 5))
    b[0, 0], b[2, 2], b[4, 4] = 2.0, 1.0, 1.0
    np.testing.assert_allclose(a @ tm.STATIONARY + tm.STATIONARY @ a.T + b, 0.0, atol=1e-12)


def test_lag_window_variance_of_the_along_track_gust_by_monte_carlo():
    """A stationary unit first-order process of rate r; the port reads its average over the past
    with weights e^(-s/tau)/tau; given the present value, the reading's spread about its
    conditional mean is ~ 2 r E[min(S, S')] = r tau for r tau << 1 (here 0.02)."""
    rng = np.random.default_rng(5)
    rate, tau, n = 2.0, 0.01, 40000
    dt = tau / 40.0
    steps = int(8 * tau / dt)
    x = rng.standard_normal(n)                        # the present value, going back in time
    e = np.exp(-rate * dt)
    avg = np.zeros(n)
    cond = np.zeros(n)
    x0 = x.copy()
    for k in range(steps):
        s = (k + 0.5) * dt
        w = np.exp(-s / tau) / tau * dt
        avg += w * x
        cond += w * np.exp(-rate * s) * x0
        x = e * x + np.sqrt(1 - e * e) * rng.standard_normal(n)    # the process is reversible
    m = np.column_stack([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    cov = tm.lag_covariance(m, np.array([rate, 1.0, 1.0]), np.array([tau]))    # V / L = rate
    expected = float(cov[0, 0, 0, 0])
    assert expected == pytest.approx(rate * tau, rel=1e-12)
    assert np.var(avg - cond) == pytest.approx(expected, rel=0.1)
