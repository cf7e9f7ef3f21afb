"""Angular-rate matching: three rows comparing the slave's gyros with the master's body rate,
appended to a model with attitude (phi) and gyro-bias (eps) states (`filter.rate_matching`).

The aircraft rides the ship rigidly (plus deck flexure), so its inertial rate in nav axes is
the ship's, Omega = C_m w_m + w_in (w_m the master's body rate w.r.t. nav, w_in Earth plus
transport rate). Its gyros read C_a^T Omega + theta' + eps + noise (theta' the flexure rate,
aircraft axes, where the model has flexure states). Predicted with the estimates,
C_a,est = (I - [phi x]) C_a and C_m,est = (I - [phi_m x]) C_m, the difference
    z_w = w_slave - C_a,est^T (C_m,est w_m + w_in)
        = eps + theta' + C_a^T [Omega x] phi - C_a^T [(C_m w_m) x] phi_m + v_w,
so H_phi = C^T [Omega x], H_eps = I, H_theta' = I, H_phi_m = -C^T [(C_m w_m) x] (H_eps and
H_theta' carry + (h/2) [w x] too: a gyro error also turns the mid-interval attitude below).
The rows see the relative misalignment phi - phi_m directly, about every axis across Omega
(no specific force needed): a ship rolling at 0.02 rad/s turns 1' of misalignment into
6e-6 rad/s = 1.2 deg/h, against a navigation gyro's 0.6 deg/h per 100 Hz sample.

Over the IMU interval [t - h, t] ending at the match the gyro gives the mean rate w_b = dtheta/h
exactly (increments), so the prediction is the interval mean too: Omega by the trapezoid of
the master rates at both ends, C_a at mid-interval = C_a(t) exp(-[dtheta/2 x]) (the nav
frame's own rotation over h/2 is below 1e-6 rad). Without the midpoint, a 10 ms interval at
0.03 rad/s would bias the prediction by ~Omega^2 h/2 = 5e-6 rad/s, as large as the signal.

R_w = (arw^2 / h + sigma_w^2) I: the gyro's white noise over the interval plus
`rate_match_sigma_dph` for what the model does not carry (vibration, unmodelled flexure rate,
the master's rate noise). Timing matters: an unknown lag dt of the master turns the ship's
angular acceleration into dt * d(Omega)/dt (1 ms at sea state 4 is ~1 deg/h); the delay state
(master_delay.py) models it.
"""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.models.base import (
    Corrections,
    ErrorModel,
    Match,
    Measurement,
    ModelWrapper,
    RateInputs,
)
from alignment_core.geometry.rotations import quat_to_dcm, rotvec_to_dcm, skew_into

PHI_LABELS = ('phi_E', 'phi_N', 'phi_U')
EPS_LABELS = ('eps_x', 'eps_y', 'eps_z')
PHI_M_LABELS = ('phim_E', 'phim_N', 'phim_U')
THETA_DOT_LABELS = ('thetadot_x', 'thetadot_y', 'thetadot_z')


def _block(labels: tuple[str, ...], names: tuple[str, ...]) -> int | None:
    """Index of the first of three consecutive states named `names`, or None."""
    if names[0] not in labels:
        return None
    i = labels.index(names[0])
    return i if labels[i:i + 3] == names else None


def mid_interval_attitude(m: Match, rate: RateInputs) -> np.ndarray:
    """C_a at the middle of the rate interval: the slave attitude at the match turned back by
    half the interval's angle increment (body axes)."""
    return quat_to_dcm(m.ins.q_nb) @ rotvec_to_dcm(-0.5 * rate.dtheta)


class RateMatching(ModelWrapper):
    """`base` + rate rows (module docstring). The states are the base's; rows are added at
    matches that carry `rate` inputs (from the second master sample on the IMU grid)."""

    def __init__(self, base: ErrorModel, arw: float, sigma_w: float) -> None:
        i_phi, i_eps = _block(base.labels, PHI_LABELS), _block(base.labels, EPS_LABELS)
        if base.nonlinear or i_phi is None or i_eps is None:
            raise ValueError(f'rate matching needs a linear model with phi and eps states, not {base.name}')
        super().__init__(base, '+rate')
        self.i_phi, self.i_eps = i_phi, i_eps
        self.i_phi_m = _block(base.labels, PHI_M_LABELS)
        self.i_theta_dot = _block(base.labels, THETA_DOT_LABELS)
        self.arw2 = float(arw) ** 2
        self.sigma2 = float(sigma_w) ** 2

    def rate_rows_of(self, m: Match, rt: RateInputs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(z_w (3,), H_w (3, n), R_w (3, 3)) at a match with rate inputs rt (= m.rate)."""
        c = mid_interval_attitude(m, rt)
        pred = c.T @ rt.omega_n
        z = rt.w_b - pred
        h = np.zeros((3, self.n))
        big = np.zeros((3, 3))
        skew_into(big, 0, 0, rt.omega_n)
        h[:, self.i_phi:self.i_phi + 3] = c.T @ big
        # a gyro error also turns the mid-interval attitude by h/2 of itself: I + (h/2) [pred x]
        gyro = np.eye(3)
        skew_into(gyro, 0, 0, 0.5 * rt.h * pred)
        h[:, self.i_eps:self.i_eps + 3] = gyro
        if self.i_phi_m is not None:
            wm = np.zeros((3, 3))
            skew_into(wm, 0, 0, rt.w_n)
            h[:, self.i_phi_m:self.i_phi_m + 3] = -c.T @ wm
        if self.i_theta_dot is not None:
            h[:, self.i_theta_dot:self.i_theta_dot + 3] = gyro
        r = np.eye(3) * (self.arw2 / rt.h + self.sigma2)
        return z, h, r

    def measurement(self, m: Match, corr: Corrections) -> Measurement:
        meas = self.base.measurement(m, corr)
        if m.rate is None:
            return meas
        z_w, h_w, r_w = self.rate_rows_of(m, m.rate)
        k = len(meas.z)
        r = np.zeros((k + 3, k + 3))
        r[:k, :k] = meas.r
        r[k:, k:] = r_w
        return Measurement(np.concatenate([meas.z, z_w]), np.vstack([meas.matrix(), h_w]), r)
