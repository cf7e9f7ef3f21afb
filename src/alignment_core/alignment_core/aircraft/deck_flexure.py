"""Deck flexure between the master INS and the aircraft's deck spot.

Per axis a second-order Gauss-Markov process theta'' + 2 beta theta' + beta^2 theta = w,
beta = 2.146 / tau, white w of spectral density q = 4 beta^3 sigma^2, so that
var(theta) = sigma^2, var(theta') = beta^2 sigma^2 and the autocorrelation
sigma^2 e^{-beta t} (1 + beta t) falls to 1/e at t = tau. Optionally a second such process
(sigma2, tau2; double-peaked deck spectra) is added, plus a static part drawn once per axis
(1-sigma static_arcmin). Optionally the intensity changes once (seed 003's model-error case:
0.02 -> 0.05 rad after 150 s): from `change_at_s` on, the driving noise of every process is
scaled by `change_factor`, so the stationary sigma moves to change_factor * sigma within a
few tau (the state itself is continuous). theta is a rotation vector in aircraft axes:
    C_a^s(t) = exp([mu x]) exp([theta(t) x])
(mu the mounting misalignment), so the aircraft rate relative to the ship is
omega_sa^a = J_r(theta) theta' (J_r the right Jacobian of SO(3)).

The state [theta, theta'] is propagated exactly at the sample rate (Van Loan: expm of
[[-A, B q B^T], [0, A^T]] dt), started from its stationary distribution, from the stream
stage_rng(seed, 'deck_flexure'). Inside an interval theta is the cubic Hermite through the
samples' (theta, theta'), and theta' its derivative: one smooth motion, consistent with the
increments. Samples are generated lazily in index order, so stepping and batch agree.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from alignment_core.compiled import kernel
from alignment_core.gauss_markov import gm2_discrete
from alignment_core.recent_rows import RecentRows
from alignment_core.rng import stage_rng
from alignment_core.units import ARCMIN
from alignment_core.validation import require

KEEP = 256
"""Samples before the least index of a read that stay readable (the next increments read back
to the previous sample)."""


@dataclass(frozen=True)
class FlexureConfig:
    """Deck flexure (off by default): sigma 3', tau 3 s; second process off (sigma2 = 0)."""
    enabled: bool = False
    sigma_arcmin: float = 3.0
    tau_s: float = 3.0
    sigma2_arcmin: float = 0.0
    tau2_s: float = 1.0
    static_arcmin: float = 3.0
    change_at_s: float = 0.0          # 0 = never
    change_factor: float = 1.0

    def validate(self) -> None:
        require(self.change_at_s >= 0.0, f"change_at_s must be >= 0 (0 = never), got {self.change_at_s}")
        require(0.0 <= self.change_factor <= 100.0, f"change_factor must be in [0, 100], got {self.change_factor}")
        for k in ('sigma_arcmin', 'sigma2_arcmin', 'static_arcmin'):
            v = getattr(self, k)
            require(0.0 <= v <= 600.0, f"{k} must be in [0, 600], got {v}")
        for k in ('tau_s', 'tau2_s'):
            v = getattr(self, k)
            require(0.0 < v <= 1000.0, f"{k} must be in (0, 1000], got {v}")




def _chol(p: np.ndarray) -> np.ndarray:
    if not np.any(p):
        return np.zeros_like(p)
    return np.linalg.cholesky(p)




class FlexureProcess:
    """theta_k, theta'_k (rad, rad/s; aircraft axes) at sample k = round(tau * rate_hz)."""

    def __init__(self, cfg: FlexureConfig, seed: int, rate_hz: float) -> None:
        self.cfg = cfg
        self.rate_hz = rate_hz
        self.dt = 1.0 / rate_hz
        self.rng = stage_rng(seed, 'deck_flexure')
        self.static = self.rng.standard_normal(3) * cfg.static_arcmin * ARCMIN
        procs = [(cfg.sigma_arcmin * ARCMIN, cfg.tau_s)]
        if cfg.sigma2_arcmin > 0.0:
            procs.append((cfg.sigma2_arcmin * ARCMIN, cfg.tau2_s))
        d = [gm2_discrete(s, t, self.dt) for s, t in procs]
        self.phi_t = np.stack([x[0].T for x in d])                      # (P, 2, 2), transposed
        self.l_t = np.stack([_chol(x[1]).T for x in d])
        p0 = np.stack([_chol(x[2]).T for x in d])
        self.x = self.rng.standard_normal((len(procs), 3, 2)) @ p0       # (P, 3 axes, 2)
        self._th, self._thd = RecentRows(3), RecentRows(3)
        self._n = 0
        self.k_change = (int(round(cfg.change_at_s * rate_hz)) if cfg.change_at_s > 0.0 and cfg.change_factor != 1.0
                         else None)
        self._store(self.x[None])

    def _store(self, xs: np.ndarray) -> None:
        """Append the samples of the states xs (m, P, 3, 2): theta (static part included), theta'."""
        s = xs.sum(axis=1)
        self._th.extend(self.static + s[..., 0])
        self._thd.extend(s[..., 1])
        self._n += len(xs)

    def _extend(self, k_max: int) -> None:
        while self._n <= k_max:
            m = min(k_max + 1 - self._n, 4096)
            noise = self.rng.standard_normal((m,) + self.x.shape)
            if self.k_change is not None:
                k = np.arange(self._n, self._n + m)        # sample index each step produces
                noise[k >= self.k_change] *= self.cfg.change_factor
            xs = _propagate(self.x, self.phi_t, noise @ self.l_t)
            self.x = xs[-1].copy()
            self._store(xs)

    def index(self, tau) -> np.ndarray:
        return np.rint(np.asarray(tau, dtype=float) * self.rate_hz).astype(np.int64)

    def at(self, k) -> tuple[np.ndarray, np.ndarray]:
        """(theta, theta') (…, 3) at sample indices k (…). The samples more than KEEP before the
        least index asked for are let go (recent_rows.py): reads move forward, in a node's run as
        in the batch pipeline's batches."""
        k = np.asarray(k)
        if k.size:
            self._extend(int(k.max()))
            out = self._th[k], self._thd[k]
            for rows in (self._th, self._thd):
                rows.forget_before(int(k.min()) - KEEP)
            return out
        return self._th[k], self._thd[k]

    def generate(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The first n samples (for tests and plots)."""
        return self.at(np.arange(n))


@kernel
def _propagate(x, phi_t, drive):
    """The states (m, P, 3, 2) after each of m exact steps x <- x phi_t + drive[j] from x (P, 3, 2),
    drive[j] = noise_j L^T: per process one BLAS product, the one numpy's x @ phi_t makes."""
    m = drive.shape[0]
    xs = np.empty((m,) + x.shape)
    x = x.copy()
    for j in range(m):
        for p in range(x.shape[0]):
            x[p] = np.dot(x[p], phi_t[p]) + drive[j, p]
        xs[j] = x
    return xs
