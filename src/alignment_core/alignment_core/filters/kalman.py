"""Linear Kalman filter with the Joseph-form covariance update."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class UpdateResult:
    """Innovation, its covariance and the normalised innovation squared of one update."""
    innovation: np.ndarray
    s: np.ndarray
    nis: float
    accepted: bool


class KalmanFilter:
    """x (n,), P (n, n). predict(Phi, Qd); update(z, H, R) in Joseph form (P stays SPD)."""

    def __init__(self, x0: np.ndarray, p0: np.ndarray) -> None:
        self.x = np.array(x0, dtype=float)
        self.P = np.array(p0, dtype=float)
        self._eye = np.eye(len(self.x))

    def predict(self, phi: np.ndarray, qd: np.ndarray) -> None:
        """x <- Phi x, P <- Phi P Phi^T + Qd (symmetric by construction up to round-off, which
        the next update's symmetrisation removes)."""
        self.x = phi @ self.x
        self.P = phi @ self.P @ phi.T + qd

    def update(self, z: np.ndarray, h: np.ndarray, r: np.ndarray,
               gate_chi2: float | None = None) -> UpdateResult:
        y = z - h @ self.x
        ph = self.P @ h.T
        s = h @ ph + r
        s_inv = np.linalg.inv(s)
        nis = float(y @ s_inv @ y)
        if gate_chi2 is not None and nis > gate_chi2:
            return UpdateResult(y, s, nis, False)
        k = ph @ s_inv
        self.x = self.x + k @ y
        ikh = self._eye - k @ h
        p = ikh @ self.P @ ikh.T + k @ r @ k.T
        self.P = 0.5 * (p + p.T)
        return UpdateResult(y, s, nis, True)
