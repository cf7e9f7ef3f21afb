"""The interface shared by every filter of the bank, and the numerical helpers they share.

Interface (a structural `Protocol`: any class with these members qualifies):

    f.x, f.P                      state (n,) and its full covariance (n, n), in f.dtype; both
                                  settable (a factored filter re-factors an assigned P)
    f.predict(phi, qd)            x <- Phi x, P <- Phi P Phi^T + Qd (+ the filter's fading)
    f.update(z, h, r, gate_chi2=None) -> UpdateResult
                                  z (m,), H (m, n), R (m, m) SPD. If gate_chi2 is given and the
                                  normalised innovation squared y^T S^-1 y exceeds it, nothing
                                  changes, the rejection is counted and accepted=False.
    f.reset_state(x=None)         x <- 0 (or x), covariance untouched: the closed-loop feedback
                                  step of an error-state filter, valid for factored filters too
    f.diagnostics() -> dict       at least: 'nis' (last), 'updates' (accepted), 'gated'
                                  (rejected), 'predicts'; fading filters add their factor(s)

Nonlinear filters (EKF, UKF, CKF) also take callables:

    f.predict_nonlinear(fun, qd, jac=None)           x <- fun(x), additive process noise Qd
    f.update_nonlinear(z, hfun, r, gate_chi2=None, jac=None) -> UpdateResult

`UpdateResult.s` and `.nis` are those the gate tested: the innovation covariance predicted by
the filter's nominal model (before any innovation-driven fading, see fading.py)."""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np
import scipy.linalg as sla

try:  # the gufuncs behind np.linalg.inv/solve, without its per-call wrapper overhead (~2.5 us)
    from numpy.linalg import _umath_linalg as _uml

    def inv(a: np.ndarray) -> np.ndarray:
        """Inverse in a's own precision (np.linalg.inv would compute float32 in float64).
        Singular input gives non-finite entries (the callers check the NIS) instead of raising."""
        return _uml.inv(a, signature='d->d' if a.dtype == np.float64 else 'f->f')

    def solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """X with a X = b for a (n, n) and b (n, k): np.linalg.solve's numbers at half its cost
        (float32 only if both are float32). Singular a gives non-finite entries (and a numpy
        RuntimeWarning) instead of raising; a filter update with them fails its NIS check."""
        single = a.dtype == np.float32 and b.dtype == np.float32
        return _uml.solve(a, b, signature='ff->f' if single else 'dd->d')
except (ImportError, AttributeError):  # pragma: no cover - other numpy layouts
    def inv(a: np.ndarray) -> np.ndarray:
        return sla.inv(a, check_finite=False).astype(a.dtype, copy=False)

    def solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.linalg.solve(a, b)


@dataclass(slots=True)
class UpdateResult:
    """Innovation, its covariance and the normalised innovation squared of one update."""
    innovation: np.ndarray
    s: np.ndarray
    nis: float
    accepted: bool


@runtime_checkable
class Filter(Protocol):
    """What every filter of the bank offers (see the module docstring)."""
    dtype: np.dtype

    @property
    def x(self) -> np.ndarray: ...

    @property
    def P(self) -> np.ndarray: ...

    def predict(self, phi: np.ndarray, qd: np.ndarray) -> None: ...

    def update(self, z: np.ndarray, h: np.ndarray, r: np.ndarray,
               gate_chi2: float | None = None) -> UpdateResult: ...

    def reset_state(self, x: np.ndarray | None = None) -> None: ...

    def diagnostics(self) -> dict[str, Any]: ...


@runtime_checkable
class NonlinearFilter(Filter, Protocol):
    """A filter that also propagates and measures through callables."""

    def predict_nonlinear(self, fun: Callable[[np.ndarray], np.ndarray], qd: np.ndarray,
                          jac: Callable[[np.ndarray], np.ndarray] | None = None) -> None: ...

    def update_nonlinear(self, z: np.ndarray, hfun: Callable[[np.ndarray], np.ndarray], r: np.ndarray,
                         gate_chi2: float | None = None,
                         jac: Callable[[np.ndarray], np.ndarray] | None = None) -> UpdateResult: ...


class Counters:
    """Bookkeeping shared by all filters: predicts, accepted and gated updates, last NIS."""

    def _init_counters(self) -> None:
        self.n_predicts = 0
        self.n_updates = 0
        self.n_gated = 0
        self.last_nis = float('nan')

    def diagnostics(self) -> dict[str, Any]:
        return {'filter': type(self).__name__, 'nis': self.last_nis, 'updates': self.n_updates,
                'gated': self.n_gated, 'predicts': self.n_predicts}


def as_dtype(a, dtype: np.dtype) -> np.ndarray:
    """a as an ndarray of dtype (a native float64 or float32 descriptor, np.dtype(...)), without a
    copy when it already is one."""
    if type(a) is np.ndarray and (a.dtype is dtype or a.dtype == dtype):
        return a
    return np.asarray(a, dtype=dtype)


def check_nis(nis: float) -> float:
    """nis, unless it shows S is not positive definite: not finite (S singular) or negative."""
    if not 0.0 <= nis < math.inf:
        raise np.linalg.LinAlgError('innovation covariance is singular, not finite or not positive definite')
    return nis


def sqrt_psd(a: np.ndarray) -> np.ndarray:
    """G (n, k) with G G^T = a for a symmetric positive semi-definite a, in a's dtype; only the
    columns of non-zero variance are kept (k <= n). Diagonal: sqrt of the non-zero diagonal;
    otherwise Cholesky, or for a singular a the eigen-decomposition with its negative round-off
    eigenvalues clipped to zero."""
    d = np.diagonal(a)
    if np.count_nonzero(a - np.diag(d)) == 0:
        nz = np.flatnonzero(d > 0)
        g = np.zeros((a.shape[0], nz.size), dtype=a.dtype)
        g[nz, np.arange(nz.size)] = np.sqrt(d[nz])
        return g
    try:
        return sla.cholesky(a, lower=True, check_finite=False)
    except np.linalg.LinAlgError:
        w, v = sla.eigh(a, check_finite=False)
        keep = w > 0
        return (v[:, keep] * np.sqrt(w[keep])).astype(a.dtype, copy=False)


def ud_psd(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(G (n, k), d (k,)) with G diag(d) G^T = a for a symmetric PSD a (for the UD time update):
    the non-zero diagonal if a is diagonal, else the positive eigenpairs."""
    dg = np.diagonal(a)
    if np.count_nonzero(a - np.diag(dg)) == 0:
        nz = np.flatnonzero(dg > 0)
        g = np.zeros((a.shape[0], nz.size), dtype=a.dtype)
        g[nz, np.arange(nz.size)] = 1
        return g, dg[nz].copy()
    w, v = sla.eigh(a, check_finite=False)
    keep = w > 0
    return v[:, keep].astype(a.dtype, copy=False), w[keep].astype(a.dtype, copy=False)


_GEQRF = {np.dtype(np.float64): sla.lapack.get_lapack_funcs('geqrf', dtype=np.float64),
          np.dtype(np.float32): sla.lapack.get_lapack_funcs('geqrf', dtype=np.float32)}


def tria_upper(a: np.ndarray) -> np.ndarray:
    """Upper-triangular S (n, n) with S S^T = a^T a, for a (k, n), k >= n, by one Householder QR
    (LAPACK geqrf in a's own precision) of a with its columns reversed: a J = Q R gives
    a^T a = J R^T R J = (J R^T J)(J R^T J)^T, and J R^T J is upper triangular. The diagonal is
    made non-negative (S D with D = diag(+-1) has the same S S^T), so the factor is unique."""
    n = a.shape[1]
    qr, _tau, _work, info = _GEQRF[a.dtype](np.array(a[:, ::-1], order='F'), overwrite_a=1)
    if info != 0:  # pragma: no cover - geqrf only fails on illegal arguments
        raise np.linalg.LinAlgError(f'geqrf info={info}')
    r = np.triu(qr[:n, :])
    s = r[::-1, ::-1].T
    sg = np.sign(np.diagonal(s))
    sg[sg == 0] = 1
    return np.ascontiguousarray(s * sg)


def chol_upper(p: np.ndarray) -> np.ndarray:
    """Upper-triangular S with S S^T = p (the Carlson convention, not the usual S^T S)."""
    if p.shape[0] == 0:
        return p.copy()
    jpj = p[::-1, ::-1]
    try:
        lo = sla.cholesky(jpj, lower=True, check_finite=False)
    except np.linalg.LinAlgError:  # semi-definite: through a QR of the eigen square root
        w, v = sla.eigh(p, check_finite=False)
        g = v * np.sqrt(np.clip(w, 0, None))
        return tria_upper(np.ascontiguousarray(g.T))
    return np.ascontiguousarray(lo[::-1, ::-1]).astype(p.dtype, copy=False)


def numerical_jacobian(fun: Callable[[np.ndarray], np.ndarray], x: np.ndarray,
                       step: np.ndarray) -> np.ndarray:
    """Central differences (f(x + h_j e_j) - f(x - h_j e_j)) / (2 h_j). Exact for a linear fun up
    to round-off of order eps |f| / h_j; the truncation error is O(h_j^2 f''')."""
    cols = []
    for j in range(x.size):
        e = np.zeros_like(x)
        e[j] = step[j]
        cols.append((np.asarray(fun(x + e)) - np.asarray(fun(x - e))) / (2.0 * step[j]))
    return np.stack(cols, axis=1)


def jacobian_steps(x: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Difference steps scaled to the state's own uncertainty: 1e-3 sigma_j (truncation error
    ~1e-6 relative when the function bends on the scale of sigma; round-off eps |f| / h), or
    1e-6 (1 + |x_j|) for a state with zero variance."""
    sig = np.sqrt(np.clip(np.diagonal(p), 0, None))
    return np.where(sig > 0, 1e-3 * sig, 1e-6 * (1.0 + np.abs(x)))
