"""Factored covariance filters: Carlson square root, Bierman-Thornton UD, and the seed-003
combination of Carlson's filter with an innovation-tested fading factor.

Both carry a factor instead of P, which squares the effective precision: the factor's condition
number is the square root of P's, and P = S S^T (or U D U^T) is positive semi-definite by
construction whatever the round-off. Measurements are processed one scalar at a time (a
correlated R is first whitened by its Cholesky factor, R = L L^T: z <- L^-1 z, H <- L^-1 H).
The gate tests the whole vector innovation against S = H P H^T + R before any scalar update.

Both scalar updates are written as whole-array operations: the inner loops of Carlson's and
Bierman's algorithms only accumulate w_i = sum_{k<j} S_ik f_k (resp. U_ik g_k) column after
column, which is an exclusive running sum along the rows, and the per-column scalars alpha_j
are running sums of f_j^2 (resp. f_j g_j) starting at r. Both are taken as one product with a
triangular matrix of ones (same terms as the loops, BLAS summation order; checked against the
textbook loops in the tests). All terms of alpha_j are non-negative, so no order matters for
its accuracy; alpha_(j-1) is summed on its own, not as alpha_j - f_j^2, which would cancel r.

dtype float32 makes every array and every operation (BLAS, LAPACK geqrf/potrf/trtrs) single
precision, for the round-off experiments of seed 003."""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from alignment_core.estimation.filters.base import (
    Counters,
    UpdateResult,
    as_dtype,
    check_nis,
    chol_upper,
    inv,
    sqrt_psd,
    tria_upper,
    ud_psd,
)

_dot = np.dot


class _Factored(Counters):
    """x handling, input casting, the whitening of R and the gate, shared by Carlson and UD."""

    def __init__(self, x0, p0, dtype=np.float64) -> None:
        self.dtype = np.dtype(dtype)
        self._x = np.array(x0, dtype=self.dtype)
        n = self._x.size
        # [upper-triangular ones | strictly upper-triangular ones]: one product gives the
        # inclusive and the exclusive running sums of the scalar updates
        self._ones_ut = np.hstack([np.triu(np.ones((n, n))), np.triu(np.ones((n, n)), 1)]).astype(self.dtype)
        self.P = p0
        self._q_key: tuple | None = None
        self._q_fac = None
        self._init_counters()

    @property
    def x(self) -> np.ndarray:
        return self._x

    @x.setter
    def x(self, value) -> None:
        self._x = np.array(value, dtype=self.dtype)

    def reset_state(self, x: np.ndarray | None = None) -> None:
        """Closed-loop feedback: x <- 0 (or x); the covariance factor is untouched."""
        self._x = np.zeros_like(self._x) if x is None else np.array(x, dtype=self.dtype)

    def _q_factor(self, qd: np.ndarray, fn):
        """fn(qd), cached on the bytes of Qd (which is usually one of a few constant matrices)."""
        key = (qd.shape, qd.tobytes())
        if key != self._q_key:
            self._q_key, self._q_fac = key, fn(qd)
        return self._q_fac

    def _hf(self, h: np.ndarray) -> np.ndarray:
        """H times the left factor (H S or H U)."""
        raise NotImplementedError

    def _s_from(self, hf: np.ndarray, r: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _scalar(self, zj, hj: np.ndarray, rj) -> None:
        raise NotImplementedError

    def _before_scalars(self, y, h, r, s0) -> None:
        """Hook between the gate and the scalar updates (the fading of SqrtFadingFilter)."""

    def _after_update(self) -> None:
        """Hook after an accepted update."""

    def update(self, z: np.ndarray, h: np.ndarray, r: np.ndarray,
               gate_chi2: float | None = None) -> UpdateResult:
        dt = self.dtype
        z, h, r = as_dtype(z, dt), as_dtype(h, dt), as_dtype(r, dt)
        y = z - _dot(h, self._x)
        s = self._s_from(self._hf(h), r)
        nis = check_nis(float(_dot(_dot(y, inv(s)), y)))
        self.last_nis = nis
        if gate_chi2 is not None and nis > gate_chi2:
            self.n_gated += 1
            return UpdateResult(y, s, nis, False)
        self._before_scalars(y, h, r, s)
        rd = np.diagonal(r)
        if np.count_nonzero(r - np.diag(rd)):          # correlated R: whiten
            lo = sla.cholesky(r, lower=True, check_finite=False)
            z = sla.solve_triangular(lo, z, lower=True, check_finite=False)
            h = sla.solve_triangular(lo, h, lower=True, check_finite=False)
            rd = np.ones(len(z), dtype=dt)
        for j in range(len(z)):
            self._scalar(z[j], h[j], rd[j])
        self._after_update()
        self.n_updates += 1
        return UpdateResult(y, s, nis, True)


class CarlsonFilter(_Factored):
    """Carlson's square-root filter: P = S S^T with S upper triangular.

    Measurement update: Carlson's triangular scalar update (no square root of a difference,
    S stays upper triangular). Time update: S- is the triangular factor of
    [S^T Phi^T; G^T] (G G^T = Qd) by one Householder QR, so Qd needs no special treatment
    (a singular Qd just has fewer columns in G; see base.sqrt_psd)."""

    @property
    def P(self) -> np.ndarray:
        return _dot(self._s, self._s.T)

    @P.setter
    def P(self, value) -> None:
        self._set_p(value)

    def _set_p(self, value) -> None:
        self._s = chol_upper(np.array(value, dtype=self.dtype))

    @property
    def S(self) -> np.ndarray:
        """The upper-triangular factor (P = S S^T)."""
        return self._s

    def predict(self, phi: np.ndarray, qd: np.ndarray) -> None:
        dt = self.dtype
        phi, qd = as_dtype(phi, dt), as_dtype(qd, dt)
        self._x = _dot(phi, self._x)
        gt = self._q_factor(qd, lambda q: np.ascontiguousarray(sqrt_psd(q).T))
        self._s = tria_upper(np.vstack([_dot(phi, self._s).T, gt]))
        self.n_predicts += 1

    def _hf(self, h):
        return _dot(h, self._s)

    def _s_from(self, hf, r):
        return _dot(hf, hf.T) + r

    def _scalar(self, zj, hj, rj) -> None:
        """Carlson's scalar update of (x, S) with z_j = h_j x + v, var(v) = r_j > 0:
        f = S^T h;  alpha_0 = r, alpha_j = alpha_(j-1) + f_j^2;  for column j:
        S_ij <- sqrt(alpha_(j-1)/alpha_j) S_ij - f_j/sqrt(alpha_j alpha_(j-1)) w_i, w_i += S_ij(old) f_j;
        finally K = w / alpha_n = P h / (h P h + r)."""
        s = self._s
        f = _dot(hj, s)
        a = _dot(f * f, self._ones_ut) + rj           # [alpha_1..alpha_n, alpha_0..alpha_(n-1)]
        n = f.size
        a_j, a_prev = a[:n], a[n:]
        g = np.sqrt(a_j * a_prev)
        t = s * f
        w = _dot(t, self._ones_ut[:, n:])             # w_ij = sum_(k<j) S_ik f_k (before column j)
        w_last = w[:, -1] + t[:, -1]                  # = S f = P h
        w *= f / g
        t = s * (a_prev / g)
        t -= w
        self._s = t
        self._x = self._x + w_last * ((zj - _dot(hj, self._x)) / a_j[-1])


class UDFilter(_Factored):
    """Bierman-Thornton UD filter: P = U diag(d) U^T, U unit upper triangular.

    Measurement update: Bierman's scalar update. Time update: Thornton's modified weighted
    Gram-Schmidt orthogonalisation of the rows of [Phi U, G] with weights diag(d, dq),
    Qd = G diag(dq) G^T (base.ud_psd)."""

    @property
    def P(self) -> np.ndarray:
        return _dot(self._u * self._d, self._u.T)

    @P.setter
    def P(self, value) -> None:
        s = chol_upper(np.array(value, dtype=self.dtype))
        sd = np.diagonal(s).copy()
        sd[sd == 0] = 1
        self._u = s / sd
        self._d = np.diagonal(s) ** 2

    @property
    def U(self) -> np.ndarray:
        return self._u

    @property
    def D(self) -> np.ndarray:
        return self._d

    def predict(self, phi: np.ndarray, qd: np.ndarray) -> None:
        dt = self.dtype
        phi, qd = as_dtype(phi, dt), as_dtype(qd, dt)
        self._x = _dot(phi, self._x)
        g, dq = self._q_factor(qd, ud_psd)
        w = np.hstack([_dot(phi, self._u), g])
        dw = np.concatenate([self._d, dq])
        n = w.shape[0]
        u = np.eye(n, dtype=dt)
        d = np.empty(n, dtype=dt)
        zero = dt.type(0)
        for j in range(n - 1, -1, -1):       # MWGS, last row first
            wj = w[j]
            wc = _dot(w[:j + 1], dw * wj)    # D-weighted inner products of rows 0..j with row j
            dj = wc[j]
            d[j] = dj
            if j > 0 and dj > zero:
                uj = wc[:j] / dj
                u[:j, j] = uj
                w[:j] -= np.outer(uj, wj)
        self._u, self._d = u, d
        self.n_predicts += 1

    def _hf(self, h):
        return _dot(h, self._u)

    def _s_from(self, hf, r):
        return _dot(hf * self._d, hf.T) + r

    def _scalar(self, zj, hj, rj) -> None:
        """Bierman's scalar update: f = U^T h, g = D f, alpha_0 = r, alpha_j = alpha_(j-1) + f_j g_j,
        d_j <- d_j alpha_(j-1)/alpha_j, U_ij <- U_ij - f_j/alpha_(j-1) b_i, b_i += U_ij(old) g_j
        (b_i starting at g_i), K = b / alpha_n."""
        u = self._u
        f = _dot(hj, u)
        g = self._d * f
        a = _dot(f * g, self._ones_ut) + rj           # [alpha_1..alpha_n, alpha_0..alpha_(n-1)]
        n = f.size
        a_j, a_prev = a[:n], a[n:]
        t = u * g
        b = _dot(t, self._ones_ut[:, n:])             # b_ij = sum_(k<j) U_ik g_k (before column j)
        b_last = b[:, -1] + t[:, -1]                  # = U D U^T h = P h
        b *= -f / a_prev
        b += u
        self._u = b
        self._d = self._d * (a_prev / a_j)
        self._x = self._x + b_last * ((zj - _dot(hj, self._x)) / a_j[-1])


class SqrtFadingFilter(CarlsonFilter):
    """Seed 003's combined filter: Carlson square-root propagation of
    P- = lam Phi P Phi^T + Qd with the innovation-tested fading factor of
    fading.FadingMemoryFilter: lam = y^T W y / tr(W S0) when that exceeds gamma, else 1 (gamma,
    whiten, lam_max as there; delayed fading as described in fading.py). The factor of the
    faded prior is obtained by one more QR,
        S- <- tria([S-^T; sqrt(lam - 1) G^T]),  G = Phi_acc S+,
    since S- S-^T + (lam - 1) G G^T = lam Phi_acc P+ Phi_acc^T + Q_acc; with lam = 1 nothing
    is done, so gamma = inf is Carlson's filter operation for operation. gamma has no default:
    see the caution in FadingMemoryFilter (in the 21-state seed-003 model, closed loop, gamma = 3
    with W = I fires on ~3 % of nominal steps and inflates the sigma of unobservable states by
    1e5 to 1e14 within 20 s, the float64 run breaking down at 75 s; gamma = 10 never fired in
    200 s)."""

    def __init__(self, x0, p0, gamma: float, whiten: bool = False, lam_max: float = float('inf'),
                 dtype=np.float64) -> None:
        if gamma < 1.0:
            raise ValueError('reserve factor gamma must be >= 1')
        self.gamma = float(gamma)
        self.whiten = whiten
        self.lam_max = float(lam_max)
        self.last_fading = 1.0
        super().__init__(x0, p0, dtype)

    _s_post: np.ndarray                   # S+ after the last update
    _phi_acc: np.ndarray | None           # product of the Phi since then; None: no predict since

    def _set_p(self, value) -> None:
        super()._set_p(value)
        self._s_post, self._phi_acc = self._s, None

    def predict(self, phi: np.ndarray, qd: np.ndarray) -> None:
        phi = as_dtype(phi, self.dtype)
        super().predict(phi, qd)
        self._phi_acc = phi if self._phi_acc is None else _dot(phi, self._phi_acc)

    def _before_scalars(self, y, h, r, s0) -> None:
        self.last_fading = 1.0
        if self._phi_acc is None or not np.isfinite(self.gamma):
            return
        w = inv(r) if self.whiten else None
        eps2 = float(y @ y) if w is None else float(y @ w @ y)
        tr_s0 = float(np.trace(s0)) if w is None else float(np.sum(w * s0))
        if not eps2 > self.gamma * tr_s0:
            return
        lam = min(eps2 / tr_s0, self.lam_max)
        self.last_fading = lam
        if lam > 1.0:
            g = _dot(self._phi_acc, self._s_post)
            self._s = tria_upper(np.vstack([self._s.T, np.sqrt(self.dtype.type(lam - 1.0)) * g.T]))

    def _after_update(self) -> None:
        self._s_post, self._phi_acc = self._s, None

    def diagnostics(self) -> dict:
        d = super().diagnostics()
        d['fading'] = self.last_fading
        return d
