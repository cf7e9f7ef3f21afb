"""The nonlinear filter of an air-data estimator by name (ekf | ukf | ckf), and the linearised
output statistics they share."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from alignment_core.estimation.filters import CubatureKalmanFilter, ExtendedKalmanFilter, UnscentedKalmanFilter

NonlinearFilter = ExtendedKalmanFilter | UnscentedKalmanFilter | CubatureKalmanFilter


def make_nonlinear_filter(algorithm: str, x0: np.ndarray, p0: np.ndarray) -> NonlinearFilter:
    """EKF, UKF (alpha 1, beta 2, kappa 0) or CKF on (x0, P0)."""
    if algorithm == 'ekf':
        return ExtendedKalmanFilter(x0, p0)
    if algorithm == 'ukf':
        return UnscentedKalmanFilter(x0, p0)
    if algorithm == 'ckf':
        return CubatureKalmanFilter(x0, p0)
    raise ValueError(f"unknown air-data filter algorithm {algorithm!r} (ekf, ukf, ckf)")


def linearised_covariance(fun: Callable[[np.ndarray], np.ndarray], x: np.ndarray,
                          p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(fun(x) (k,), J P J^T (k, k)) with J by central differences of steps 1e-3 sigma_j for a
    vectorized fun ((N, n) -> (N, k)); states of zero variance contribute nothing."""
    sig = np.sqrt(np.clip(np.diagonal(p), 0.0, None))
    used = np.flatnonzero(sig > 0.0)
    steps = 1e-3 * sig[used]
    pts = np.repeat(x[None, :], 2 * used.size + 1, axis=0)
    pts[1 + np.arange(used.size), used] += steps
    pts[1 + used.size + np.arange(used.size), used] -= steps
    y = fun(pts)
    jac = ((y[1:1 + used.size] - y[1 + used.size:]) / (2.0 * steps[:, None])).T      # (k, u)
    return y[0], jac @ p[np.ix_(used, used)] @ jac.T
