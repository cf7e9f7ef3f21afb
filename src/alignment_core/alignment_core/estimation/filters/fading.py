"""Fading filters on the full covariance: fading memory (fixed or innovation-tested factor) and
the strong tracking filter (Zhou Donghua; single and multiple fading factors).

The innovation-driven factors need the innovation of time k to decide how much to fade the
prediction to time k, which `predict` has already been asked for. The API handles this
honestly with a *delayed fading*:

* `predict(Phi, Qd)` commits the nominal prediction x <- Phi x, P <- Phi P Phi^T + Qd (what a
  KF would do; P read between updates is this nominal prediction) and keeps the product
  Phi_acc of the transitions since the last accepted update.
* `update` first forms the innovation y with the nominal S0 = H P H^T + R and applies the gate
  to it (a chi-square test of the nominal model: gating on the faded S would be useless, since
  fading inflates S towards y y^T and makes any outlier look normal). If accepted, it computes
  the factor(s) and replaces the prior by the faded one,
      P- = Lambda^(1/2) F Lambda^(1/2) + Q_acc,   F = Phi_acc P+ Phi_acc^T,  Q_acc = P - F,
  i.e. P- = P + (Lambda^(1/2) F Lambda^(1/2) - F), where P+ is the covariance after the last
  accepted update; with several predicts between updates this fades everything carried over
  from the last update, and Q_acc (the process noise accumulated since) is not faded. With one
  predict per update it is exactly P- = L Phi P Phi^T + Qd of the papers. x does not depend on
  the fading, so nothing else changes. Then the ordinary Joseph update follows.
* No fading is applied when no predict happened since the last accepted update, nor after a
  gated measurement (the pending fading stays pending for the next accepted one).
* reset_state() (closed-loop feedback) only zeroes x and leaves the pending fading intact.

Replacing P from outside (f.P = ...) drops the pending fading and restarts from that P.
"""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.filters.base import UpdateResult, as_dtype, check_nis, inv
from alignment_core.estimation.filters.kalman import KalmanFilter

_dot = np.dot


class _DelayedFading(KalmanFilter):
    """KalmanFilter plus the bookkeeping of the delayed fading (see the module docstring)."""

    def __init__(self, x0, p0, dtype=np.float64) -> None:
        super().__init__(x0, p0, dtype)
        self._p_post = self.P        # P+ after the last accepted update (an array read never changes)
        self._phi_acc: np.ndarray | None = None   # product of the Phi since then; None: no predict since
        self._p_written = self.P     # the P this object last wrote, to detect outside assignment
        self.last_fading: float | np.ndarray = 1.0
        self.last_nis_faded = float('nan')

    def _check_outside_p(self) -> None:
        if self.P is not self._p_written:      # P assigned from outside: restart from it
            self.P = as_dtype(self.P, self.dtype)
            self._p_post, self._phi_acc, self._p_written = self.P, None, self.P

    def _propagate(self, phi: np.ndarray, qd: np.ndarray) -> None:
        super().predict(phi, qd)

    def predict(self, phi: np.ndarray, qd: np.ndarray) -> None:
        self._check_outside_p()
        phi = as_dtype(phi, self.dtype)
        self._propagate(phi, qd)
        self._phi_acc = phi if self._phi_acc is None else _dot(phi, self._phi_acc)
        self._p_written = self.P

    def _carried(self) -> np.ndarray:
        """F = Phi_acc P+ Phi_acc^T: the part of the prior carried over from the last update
        (called after a predict only)."""
        phi = self._phi_acc
        assert phi is not None
        return _dot(_dot(phi, self._p_post), phi.T)

    def _fade(self, y, h, r, s0) -> np.ndarray | None:
        """The faded prior P- (or None for no fading); sets last_fading."""
        raise NotImplementedError

    def _observe(self, y) -> None:
        """Hook: an accepted innovation (the STF keeps its V0 recursion here)."""

    def update(self, z: np.ndarray, h: np.ndarray, r: np.ndarray,
               gate_chi2: float | None = None) -> UpdateResult:
        self._check_outside_p()
        dt = self.dtype
        z, h, r = as_dtype(z, dt), as_dtype(h, dt), as_dtype(r, dt)
        y, ph, s0 = self._innovation(z, h, r, self.x, self.P)
        s_inv = inv(s0)
        nis = check_nis(float(_dot(_dot(y, s_inv), y)))
        self.last_nis = nis
        if gate_chi2 is not None and nis > gate_chi2:
            self.n_gated += 1
            return UpdateResult(y, s0, nis, False)
        self._observe(y)
        self.last_fading = 1.0
        if self._phi_acc is not None:
            p_faded = self._fade(y, h, r, s0)
            if p_faded is not None:
                self.P = p_faded
                _, ph, s = self._innovation(z, h, r, self.x, self.P)
                s_inv = inv(s)
        self.last_nis_faded = float(_dot(_dot(y, s_inv), y))
        self._joseph(y, ph, s_inv, h, r)
        self._p_post, self._phi_acc, self._p_written = self.P, None, self.P
        self.n_updates += 1
        return UpdateResult(y, s0, nis, True)

    def _weight(self, r: np.ndarray, whiten: bool) -> np.ndarray | None:
        return inv(r) if whiten else None

    @staticmethod
    def _tr(w: np.ndarray | None, a: np.ndarray) -> float:
        """tr(W a) for symmetric W and a (tr a when W is None)."""
        return float(np.trace(a)) if w is None else float(np.sum(w * a))

    def diagnostics(self) -> dict:
        d = super().diagnostics()
        lam = self.last_fading
        if isinstance(lam, np.ndarray):
            lam = lam.copy()
        elif getattr(self, 'alpha', None) is not None:    # multiple factors: always one per state
            lam = np.full(self.x.shape, lam, dtype=self.dtype)
        d['fading'] = lam
        d['nis_faded'] = self.last_nis_faded
        return d


class FadingMemoryFilter(_DelayedFading):
    """Fading-memory Kalman filter.

    Fixed factor: P- = lam Phi P Phi^T + Qd at every predict (lam >= 1; lam = 1 is the KF).

    Innovation-tested factor (seed 003; gamma given, gamma >= 1 the reserve factor): with the
    nominal innovation covariance S0 = E[y y^T] = H P H^T + R (P the nominal prediction),
        if y^T W y > gamma tr(W S0):   lam_a = y^T W y / tr(W S0)   (> gamma)
        else:                          lam_a = 1,
    and P- = lam_a F + Q_acc (F, Q_acc as in the module docstring). "Ratio of traces" is read
    literally, tr(W y y^T) / tr(W E[y y^T]). (Choosing lam_a so that the faded S matches y y^T,
    (y^T W y - tr(W S0) + tr(W M)) / tr(W M) with M = H F H^T, inflates far more when R dominates
    S0 and, in the tests' 21-state model, winds the unobservable states up within seconds.)
    W = I (seed 003) or W = R^-1 (whiten=True: unit-free when the channels have different units,
    e.g. m/s and rad). lam_max caps lam_a.

    Caution: any fading multiplies the variance of unobservable state combinations, which no
    measurement brings back; false alarms of the test (y^T W y / tr(W S0) has mean 1 under the
    nominal model) therefore ratchet them up. Choose gamma so that false alarms are rare over the
    run (e.g. the 1 - 1e-6 quantile of y^T W y / tr(W S0)), or cap lam_max."""

    def __init__(self, x0, p0, lam: float = 1.0, gamma: float | None = None, whiten: bool = False,
                 lam_max: float = float('inf'), dtype=np.float64) -> None:
        if lam < 1.0:
            raise ValueError('fading factor lam must be >= 1')
        if gamma is not None and gamma < 1.0:
            raise ValueError('reserve factor gamma must be >= 1')
        super().__init__(x0, p0, dtype)
        self.lam = float(lam)
        self.gamma = gamma
        self.whiten = whiten
        self.lam_max = float(lam_max)
        self._lam_acc = 1.0

    def _propagate(self, phi, qd) -> None:
        dt = self.dtype
        self.x = _dot(phi, self.x)
        fp = _dot(_dot(phi, self.P), phi.T)
        if self.lam != 1.0:
            fp = self.lam * fp
            self._lam_acc = self._lam_acc * self.lam if self._phi_acc is not None else self.lam
        self.P = fp + as_dtype(qd, dt)
        self.n_predicts += 1

    def _carried(self) -> np.ndarray:
        f = super()._carried()
        return f if self.lam == 1.0 else self._lam_acc * f

    def _fade(self, y, h, r, s0):
        if self.gamma is None:
            return None
        w = self._weight(r, self.whiten)
        eps2 = float(y @ y) if w is None else float(y @ w @ y)
        tr_s0 = self._tr(w, s0)
        if not eps2 > self.gamma * tr_s0:
            return None
        lam = min(eps2 / tr_s0, self.lam_max)
        self.last_fading = lam
        return self.P + (lam - 1.0) * self._carried()


class StrongTrackingFilter(_DelayedFading):
    """Strong tracking filter (Zhou Donghua), suboptimal fading factor(s) from the innovations.

    V0(k) = y y^T at the first update, else (rho V0(k-1) + y y^T) / (1 + rho)
    N = V0 - beta R - H Q_acc H^T,  M = H F H^T  (F = Phi P+ Phi^T with one predict per update;
    H Q_acc H^T = S0 - R - M), traces weighted by W = I (default) or R^-1 (whiten=True).

    Single factor (alpha None):  lam = max(1, tr(W N) / tr(W M)),  P- = lam F + Q_acc.

    Multiple factors (alpha = (alpha_1..alpha_n) >= 1, prior knowledge of which states may
    change, as in the paper):
        c = tr(W N) / tr(W H A^(1/2) F A^(1/2) H^T),   A = diag(alpha)
        lam_i = max(1, alpha_i c),                      P- = L^(1/2) F L^(1/2) + Q_acc.
    Why this is consistent: the paper's C_k = tr N / sum_i alpha_i M_ii pairs a state index i
    (n of them) with the diagonal of an m x m measurement-space matrix. Here numerator and
    denominator are both traces of m x m measurement-space covariances (in the same weighting W),
    so c is a pure number for any units of x and z: it is the scale for which the faded prior
    seen through H matches the excess innovation covariance, tr(W H (c A)^(1/2) F (c A)^(1/2) H^T)
    = tr(W N), exactly when no lam_i is clipped at 1. The denominator expands to
    sum_ij sqrt(alpha_i alpha_j) F_ij (H^T W H)_ji: each state weighted by how the measurement
    sees it. The symmetric form L^(1/2) F L^(1/2) (instead of the paper's L F, which is not even
    symmetric) multiplies the variance of state i by lam_i and keeps every correlation
    coefficient, so the faded F stays a covariance. alpha = 1 gives the single factor."""

    def __init__(self, x0, p0, rho: float = 0.95, beta: float = 1.0, alpha=None, whiten: bool = False,
                 lam_max: float = float('inf'), dtype=np.float64) -> None:
        if not 0.0 < rho <= 1.0:
            raise ValueError('forgetting factor rho must be in (0, 1]')
        if beta < 1.0:
            raise ValueError('weakening factor beta must be >= 1')
        super().__init__(x0, p0, dtype)
        self.rho = float(rho)
        self.beta = float(beta)
        self.alpha = None if alpha is None else np.asarray(alpha, dtype=self.dtype)
        if self.alpha is not None and (self.alpha.shape != self.x.shape or np.any(self.alpha < 1.0)):
            raise ValueError('alpha must be (n,) with every alpha_i >= 1')
        self.whiten = whiten
        self.lam_max = float(lam_max)
        self.v0: np.ndarray | None = None

    def _observe(self, y) -> None:
        yy = np.outer(y, y)
        self.v0 = yy if self.v0 is None else (self.rho * self.v0 + yy) / (1.0 + self.rho)

    def _fade(self, y, h, r, s0):
        w = self._weight(r, self.whiten)
        f = self._carried()
        m = h @ f @ h.T
        n = self.v0 - self.beta * r - (s0 - r - m)
        tr_n = self._tr(w, n)
        if self.alpha is None:
            tr_m = self._tr(w, m)
            if not (tr_m > 0.0 and tr_n > tr_m):
                return None
            lam = min(tr_n / tr_m, self.lam_max)
            self.last_fading = lam
            return self.P + (lam - 1.0) * f
        sa = np.sqrt(self.alpha)
        tr_ma = self._tr(w, h @ (f * np.outer(sa, sa)) @ h.T)
        if not tr_ma > 0.0:
            return None
        lam = np.clip(self.alpha * (tr_n / tr_ma), 1.0, self.lam_max).astype(self.dtype)
        self.last_fading = lam
        if np.all(lam == 1.0):
            return None
        sl = np.sqrt(lam)
        return self.P + (f * np.outer(sl, sl) - f)
