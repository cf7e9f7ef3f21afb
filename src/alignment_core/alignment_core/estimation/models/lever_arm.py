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

from alignment_core.estimation.models.base import AugmentedModel, Corrections, ErrorModel, Match, rows_of
from alignment_core.geometry.rotations import skew
from alignment_core.navigation.strapdown import NavState


class LeverArmStates(AugmentedModel):
    """`base` + dr (3); every method delegates to `base` for its own states."""

    def __init__(self, base: ErrorModel, sigma_m: float) -> None:
        super().__init__(base, '+lever_arm', ('dr_x', 'dr_y', 'dr_z'), sigma_m)
        self._velocity = rows_of(self.velocity_rows)

    def fill_columns(self, h: np.ndarray, m: Match) -> None:
        nb = self.nb
        h[:len(self.velocity_rows), nb:nb + 3] = (m.c_m @ skew(m.w_m))[self._velocity]

    def feedback_in(self, x: np.ndarray, p: np.ndarray, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        nb = self.nb
        x_new = self.base.feedback_in(x, p, m, nav, corr)
        corr.dr = corr.dr + x[nb:nb + 3]
        x_new[nb:nb + 3] = 0.0
        return x_new
