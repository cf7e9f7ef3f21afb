"""Seed 002's 10-state horizontal velocity-matching model (`seed002_10`), in the paper's order

    x = [dV_E, dV_N, phi_E, phi_N, phi_U, nabla_x, nabla_y, eps_x, eps_y, eps_z]

(nabla and eps body axes, FLU: x forward, y left; the paper's right-forward-up x, y span the same
horizontal body plane). The vertical channel is ignored: no dV_U state, and the strapdown's
vertical velocity is held to the reference's at every update (an external height/vertical
damping, as the paper's "vertical channel ignored" requires), so dV_U = 0 in the dynamics.
F is the velocity-matching model's (velocity_matching.py) restricted to these states:
    phi'  = -[w_in x] phi - C_b^n eps
    dV_h' = ([f^n x] phi)_h - ([(2 w_ie + w_en) x] dV)_h + (C_b^n [nabla_x, nabla_y, 0])_h
(the accelerometer z bias, nearly vertical, is left out as in the paper). Phi = I + F h +
(F h)^2 / 2; Qd = diag(vrw^2 h (2), arw^2 h (3), accel bias rw^2 h (2), gyro bias rw^2 h (3)).
Measurement: z = (V_slave - V_ref)_(E, N) = [I2 0] x + v (Joseph update, as the paper).

Observability (tested): at constant velocity on a level, steady deck only phi_E, phi_N (and
the bias combinations) are seen; yaw needs horizontal acceleration -- on a ship, the lever-arm
acceleration of its yaw, roll and pitch motion.
"""
from __future__ import annotations

import numpy as np

from alignment_core.estimation.models.base import (
    DV,
    EPS,
    NABLA,
    PHI,
    Corrections,
    ErrorModel,
    Match,
    Measurement,
    Propagation,
    nominal_attitude,
    relative_misalignment,
)
from alignment_core.estimation.models.velocity_matching import attitude_variances, continuous, noise_densities
from alignment_core.geometry.rotations import quat_to_dcm
from alignment_core.geometry.rotations_compiled import rotate_attitude
from alignment_core.navigation.strapdown import NavState
from alignment_core.units import DPH, UG

LABELS = ('dV_E', 'dV_N', 'phi_E', 'phi_N', 'phi_U', 'nabla_x', 'nabla_y', 'eps_x', 'eps_y', 'eps_z')
VM_INDEX = np.array([3, 4, 0, 1, 2, 9, 10, 6, 7, 8])      # these states in the 12-state model
H = np.hstack([np.eye(2), np.zeros((2, 8))])


class Seed002Horizontal(ErrorModel):
    """seed002_10 (module docstring)."""
    name = 'seed002_10'
    labels = LABELS
    kinds = (DV,) * 2 + (PHI,) * 3 + (NABLA,) * 2 + (EPS,) * 3
    attitude = slice(2, 5)
    velocity_rows = (0, 1)

    def __init__(self, cfg) -> None:
        self.cfg = cfg
        self.noise = noise_densities(cfg)
        self._qd: dict[float, np.ndarray] = {}

    def initial_covariance(self) -> np.ndarray:
        c = self.cfg
        return np.diag(np.concatenate([np.full(2, c.init_velocity_sigma_mps ** 2), attitude_variances(c),
                                       np.full(2, (c.accel_bias_sigma_ug * UG) ** 2),
                                       np.full(3, (c.gyro_bias_sigma_dph * DPH) ** 2)]))

    def continuous(self, p: Propagation) -> np.ndarray:
        return continuous(p.c_nb, p.f_n, p.w_ie, p.w_en)[np.ix_(VM_INDEX, VM_INDEX)]

    def process_noise(self, h: float) -> np.ndarray:
        qd = self._qd.get(h)
        if qd is None:
            q = self.noise
            qd = self._qd[h] = np.diag(np.repeat([q.vrw ** 2 * h, q.arw ** 2 * h, q.accel_bias_rw ** 2 * h,
                                                  q.gyro_bias_rw ** 2 * h], [2, 3, 2, 3]))
        return qd

    def measurement(self, m: Match, corr: Corrections) -> Measurement:
        return Measurement(m.z_vel[0:2], H, m.r_vel[0:2, 0:2])

    def feedback(self, x, p, m: Match, nav: NavState, corr: Corrections) -> np.ndarray:
        nav.q_nb = rotate_attitude(nav.q_nb, x[2:5])
        nav.v_n = np.array([nav.v_n[0] - x[0], nav.v_n[1] - x[1], m.v_ref[2]])
        corr.ba = corr.ba + np.array([x[5], x[6], 0.0])
        corr.bg = corr.bg + x[7:10]
        return np.zeros(10)

    def misalignment(self, x, p, m: Match, nav: NavState, corr: Corrections):
        return relative_misalignment(nominal_attitude(m), quat_to_dcm(nav.q_nb), p[2:5, 2:5])
