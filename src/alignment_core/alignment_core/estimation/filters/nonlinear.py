"""Nonlinear filters: extended, unscented (scaled unscented transform) and cubature Kalman
filters. All take the linear predict(Phi, Qd) / update(z, H, R) of the common interface and, in
addition, callables:

    predict_nonlinear(fun, qd, jac=None)          x_k = fun(x_(k-1)) + w,  w ~ N(0, Qd)
    update_nonlinear(z, hfun, r, gate_chi2=None, jac=None)   z = hfun(x) + v,  v ~ N(0, R)

fun and hfun map one state (n,) to (n,) / (m,). jac (EKF only) returns the Jacobian at x; without
it the EKF uses central differences with steps 1e-3 sigma_j (base.numerical_jacobian). A callable
with the attribute `vectorized = True` maps a batch of states (N, n) to (N, n) / (N, m) instead:
the sigma-point filters then evaluate all their points in one call (same numbers, far fewer
Python calls).

For linear maps the sigma-point rules are exact (they integrate polynomials of degree 3, and
degree 2 exactly is all a linear-Gaussian step needs), so the linear predict/update of UKF and
CKF compute that result directly: KF prediction, and the update x += K y,
P <- P - K S K^T with K = P H^T S^-1 (the Joseph form is kept for the EKF, which is a KF).
float64 only."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.linalg as sla

from alignment_core.estimation.filters.base import (
    Counters,
    UpdateResult,
    as_dtype,
    check_nis,
    inv,
    jacobian_steps,
    numerical_jacobian,
)
from alignment_core.estimation.filters.kalman import KalmanFilter

Fn = Callable[[np.ndarray], np.ndarray]
_dot = np.dot


def _evaluate(fun: Fn, pts: np.ndarray) -> np.ndarray:
    """fun at every row of pts (N, n): one call if fun is vectorized, else one per row."""
    if getattr(fun, 'vectorized', False):
        return np.asarray(fun(pts), dtype=float)
    return np.array([fun(p) for p in pts], dtype=float)


def _jacobian(fun: Fn, x: np.ndarray, step: np.ndarray) -> np.ndarray:
    """Central differences of fun at x (base.numerical_jacobian), all 2n points in one call
    when fun is vectorized."""
    if not getattr(fun, 'vectorized', False):
        return numerical_jacobian(fun, x, step)
    e = np.diag(step)
    y = _evaluate(fun, np.concatenate([x + e, x - e]))
    n = x.size
    return ((y[:n] - y[n:]) / (2.0 * step[:, None])).T


class ExtendedKalmanFilter(KalmanFilter):
    """EKF: the KalmanFilter (Joseph update) linearised about the current estimate."""

    def predict_nonlinear(self, fun: Fn, qd: np.ndarray, jac: Fn | None = None) -> None:
        x = self.x
        phi = jac(x) if jac is not None else _jacobian(fun, x, jacobian_steps(x, self.P))
        phi = as_dtype(phi, self.dtype)
        self.x = as_dtype(_evaluate(fun, x[None, :])[0], self.dtype).copy()
        self.P = _dot(_dot(phi, self.P), phi.T) + as_dtype(qd, self.dtype)
        self.n_predicts += 1

    def update_nonlinear(self, z: np.ndarray, hfun: Fn, r: np.ndarray, gate_chi2: float | None = None,
                         jac: Fn | None = None) -> UpdateResult:
        x = self.x
        h = jac(x) if jac is not None else _jacobian(hfun, x, jacobian_steps(x, self.P))
        dt = self.dtype
        h, r = as_dtype(h, dt), as_dtype(r, dt)
        y = as_dtype(z, dt) - as_dtype(_evaluate(hfun, x[None, :])[0], dt)
        ph = _dot(self.P, h.T)
        s = _dot(h, ph) + r
        s_inv = inv(s)
        nis = check_nis(float(_dot(_dot(y, s_inv), y)))
        self.last_nis = nis
        if gate_chi2 is not None and nis > gate_chi2:
            self.n_gated += 1
            return UpdateResult(y, s, nis, False)
        self._joseph(y, ph, s_inv, h, r)
        self.n_updates += 1
        return UpdateResult(y, s, nis, True)


class _SigmaPointFilter(Counters):
    """Shared machinery of UKF and CKF: points X_i = x + (chol factor columns) * spread, mean
    weights wm, covariance weights wc."""

    def __init__(self, x0, p0) -> None:
        self.dtype = np.dtype(np.float64)
        self.x = np.array(x0, dtype=float)
        self.P = np.array(p0, dtype=float)
        self._init_counters()

    def reset_state(self, x: np.ndarray | None = None) -> None:
        self.x = np.zeros_like(self.x) if x is None else np.array(x, dtype=float)

    def _weights(self, n: int) -> tuple[float, np.ndarray, np.ndarray]:
        """(spread c, wm, wc) with points x, x +- c L e_i (i = 1..n), in that order."""
        raise NotImplementedError

    @staticmethod
    def _sqrt(p: np.ndarray) -> np.ndarray:
        try:
            return sla.cholesky(p, lower=True, check_finite=False)
        except np.linalg.LinAlgError:  # semi-definite P: symmetric square root
            w, v = np.linalg.eigh(p)
            return v * np.sqrt(np.clip(w, 0.0, None))

    def sigma_points(self, x: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(X (N, n), wm (N,), wc (N,))."""
        n = x.size
        c, wm, wc = self._weights(n)
        a = c * self._sqrt(p).T                    # rows: c L e_i
        pts = np.concatenate([x[None, :], x + a, x - a]) if wm.size == 2 * n + 1 else \
            np.concatenate([x + a, x - a])
        return pts, wm, wc

    def predict(self, phi: np.ndarray, qd: np.ndarray) -> None:
        self.x = _dot(phi, self.x)
        self.P = _dot(_dot(phi, self.P), phi.T) + qd
        self.n_predicts += 1

    def predict_nonlinear(self, fun: Fn, qd: np.ndarray, jac: Fn | None = None) -> None:
        pts, wm, wc = self.sigma_points(self.x, self.P)
        y = _evaluate(fun, pts)
        xm = _dot(wm, y)
        dy = y - xm
        p = _dot(dy.T * wc, dy) + qd
        self.x = xm
        self.P = 0.5 * (p + p.T)
        self.n_predicts += 1

    def _finish(self, y, s, pxz, gate_chi2) -> UpdateResult:
        s_inv = inv(s)
        nis = check_nis(float(_dot(_dot(y, s_inv), y)))
        self.last_nis = nis
        if gate_chi2 is not None and nis > gate_chi2:
            self.n_gated += 1
            return UpdateResult(y, s, nis, False)
        k = _dot(pxz, s_inv)
        self.x = self.x + _dot(k, y)
        p = self.P - _dot(_dot(k, s), k.T)
        self.P = 0.5 * (p + p.T)
        self.n_updates += 1
        return UpdateResult(y, s, nis, True)

    def update(self, z: np.ndarray, h: np.ndarray, r: np.ndarray,
               gate_chi2: float | None = None) -> UpdateResult:
        pxz = _dot(self.P, h.T)
        return self._finish(z - _dot(h, self.x), _dot(h, pxz) + r, pxz, gate_chi2)

    def update_nonlinear(self, z: np.ndarray, hfun: Fn, r: np.ndarray, gate_chi2: float | None = None,
                         jac: Fn | None = None) -> UpdateResult:
        """Points redrawn from the predicted (x, P), so the cross-covariance includes Qd."""
        pts, wm, wc = self.sigma_points(self.x, self.P)
        zs = _evaluate(hfun, pts)
        zm = _dot(wm, zs)
        dz = zs - zm
        dx = pts - self.x
        s = _dot(dz.T * wc, dz) + r
        pxz = _dot(dx.T * wc, dz)
        return self._finish(np.asarray(z, dtype=float) - zm, s, pxz, gate_chi2)


class UnscentedKalmanFilter(_SigmaPointFilter):
    """UKF with the scaled unscented transform (Julier 2002; Wan & van der Merwe):
    lambda = alpha^2 (n + kappa) - n, points x and x +- sqrt(n + lambda) L e_i (P = L L^T),
    wm_0 = lambda / (n + lambda), wc_0 = wm_0 + 1 - alpha^2 + beta, wm_i = wc_i = 1 / (2 (n + lambda)).
    Defaults alpha = 1, beta = 2 (Gaussian prior), kappa = 0: then wm_0 = 0, wc_0 = 2 and no
    weight is negative, which avoids the large negative centre weight (and its cancellation)
    of a small alpha."""

    def __init__(self, x0, p0, alpha: float = 1.0, beta: float = 2.0, kappa: float = 0.0) -> None:
        super().__init__(x0, p0)
        self.alpha, self.beta, self.kappa = float(alpha), float(beta), float(kappa)
        n = self.x.size
        if self.alpha ** 2 * (n + self.kappa) <= 0.0:
            raise ValueError('alpha^2 (n + kappa) must be > 0')

    def _weights(self, n):
        lam = self.alpha ** 2 * (n + self.kappa) - n
        c = np.sqrt(n + lam)
        wm = np.full(2 * n + 1, 0.5 / (n + lam))
        wc = wm.copy()
        wm[0] = lam / (n + lam)
        wc[0] = wm[0] + 1.0 - self.alpha ** 2 + self.beta
        return c, wm, wc


class CubatureKalmanFilter(_SigmaPointFilter):
    """CKF (Arasaratnam & Haykin 2009): third-order spherical-radial rule, 2n points
    x +- sqrt(n) L e_i with equal weights 1 / (2n)."""

    def _weights(self, n):
        w = np.full(2 * n, 0.5 / n)
        return np.sqrt(n), w, w
