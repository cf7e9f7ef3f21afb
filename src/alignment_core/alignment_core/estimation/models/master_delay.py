"""Master-data delay state: one random constant dt (s), the part of the master's latency the
user does not know (`filter.master_delay_state`), appended to a linear model.

The engine dates master data at stamp - master_latency_s; if they are really valid dt earlier,
every master-derived reference quantity q is reported as q(t - dt) = q(t) - q' dt, and each
measurement row z = slave - reference gains + q' dt:
    velocity rows   q = the deck spot's velocity (master velocity + lever-arm term; the LDV is
                    not delayed), q' = its acceleration a_n (nav frame): H = a_n
    attitude rows   the master attitude C_m(t - dt) = (I - [w_n dt x]) C_m(t), w_n = C_m w_m:
                    an attitude error phi_m = w_n dt, so H = -w_n (seed003's rows carry -phi_m)
    rate rows       q = C_a^T C_m w_m, q' = C_a^T d(C_m w_m)/dt: H = C^T w_dot_n
(first order in dt; exact in dt for a constant acceleration). The engine gives a_n from the
slave's own velocity change while the aircraft is parked (its acceleration is the spot's) and
from successive master samples once the LDV sees it move (the stroke's acceleration is the
LDV's, not delayed). dt is not fed back: the filter keeps it in its state (like phi_m) and
every later innovation accounts for it; the published misalignment compares the slave with the
master attitude brought forward by dt. Observable through the ship's accelerations: at sea
state 4 (0.1-0.3 m/s^2 at the spot) 10 ms is 1-3 mm/s, a few seconds of 1 cm/s LDV noise.
"""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.models.base import (
    AugmentedModel,
    Corrections,
    ErrorModel,
    Match,
    rows_of,
)
from alignment_core.estimation.models.rate_matching import mid_interval_attitude
from alignment_core.geometry.rotations import floats, rotvec_to_dcm_f
from alignment_core.navigation.strapdown import NavState


class MasterDelayState(AugmentedModel):
    """`base` + dt_master (1), prior sigma `sigma_s`, dt' = 0."""

    def __init__(self, base: ErrorModel, sigma_s: float) -> None:
        super().__init__(base, '+delay', ('dt_master',), sigma_s)
        self._velocity = rows_of(self.velocity_rows)
        self._attitude = rows_of(self.attitude_rows)

    def column(self, m: Match, rows: int) -> np.ndarray:
        """dz/d(dt) for a measurement of `rows` rows (velocity, attitude, then rate rows)."""
        col = np.zeros(rows)
        nv, na = len(self.velocity_rows), len(self.attitude_rows)
        if m.a_n is not None:
            col[:nv] = m.a_n[self._velocity]
        if na and m.w_n is not None:
            col[nv:nv + na] = -m.w_n[self._attitude]
        if rows > nv + na and m.rate is not None:
            col[nv + na:nv + na + 3] = mid_interval_attitude(m, m.rate).T @ m.rate.w_dot_n
        return col

    def fill_columns(self, h: np.ndarray, m: Match) -> None:
        h[:, self.nb] = self.column(m, h.shape[0])

    def feedback_in(self, x: np.ndarray, p: np.ndarray, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        return self.base.feedback_in(x, p, m, nav, corr)      # dt is kept, not fed back

    def misalignment(self, x, p, m: Match, nav: NavState, corr: Corrections):
        """The base model's, against the master attitude brought forward by the estimated delay,
        C_m(t) = exp([w_n dt x]) C_m(t - dt) (the dt sigma's share, |w_n| sigma_dt, is left out:
        0.02 rad/s x 1 ms is 0.07')."""
        if m.w_n is not None:
            dt = float(x[self.nb])
            wx, wy, wz = floats(m.w_n)
            m = m.with_master_attitude(np.array(rotvec_to_dcm_f(wx * dt, wy * dt, wz * dt)).reshape(3, 3) @ m.c_m)
        return self.base.misalignment(x[:self.nb], p[:self.nb, :self.nb], m, nav, corr)
