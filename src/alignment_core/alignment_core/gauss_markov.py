"""Gauss-Markov processes: exact discretisation shared by the truth models (deck flexure)
and the filter models that estimate them."""
from __future__ import annotations

import numpy as np
from scipy.linalg import expm

BETA_TAU = 2.146


def gm2_discrete(sigma: float, tau: float, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact discretisation of the second-order Gauss-Markov process over dt:
    (Phi, Qd, P_stationary), each (2, 2), state [theta, theta']."""
    beta = BETA_TAU / tau
    a = np.array([[0.0, 1.0], [-beta**2, -2.0 * beta]])
    q = np.array([[0.0, 0.0], [0.0, 4.0 * beta**3 * sigma**2]])
    m = np.zeros((4, 4))
    m[:2, :2] = -a
    m[:2, 2:] = q
    m[2:, 2:] = a.T
    e = expm(m * dt)
    phi = e[2:, 2:].T
    qd = phi @ e[:2, 2:]
    qd = 0.5 * (qd + qd.T)
    return phi, qd, np.diag([sigma**2, beta**2 * sigma**2])
