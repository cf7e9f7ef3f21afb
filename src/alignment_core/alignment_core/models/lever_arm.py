"""Lever-arm error states: three random constants dr = r_true - r_used (ship axes) appended to
any velocity-matching model (`filter.lever_arm_states: true`).

The reference velocity carries the lever-arm term C_m (w_m x r_used); the slave really moves
with C_m (w_m x r_true), so every velocity row of the measurement gains
    z_v = ... + C_m [w_m x] dr,        H_dr = rows `velocity_rows` of C_m [w_m x]
(to first order: the master attitude error times dr is second order). dr' = 0, no process
noise; prior sigma `lever_arm_sigma_m`. Feedback adds dr to the engine's lever-arm correction.
Observable only while the ship rotates: |w_m| of 0.01-0.02 rad/s at sea state 4 makes 1 m of
arm error a 1-2 cm/s signal (the LDV's noise is 1 cm/s at 100 Hz).
"""
from __future__ import annotations

import numpy as np

from ..attitude import skew
from ..strapdown import NavState
from .base import OTHER, Corrections, ErrorModel, Match, Measurement, Propagation


class LeverArmStates(ErrorModel):
    """`base` + dr (3); every method delegates to `base` for its own states."""

    def __init__(self, base: ErrorModel, sigma_m: float) -> None:
        if base.nonlinear:
            raise ValueError('lever-arm states need a linear base model')
        self.base = base
        self.name = base.name + '+lever_arm'
        self.labels = base.labels + ('dr_x', 'dr_y', 'dr_z')
        self.kinds = base.kinds + (OTHER,) * 3
        self.attitude = base.attitude
        self.velocity_rows = base.velocity_rows
        self.attitude_rows = base.attitude_rows
        self.nb = base.n
        self.sigma = float(sigma_m)
        self._qd: dict[float, np.ndarray] = {}

    def _grow(self, a: np.ndarray, corner: float) -> np.ndarray:
        out = np.zeros((self.nb + 3, self.nb + 3))
        out[:self.nb, :self.nb] = a
        out[self.nb:, self.nb:] = corner * np.eye(3)
        return out

    def initial_covariance(self) -> np.ndarray:
        return self._grow(self.base.initial_covariance(), self.sigma ** 2)

    def continuous(self, p: Propagation) -> np.ndarray:
        return self._grow(self.base.continuous(p), 0.0)

    def transition(self, p: Propagation) -> np.ndarray:
        return self._grow(self.base.transition(p), 1.0)

    def process_noise(self, h: float) -> np.ndarray:
        qd = self._qd.get(h)
        if qd is None:
            qd = self._qd[h] = self._grow(self.base.process_noise(h), 0.0)
        return qd

    def measurement(self, m: Match, corr: Corrections) -> Measurement:
        z, h, r, _ = self.base.measurement(m, corr)
        hh = np.zeros((h.shape[0], self.nb + 3))
        hh[:, :self.nb] = h
        cw = m.c_m @ skew(m.w_m)
        for row, axis in enumerate(self.velocity_rows):
            hh[row, self.nb:] = cw[axis]
        return Measurement(z, hh, r)

    def feedback(self, x, p, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        xb = self.base.feedback(x[:self.nb], p[:self.nb, :self.nb], m, nav, corr)
        corr.dr = corr.dr + x[self.nb:]
        return np.concatenate([xb, np.zeros(3)])

    def misalignment(self, x, p, m: Match, nav: NavState, corr: Corrections):
        return self.base.misalignment(x[:self.nb], p[:self.nb, :self.nb], m, nav, corr)
